//! The UMAT for a host without `PNEWDT` (`HostSignal::NanStress`, as Kratos calls it):
//! every point numbered 0, two calls per iteration (stress, then tangent) answered by one
//! solve, `TIME(2)` never read, the answers those of a host with `PNEWDT` (NaN in `STRESS`
//! where that host is asked for a smaller step), table mode refused.
//! c_examples/kratos_umat.c makes the same calls through `umat_` on two threads.

mod common;

use rve::host::{HostSignal, Hypothesis, SearchPath, Umat, UmatCall, UmatOutputs};

const INCREMENTS: usize = 10;

fn umat() -> Umat {
    Umat::new(SearchPath::new([common::repo("scenes")]))
}

/// STRESS, DDSDDE, PNEWDT and STATEV after one call at increment `k` of point `noel`.
struct Answer {
    stress: Vec<f64>,
    ddsdde: Vec<f64>,
    pnewdt: f64,
    statev: Vec<f64>,
    failed: bool,
}

fn call(table: &Umat, signal: HostSignal, noel: i32, k: usize, statev: &[f64]) -> Answer {
    let step = 3e-4 / INCREMENTS as f64;
    let stran = [step * k as f64, 0.0, 0.0];
    let dstran = [step, 0.0, 0.0];
    let mut c: UmatCall = common::cycle_call("paper_rve", &[], &stran, &dstran, noel, k);
    if signal == HostSignal::NanStress {
        // One TIME value: a read of TIME(2) would meet NaN (and the state refuse it).
        c.time[1] = f64::NAN;
        c.npt = 0;
        c.kinc = 1;
    }
    assert_eq!(c.hypothesis, Hypothesis::PlaneStress);
    let (mut stress, mut ddsdde, mut pnewdt) = (vec![0.0; 3], vec![0.0; 9], 0.0);
    let mut statev = statev.to_vec();
    let mut out = UmatOutputs {
        stress: &mut stress,
        ddsdde: &mut ddsdde,
        statev: &mut statev,
        pnewdt: &mut pnewdt,
    };
    let failed = table.call_as(&c, &mut out, signal).is_err();
    Answer {
        stress,
        ddsdde,
        pnewdt,
        statev,
        failed,
    }
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn two_calls_per_iteration_solve_once_and_give_the_pnewdt_hosts_answers() {
    let model = rve::model::cache::model_for_file(&common::repo("scenes/paper_rve.toml")).unwrap();
    let n = model.statev_len() + 5;
    let (kratos, reference) = (umat(), umat());
    let (mut kept, mut kept_ref) = (vec![0.0; n], vec![0.0; n]);
    let mut nan_steps = 0;
    for k in 0..INCREMENTS {
        let stress_call = call(&kratos, HostSignal::NanStress, 0, k, &kept);
        let tangent_call = call(&kratos, HostSignal::NanStress, 0, k, &kept);
        let r = call(&reference, HostSignal::Pnewdt, 1, k, &kept_ref);
        assert!(!r.failed && !stress_call.failed, "increment {k}");
        assert_eq!(
            bits(&stress_call.stress),
            bits(&tangent_call.stress),
            "increment {k}"
        );
        assert_eq!(
            bits(&stress_call.ddsdde),
            bits(&r.ddsdde),
            "increment {k}: DDSDDE"
        );
        if r.pnewdt > 0.0 && r.pnewdt < 1.0 {
            nan_steps += 1;
            assert!(
                stress_call.stress.iter().all(|s| s.is_nan()),
                "increment {k}"
            );
        } else {
            assert_eq!(
                bits(&stress_call.stress),
                bits(&r.stress),
                "increment {k}: STRESS"
            );
            assert_eq!(
                stress_call.pnewdt, 0.0,
                "no request: the caller's PNEWDT stays 0"
            );
        }
        kept = tangent_call.statev;
        kept_ref = r.statev;
    }
    let stats = kratos.stats();
    println!("{nan_steps} NaN increments of {INCREMENTS}; {stats:?}");
    assert_eq!(stats.calls, 2 * INCREMENTS as u64);
    assert_eq!(
        stats.repeats, INCREMENTS as u64,
        "each tangent call repeats its stress call"
    );
    assert_eq!(stats.points, 0, "STATEV mode puts no point in the table");
    assert_eq!(stats.failures, 0);
}

#[test]
fn table_mode_is_refused_without_pnewdt_and_kept_with_it() {
    let table = umat();
    let a = call(&table, HostSignal::NanStress, 0, 0, &[0.0; 5]);
    assert!(a.failed && a.stress.iter().all(|s| s.is_nan()));
    let b = call(&table, HostSignal::Pnewdt, 1, 0, &[0.0; 5]);
    assert!(!b.failed && b.stress.iter().all(|s| s.is_finite()) && b.stress[0] > 0.0);
}

#[test]
fn a_failure_without_pnewdt_is_nan_in_stress_with_pnewdt_stress_untouched() {
    let model = rve::model::cache::model_for_file(&common::repo("scenes/paper_rve.toml")).unwrap();
    let n = model.statev_len();
    let table = umat();
    let mut statev = call(&table, HostSignal::NanStress, 0, 0, &vec![0.0; n]).statev;
    statev[5] += 1.0;
    let a = call(&table, HostSignal::NanStress, 0, 1, &statev);
    assert!(a.failed && a.stress.iter().all(|s| s.is_nan()));
    let b = call(&table, HostSignal::Pnewdt, 1, 1, &statev);
    assert!(b.failed && b.stress == [0.0; 3] && b.pnewdt > 0.0 && b.pnewdt < 1.0);
}

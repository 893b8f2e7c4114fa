//! The UMAT refuses a `DTIME` that is no time increment: not finite, for every material,
//! and negative where the material's integration reads it (IMPL-EX). Through the exported
//! `rve_umat`, as each host style calls it: with `PNEWDT` and two `TIME` values
//! (CalculiX, Abaqus), and with a NULL `PNEWDT` and one `TIME` value (Kratos). A refused
//! call names `DTIME` and its value, asks for a smaller step (`PNEWDT` < 1, or NaN in
//! `STRESS` without `PNEWDT`), and leaves `STRESS` (with `PNEWDT`) and `STATEV` as they
//! came.

mod common;

use std::ffi::{c_char, c_int};
use std::ptr::{null, null_mut};

use rve::host::{HostSignal, SearchPath, Umat, UmatCall, UmatOutputs};

const SCENE: &str = "scenes/paper_rve_host_implex.toml";

/// What one call returned.
struct Returned {
    stress: [f64; 3],
    statev: Vec<f64>,
    pnewdt: Option<f64>,
    message: String,
}

/// One plane-stress call of point 1 at `DTIME` = `dtime` from the virgin state (`STATEV`
/// filled with 7, an impossible state, to see that nothing is written on refusal).
fn call(signal: HostSignal, dtime: f64, statev_len: usize, virgin: bool) -> Returned {
    // Every call of this binary names the IMPL-EX scene (read once by the library).
    std::env::set_var("MESORVE_UMAT_SCENE", common::repo(SCENE));
    let fill = if virgin { 0.0 } else { 7.0 };
    let mut stress = [-5.0; 3];
    let mut statev = vec![fill; statev_len];
    let mut ddsdde = [0.0; 9];
    let mut pnewdt = 1.0;
    let (stran, dstran) = ([0.0; 3], [1e-5, 0.0, 0.0]);
    let time = [0.0, 0.0];
    let (ndi, nshr, ntens, nstatv, nprops) = (2 as c_int, 1, 3, statev_len as c_int, 0);
    let (noel, npt, kstep, kinc, layer, kspt) = (1 as c_int, 1, 1, 1, 1, 1);
    let mut scalar = 0.0;
    let cmname = b"CONCRETE";
    let pnewdt_ptr = match signal {
        HostSignal::Pnewdt => &mut pnewdt as *mut f64,
        HostSignal::NanStress => null_mut(),
    };
    // SAFETY: every pointer is valid for the length the UMAT reads (rve_umat's contract).
    unsafe {
        rve::ffi::rve_umat(
            stress.as_mut_ptr(),
            statev.as_mut_ptr(),
            ddsdde.as_mut_ptr(),
            &mut scalar,
            &mut scalar,
            &mut scalar,
            &mut scalar,
            null_mut(),
            null_mut(),
            null_mut(),
            stran.as_ptr(),
            dstran.as_ptr(),
            time.as_ptr(),
            &dtime,
            null(),
            null(),
            null(),
            null(),
            cmname.as_ptr().cast::<c_char>(),
            &ndi,
            &nshr,
            &ntens,
            &nstatv,
            null(),
            &nprops,
            null(),
            null(),
            pnewdt_ptr,
            null(),
            null(),
            null(),
            &noel,
            &npt,
            &layer,
            &kspt,
            &kstep,
            &kinc,
            cmname.len(),
        );
    }
    Returned {
        stress,
        statev,
        pnewdt: (signal == HostSignal::Pnewdt).then_some(pnewdt),
        message: rve::ffi::last_error_message(),
    }
}

fn statev_len() -> usize {
    let model = rve::model::cache::model_for_file(&common::repo(SCENE)).unwrap();
    model.statev_len() + 5
}

#[test]
fn a_non_finite_or_negative_dtime_is_refused_in_each_host_style() {
    let n = statev_len();
    for signal in [HostSignal::Pnewdt, HostSignal::NanStress] {
        for dtime in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -1.0] {
            let r = call(signal, dtime, n, false);
            let what = format!("{signal:?}, DTIME = {dtime}: {}", r.message);
            assert!(r.message.contains(&format!("DTIME = {dtime}")), "{what}");
            assert!(r.statev.iter().all(|&v| v == 7.0), "{what}: STATEV written");
            match r.pnewdt {
                Some(p) => {
                    assert!(p > 0.0 && p < 1.0, "{what}: PNEWDT {p}");
                    assert_eq!(r.stress, [-5.0; 3], "{what}: STRESS written");
                }
                None => assert!(r.stress.iter().all(|s| s.is_nan()), "{what}: no NaN"),
            }
        }
        // The same call with a time increment answers.
        let r = call(signal, 0.1, n, true);
        assert!(
            r.stress[0] > 0.0 && r.stress.iter().all(|s| s.is_finite()),
            "{signal:?}"
        );
        assert!(
            r.pnewdt.is_none_or(|p| p == 1.0),
            "{signal:?}: {:?}",
            r.pnewdt
        );
    }
}

/// Implicit integration does not read `DTIME`: a negative one is answered as any other,
/// a non-finite one refused.
#[test]
fn implicit_integration_takes_a_negative_dtime_and_refuses_a_nan() {
    let table = Umat::new(SearchPath::new([common::repo("scenes")]));
    let model = rve::model::cache::model_for_file(&common::repo("scenes/paper_rve.toml")).unwrap();
    let (stran, dstran) = ([0.0; 3], [1e-5, 0.0, 0.0]);
    for (dtime, answers) in [(-1.0, true), (f64::NAN, false)] {
        let mut c: UmatCall = common::cycle_call("paper_rve", &[], &stran, &dstran, 1, 0);
        c.dtime = dtime;
        let (mut stress, mut ddsdde, mut pnewdt) = (vec![0.0; 3], vec![0.0; 9], 1.0);
        let mut statev = vec![0.0; model.statev_len() + 5];
        let mut out = UmatOutputs {
            stress: &mut stress,
            ddsdde: &mut ddsdde,
            statev: &mut statev,
            pnewdt: &mut pnewdt,
        };
        let result = table.call(&c, &mut out);
        assert_eq!(result.is_ok(), answers, "DTIME = {dtime}: {result:?}");
        if let Err(f) = result {
            assert!(f.error.to_string().contains("DTIME = NaN"), "{f}");
            assert!(stress == [0.0; 3] && pnewdt < 1.0);
        }
    }
}

//! What checking that a host's `STATEV` is this point's costs, against the IMPL-EX update
//! it guards: `cargo bench --bench statev_checks` prints one table.
//!
//! One point of `scenes/paper_rve_host_implex.toml` follows the paper's §5.2.2 cycle
//! through `Umat::call` in STATEV mode, as CalculiX calls it (two calls per increment from
//! the start-of-increment values, the last call's values kept). Timed, per increment, by
//! medians over `ROUNDS` rounds:
//! - the UMAT call (the IMPL-EX update with everything around it);
//! - the strain check (`host::strain_mismatch`: `STRAN` against the committed strain),
//!   which runs at every call;
//! - the whole read of the values (`statev::read`: integer checks, CRC-32C, the
//!   fingerprint, the decoding), which runs when the values change; only the fingerprint
//!   comparison in it is new, so this is an upper bound of what the fingerprint adds.
//!
//! Timing tests do not belong in the test suite (noisy machines); this is the place.

use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use mesorve_core::state::statev;
use rve::host::{strain_mismatch, Hypothesis, SearchPath, Umat, UmatCall, UmatOutputs};
use rve::model::cache;
use rve::scene::path_points;

const ROUNDS: usize = 5;
/// Repetitions of a check per timing (each is well below a microsecond).
const REPEATS: u32 = 1000;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let scene = rve::Scene::from_file(dir.join("paper_rve_cycle.toml")).unwrap();
    let path = path_points(&scene.spec.path);
    let model = cache::model_for_file(&dir.join("paper_rve_host_implex.toml")).unwrap();
    let n = model.statev_len();
    let (mut calls, mut strain, mut read) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..ROUNDS {
        let umat = Umat::new(SearchPath::new([dir.clone()]));
        let mut statev = vec![0.0; n + 3];
        for (k, &end) in path.iter().enumerate() {
            let start = if k == 0 { [0.0; 3] } else { path[k - 1] };
            let mut written = statev.clone();
            let t = Instant::now();
            let near = std::array::from_fn(|c| start[c] + 0.99 * (end[c] - start[c]));
            for target in [near, end] {
                written.clone_from(&statev);
                call(&umat, k, start, target, &mut written);
            }
            calls.push(t.elapsed().as_secs_f64() * 1e6 / 2.0);
            let t = Instant::now();
            for _ in 0..REPEATS {
                black_box(strain_mismatch(black_box(end), black_box(start)));
            }
            strain.push(t.elapsed().as_secs_f64() * 1e6 / f64::from(REPEATS));
            let t = Instant::now();
            for _ in 0..REPEATS / 10 {
                let stored = statev::read(
                    black_box(&written[..n]),
                    model.state_sizes(),
                    model.interface_points(),
                    model.fingerprint(),
                );
                black_box(stored.unwrap());
            }
            read.push(t.elapsed().as_secs_f64() * 1e6 / f64::from(REPEATS / 10));
            statev = written;
        }
    }
    let call_us = median(&mut calls);
    let (strain_us, read_us) = (median(&mut strain), median(&mut read));
    println!("| per call, paper_rve_host_implex, {} increments x {ROUNDS} rounds | median (us) | share of the call |", path.len());
    println!("|---|---|---|");
    println!("| UMAT call (IMPL-EX update, STATEV mode) | {call_us:.1} | 1 |");
    println!(
        "| strain check (every call) | {strain_us:.4} | {:.2e} |",
        strain_us / call_us
    );
    println!("| whole read of the values, fingerprint included (when they change) | {read_us:.2} | {:.2e} |", read_us / call_us);
}

fn call(umat: &Umat, k: usize, start: [f64; 3], target: [f64; 3], statev: &mut [f64]) {
    let dstran: Vec<f64> = (0..3).map(|c| target[c] - start[c]).collect();
    let (mut stress, mut ddsdde, mut pnewdt) = ([0.0; 3], [0.0; 9], 1e36);
    let c = UmatCall {
        cmname: "PAPER_RVE_HOST_IMPLEX",
        props: &[],
        hypothesis: Hypothesis::PlaneStress,
        stran: &start,
        dstran: &dstran,
        time: [0.1 * k as f64; 2],
        dtime: 0.1,
        noel: 1,
        npt: 1,
        kstep: 1,
        kinc: k as i32 + 1,
        celent: None,
    };
    let mut out = UmatOutputs {
        stress: &mut stress,
        ddsdde: &mut ddsdde,
        statev,
        pnewdt: &mut pnewdt,
    };
    umat.call(&c, &mut out).expect("the cycle's calls answer");
}

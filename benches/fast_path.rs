//! Fast-path benchmark: `cargo bench --bench fast_path` prints two tables.
//!
//! 1. The unloading and compression increments of section 5.2.2's cycle on the paper RVE
//!    (`scenes/paper_rve_cycle.toml`): per increment, from the committed state the cycle
//!    reaches there, the median time of the update answered by the fast path and of the
//!    full solve (the same scene with `solver.fast_path = false`, from the same state with
//!    its unknowns formed, as a run without the fast path holds it), in the same run,
//!    alternating; then the medians over the increments the fast path answers, and their
//!    ratio.
//! 2. Memory in the fast steady state: `N` instances (default 10^5,
//!    `MESORVE_BENCH_INSTANCES`) loaded with the committed state of the cycle's increment
//!    28 (unloading, answered by the fast path), each then updated by the fast path at
//!    the next strain and committed (the trial state released, the fast-path data kept):
//!    the resident set before and after, and per instance.
//!
//! Timing does not belong in the test suite (noisy machines); this is the place.

use std::sync::Arc;
use std::time::Instant;

use mesorve_core::solver::Answer;
use mesorve_core::state::{persist, StateSizes};
use rve::{Instance, Model, Scene, TangentRequest};

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The resident set now (not the peak), MiB.
fn rss_mib() -> f64 {
    let s = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    s.lines()
        .find(|l| l.starts_with("VmRSS:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// Median seconds of `f` over `reps` calls.
fn time(reps: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..reps)
        .map(|_| {
            let t0 = Instant::now();
            f();
            t0.elapsed().as_secs_f64()
        })
        .collect();
    median(&mut t)
}

fn main() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/paper_rve_cycle.toml");
    let scene = Scene::from_file(path).unwrap();
    let fast_model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut off = scene.clone();
    off.spec.solver.fast_path = false;
    let full_model = Arc::new(Model::from_scene(&off).unwrap());
    let sizes = StateSizes {
        unknowns: fast_model.discretization().n(),
        history: fast_model.discretization().history_len(),
    };
    let targets = rve::scene::path_points(&scene.spec.path);
    let mut ws = fast_model.workspace();
    let mut ws_full = full_model.workspace();
    let mut inst = Instance::new(fast_model.clone());
    let mut full = Instance::new(full_model.clone());

    println!(
        "| increment | strain eps_xx | answer | fast path (us) | full solve (us) | full / fast |"
    );
    println!("|---|---|---|---|---|---|");
    let (mut fast_times, mut full_times, mut ratios) = (Vec::new(), Vec::new(), Vec::new());
    let mut state_28 = None;
    let mut dropped = 0;
    for (k, &eps) in targets.iter().enumerate() {
        let r = inst
            .update(eps, &mut ws, TangentRequest::Consistent)
            .unwrap();
        inst.revert();
        if k >= 21 && r.report.answer == Answer::FastPath {
            // The same state for the full solve, with its unknowns formed.
            let current = fast_model.current_state(inst.committed()).unwrap();
            full.load_state(&persist::encode(&current, sizes, fast_model.fingerprint()).unwrap())
                .unwrap();
            let (mut tf, mut ts) = (Vec::new(), Vec::new());
            for _ in 0..5 {
                tf.push(time(200, || {
                    inst.update(eps, &mut ws, TangentRequest::Consistent)
                        .unwrap();
                    inst.revert();
                }));
                ts.push(time(5, || {
                    full.update(eps, &mut ws_full, TangentRequest::Consistent)
                        .unwrap();
                    full.revert();
                }));
            }
            let (f, s) = (median(&mut tf), median(&mut ts));
            println!(
                "| {} | {:.3e} | fast path | {:.2} | {:.0} | {:.0} |",
                k + 1,
                eps[0],
                1e6 * f,
                1e6 * s,
                s / f
            );
            fast_times.push(f);
            full_times.push(s);
            ratios.push(s / f);
        } else if k >= 21 {
            dropped += 1;
            println!("| {} | {:.3e} | solved | | | |", k + 1, eps[0]);
        }
        inst.update(eps, &mut ws, TangentRequest::Consistent)
            .unwrap();
        inst.commit().unwrap();
        if k + 1 == 28 {
            state_28 = Some(inst.save_state().unwrap());
        }
    }
    println!();
    println!("| unloading and compression increments (22-60) | value |");
    println!("|---|---|");
    println!(
        "| answered by the fast path | {} of {} |",
        fast_times.len(),
        fast_times.len() + dropped
    );
    println!(
        "| fast path, median update | {:.2} us |",
        1e6 * median(&mut fast_times)
    );
    println!(
        "| full solve, median update | {:.0} us |",
        1e6 * median(&mut full_times)
    );
    println!(
        "| full / fast, median of the per-increment ratios | {:.0} |",
        median(&mut ratios)
    );

    // 2. Memory of N instances in the fast steady state.
    let n: usize = std::env::var("MESORVE_BENCH_INSTANCES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(100_000);
    let bytes = state_28.expect("the cycle has 28 increments");
    let next = targets[28];
    drop((inst, full, ws_full));
    let rss0 = rss_mib();
    let t0 = Instant::now();
    let mut instances = Vec::with_capacity(n);
    let mut fast = 0;
    for _ in 0..n {
        let mut i = Instance::new(fast_model.clone());
        i.load_state(&bytes).unwrap();
        let r = i.update(next, &mut ws, TangentRequest::Consistent).unwrap();
        fast += usize::from(r.report.answer == Answer::FastPath);
        i.commit().unwrap();
        instances.push(i);
    }
    let seconds = t0.elapsed().as_secs_f64();
    let rss = rss_mib();
    let per_state = instances[0].state_bytes();
    println!();
    println!("| {n} instances in the fast steady state (cycle increment 29) | value |");
    println!("|---|---|");
    println!("| answered by the fast path | {fast} of {n} |");
    println!("| load + fast update + commit, all | {seconds:.2} s |");
    println!("| resident set before / after | {rss0:.0} / {rss:.0} MiB |");
    println!(
        "| resident set of the instances | {:.0} MiB ({:.1} KiB per instance) |",
        rss - rss0,
        1024.0 * (rss - rss0) / n as f64
    );
    println!("| bytes an instance owns (Instance::state_bytes) | {per_state} |");
    println!(
        "| state bytes saved (format {}) | {} |",
        rve::STATE_FORMAT_VERSION,
        instances[0].state_size().unwrap()
    );
}

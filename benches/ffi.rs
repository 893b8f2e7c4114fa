//! C-ABI benchmark: call overhead against the safe API, memory of 10^5 instances, batch
//! throughput on 1 and 2 threads. `cargo bench --bench ffi` (env MESORVE_BENCH_INSTANCES
//! sets the instance count, default 100000).

use std::ffi::CString;
use std::sync::Arc;
use std::time::Instant;

use rve::ffi::*;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn peak_rss_mib() -> f64 {
    let s = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    s.lines()
        .find(|l| l.starts_with("VmHWM:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn main() {
    let path_str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/paper_rve.toml");
    let path = CString::new(path_str).unwrap();
    let e = [5e-5, 0.0, 0.0];
    let reps = 200;

    // 1. Overhead: the same trial update through the safe API and through the C ABI.
    let scene = rve::Scene::from_file(path_str).unwrap();
    let model = Arc::new(rve::Model::from_scene(&scene).unwrap());
    let mut inst = rve::Instance::new(model.clone());
    let mut ws = model.workspace();
    let mut h = 0;
    assert_eq!(unsafe { rve_init_file(path.as_ptr(), &mut h) }, 0);
    let (mut safe, mut ffi) = (Vec::new(), Vec::new());
    let (mut sig, mut d) = ([0.0; 3], [0.0; 9]);
    for _ in 0..reps {
        let t = Instant::now();
        let r = inst
            .update(e, &mut ws, rve::TangentRequest::Consistent)
            .unwrap();
        safe.push(t.elapsed().as_secs_f64());
        std::hint::black_box(r);
        let t = Instant::now();
        let s = unsafe { rve_update(h, e.as_ptr(), sig.as_mut_ptr(), d.as_mut_ptr(), 0) };
        ffi.push(t.elapsed().as_secs_f64());
        assert_eq!(s, 0);
    }
    let (ms, mf) = (median(safe), median(ffi));
    println!("| measure | value |");
    println!("|---|---|");
    println!(
        "| trial update, safe API (median of {reps}) | {:.1} us |",
        1e6 * ms
    );
    println!(
        "| trial update, C ABI rve_update (median of {reps}) | {:.1} us |",
        1e6 * mf
    );
    println!("| C ABI / safe | {:.3} |", mf / ms);
    println!("| C ABI overhead | {:.2} us |", 1e6 * (mf - ms));
    // Pure boundary cost: a call that fails at the handle check.
    let t = Instant::now();
    for _ in 0..100_000 {
        std::hint::black_box(rve_commit(std::hint::black_box(1)));
    }
    println!(
        "| boundary round trip (rve_commit on a bad handle) | {:.0} ns |",
        1e9 * t.elapsed().as_secs_f64() / 1e5
    );
    rve_free(h);
    drop((inst, ws, model));

    // 2. Memory: N instances of the paper scene, each updated once (trial kept).
    let n: usize = std::env::var("MESORVE_BENCH_INSTANCES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(100_000);
    let rss0 = peak_rss_mib();
    let t = Instant::now();
    let handles: Vec<RveHandle> = (0..n)
        .map(|_| {
            let mut h = 0;
            assert_eq!(unsafe { rve_init_file(path.as_ptr(), &mut h) }, 0);
            h
        })
        .collect();
    let t_init = t.elapsed().as_secs_f64();
    let strains: Vec<f64> = (0..n)
        .flat_map(|k| [e[0] * (1.0 + 1e-6 * k as f64), 0.0, 0.0])
        .collect();
    let mut stresses = vec![0.0; 3 * n];
    let mut tangents = vec![0.0; 9 * n];
    let mut statuses = vec![0u32; n];
    let mut batch_at = |strains: &[f64], m: usize, threads: usize| {
        let t = Instant::now();
        let s = unsafe {
            rve_update_batch(
                handles.as_ptr(),
                m,
                strains.as_ptr(),
                stresses.as_mut_ptr(),
                tangents.as_mut_ptr(),
                statuses.as_mut_ptr(),
                0,
                threads,
            )
        };
        assert_eq!(s, 0);
        m as f64 / t.elapsed().as_secs_f64()
    };
    let tp2_all = batch_at(&strains, n, 2);
    let rss = peak_rss_mib();
    println!("| init of {n} instances (models built by this process: {}, one per scene lifetime) | {:.2} s |", rve_model_builds(), t_init);
    println!(
        "| peak RSS after {n} instances updated once | {:.0} MiB (before: {:.0} MiB) |",
        rss, rss0
    );
    println!(
        "| per instance | {:.1} KiB |",
        1024.0 * (rss - rss0) / n as f64
    );
    // 2b. Steady state: two more increments in the same direction, committed. Every
    // state of every instance then holds a sensitivity (filled by the first increment)
    // and a path curvature (by the second and third: a virgin state has neither).
    for multiple in [2.0, 3.0] {
        for &h in &handles {
            assert_eq!(rve_commit(h), 0);
        }
        let further: Vec<f64> = strains.iter().map(|e| multiple * e).collect();
        batch_at(&further, n, 2);
    }
    let rss_steady = peak_rss_mib();
    println!(
        "| peak RSS after {n} instances in the steady state (three increments) | {:.0} MiB ({:.1} KiB per instance) |",
        rss_steady,
        1024.0 * (rss_steady - rss0) / n as f64
    );
    // 3. Batch throughput (consistent tangent): trial updates from the committed third
    // increment (1.5e-4) to 1.75e-4, a pre-peak increment with both predictor terms.
    let m = n.min(4000);
    let next: Vec<f64> = strains.iter().map(|e| 3.5 * e).collect();
    let tp1 = batch_at(&next, m, 1);
    let tp2 = batch_at(&next, m, 2);
    println!(
        "| batch, 1 thread ({m} pre-peak increments) | {:.0} updates/s |",
        tp1
    );
    println!(
        "| batch, 2 threads ({m} pre-peak increments) | {:.0} updates/s ({:.2}x) |",
        tp2,
        tp2 / tp1
    );
    println!(
        "| batch, 2 threads ({n} first updates, from the virgin state) | {:.0} updates/s |",
        tp2_all
    );
}

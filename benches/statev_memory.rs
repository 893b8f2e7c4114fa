//! Library memory of UMAT points in `STATEV` mode, and their call times:
//! `cargo bench --bench statev_memory` (env `MESORVE_BENCH_POINTS`, default 20000).
//!
//! Each scene runs in a fresh process (this binary again, env `MESORVE_BENCH_PART` = the
//! scene file), so that its peak RSS (`VmHWM`) is its own. The process calls `rve_umat`
//! as CalculiX does on one thread, with `PNEWDT` (so the library keeps its `(NOEL, NPT)`
//! table): N points (NOEL 1..N, NPT 1), plane stress (`NTENS` 3), `NSTATV` =
//! `umat_nstatv` + 5 mirrors, the scene named by `MESORVE_UMAT_SCENE`. Two loading
//! increments, eps_xx = 1.25e-5 then 2.5e-5 (pre-peak). In each increment every point
//! gets two calls from its start-of-increment `STATEV`, at the increment's strain: the
//! first solves, the second (the host's tangent call) repeats it; the values written by
//! the last call are kept for the next increment. The second increment's first call
//! rebuilds the state from `STATEV` (implicit: one factorization) and solves.
//!
//! - **Memory.** The host's `STATEV` arrays (N x NSTATV doubles), the call buffers and a
//!   warm-up of 64 other points (model, workspaces) exist and are written through
//!   before the baseline; library memory = (peak RSS after the increments - baseline) / N.
//! - **Time.** Every call is timed; medians per increment of the solving calls and of the
//!   repeated ones. Every first call must solve and every second one repeat it (the
//!   UMAT's counters, `rve::host::global().stats()`, must move by N solves and N
//!   repeats per increment; the bench also asserts a nonzero stress, new values written,
//!   and the repeat's stress and values equal to the solve's bit for bit), so no cache
//!   answers a timed solve: each point's first call of an increment is its only solve at
//!   that strain from those values.
//!
//! The main process prints the scene sizes and runs both scenes (`paper_rve.toml`,
//! implicit, and `paper_rve_host_implex.toml`, IMPL-EX).

mod common;
use common::{load_average, peak_rss_mib};

use std::ffi::c_int;
use std::process::Command;
use std::time::Instant;

use rve::ffi::rve_umat;

const SCENES: [&str; 2] = ["paper_rve.toml", "paper_rve_host_implex.toml"];
/// The two loading increments (eps_xx, total at the end of each).
const STRAINS: [f64; 2] = [1.25e-5, 2.5e-5];
const MIRRORS: usize = 5;
const WARM_UP: usize = 64;

fn scene_path(file: &str) -> String {
    format!("{}/scenes/{file}", env!("CARGO_MANIFEST_DIR"))
}

fn points() -> usize {
    std::env::var("MESORVE_BENCH_POINTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20_000)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// One `rve_umat` call of point `noel` in increment `kinc` (1-based) from `stran` to
/// `target` (eps_xx), `STATEV` in/out; returns the stress.
fn call(noel: usize, kinc: usize, stran: f64, target: f64, statev: &mut [f64]) -> [f64; 3] {
    let (mut stress, mut ddsdde) = ([0.0; 3], [0.0; 9]);
    let stran3 = [stran, 0.0, 0.0];
    let dstran = [target - stran, 0.0, 0.0];
    assert_eq!(stran + dstran[0], target, "STRAN + DSTRAN rounds");
    let time = [(kinc - 1) as f64; 2];
    let (dtime, mut pnewdt) = (1.0, 1e36);
    let (ndi, nshr, ntens, nprops) = (2 as c_int, 1 as c_int, 3 as c_int, 0 as c_int);
    let nstatv = statev.len() as c_int;
    let (noel, npt, kstep, kinc) = (noel as c_int, 1 as c_int, 1 as c_int, kinc as c_int);
    let mut scratch = [0.0f64; 9];
    let props = [0.0f64; 1];
    let name = b"PAPER_RVE";
    let p = scratch.as_mut_ptr();
    unsafe {
        rve_umat(
            stress.as_mut_ptr(),
            statev.as_mut_ptr(),
            ddsdde.as_mut_ptr(),
            p,
            p,
            p,
            p,
            p,
            p,
            p,
            stran3.as_ptr(),
            dstran.as_ptr(),
            time.as_ptr(),
            &dtime,
            p,
            p,
            p,
            p,
            name.as_ptr().cast(),
            &ndi,
            &nshr,
            &ntens,
            &nstatv,
            props.as_ptr(),
            &nprops,
            p,
            p,
            &mut pnewdt,
            p,
            p,
            p,
            &noel,
            &npt,
            &kstep,
            &kstep,
            &kstep,
            &kinc,
            name.len(),
        );
    }
    assert!(
        pnewdt >= 1.0,
        "point {noel}, increment {kinc}: the call failed"
    );
    stress
}

fn main() {
    if let Ok(scene) = std::env::var("MESORVE_BENCH_PART") {
        return part(&scene, points());
    }
    println!("load average (1 min) at the start: {}", load_average());
    for scene in SCENES {
        let exe = std::env::current_exe().unwrap();
        let status = Command::new(exe)
            .env("MESORVE_BENCH_PART", scene)
            .env("MESORVE_UMAT_SCENE", scene_path(scene))
            .status()
            .unwrap();
        assert!(status.success(), "{scene}: {status}");
    }
    println!("load average (1 min) at the end: {}", load_average());
}

/// Times (us) of the solving and the repeated calls of one increment over `range`.
fn increment(
    kinc: usize,
    range: std::ops::Range<usize>,
    host: &mut [f64],
    buf: &mut [f64],
) -> (Vec<f64>, Vec<f64>) {
    let n = buf.len();
    let stran = if kinc == 1 { 0.0 } else { STRAINS[kinc - 2] };
    let target = STRAINS[kinc - 1];
    let (mut solves, mut repeats) = (Vec::new(), Vec::new());
    let (before, calls) = (rve::host::global().stats(), range.len() as u64);
    for i in range {
        let start = &mut host[i * n..(i + 1) * n];
        buf.copy_from_slice(start);
        let t = Instant::now();
        let s1 = call(i + 1, kinc, stran, target, buf);
        solves.push(t.elapsed().as_secs_f64() * 1e6);
        let written = buf[..n - MIRRORS].to_vec();
        assert!(
            s1[0] > 0.0 && written != start[..n - MIRRORS],
            "no new state written"
        );
        buf.copy_from_slice(start);
        let t = Instant::now();
        let s2 = call(i + 1, kinc, stran, target, buf);
        repeats.push(t.elapsed().as_secs_f64() * 1e6);
        assert_eq!(s1.map(f64::to_bits), s2.map(f64::to_bits));
        assert_eq!(
            buf[..n - MIRRORS],
            written[..],
            "the repeat wrote other values"
        );
        start.copy_from_slice(buf);
    }
    let after = rve::host::global().stats();
    assert_eq!(
        after.solves - before.solves,
        calls,
        "a first call was not solved"
    );
    assert_eq!(
        after.repeats - before.repeats,
        calls,
        "a second call was solved"
    );
    (solves, repeats)
}

/// One scene in this process: warm-up, baseline, N points through both increments.
fn part(scene: &str, n: usize) {
    let model = rve::model::cache::model_for_file(std::path::Path::new(&scene_path(scene)))
        .expect("the scene builds");
    let nstatv = model.statev_len() + MIRRORS;
    drop(model);
    let total = n + WARM_UP;
    let mut host = vec![0.0f64; total * nstatv];
    host.iter_mut().for_each(|v| *v = 0.0);
    let mut buf = vec![1.0f64; nstatv];
    for kinc in 1..=2 {
        increment(kinc, n..total, &mut host, &mut buf);
    }
    let rss0 = peak_rss_mib();
    let t = Instant::now();
    let mut rows = Vec::new();
    for kinc in 1..=2 {
        let (s, r) = increment(kinc, 0..n, &mut host, &mut buf);
        rows.push((kinc, median(s), median(r)));
    }
    let seconds = t.elapsed().as_secs_f64();
    let rss = peak_rss_mib();
    let host_mib = (host.len() * 8) as f64 / 1048576.0;
    println!();
    println!("| {scene}, {n} points, STATEV mode through rve_umat | value |");
    println!("|---|---|");
    println!("| NSTATV (umat_nstatv + mirrors); host STATEV arrays, counted apart | {nstatv}; {host_mib:.0} MiB |");
    println!("| peak RSS before the points / with them | {rss0:.0} / {rss:.0} MiB |");
    println!(
        "| library memory of the points | {:.0} MiB, {:.0} bytes per point |",
        rss - rss0,
        (rss - rss0) * 1048576.0 / n as f64
    );
    println!(
        "| the same per point, for 10^5 points | {:.2} GiB |",
        (rss - rss0) / n as f64 * 1e5 / 1024.0
    );
    for (kinc, s, r) in rows {
        println!(
            "| increment {kinc}: median solving call / repeated call | {s:.1} us / {r:.1} us |"
        );
    }
    println!("| wall time of the 4N calls | {seconds:.1} s |");
    println!("| load average (1 min) after | {} |", load_average());
}

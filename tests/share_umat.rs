//! Answer sharing in the UMAT's STATEV mode (`[solver] share_tolerance`, docs/sharing.md):
//! points called in turn at every increment (two calls an increment, as CalculiX's
//! iterations), against the same run without sharing. On the paper's cycle: four points
//! of the IMPL-EX host scene, two at the same strain, one within the tolerance of them,
//! one far; the points at the anchor's strain equal the exact run to round-off, the near
//! one is within the tolerance, some calls are shared, and every written STATEV passes
//! the next increment's checks (its own strain and time). On fine increments through the
//! peak and back, at every tolerance the scene accepts, for IMPL-EX step sharing and
//! implicit answer sharing: every point within the tolerance of its own exact run.

mod common;

use rve::host::{SearchPath, Umat, UmatOutputs};
use rve::model::cache;

const IMPLEX: &str = "scenes/paper_rve_host_implex.toml";

/// The scene `base` with `extra` in `[solver]`, written to `dir/name.toml`.
fn scene_of(base: &str, dir: &std::path::Path, name: &str, extra: &str) -> usize {
    let text = std::fs::read_to_string(common::repo(base)).unwrap();
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(
        &file,
        text.replace("[solver]\n", &format!("[solver]\n{extra}\n")),
    )
    .unwrap();
    cache::model_for_file(&file).unwrap().statev_len()
}

/// The IMPL-EX host scene with `extra` in `[solver]`, written to `dir/name.toml`.
fn scene(dir: &std::path::Path, name: &str, extra: &str) -> usize {
    scene_of(IMPLEX, dir, name, extra)
}

const SCALES: [f64; 4] = [1.0, 1.0, 1.002, 1.5];

/// The paper's cycle (`scenes/paper_rve_cycle.toml`).
fn cycle() -> Vec<[f64; 3]> {
    rve::scene::path_points(&common::scene("scenes/paper_rve_cycle.toml").spec.path)
}

/// Every point's stress at every increment's last call, and the UMAT's stats.
fn run(dir: &std::path::Path, cmname: &str, n: usize) -> (Vec<[f64; 3]>, rve::host::UmatStats) {
    run_on(dir, cmname, n, &cycle(), &SCALES)
}

/// [`run`] along `path` scaled by each of `scales`.
fn run_on(
    dir: &std::path::Path,
    cmname: &str,
    n: usize,
    path: &[[f64; 3]],
    scales: &[f64],
) -> (Vec<[f64; 3]>, rve::host::UmatStats) {
    let umat = Umat::new(SearchPath::new([dir.to_path_buf()]));
    let mut statev = vec![vec![0.0; n + 5]; scales.len()];
    let mut out = Vec::new();
    for k in 0..path.len() {
        let start = if k == 0 { [0.0; 3] } else { path[k - 1] };
        let mut written = statev.clone();
        let mut last = vec![[0.0; 3]; scales.len()];
        for fraction in [0.99, 1.0] {
            for (p, s) in scales.iter().enumerate() {
                let from: Vec<f64> = start.iter().map(|v| v * s).collect();
                let d: Vec<f64> = (0..3)
                    .map(|c| s * (start[c] + fraction * (path[k][c] - start[c])) - from[c])
                    .collect();
                written[p].clone_from(&statev[p]);
                let (mut stress, mut ddsdde, mut pnewdt) = (vec![0.0; 3], vec![0.0; 9], 1.0);
                let c = common::cycle_call(cmname, &[], &from, &d, p as i32 + 1, k);
                let mut o = UmatOutputs {
                    stress: &mut stress,
                    ddsdde: &mut ddsdde,
                    statev: &mut written[p],
                    pnewdt: &mut pnewdt,
                };
                umat.call(&c, &mut o)
                    .unwrap_or_else(|f| panic!("increment {k}: {f}"));
                last[p] = [stress[0], stress[1], stress[2]];
            }
        }
        statev = written;
        out.extend(last);
    }
    (out, umat.stats())
}

#[test]
fn statev_mode_shares_within_the_tolerance() {
    let dir = std::env::temp_dir().join(format!("mesorve-share-umat-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let n = scene(&dir, "exact", "");
    assert_eq!(scene(&dir, "shared", "share_tolerance = 0.005"), n);
    let (exact, exact_stats) = run(&dir, "EXACT", n);
    let (shared, stats) = run(&dir, "SHARED", n);
    assert_eq!(exact_stats.shared, 0);
    assert!(stats.shared > 0, "{stats:?}");
    assert!(
        stats.solves < exact_stats.solves,
        "{stats:?} against {exact_stats:?}"
    );
    let largest = exact.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut worst = 0.0f64;
    for (i, (a, b)) in exact.iter().zip(&shared).enumerate() {
        let p = i % SCALES.len();
        if p < 2 {
            // A follower that solves again rebuilds its state from STATEV (the anchor kept
            // its step): equal to round-off, not bit for bit.
            let d = (0..3).fold(0.0f64, |m, c| m.max((a[c] - b[c]).abs()));
            assert!(d <= 1e-12 * largest, "point {p}, row {i}: {d}");
        }
        worst = worst.max((0..3).fold(0.0f64, |m, c| m.max((a[c] - b[c]).abs())));
    }
    eprintln!(
        "UMAT sharing: {} solved, {} shared (exact: {} solved); largest difference {:.3e} of the largest stress",
        stats.solves, stats.shared, exact_stats.solves, worst / largest
    );
    assert!(worst <= 0.005 * largest, "{worst} > 0.005 x {largest}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Fine increments through the peak and back (240 to 3e-4, 120 back to 0), six points at
/// scales 0.97-1.04 (two at the same scale), each tolerance the scene accepts: every point
/// within the tolerance of its own exact run, in each scene.
#[test]
fn statev_mode_holds_every_tolerance_on_fine_increments() {
    let dir = std::env::temp_dir().join(format!("mesorve-share-fine-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = common::share_paths::up_and_back([1.0, -0.195, -0.00045], 3e-4, (240, 120), 0.0);
    let scales = [0.97, 0.99, 1.0, 1.0, 1.01, 1.04];
    for base in [IMPLEX, "scenes/paper_rve_host.toml"] {
        let n = scene_of(base, &dir, "fine_exact", "");
        let (exact, _) = run_on(&dir, "FINE_EXACT", n, &path, &scales);
        for (t, tol) in common::share_paths::TOLERANCES.iter().enumerate() {
            let name = format!("fine_shared_{t}");
            scene_of(base, &dir, &name, &format!("share_tolerance = {tol}"));
            let (shared, stats) = run_on(&dir, &name.to_uppercase(), n, &path, &scales);
            let rows = |v: &[[f64; 3]]| -> Vec<Vec<[f64; 3]>> {
                v.chunks(scales.len()).map(<[[f64; 3]]>::to_vec).collect()
            };
            let (worst, point) = common::share_paths::worst_point(&rows(&exact), &rows(&shared));
            eprintln!("{base}, STATEV mode, share_tolerance {tol}: worst point {point} at {worst:.2e}; {} solved, {} shared", stats.solves, stats.shared);
            assert!(stats.shared > 0, "{base}, {tol}: {stats:?}");
            assert!(
                worst <= *tol,
                "{base}, share_tolerance {tol}: point {point} is {worst} off"
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

//! Answer sharing in the UMAT's STATEV mode (`[solver] share_tolerance`, docs/sharing.md):
//! four points of the IMPL-EX host scene called in turn at every increment of the paper's
//! cycle (two calls an increment, as CalculiX's iterations), two at the same strain, one
//! within the tolerance of them, one far. Against the same run without sharing: the
//! points at the anchor's strain are bit-identical, the near one within the tolerance of
//! the largest stress, some calls are shared, and every written STATEV passes the next
//! increment's checks (its own strain and time).

mod common;

use rve::host::{SearchPath, Umat, UmatOutputs};
use rve::model::cache;

/// The host scene with `extra` in `[solver]`, written to `dir/name.toml`.
fn scene(dir: &std::path::Path, name: &str, extra: &str) -> usize {
    let text = std::fs::read_to_string(common::repo("scenes/paper_rve_host_implex.toml")).unwrap();
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(
        &file,
        text.replace("[solver]\n", &format!("[solver]\n{extra}\n")),
    )
    .unwrap();
    cache::model_for_file(&file).unwrap().statev_len()
}

const SCALES: [f64; 4] = [1.0, 1.0, 1.002, 1.5];

/// Every point's stress at every increment's last call, and the UMAT's stats.
fn run(dir: &std::path::Path, cmname: &str, n: usize) -> (Vec<[f64; 3]>, rve::host::UmatStats) {
    let umat = Umat::new(SearchPath::new([dir.to_path_buf()]));
    let scene = common::scene("scenes/paper_rve_cycle.toml");
    let path = rve::scene::path_points(&scene.spec.path);
    let mut statev = vec![vec![0.0; n + 5]; SCALES.len()];
    let mut out = Vec::new();
    for k in 0..path.len() {
        let start = if k == 0 { [0.0; 3] } else { path[k - 1] };
        let mut written = statev.clone();
        let mut last = vec![[0.0; 3]; SCALES.len()];
        for fraction in [0.99, 1.0] {
            for (p, s) in SCALES.iter().enumerate() {
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

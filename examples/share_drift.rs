//! Sharing's error on fine increments (docs/sharing.md, "The error holds"): `n` points
//! along one strain direction at scales 0.97-1.04, loaded through the peak to 3e-4 in
//! `N` increments and unloaded to 0 in `N/2`, with and without `share_tolerance`. Prints
//! one row per case: the largest stress difference over the largest stress (all points),
//! the worst point's difference over its own largest stress, and the calls shared.
//!
//! `cargo run --release --example share_drift [DIRECTION_X DIRECTION_Y DIRECTION_XY]`
//! (default `1 -0.195 -0.00045`).

#[path = "../tests/common/share_paths.rs"]
mod share_paths;

use share_paths::{model, run, up_and_back, worst_point};

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("a number"))
        .collect();
    let direction = if args.len() == 3 {
        [args[0], args[1], args[2]]
    } else {
        [1.0, -0.195, -0.00045]
    };
    let implex = "scenes/paper_rve_host_implex.toml";
    let implicit = "scenes/paper_rve_host.toml";
    let rows = [
        (implex, 12, 0.005, 400),
        (implex, 12, 0.01, 400),
        (implex, 12, 0.02, 400),
        (implex, 12, 0.05, 60),
        (implex, 12, 0.05, 200),
        (implex, 12, 0.05, 400),
        (implex, 12, 0.1, 400),
        (implicit, 8, 0.05, 200),
        (implicit, 8, 0.1, 400),
    ];
    println!("direction {direction:?}");
    println!("| scene | points | share_tolerance | N | largest difference / largest stress | worst point / its largest stress | calls shared |");
    println!("|---|---|---|---|---|---|---|");
    for (scene, n, tol, incs) in rows {
        let scales: Vec<f64> = (0..n)
            .map(|k| 0.97 + 0.07 * k as f64 / (n - 1) as f64)
            .collect();
        let base = up_and_back(direction, 3e-4, (incs, incs / 2), 0.0);
        let paths: Vec<Vec<[f64; 3]>> = scales
            .iter()
            .map(|s| base.iter().map(|e| e.map(|v| v * s)).collect())
            .collect();
        let (exact, _) = run(&model(scene, None), &paths);
        let (shared, (solved, followers)) = run(&model(scene, Some(tol)), &paths);
        let largest = exact
            .iter()
            .flatten()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = exact
            .iter()
            .flatten()
            .flatten()
            .zip(shared.iter().flatten().flatten())
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let (worst, _) = worst_point(&exact, &shared);
        println!(
            "| `{scene}` | {n} | {tol} | {incs} | {:.4} | {worst:.4} | {followers} of {} |",
            diff / largest,
            solved + followers
        );
    }
}

//! Sharing's error control over many random cases (docs/sharing.md): for each scene and
//! each tolerance a scene accepts, `CASES` random paths (`tests/common/share_paths.rs`:
//! direction, amplitude past the peak, increments, unloading depth, pre-loads, scales
//! within 5 % of 1), every point against its own exact run. Prints, per scene and
//! tolerance, the worst point's error over the tolerance and the shared fraction of the
//! calls; fails (exit code 1) if any point exceeds its tolerance.
//!
//! `cargo bench --bench share_error [-- CASES [SEED]]` (default 40 cases from seed 1000).

#[path = "../tests/common/share_paths.rs"]
mod share_paths;

use share_paths::{model, random_case, run, worst_point, TOLERANCES};

fn main() {
    let args: Vec<String> = std::env::args().filter(|a| !a.starts_with("--")).collect();
    let cases: u64 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(40);
    let seed: u64 = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(1000);
    println!("{cases} random cases from seed {seed}, 8 points each");
    println!(
        "| scene | share_tolerance | worst error / tolerance | seed of the worst | calls shared |"
    );
    println!("|---|---|---|---|---|");
    let mut failed = false;
    for scene in [
        "scenes/paper_rve_host_implex.toml",
        "scenes/paper_rve_host.toml",
    ] {
        let exact_model = model(scene, None);
        let shared_models: Vec<_> = TOLERANCES.iter().map(|&t| model(scene, Some(t))).collect();
        let mut worst = vec![(0.0f64, 0u64); TOLERANCES.len()];
        let mut counts = vec![(0usize, 0usize); TOLERANCES.len()];
        for case in seed..seed + cases {
            let (paths, _) = random_case(case, 8, 0.05);
            let (exact, _) = run(&exact_model, &paths);
            for (t, tol) in TOLERANCES.iter().enumerate() {
                let (shared, (s, f)) = run(&shared_models[t], &paths);
                let (w, _) = worst_point(&exact, &shared);
                if w / tol > worst[t].0 {
                    worst[t] = (w / tol, case);
                }
                counts[t] = (counts[t].0 + s, counts[t].1 + f);
                failed |= w > *tol;
            }
        }
        for (t, tol) in TOLERANCES.iter().enumerate() {
            let (s, f) = counts[t];
            println!(
                "| {scene} | {tol} | {:.3} | {} | {:.3} |",
                worst[t].0,
                worst[t].1,
                f as f64 / (s + f) as f64
            );
        }
    }
    if failed {
        eprintln!("a point exceeded its tolerance");
        std::process::exit(1);
    }
}

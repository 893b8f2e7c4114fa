//! Answer sharing against the exact run (docs/sharing.md): a batch of points of the
//! IMPL-EX host scene along scaled copies of one strain path (through the peak and back),
//! for each error indicator and tolerance: solved and shared points, and the largest
//! stress difference over the largest stress.
//!
//! `cargo run --release --example share_study [points]` (default 200).

use std::sync::Arc;

use rve::model::batch::{update_batch_with, BatchOutputs, BatchStep, PointReport};
use rve::model::share::{self, Indicator};
use rve::{Instance, Model, Scene, TangentRequest};

const SCENE: &str = include_str!("../scenes/paper_rve_host_implex.toml");
const INCREMENTS: usize = 24;

fn model(extra: &str) -> Arc<Model> {
    let text = SCENE.replace("[solver]\n", &format!("[solver]\n{extra}\n"));
    let scene = Scene::from_toml_str(&text, env!("CARGO_MANIFEST_DIR")).expect("scene");
    Arc::new(Model::from_scene(&scene).expect("model"))
}

fn along(i: usize) -> f64 {
    let up = 14;
    if i < up {
        (i + 1) as f64
    } else {
        (2 * up - 1 - i) as f64 * 0.6 + 0.4 * up as f64
    }
}

/// Point `p` of `n`: a size in [0.2, 1.6] and a direction that turns with it, as the
/// points of a bent member (a smooth field sampled at `n` points).
fn strain(i: usize, p: usize, n: usize) -> [f64; 3] {
    let x = p as f64 / n as f64;
    let e = 1.6e-5 * along(i) * (0.2 + 1.4 * x);
    [e, -(0.2 - 0.3 * x) * e, (0.05 + 0.1 * x) * e]
}

/// The stresses of every increment and the (solved, shared) counts.
fn run(model: &Arc<Model>, n: usize, indicator: Indicator) -> (Vec<[f64; 3]>, (usize, usize)) {
    let mut points: Vec<Instance> = (0..n).map(|_| Instance::new(model.clone())).collect();
    let (mut all, mut counts) = (Vec::new(), (0, 0));
    for i in 0..INCREMENTS {
        let strains: Vec<[f64; 3]> = (0..n).map(|p| strain(i, p, n)).collect();
        let (mut stresses, mut tangents) = (vec![[0.0; 3]; n], vec![[0.0; 9]; n]);
        let mut reports = vec![PointReport::default(); n];
        let step = BatchStep {
            dtime: 1.0,
            request: TangentRequest::Consistent,
            threads: 2,
        };
        let out = BatchOutputs {
            stresses: &mut stresses,
            tangents: Some(&mut tangents),
            reports: &mut reports,
        };
        let failures =
            update_batch_with(&mut points, &strains, step, indicator, out).expect("batch");
        assert!(failures.is_empty());
        points.iter_mut().for_each(|p| p.commit().expect("commit"));
        let (s, f) = share::counts(&reports);
        counts = (counts.0 + s, counts.1 + f);
        all.extend(stresses);
    }
    (all, counts)
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map_or(200, |a| a.parse().expect("points"));
    let t0 = std::time::Instant::now();
    let (exact, _) = run(&model(""), n, Indicator::default());
    let exact_time = t0.elapsed().as_secs_f64();
    let largest = exact.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    println!("{n} points, {INCREMENTS} increments; exact run {exact_time:.2} s, largest stress {largest:.4} MPa");
    println!("| share_tolerance | indicator | solved | shared | largest stress difference / largest stress | time / exact |");
    println!("|---|---|---|---|---|---|");
    for tol in [0.001, 0.005, 0.02, 0.05] {
        let m = model(&format!("share_tolerance = {tol}"));
        for indicator in [
            Indicator::Plain,
            Indicator::FirstOrder,
            Indicator::Branch,
            Indicator::History,
        ] {
            let t0 = std::time::Instant::now();
            let (shared, (solved, followers)) = run(&m, n, indicator);
            let time = t0.elapsed().as_secs_f64();
            let diff = exact
                .iter()
                .flatten()
                .zip(shared.iter().flatten())
                .fold(0.0f64, |d, (a, b)| d.max((a - b).abs()));
            println!(
                "| {tol} | {indicator:?} | {solved} | {followers} | {:.2e} | {:.2} |",
                diff / largest,
                time / exact_time
            );
        }
    }
}

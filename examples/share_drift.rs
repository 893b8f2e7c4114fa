//! Sharing's accumulated error (issue 50): `n` points along one strain direction at scales
//! spread around 1, loaded through the peak in `incs` increments and unloaded, with and
//! without `share_tolerance`; the largest stress difference over the largest stress.
//!
//! `cargo run --release --example share_drift SCENE TOL INCS [POINTS] [AMPLITUDE]`

use std::sync::Arc;

use rve::model::batch::{update_batch, BatchOutputs, BatchStep, PointReport};
use rve::model::share;
use rve::{Instance, Model, Scene, TangentRequest};

fn model(path: &str, extra: &str) -> Arc<Model> {
    let text = std::fs::read_to_string(path).expect("scene");
    let text = text.replace("[solver]\n", &format!("[solver]\n{extra}\n"));
    let scene = Scene::from_toml_str(&text, env!("CARGO_MANIFEST_DIR")).expect("scene");
    Arc::new(Model::from_scene(&scene).expect("model"))
}

fn run(
    model: &Arc<Model>,
    scales: &[f64],
    path: &[f64],
    dir: [f64; 3],
) -> (Vec<[f64; 3]>, (usize, usize)) {
    let n = scales.len();
    let mut points: Vec<Instance> = (0..n).map(|_| Instance::new(model.clone())).collect();
    let (mut all, mut counts) = (Vec::new(), (0, 0));
    for &a in path {
        let strains: Vec<[f64; 3]> = scales.iter().map(|s| dir.map(|d| d * a * s)).collect();
        let (mut stresses, mut tangents) = (vec![[0.0; 3]; n], vec![[0.0; 9]; n]);
        let mut reports = vec![PointReport::default(); n];
        let step = BatchStep {
            dtime: 1.0,
            request: TangentRequest::Consistent,
            threads: 1,
        };
        let out = BatchOutputs {
            stresses: &mut stresses,
            tangents: Some(&mut tangents),
            reports: &mut reports,
        };
        let failures = update_batch(&mut points, &strains, step, out).expect("batch");
        assert!(
            failures.is_empty(),
            "{:?}",
            failures.first().map(|f| f.1.to_string())
        );
        points.iter_mut().for_each(|p| p.commit().expect("commit"));
        if let Ok(w) = std::env::var("WATCH") {
            let w: usize = w.parse().unwrap();
            let h = &points[w].committed().history;
            let hmax = h.iter().fold(0.0f64, |m, v| m.max(*v));
            eprintln!(
                "a={a:.3e} p{w} from {:?} s={:.4} hmax={hmax:.4e} step={} at_start={} lin={}",
                reports[w].shared_from,
                stresses[w][0],
                points[w].committed().implex.step,
                points[w].committed().implex.at_start,
                points[w].committed().linear.valid
            );
        }
        let (s, f) = share::counts(&reports);
        counts = (counts.0 + s, counts.1 + f);
        all.extend(stresses);
    }
    (all, counts)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = &args[1];
    let tol: f64 = args[2].parse().unwrap();
    let incs: usize = args[3].parse().unwrap();
    let n: usize = args.get(4).map_or(12, |a| a.parse().unwrap());
    let amp: f64 = args.get(5).map_or(3e-4, |a| a.parse().unwrap());
    let scales: Vec<f64> = (0..n)
        .map(|k| 0.97 + 0.07 * k as f64 / (n - 1) as f64)
        .collect();
    let mut path: Vec<f64> = (1..=incs).map(|i| amp * i as f64 / incs as f64).collect();
    path.extend((1..=incs / 2).map(|i| amp * (1.0 - i as f64 / (incs / 2) as f64)));
    let dir = [1.0, -0.195, -0.00045];
    let (exact, _) = run(&model(scene, ""), &scales, &path, dir);
    let (shared, counts) = run(
        &model(scene, &format!("share_tolerance = {tol}")),
        &scales,
        &path,
        dir,
    );
    let largest = exact.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let (mut worst, mut at) = (0.0f64, 0);
    for (k, (a, b)) in exact.iter().zip(&shared).enumerate() {
        let d = (0..3).fold(0.0f64, |m, i| m.max((a[i] - b[i]).abs()));
        if d > worst {
            worst = d;
            at = k;
        }
    }
    println!(
        "tol {tol} incs {incs}: solved {} shared {}; largest difference {:.4} of {largest:.3} (point {} increment {}: {:?} vs {:?})",
        counts.0, counts.1, worst / largest, at % n, at / n, shared[at], exact[at]
    );
}

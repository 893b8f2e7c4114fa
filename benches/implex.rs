//! IMPL-EX against implicit integration: `cargo bench --bench implex` prints one row per
//! scene and scheme.
//!
//! Each path is followed as a host does it, two updates per increment: the host's first
//! iteration at 99 % of the increment's strain step, then its second at the increment's
//! strain (a new strain: the repeated-trial cache answers neither), then a commit. Times
//! are medians over `RUNS` fresh instances, per update kind; factorizations are counted
//! by the solver (`IncrementReport::factorizations`), per increment (both updates).
//!
//! Timing tests do not belong in the test suite (noisy machines); this is the place.

use std::sync::Arc;
use std::time::Instant;

use rve::scene::path_points;
use rve::{Instance, Model, Scene, TangentRequest};

const RUNS: usize = 5;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

struct Row {
    first_ms: f64,
    second_ms: f64,
    mean_increment_ms: f64,
    factorizations: f64,
    state_bytes: usize,
}

/// Follows `points` `RUNS` times (see the module docs).
fn follow(model: &Arc<Model>, points: &[[f64; 3]]) -> Row {
    let (mut first, mut second, mut totals) = (Vec::new(), Vec::new(), Vec::new());
    let mut factorizations = 0u64;
    let mut state_bytes = 0;
    for _ in 0..RUNS {
        let mut instance = Instance::new(model.clone());
        let mut ws = model.workspace();
        let (mut previous, mut total) = ([0.0; 3], 0.0);
        factorizations = 0;
        for &eps in points {
            let near = std::array::from_fn(|c| previous[c] + 0.99 * (eps[c] - previous[c]));
            let dt = (0..3)
                .map(|c| (eps[c] - previous[c]).powi(2))
                .sum::<f64>()
                .sqrt();
            let t0 = Instant::now();
            let a = instance.update_timed(near, dt, &mut ws, TangentRequest::Consistent);
            let t1 = Instant::now();
            let b = instance.update_timed(eps, dt, &mut ws, TangentRequest::Consistent);
            let t2 = Instant::now();
            let (a, b) = (a.expect("first update"), b.expect("second update"));
            instance.commit().expect("commit");
            factorizations += u64::from(a.report.factorizations + b.report.factorizations);
            first.push((t1 - t0).as_secs_f64() * 1e3);
            second.push((t2 - t1).as_secs_f64() * 1e3);
            total += (t2 - t0).as_secs_f64() * 1e3;
            previous = eps;
        }
        totals.push(total / points.len() as f64);
        state_bytes = instance.save_state().expect("state").len();
    }
    Row {
        first_ms: median(&mut first),
        second_ms: median(&mut second),
        mean_increment_ms: median(&mut totals),
        factorizations: factorizations as f64 / points.len() as f64,
        state_bytes,
    }
}

fn main() {
    let root = env!("CARGO_MANIFEST_DIR");
    println!(
        "| scene | scheme | increments | first update (median ms) | second update (median ms) | \
         increment, mean (ms) | factorizations per increment | state bytes |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for scene in ["paper_rve.toml", "paper_rve_cycle.toml"] {
        let text = std::fs::read_to_string(format!("{root}/scenes/{scene}")).expect("scene");
        for scheme in ["implicit", "implex"] {
            let text = text.replacen(
                "[solver]\n",
                &format!("[solver]\nintegration = \"{scheme}\"\n"),
                1,
            );
            let scene_data = Scene::from_toml_str(&text, format!("{root}/scenes")).expect("scene");
            let points = path_points(&scene_data.spec.path);
            let model = Arc::new(Model::from_scene(&scene_data).expect("model"));
            let r = follow(&model, &points);
            println!(
                "| {scene} | {scheme} | {} | {:.3} | {:.3} | {:.3} | {:.2} | {} |",
                points.len(),
                r.first_ms,
                r.second_ms,
                r.mean_increment_ms,
                r.factorizations,
                r.state_bytes
            );
        }
    }
}

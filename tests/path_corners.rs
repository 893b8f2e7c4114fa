//! Path following round a corner of the traced path (`solver::arclength`, "Corners").
//!
//! The paper RVE pulled along y to 2.6e-4 in 40 increments snaps back at increment 34.
//! Its traced path passes both limit points of the first snap and then turns back at a
//! corner: `t` reverses through a kink of the law (points leaving the loading envelope
//! together), not at a smooth limit point, and every corrector along the incoming
//! tangent cycles between two interface branch sets at any arc length. Without the
//! corner rule the path was lost there and secant iterations from the increment's start
//! found another equilibrium, with no certified snap (`limit_points` 0). With it the
//! trace goes round the corner, passes one more limit point, and lands.

mod common;

use std::sync::Arc;

use rve::scene::Scene;
use rve::{Instance, Model, TangentRequest};

#[test]
fn a_trace_goes_round_a_corner_and_lands() {
    let text = common::paper_scene_with(&[
        ("to = [2.2e-4, 0.0, 0.0]", "to = [0.0, 2.6e-4, 0.0]"),
        ("increments = 20", "increments = 40"),
    ]);
    let mut scene = Scene::from_toml_str(&text, ".").unwrap_or_else(|e| panic!("{e}\n{text}"));
    scene.spec.solver.fast_path = false;
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut ws = model.workspace();
    let mut inst = Instance::new(model.clone());
    let mut steps = Vec::new();
    for eps in rve::scene::path_points(&scene.spec.path) {
        let r = inst
            .update(eps, &mut ws, TangentRequest::Consistent)
            .unwrap_or_else(|e| panic!("increment {}: {e}", steps.len() + 1));
        inst.commit().unwrap();
        steps.push((r.stress[1], r.report.limit_points, r.report.iterations));
    }
    let peak = (0..steps.len())
        .max_by(|&a, &b| steps[a].0.total_cmp(&steps[b].0))
        .unwrap();
    let (stress, limit_points, iterations) = steps[peak + 1];
    println!(
        "peak at increment {}: {:.4}; next: {stress:.4}, {limit_points} limit points, {iterations} iterations",
        peak + 1,
        steps[peak].0
    );
    assert_eq!(peak + 1, 33, "the stress peak moved");
    assert!(
        stress < 0.8 * steps[peak].0,
        "increment {} does not snap: {stress} after {}",
        peak + 2,
        steps[peak].0
    );
    // Landed from a traced path with both limit points of the first snap and the one
    // after the corner: the trace was not lost (a lost trace certifies none).
    assert!(
        limit_points >= 3,
        "increment {}: {limit_points} limit points certified",
        peak + 2
    );
}

//! Path following round a corner of the traced path (`solver::arclength`, "Corners").
//!
//! The paper RVE pulled along y to 2.6e-4 in 40 increments snaps back at increment 34.
//! Its traced path passes both limit points of the first snap and then turns back at a
//! corner: `t` reverses through a kink of the law (points leaving the loading envelope
//! together), not at a smooth limit point, and every corrector along the incoming
//! tangent cycles between two interface branch sets at any arc length. Without the
//! corner rule the path was lost there and secant iterations from the increment's start
//! found another equilibrium, with no certified snap (`limit_points` 0). With it the
//! trace goes round the corner, passes one more limit point, and lands. In 32
//! increments the snap meets a corner the reversal cannot round, and a long forward arc
//! crosses it. On hard case 118 the reversal finds the nearly elastic unloading branch,
//! which is refused, and the long arc crosses that corner too.

mod common;

use std::sync::Arc;

use rve::scene::Scene;
use rve::{Instance, Model, TangentRequest};

/// Follows `targets` with one update per increment from the committed state: per
/// increment, the stress along y, the certified limit points and the factorizations.
fn follow(model: Arc<Model>, targets: impl IntoIterator<Item = [f64; 3]>) -> Vec<(f64, u32, u32)> {
    let mut ws = model.workspace();
    let mut inst = Instance::new(model);
    let mut steps = Vec::new();
    for eps in targets {
        let r = inst
            .update(eps, &mut ws, TangentRequest::Consistent)
            .unwrap_or_else(|e| panic!("increment {}: {e}", steps.len() + 1));
        inst.commit().unwrap();
        steps.push((r.stress[1], r.report.limit_points, r.report.factorizations));
    }
    steps
}

/// The paper RVE pulled along y to 2.6e-4 in `increments` increments, without the fast
/// path (see [`follow`]).
fn pull_along_y(increments: u32) -> Vec<(f64, u32, u32)> {
    let text = common::paper_scene_with(&[
        ("to = [2.2e-4, 0.0, 0.0]", "to = [0.0, 2.6e-4, 0.0]"),
        ("increments = 20", &format!("increments = {increments}")),
    ]);
    let mut scene = Scene::from_toml_str(&text, ".").unwrap_or_else(|e| panic!("{e}\n{text}"));
    scene.spec.solver.fast_path = false;
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    follow(model, rve::scene::path_points(&scene.spec.path))
}

/// The first increment after the stress peak whose stress falls below 0.8 of the peak:
/// its index (from 1), limit points and factorizations.
fn snap_after_peak(steps: &[(f64, u32, u32)]) -> (usize, u32, u32) {
    let peak = (0..steps.len())
        .max_by(|&a, &b| steps[a].0.total_cmp(&steps[b].0))
        .unwrap();
    let snap = (peak + 1..steps.len())
        .find(|&k| steps[k].0 < 0.8 * steps[peak].0)
        .unwrap_or_else(|| panic!("no snap after the peak at increment {}", peak + 1));
    let (stress, limit_points, factorizations) = steps[snap];
    println!(
        "peak at increment {}: {:.4}; snap at {}: {stress:.4}, {limit_points} limit points, \
         {factorizations} factorizations",
        peak + 1,
        steps[peak].0,
        snap + 1
    );
    (snap + 1, limit_points, factorizations)
}

#[test]
fn a_trace_goes_round_a_corner_and_lands() {
    let (snap, limit_points, _) = snap_after_peak(&pull_along_y(40));
    assert_eq!(snap, 34, "the snap moved");
    // Landed from a traced path with both limit points of the first snap and the one
    // after the corner: the trace was not lost (a lost trace certifies none).
    assert!(
        limit_points >= 3,
        "increment {snap}: {limit_points} limit points certified"
    );
}

/// In 32 increments the snap (increment 28) meets a second corner at `t` = -1.12 where
/// the reversal only finds the elastic unloading branch. Short forward arcs cycle there;
/// the long arc over the corner (`CORNER_JUMP`) reaches past the target and lands.
/// Before it, the trace was lost and secant iterations landed with no certified limit
/// point, in 118 factorizations.
#[test]
fn a_long_arc_crosses_a_corner_the_reversal_cannot_round() {
    let (snap, limit_points, factorizations) = snap_after_peak(&pull_along_y(32));
    assert_eq!(snap, 28, "the snap moved");
    assert!(
        limit_points >= 2,
        "increment {snap}: {limit_points} limit points certified (the trace was lost)"
    );
    assert!(
        factorizations < 100,
        "increment {snap}: {factorizations} factorizations"
    );
}

/// Hard case 118 (a turn from x to y on an ellipse RVE): at the corner of its worst
/// increment the reversed attempt converges with 1 of 80 points still loading, the
/// nearly elastic unloading branch. Kept, it led the trace back to `t = -8.5` and the
/// increment ended in secant iterations (197 iterations, no certified limit point); refused
/// (`CORNER_LOADING`), the long arc crosses the corner and the trace lands.
#[test]
fn a_reversal_onto_a_nearly_elastic_branch_is_refused() {
    let case = common::hard_paths::case(118);
    let scene = Scene::from_toml_str(&case.scene, common::repo("scenes")).unwrap();
    let steps = follow(
        Arc::new(Model::from_scene(&scene).unwrap()),
        case.targets.iter().copied(),
    );
    // The first increment with the most factorizations.
    let worst = (0..steps.len())
        .max_by_key(|&k| (steps[k].2, std::cmp::Reverse(k)))
        .unwrap();
    let (increment, factorizations, limit_points) = (worst + 1, steps[worst].2, steps[worst].1);
    println!(
        "worst increment {increment}: {factorizations} factorizations, {limit_points} limit points"
    );
    assert!(
        limit_points >= 2,
        "increment {increment}: {limit_points} limit points certified (the trace was lost)"
    );
    assert!(
        factorizations < 150,
        "increment {increment}: {factorizations} factorizations"
    );
}

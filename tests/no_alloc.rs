//! The hot path allocates nothing: once a workspace and an instance exist (and the
//! factorization buffers have grown on a first update, and the quantized buffers of the
//! instance's two states on the first three: a virgin state has none, the sensitivity is
//! first filled by the first increment and the path curvature by the second, see
//! `mesorve_core::state::Sensitivity` and `mesorve_core::state::PathCurvature`), `Instance::update` and
//! `commit` make no heap allocation, on loading, unloading and contact increments alike, and
//! neither does the fast path (`mesorve_core::solver::fast_path`). The hot
//! path is every increment that converges in one step with LDL^T or checked LBL^T
//! factorizations; faer's supernodal LU (the last resort for indefinite tangents)
//! allocates inside faer, and so do the fallbacks (path following, error messages), which
//! are asserted to be rare instead.

mod common;
#[path = "common/counting_alloc.rs"]
mod counting_alloc;

use std::sync::Arc;

use counting_alloc::count_allocations;
use rve::{Instance, Model, TangentRequest};

#[test]
fn update_and_commit_do_not_allocate() {
    let scene = common::scene("scenes/paper_rve_cycle.toml");
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut ws = model.workspace();
    let mut inst = Instance::new(model.clone());
    let path = rve::scene::path_points(&scene.spec.path);
    // Warm-up: the first update sizes faer's numeric buffers and the trial's sensitivity,
    // the second the other state's sensitivity and its path curvature, the third the
    // first state's curvature (the states swap on commit).
    for eps in &path[..3] {
        inst.update(*eps, &mut ws, TangentRequest::Consistent)
            .unwrap();
        inst.commit().unwrap();
    }
    let (mut total, mut checked, mut fast) = (0, 0, 0);
    let mut transitions = Vec::new();
    let mut previous_fast = false;
    for (k, eps) in path.iter().enumerate().skip(3) {
        let mut report = None;
        let n = count_allocations(|| {
            report = inst
                .update(*eps, &mut ws, TangentRequest::Consistent)
                .ok()
                .map(|r| r.report);
            inst.commit().unwrap();
        });
        let report = report.unwrap_or_else(|| panic!("increment {} failed", k + 1));
        total += 1;
        if report.answer.is_fast() {
            assert_eq!(n, 0, "fast increment {}: {n} allocations", k + 1);
            (checked, fast) = (checked + 1, fast + 1);
        } else if report.lu_factorizations == 0 && report.substeps == 1 {
            // Two transitions allocate, once each: the first full update after fast ones
            // re-creates the trial state that a fast commit released, and an update that
            // finds a linear branch set may give the fast path's data new buffers.
            if previous_fast || inst.committed().linear.valid {
                assert!(
                    n <= 8,
                    "increment {}: {n} allocations at a transition",
                    k + 1
                );
                transitions.push((k + 1, n));
            } else {
                assert_eq!(n, 0, "increment {}: {n} allocations ({report:?})", k + 1);
                checked += 1;
            }
        }
        previous_fast = report.answer.is_fast();
    }
    println!("{fast} fast increments, transitions (increment, allocations): {transitions:?}");
    assert!(fast >= 30, "only {fast} fast increments");
    // The allocation-free path is the rule: 57 increments, all but the peak ones and two
    // transitions (into unloading, into compression).
    assert!(
        checked + 3 + transitions.len() >= total && transitions.len() <= 2,
        "only {checked} of {total} increments on the hot path, transitions {transitions:?}"
    );
}

/// The factorizations of indefinite tangents work in the workspace's buffers: after one
/// warm-up call, factorizing and solving allocate nothing, both for the checked LDL^T
/// (the converged tangent with its diagonal shifted down by a quarter of its mean) and
/// for the checked LBL^T it falls back to (the same with every diagonal entry zero: the
/// unpivoted LDL^T meets a zero pivot).
#[test]
fn checked_indefinite_factorizations_do_not_allocate() {
    use mesorve_core::solver::FactorKind;

    let scene = common::scene("scenes/paper_rve.toml");
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut ws = model.workspace();
    let mut inst = Instance::new(model.clone());
    inst.update([1e-4, 0.0, 0.0], &mut ws, TangentRequest::Consistent)
        .unwrap();
    let pattern = &model.discretization().pattern;
    let mean_diagonal = pattern
        .diagonal_slots
        .iter()
        .map(|&s| ws.tangent_values()[s as usize])
        .sum::<f64>()
        / pattern.n as f64;
    let mut shifted = ws.tangent_values().to_vec();
    let mut zero_diagonal = ws.tangent_values().to_vec();
    for &s in &pattern.diagonal_slots {
        shifted[s as usize] -= 0.25 * mean_diagonal;
        zero_diagonal[s as usize] = 0.0;
    }
    for (values, expected) in [
        (shifted, FactorKind::LdltIndefinite),
        (zero_diagonal, FactorKind::Lblt),
    ] {
        let mut rhs = vec![1.0; pattern.n];
        let run = |ws: &mut rve::Workspace, rhs: &mut [f64]| {
            let factorization = ws.factorization();
            let kind = factorization
                .factorize(
                    model.linear_solver(),
                    &pattern.symbolic,
                    &values,
                    mesorve_core::solver::FactorUse::OneUse,
                    true,
                )
                .unwrap();
            factorization.solve(model.linear_solver(), rhs, 1);
            kind
        };
        assert_eq!(run(&mut ws, &mut rhs), expected);
        let mut kind = None;
        let n = count_allocations(|| kind = Some(run(&mut ws, &mut rhs)));
        assert_eq!(kind, Some(expected));
        assert_eq!(
            n, 0,
            "{n} allocations in a checked {expected:?} and its solve"
        );
    }
}

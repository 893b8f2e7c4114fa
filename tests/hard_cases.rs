//! Hard cases with the paper's contact law: 40 seeded paths a host could hand
//! an RVE past the peak (`common/hard_paths.rs`: uniaxial strain in a random direction,
//! uniaxial-stress-like paths with Poisson contraction, pure shear and its reversal,
//! biaxial paths, tension then compression, unload and reload beyond the old peak, a turn
//! from x to y, one to three increments across the softening branch; circles or ellipses
//! from a random seed, a random mesh size, periodic or linear BC, `lambda_p` from 1e4 to
//! 1e9). Every path must complete. A failed update must fail cleanly (a typed error, a step
//! ratio below 1, the committed state unchanged), and a host that retries with that ratio
//! must finish the path: the host loop here does what a UMAT host does with PNEWDT.

mod common;

use std::sync::Arc;

use common::hard_paths::{self, host_follow};
use rve::{Instance, Model, Scene};

/// The case's model, with `max_iterations = 40` of its `[solver]` replaced by `solver`.
fn model_of(case: &hard_paths::HardCase, solver: &str) -> Arc<Model> {
    let text = case.scene.replace("max_iterations = 40", solver);
    let scene = Scene::from_toml_str(&text, common::repo("scenes")).unwrap();
    Arc::new(
        Model::from_scene(&scene)
            .unwrap_or_else(|e| panic!("seed {} ({}): {e}", case.seed, case.setup)),
    )
}

/// Every one of the 40 paths completes, each increment in a single update.
#[test]
fn every_hard_case_completes() {
    let mut kinds = std::collections::BTreeSet::new();
    let mut max_lambda = 0.0f64;
    let mut failures = Vec::new();
    for seed in 0..40 {
        let case = hard_paths::case(seed);
        kinds.insert(case.kind);
        let lambda: f64 = case.setup.rsplit(' ').next().unwrap().parse().unwrap();
        max_lambda = max_lambda.max(lambda);
        let mut inst = Instance::new(model_of(&case, "max_iterations = 40"));
        match host_follow(&mut inst, &case.targets) {
            Ok(run) if run.retries == 0 => {}
            Ok(run) => failures.push(format!(
                "seed {seed} ({}, {}): {} host retries",
                case.kind, case.setup, run.retries
            )),
            Err(e) => failures.push(format!("seed {seed} ({}, {}): {e}", case.kind, case.setup)),
        }
    }
    assert_eq!(kinds.len(), hard_paths::KINDS.len());
    assert!(max_lambda > 1e8, "largest lambda_p drawn {max_lambda:e}");
    assert!(failures.is_empty(), "{failures:#?}");
}

/// With a solver cut down to fail (3 Newton iterations, no bisection of its own, no secant
/// iterations), every failure is clean and the host loop finishes every path (measured:
/// 18 retries on 3 of the 40 paths, 15 of them on one). Path following is left on: without
/// it a snap-back cannot be passed at any step. With 10 secant iterations, as before
/// the corrector's cycle rule changed (`newton::comes_back`), nothing fails any more.
#[test]
fn host_retries_finish_after_clean_failures() {
    let (mut retries, mut paths_retried) = (0, 0);
    for seed in 0..40 {
        let case = hard_paths::case(seed);
        let model = model_of(
            &case,
            "max_iterations = 3\nmax_substep_depth = 0\nmax_secant_iterations = 0",
        );
        let mut inst = Instance::new(model);
        let run = host_follow(&mut inst, &case.targets)
            .unwrap_or_else(|e| panic!("seed {seed} ({}, {}): {e}", case.kind, case.setup));
        retries += run.retries;
        paths_retried += usize::from(run.retries > 0);
    }
    // The cut-down solver does fail: the retries are exercised, on more than one path.
    assert!(
        retries >= 10 && paths_retried >= 3,
        "only {retries} failures to retry, on {paths_retried} paths"
    );
}

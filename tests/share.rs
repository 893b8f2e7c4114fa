//! Answer sharing in the batch (`[solver] share_tolerance`, `rve::model::share`,
//! docs/sharing.md), on the IMPL-EX host scene along a path through the peak and back:
//! a homogeneous batch solves one point per increment and equals the exact run; a
//! heterogeneous batch stays within the tolerance's stated bound of the exact run; 1 and 2
//! threads give the same answers bit for bit; two materials never share; bad values of
//! the key are refused with the key's name.

use std::sync::Arc;

use rve::model::batch::{update_batch, BatchOutputs, BatchStep, PointReport};
use rve::model::share;
use rve::{Error, Instance, Model, Scene, TangentRequest};

const SCENE: &str = include_str!("../scenes/paper_rve_host_implex.toml");

/// The host scene with `extra` lines added to its `[solver]` table and `sigma_c` set.
fn model(extra: &str, sigma_c: f64) -> Arc<Model> {
    let text = SCENE
        .replace("[solver]\n", &format!("[solver]\n{extra}\n"))
        .replace("sigma_c = 4.0", &format!("sigma_c = {sigma_c}"));
    let scene = Scene::from_toml_str(&text, env!("CARGO_MANIFEST_DIR")).unwrap();
    Arc::new(Model::from_scene(&scene).unwrap())
}

/// The path's position at increment `i` (up to past the peak, then back).
fn along(i: usize) -> f64 {
    let up = 14;
    if i < up {
        (i + 1) as f64
    } else {
        (2 * up - 1 - i) as f64 * 0.6 + 0.4 * up as f64
    }
}

/// A uniaxial-like strain of size `s` times the path's step.
fn strain(s: f64) -> [f64; 3] {
    let e = 1.6e-5 * s;
    [e, -0.2 * e, 0.05 * e]
}

struct Run {
    stresses: Vec<Vec<[f64; 3]>>,
    reports: Vec<Vec<PointReport>>,
}

/// Every increment of the path through `update_batch` on `threads`, each point's strain
/// `strain(along * scales[p])`, each committed after the batch.
fn run(points: &mut [Instance], scales: &[f64], threads: usize) -> Run {
    let mut run = Run {
        stresses: Vec::new(),
        reports: Vec::new(),
    };
    for i in 0..24 {
        let strains: Vec<[f64; 3]> = scales.iter().map(|s| strain(along(i) * s)).collect();
        let n = points.len();
        let (mut stresses, mut tangents) = (vec![[0.0; 3]; n], vec![[0.0; 9]; n]);
        let mut reports = vec![PointReport::default(); n];
        let step = BatchStep {
            dtime: 1.0,
            request: TangentRequest::Consistent,
            threads,
        };
        let out = BatchOutputs {
            stresses: &mut stresses,
            tangents: Some(&mut tangents),
            reports: &mut reports,
        };
        let failures = update_batch(points, &strains, step, out).unwrap();
        assert!(failures.is_empty(), "{failures:?}");
        points.iter_mut().for_each(|p| p.commit().unwrap());
        run.stresses.push(stresses);
        run.reports.push(reports);
    }
    run
}

fn instances(model: &Arc<Model>, n: usize) -> Vec<Instance> {
    (0..n).map(|_| Instance::new(model.clone())).collect()
}

/// The largest stress difference of two runs, over the largest stress of the first.
fn relative_difference(exact: &Run, shared: &Run) -> f64 {
    let all = |r: &Run| -> Vec<f64> { r.stresses.iter().flatten().flatten().copied().collect() };
    let (a, b) = (all(exact), all(shared));
    let largest = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = a
        .iter()
        .zip(&b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    diff / largest
}

#[test]
fn homogeneous_batch_solves_once_per_increment_and_equals_the_exact_run() {
    let exact_model = model("", 4.0);
    let shared_model = model("share_tolerance = 0.005", 4.0);
    let scales = [1.0; 6];
    let exact = run(&mut instances(&exact_model, 6), &scales, 2);
    let shared = run(&mut instances(&shared_model, 6), &scales, 2);
    // Every follower takes point 0's step, or carries its own over (an unloading point's
    // step is the last one's: exact and free, as the anchor's): one factorization at most
    // per increment, all of them point 0's.
    for (i, reports) in shared.reports.iter().enumerate() {
        for r in &reports[1..] {
            assert!(r.factorizations == 0, "increment {i}: {r:?}");
            assert!(r.shared_from == Some(0) || r.fast, "increment {i}: {r:?}");
        }
    }
    let shared_calls: usize = shared.reports.iter().map(|r| share::counts(r).1).sum();
    assert!(shared_calls >= 5 * 12, "{shared_calls} shared calls");
    for (a, b) in exact
        .stresses
        .iter()
        .flatten()
        .zip(shared.stresses.iter().flatten())
    {
        assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
    }
}

/// Scales of a heterogeneous batch: clusters of points within a few tenths of a percent
/// of each other, and points that no other matches.
const SCALES: [f64; 10] = [1.0, 1.001, 1.003, 0.998, 1.2, 1.202, 0.5, 0.501, 0.8, 1.5];

#[test]
fn heterogeneous_batch_within_the_tolerance_of_the_exact_run() {
    let tol = 0.005;
    let exact = run(&mut instances(&model("", 4.0), SCALES.len()), &SCALES, 2);
    let shared_model = model(&format!("share_tolerance = {tol}"), 4.0);
    let shared = run(&mut instances(&shared_model, SCALES.len()), &SCALES, 2);
    let difference = relative_difference(&exact, &shared);
    let total: (usize, usize) = shared
        .reports
        .iter()
        .map(|r| share::counts(r))
        .fold((0, 0), |(a, b), (c, d)| (a + c, b + d));
    eprintln!("heterogeneous: largest stress difference {difference:.3e} of the largest stress; solved {}, shared {}", total.0, total.1);
    assert!(total.1 > 0, "some points share");
    assert!(difference <= tol, "{difference} > {tol}");
}

#[test]
fn one_and_two_threads_give_the_same_shared_answers() {
    let m = model("share_tolerance = 0.005", 4.0);
    let one = run(&mut instances(&m, SCALES.len()), &SCALES, 1);
    let two = run(&mut instances(&m, SCALES.len()), &SCALES, 2);
    for (a, b) in one
        .stresses
        .iter()
        .flatten()
        .zip(two.stresses.iter().flatten())
    {
        assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
    }
    assert_eq!(one.reports, two.reports);
}

#[test]
fn never_shares_across_materials() {
    let a = model("share_tolerance = 0.005", 4.0);
    let b = model("share_tolerance = 0.005", 4.5);
    // Same scene text, built twice: equal fingerprints, but other models (and in a host,
    // other materials): not shared either.
    let a2 = model("share_tolerance = 0.005", 4.0);
    let mut points: Vec<Instance> = [&a, &b, &a2, &a, &b, &a2]
        .iter()
        .map(|m| Instance::new((*m).clone()))
        .collect();
    let shared = run(&mut points, &[1.0; 6], 2);
    let mut shared_calls = 0;
    for reports in &shared.reports {
        for (k, r) in reports.iter().enumerate() {
            // Point k >= 3 may only follow point k - 3, its own model's twin (or carry its
            // own step over).
            assert!(
                r.shared_from.is_none() || r.shared_from == Some(k - 3),
                "{k}: {r:?}"
            );
            shared_calls += usize::from(r.shared_from.is_some());
        }
    }
    assert!(shared_calls >= 3 * 12, "{shared_calls} shared calls");
}

#[test]
fn bad_share_tolerance_is_refused_by_name() {
    for bad in ["0.0", "-0.01", "0.5", "nan", "inf"] {
        let text = SCENE.replace(
            "[solver]\n",
            &format!("[solver]\nshare_tolerance = {bad}\n"),
        );
        match Scene::from_toml_str(&text, env!("CARGO_MANIFEST_DIR")) {
            Err(Error::Scene { key, .. }) => assert_eq!(key, "solver.share_tolerance"),
            other => panic!("share_tolerance = {bad}: {other:?}"),
        }
    }
}

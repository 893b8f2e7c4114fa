//! The safe batch API (`rve::model::batch`): instances of the IMPL-EX host scene along a
//! path past the peak with non-uniform time increments; each increment through
//! `update_batch` on 1 and on 2 threads and through `Instance::update_timed` one by one
//! must give the same stresses, tangents and reports, bit for bit; a point at a NaN strain
//! fails alone, named by its index, with its outputs untouched. Under
//! `solver.step_tolerance` each point reports its IMPL-EX error estimate.

use std::sync::Arc;

use rve::model::batch::{update_batch, BatchOutputs, BatchStep, PointReport, Reliability};
use rve::{Error, Instance, Model, Scene, TangentRequest};

const N: usize = 5;

const SCENE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scenes/paper_rve_host_implex.toml"
);

fn model() -> Arc<Model> {
    Arc::new(Model::from_scene(&Scene::from_file(SCENE).unwrap()).unwrap())
}

/// Point `p`'s strain at position `along` of the path (past the peak for the last points).
fn strain(along: f64, p: usize) -> [f64; 3] {
    let scale = along * 7.6e-6 * (p + 1) as f64 / N as f64;
    [scale, -0.2 * scale, 0.05 * scale]
}

struct Outputs {
    stresses: Vec<[f64; 3]>,
    tangents: Vec<[f64; 9]>,
    reports: Vec<PointReport>,
}

fn batch(points: &mut [Instance], strains: &[[f64; 3]], dtime: f64, threads: usize) -> Outputs {
    let mut o = Outputs {
        stresses: vec![[0.0; 3]; points.len()],
        tangents: vec![[0.0; 9]; points.len()],
        reports: vec![PointReport::default(); points.len()],
    };
    let step = BatchStep {
        dtime,
        request: TangentRequest::Consistent,
        threads,
    };
    let out = BatchOutputs {
        stresses: &mut o.stresses,
        tangents: Some(&mut o.tangents),
        reports: &mut o.reports,
    };
    let failures = update_batch(points, strains, step, out).unwrap();
    assert!(failures.is_empty(), "{failures:?}");
    o
}

#[test]
fn batch_equals_point_by_point_on_any_thread_count() {
    let model = model();
    let mut sets: Vec<Vec<Instance>> = (0..3)
        .map(|_| (0..N).map(|_| Instance::new(model.clone())).collect())
        .collect();
    let mut ws = model.workspace();
    let (mut along, mut solved) = (0.0, 0);
    for (s, dt) in [1.0, 2.0, 0.5, 1.0, 3.0, 1.5, 1.0, 2.0]
        .repeat(2)
        .into_iter()
        .enumerate()
    {
        along += if s < 8 { 3.0 } else { -2.0 } * dt;
        let strains: Vec<[f64; 3]> = (0..N).map(|p| strain(along, p)).collect();
        let one = batch(&mut sets[1], &strains, dt, 1);
        let two = batch(&mut sets[2], &strains, dt, 2);
        for p in 0..N {
            let r = sets[0][p]
                .update_timed(strains[p], dt, &mut ws, TangentRequest::Consistent)
                .unwrap();
            let report = PointReport::from_response(&r);
            assert_eq!(report.error_estimate, 0.0, "no step_tolerance: no estimate");
            for o in [&one, &two] {
                assert_eq!(o.stresses[p].map(f64::to_bits), r.stress.map(f64::to_bits));
                assert_eq!(o.tangents[p].map(f64::to_bits), r.tangent.map(f64::to_bits));
                assert_eq!(o.reports[p], report, "increment {s}, point {p}");
            }
            solved += usize::from(!report.fast && report.factorizations > 0);
        }
        for set in &mut sets {
            set.iter_mut().for_each(|i| i.commit().unwrap());
        }
    }
    assert!(
        solved > N,
        "the path must make the points solve ({solved} solves)"
    );
}

#[test]
fn a_failing_point_fails_alone() {
    let model = model();
    let mut points: Vec<Instance> = (0..N).map(|_| Instance::new(model.clone())).collect();
    let mut strains: Vec<[f64; 3]> = (0..N).map(|p| strain(10.0, p)).collect();
    strains[3][1] = f64::NAN;
    let mut stresses = vec![[7.0; 3]; N];
    let mut reports = vec![PointReport::default(); N];
    let step = BatchStep {
        dtime: 1.0,
        request: TangentRequest::None,
        threads: 2,
    };
    let out = BatchOutputs {
        stresses: &mut stresses,
        tangents: None,
        reports: &mut reports,
    };
    let failures = update_batch(&mut points, &strains, step, out).unwrap();
    assert_eq!(failures.len(), 1);
    assert_eq!(failures[0].0, 3);
    assert!(
        matches!(failures[0].1, Error::BadStrain { .. }),
        "{:?}",
        failures[0].1
    );
    assert_eq!(
        stresses[3], [7.0; 3],
        "a failed point's stress is not written"
    );
    assert_eq!(reports[3].reliability, Reliability::Failed);
    for p in [0, 1, 2, 4] {
        assert_ne!(stresses[p], [7.0; 3]);
        assert_eq!(reports[p].reliability, Reliability::Reliable);
        assert!(points[p].has_trial());
    }
    assert!(!points[3].has_trial());
    let bad_dt = BatchStep {
        dtime: f64::INFINITY,
        ..step
    };
    let out = BatchOutputs {
        stresses: &mut stresses,
        tangents: None,
        reports: &mut reports,
    };
    let e = update_batch(&mut points, &strains, bad_dt, out).unwrap_err();
    assert!(matches!(e, Error::HostConvention(_)), "{e:?}");
}

/// With `step_tolerance`, every point's `error_estimate` is its update's estimate
/// (`eta / tol`), and the points past the peak at the path's coarse steps exceed the
/// tolerance, with a ratio below 1; without it the estimate is 0 (the first test).
#[test]
fn the_report_carries_the_error_estimate() {
    let text = std::fs::read_to_string(SCENE).unwrap().replace(
        "integration = \"implex\"\n",
        "integration = \"implex\"\nstep_tolerance = 0.01\nsmallest_step = 1e-3\n",
    );
    let scene = Scene::from_toml_str(&text, env!("CARGO_MANIFEST_DIR")).unwrap();
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut points: Vec<Instance> = (0..N).map(|_| Instance::new(model.clone())).collect();
    let mut alone: Vec<Instance> = (0..N).map(|_| Instance::new(model.clone())).collect();
    let mut ws = model.workspace();
    let (mut largest, mut smallest_ratio) = (0.0f64, f64::INFINITY);
    for s in 1..=8 {
        let strains: Vec<[f64; 3]> = (0..N).map(|p| strain(3.0 * s as f64, p)).collect();
        let out = batch(&mut points, &strains, 1.0, 2);
        for p in 0..N {
            let r = alone[p]
                .update_timed(strains[p], 1.0, &mut ws, TangentRequest::Consistent)
                .unwrap();
            let estimate = r
                .report
                .error_estimate
                .expect("an estimate under step_tolerance");
            assert_eq!(out.reports[p].error_estimate.to_bits(), estimate.to_bits());
            largest = largest.max(estimate);
            smallest_ratio = smallest_ratio.min(out.reports[p].suggested_step_ratio);
        }
        points
            .iter_mut()
            .chain(&mut alone)
            .for_each(|i| i.commit().unwrap());
    }
    assert!(
        largest > 1.0 && smallest_ratio < 1.0,
        "past the peak some point exceeds the tolerance: largest estimate {largest}, \
         smallest ratio {smallest_ratio}"
    );
}

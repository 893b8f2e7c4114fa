//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod hard_paths;
mod paths;
pub mod share_paths;

#[allow(unused_imports)]
pub use paths::{paper_scene_with, repo, rve_exe, scene};

/// One `update_batch` of `points` at `strains` (`dtime` 1, the consistent tangent, on
/// `threads`), every point succeeding: their stresses and reports.
pub fn batch_consistent(
    points: &mut [rve::Instance],
    strains: &[[f64; 3]],
    threads: usize,
) -> (Vec<[f64; 3]>, Vec<rve::model::batch::PointReport>) {
    use rve::model::batch::{update_batch, BatchOutputs, BatchStep, PointReport};
    let n = points.len();
    let (mut stresses, mut tangents) = (vec![[0.0; 3]; n], vec![[0.0; 9]; n]);
    let mut reports = vec![PointReport::default(); n];
    let step = BatchStep {
        dtime: 1.0,
        request: rve::TangentRequest::Consistent,
        threads,
    };
    let out = BatchOutputs {
        stresses: &mut stresses,
        tangents: Some(&mut tangents),
        reports: &mut reports,
    };
    let failures = update_batch(points, strains, step, out).unwrap();
    assert!(failures.is_empty(), "{failures:?}");
    (stresses, reports)
}

/// `max |a_i - b_i| / max |b_i|`: the relative difference of two stress or tangent arrays.
pub fn max_rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

/// A plane-stress UMAT call of the paper's cycle as the STATEV tests make it: increment `k`
/// (`KINC` = k + 1, `KSTEP` 1) of point (`noel`, 1), `TIME(2)` = 0.1 k, `DTIME` = 0.1.
pub fn cycle_call<'a>(
    cmname: &'a str,
    props: &'a [f64],
    stran: &'a [f64],
    dstran: &'a [f64],
    noel: i32,
    k: usize,
) -> rve::host::UmatCall<'a> {
    let time = 0.1 * k as f64;
    rve::host::UmatCall {
        cmname,
        props,
        hypothesis: rve::host::Hypothesis::PlaneStress,
        stran,
        dstran,
        time: [time, time],
        dtime: 0.1,
        noel,
        npt: 1,
        kstep: 1,
        kinc: k as i32 + 1,
        celent: None,
    }
}

/// Follows `points` with `instance`, each increment's time step the norm of its strain
/// increment (as `rve run` does), committing every increment; the responses.
pub fn follow_committed(instance: &mut rve::Instance, points: &[[f64; 3]]) -> Vec<rve::Response> {
    let model = instance.model().clone();
    let mut ws = model.workspace();
    let mut previous = [0.0; 3];
    let mut out = Vec::new();
    for &eps in points {
        let dt = (0..3)
            .map(|c| (eps[c] - previous[c]).powi(2))
            .sum::<f64>()
            .sqrt();
        previous = eps;
        let r = instance
            .update_timed(
                eps,
                dt,
                &mut ws,
                mesorve_core::solver::TangentRequest::Consistent,
            )
            .unwrap();
        instance.commit().unwrap();
        out.push(r);
    }
    out
}

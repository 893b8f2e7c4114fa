//! Viscous regularization of the ITZ (`materials.itz.viscosity`) on the paper's RVE: the
//! homogenized tangent is the derivative of the stress (central differences) at an
//! increment where the inviscid law snaps back, and the snap-back is gone from the
//! strain-driven response.

mod common;

use std::sync::Arc;

use rve::scene::{path_points, Scene};
use rve::solver::TangentRequest;
use rve::{Instance, Model};

/// The section 5.2.2 cycle with viscosity `eta` and a tight Newton tolerance.
fn model(eta: f64) -> (Arc<Model>, Vec<[f64; 3]>) {
    let text = std::fs::read_to_string(common::repo("scenes/paper_rve_cycle.toml"))
        .unwrap()
        .replacen(
            "beta = 0.707,",
            &format!("beta = 0.707, viscosity = {eta:e},"),
            1,
        )
        .replacen("tolerance = 1e-6", "tolerance = 1e-11", 1);
    let scene = Scene::from_toml_str(&text, common::repo("scenes")).unwrap();
    let points = path_points(&scene.spec.path);
    (Arc::new(Model::from_scene(&scene).unwrap()), points)
}

/// At the increment where the inviscid law snaps back (the cycle's 19th-20th), with
/// `eta` a fifth of the step's time: no limit point, and the consistent tangent matches
/// central differences of the stress over the same time increment.
#[test]
fn viscous_tangent_is_the_derivative_of_the_stress() {
    let dt = 1.15e-5;
    let (model, points) = model(0.2 * dt);
    let mut instance = Instance::new(model.clone());
    let mut ws = model.workspace();
    let mut limit_points = 0;
    for &eps in &points[..19] {
        let r = instance
            .update_timed(eps, dt, &mut ws, TangentRequest::Consistent)
            .unwrap();
        limit_points += r.report.limit_points;
        instance.commit().unwrap();
    }
    let eps = points[19];
    let base = instance
        .update_timed(eps, dt, &mut ws, TangentRequest::Consistent)
        .unwrap();
    assert_eq!(limit_points + base.report.limit_points, 0, "no snap-back");
    assert!(base.report.loading > 0);
    let d = base.tangent;
    let scale = d.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let h = 1e-8;
    for j in 0..3 {
        let (mut plus, mut minus) = (eps, eps);
        plus[j] += h;
        minus[j] -= h;
        let rp = instance
            .update_timed(plus, dt, &mut ws, TangentRequest::None)
            .unwrap();
        let rm = instance
            .update_timed(minus, dt, &mut ws, TangentRequest::None)
            .unwrap();
        for i in 0..3 {
            let fd = (rp.stress[i] - rm.stress[i]) / (2.0 * h);
            assert!(
                (fd - d[3 * i + j]).abs() <= 1e-5 * scale,
                "D{i}{j}: {} vs central difference {fd}",
                d[3 * i + j]
            );
        }
    }
}

//! The linear elastic interface law (`materials.linear_itz`) against its closed form.
//!
//! A cell of width `w` cut by one straight vertical interface (`geometry.kind =
//! "straight_interface"`), one material on both sides, periodic conditions: the fields
//! are uniform, and the interface is a compliant layer in series with the bulk. The jump
//! `[delta_s, delta_n]` across the line adds `delta_n / w` to the mean `eps_xx` and
//! `delta_s / w` to the mean `gamma_xy`, while the traction equals the uniform stress,
//! `t_n = s_xx = k_n delta_n`, `t_s = s_xy = k_s delta_s`. Hence
//!
//! ```text
//! eps = D^-1 sigma + (1/w) [s_xx / k_n, 0, s_xy / k_s]
//! D_hom = (D^-1 + diag(1/(w k_n), 0, 1/(w k_s)))^-1
//! ```
//!
//! The law has no history, so the response is linear: any strain, any order.

use std::sync::Arc;

use mesorve_core::material::{Analysis, IsotropicElastic};
use nalgebra::{Matrix3, Vector3};
use rve::{Instance, Model, Scene, TangentRequest};

const WIDTH: f64 = 2.0;
const K_N: f64 = 1e5;
const K_S: f64 = 4e4;

fn scene(analysis: &str) -> Scene {
    let text = format!(
        r#"
[cell]
size = [{WIDTH}, 2.0]
analysis = "{analysis}"
[geometry]
kind = "straight_interface"
x = 0.7
[mesh]
size = 0.25
interface_size = 0.25
[materials]
matrix = {{ young = 30000.0, poisson = 0.2 }}
aggregate = {{ young = 30000.0, poisson = 0.2 }}
linear_itz = {{ shear_stiffness = {K_S}, normal_stiffness = {K_N} }}
[effects]
cohesive = true
contact = false
[boundary]
kind = "periodic"
[solver]
tolerance = 1e-10
"#
    );
    Scene::from_toml_str(&text, ".").expect("scene")
}

fn closed_form(analysis: Analysis) -> Matrix3<f64> {
    let bulk = IsotropicElastic {
        young: 30000.0,
        poisson: 0.2,
    }
    .stiffness(analysis);
    let layer =
        Matrix3::from_diagonal(&Vector3::new(1.0 / (WIDTH * K_N), 0.0, 1.0 / (WIDTH * K_S)));
    (bulk.try_inverse().unwrap() + layer).try_inverse().unwrap()
}

#[test]
fn straight_linear_interface_matches_the_series_layer() {
    for (name, analysis) in [
        ("plane_strain", Analysis::PlaneStrain),
        ("plane_stress", Analysis::PlaneStress),
    ] {
        let model = Arc::new(Model::from_scene(&scene(name)).unwrap());
        assert!(
            !model.discretization().interfaces.is_empty(),
            "{name}: the line has ITZ elements"
        );
        assert_eq!(
            model.discretization().history_len(),
            0,
            "{name}: the law keeps no history"
        );
        let expected = closed_form(analysis);
        let mut ws = model.workspace();
        let mut inst = Instance::new(model.clone());
        // A path with a reversal: a history-free law answers every point alike.
        for strain in [[1e-4, -3e-5, 2e-4], [-2e-4, 5e-5, -1e-4], [3e-5, 1e-4, 0.0]] {
            let r = inst
                .update(strain, &mut ws, TangentRequest::Consistent)
                .unwrap();
            inst.commit().unwrap();
            let sigma = expected * Vector3::from(strain);
            let scale = sigma.norm();
            for i in 0..3 {
                assert!(
                    (r.stress[i] - sigma[i]).abs() <= 1e-9 * scale,
                    "{name} {strain:?}: stress {:?} vs {sigma:?}",
                    r.stress
                );
            }
            let d_scale = expected.norm();
            for i in 0..3 {
                for j in 0..3 {
                    assert!(
                        (r.tangent[3 * i + j] - expected[(i, j)]).abs() <= 1e-9 * d_scale,
                        "{name}: D[{i}][{j}] = {} vs {}",
                        r.tangent[3 * i + j],
                        expected[(i, j)]
                    );
                }
            }
        }
        // The interface makes the cell softer than the bulk in xx and xy, not in yy.
        let bulk = IsotropicElastic {
            young: 30000.0,
            poisson: 0.2,
        }
        .stiffness(analysis);
        assert!(expected[(0, 0)] < 0.95 * bulk[(0, 0)] && expected[(2, 2)] < 0.95 * bulk[(2, 2)]);
    }
}

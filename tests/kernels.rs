//! Cross-module checks of the kernels through the public API: no heap allocation in the
//! hot-path kernels, and a small end-to-end consistency check between the triangle and
//! interface element sign conventions.

use mesorve_core::element::{
    interface4, triangle, InterfaceGeometry, InterfaceQuadrature, MAX_POINTS,
};
use mesorve_core::interface::{CohesiveHistory, CohesiveLaw, ContactShear, Penalty};
use mesorve_core::material::{Analysis, IsotropicElastic};
use nalgebra::{SVector, Vector3};

#[path = "common/counting_alloc.rs"]
mod counting_alloc;
use counting_alloc::count_allocations;

fn law() -> CohesiveLaw {
    CohesiveLaw {
        sigma_c: 4.0,
        delta_c: 2e-4,
        beta: 0.707,
        penalty: Penalty::PerLength { lambda_p: 1e5 },
        contact: true,
        contact_shear: ContactShear::Penalty,
    }
}

#[test]
fn kernels_do_not_allocate() {
    let mat = IsotropicElastic {
        young: 25000.0,
        poisson: 0.2,
    };
    let coords = [[0.0, 0.0], [1.0, 0.1], [0.2, 0.9]];
    let g = InterfaceGeometry::from_nodes([0.0, 0.0], [0.6, 0.8]);
    let l = law();
    let committed = [0.0; MAX_POINTS];
    let mut trial = [0.0; MAX_POINTS];
    let u6 = SVector::<f64, 6>::from_fn(|i, _| 1e-4 * i as f64);
    let mut sink = 0.0;
    let n = count_allocations(|| {
        for step in 0..100 {
            let s = step as f64 * 1e-5;
            for a in [Analysis::PlaneStrain, Analysis::PlaneStress] {
                let d = mat.stiffness(a);
                let (b, area) = triangle::b_matrix(&coords);
                let eps = triangle::strain(&b, &u6);
                let sig = d * eps;
                sink += triangle::stiffness(&b, area, &d)[(0, 0)];
                sink += triangle::internal_force(&b, area, &sig)[0];
                sink += mat.out_of_plane_stress(a, &sig);
            }
            let u8 =
                SVector::<f64, 8>::from_fn(|i, _| if i >= 4 { s * (i as f64 - 5.5) } else { 0.0 });
            for q in [InterfaceQuadrature::Gauss3, InterfaceQuadrature::Lobatto2] {
                let r = interface4::evaluate(&g, q, &l, &committed, &u8, &mut trial);
                sink += r.force[0] + r.stiffness[(0, 0)];
                sink += interface4::local_jumps(&g, q, &u8)[0][1];
            }
            sink += l
                .evaluate(&CohesiveHistory::default(), [s, -s], 0.5)
                .traction[1];
        }
    });
    assert!(sink.is_finite());
    assert_eq!(n, 0, "kernels allocated {n} times");
}

/// A bar of two triangles glued by an interface element, pulled apart along the
/// interface normal: the forces the interface puts on its nodes oppose the opening, in
/// the same sign convention as the triangle's internal force (residual = F_int - F_ext).
#[test]
fn interface_and_triangle_share_the_internal_force_convention() {
    // Inclusion side A below y = 0, matrix side B above; the edge runs from (1,0) to
    // (0,0) so that n = (s_y, -s_x) = (0, 1) points up, out of the inclusion.
    let g = InterfaceGeometry::from_nodes([1.0, 0.0], [0.0, 0.0]);
    assert_eq!(g.normal, [0.0, 1.0]);
    // Move side B up by an opening w: the interface resists with +t_n on B (up) ...
    let w = 0.5e-4;
    let u = SVector::<f64, 8>::from_column_slice(&[0.0, 0.0, 0.0, 0.0, 0.0, w, 0.0, w]);
    let committed = [0.0; MAX_POINTS];
    let mut trial = [0.0; MAX_POINTS];
    let r = interface4::evaluate(
        &g,
        InterfaceQuadrature::Gauss3,
        &law(),
        &committed,
        &u,
        &mut trial,
    );
    let t = law().envelope(w);
    assert!((r.force[5] + r.force[7] - t * g.length).abs() < 1e-12);
    // ... exactly as a triangle stretched upwards has internal force +sigma on its top.
    let mat = IsotropicElastic {
        young: 1000.0,
        poisson: 0.0,
    };
    let (b, area) = triangle::b_matrix(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
    let ut = SVector::<f64, 6>::from_column_slice(&[0.0, 0.0, 0.0, 0.0, 0.0, 1e-3]);
    let sig = mat.stress(Analysis::PlaneStress, &triangle::strain(&b, &ut));
    assert!((sig - Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
    let f = triangle::internal_force(&b, area, &sig);
    assert!(f[5] > 0.0, "top node pulled up has positive internal force");
}

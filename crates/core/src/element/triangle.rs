//! The 3-node constant-strain triangle (CST) of the matrix and the aggregates
//! (paper section 3.1).
//!
//! ```text
//!        2
//!        | \         nodes counter-clockwise (mesh convention), dofs per node (x, y):
//!        |   \       u = [u0x, u0y, u1x, u1y, u2x, u2y]
//!        0 --- 1
//! ```
//! Linear shape functions `N_i = (a_i + b_i x + c_i y) / (2A)` with, cyclically
//! `(i, j, k)`: `b_i = y_j - y_k`, `c_i = x_k - x_j`, and the signed area
//! `2A = (x1 - x0)(y2 - y0) - (x2 - x0)(y1 - y0)`. The strain-displacement matrix
//! (engineering shear, Voigt `[xx, yy, xy]`):
//! ```text
//!             | b0  0  b1  0  b2  0  |
//! B = 1/(2A)  | 0   c0  0  c1  0  c2 |      strain = B u,   gamma_xy = du_x/dy + du_y/dx
//!             | c0  b0 c1  b1 c2  b2 |
//! ```
//! Per unit thickness: stiffness `K = |A| B^T D B`, internal force `F = |A| B^T sigma`
//! (the strain is constant, one-point quadrature is exact).

use nalgebra::{Matrix3, SMatrix};
use nalgebra::{SVector, Vector3};

/// Strain-displacement matrix `B` (3x6) and the signed area `A` of a triangle.
///
/// `A > 0` for counter-clockwise nodes (the mesh convention). `B` is the exact gradient
/// for either orientation; [`stiffness`] and [`internal_force`] use `|A|`. A degenerate
/// triangle (`A == 0`) gives non-finite entries; the mesh never produces one.
pub fn b_matrix(coords: &[[f64; 2]; 3]) -> (SMatrix<f64, 3, 6>, f64) {
    let [[x0, y0], [x1, y1], [x2, y2]] = *coords;
    let two_a = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
    let inv = 1.0 / two_a;
    let b = [(y1 - y2) * inv, (y2 - y0) * inv, (y0 - y1) * inv];
    let c = [(x2 - x1) * inv, (x0 - x2) * inv, (x1 - x0) * inv];
    #[rustfmt::skip]
    let bm = SMatrix::<f64, 3, 6>::new(
        b[0], 0.0,  b[1], 0.0,  b[2], 0.0,
        0.0,  c[0], 0.0,  c[1], 0.0,  c[2],
        c[0], b[0], c[1], b[1], c[2], b[2],
    );
    (bm, 0.5 * two_a)
}

/// Strain `[eps_xx, eps_yy, gamma_xy] = B u`.
#[inline]
pub fn strain(b: &SMatrix<f64, 3, 6>, u: &SVector<f64, 6>) -> Vector3<f64> {
    b * u
}

/// Element stiffness `|A| B^T D B` (6x6, symmetric when `D` is).
#[inline]
pub fn stiffness(b: &SMatrix<f64, 3, 6>, area: f64, d: &Matrix3<f64>) -> SMatrix<f64, 6, 6> {
    let db = d * b;
    (b.transpose() * db) * area.abs()
}

/// Internal force `|A| B^T sigma` (6-vector) for the element's constant stress.
#[inline]
pub fn internal_force(b: &SMatrix<f64, 3, 6>, area: f64, stress: &Vector3<f64>) -> SVector<f64, 6> {
    (b.transpose() * stress) * area.abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Analysis, IsotropicElastic};

    const TRI: [[f64; 2]; 3] = [[0.3, -0.2], [2.1, 0.4], [0.9, 1.7]];

    fn d() -> Matrix3<f64> {
        IsotropicElastic {
            young: 25000.0,
            poisson: 0.2,
        }
        .stiffness(Analysis::PlaneStress)
    }

    /// Nodal values of the field `u(x) = u0 + G x`.
    fn linear_field(u0: [f64; 2], g: [[f64; 2]; 2]) -> SVector<f64, 6> {
        SVector::<f64, 6>::from_fn(|r, _| {
            let p = TRI[r / 2];
            let i = r % 2;
            u0[i] + g[i][0] * p[0] + g[i][1] * p[1]
        })
    }

    #[test]
    fn area_and_orientation() {
        let (_, a) = b_matrix(&TRI);
        let expected = 0.5 * ((2.1 - 0.3) * (1.7 + 0.2) - (0.9 - 0.3) * (0.4 + 0.2));
        assert!((a - expected).abs() < 1e-15);
        let cw = [TRI[0], TRI[2], TRI[1]];
        let (bcw, acw) = b_matrix(&cw);
        assert!((acw + a).abs() < 1e-15);
        // Same gradient whatever the orientation.
        let g = [[1e-3, -2e-4], [5e-4, 3e-4]];
        let u = linear_field([0.0; 2], g);
        let ucw = SVector::<f64, 6>::from_column_slice(&[u[0], u[1], u[4], u[5], u[2], u[3]]);
        let (b, _) = b_matrix(&TRI);
        assert!((strain(&b, &u) - strain(&bcw, &ucw)).norm() < 1e-15);
    }

    #[test]
    fn patch_test_linear_field_gives_exact_strain() {
        let (b, _) = b_matrix(&TRI);
        let g = [[1.2e-3, -0.7e-3], [0.4e-3, -2.5e-3]];
        let u = linear_field([0.01, -0.02], g);
        let eps = strain(&b, &u);
        let expected = Vector3::new(g[0][0], g[1][1], g[0][1] + g[1][0]);
        assert!((eps - expected).norm() < 1e-14, "{eps} vs {expected}");
    }

    #[test]
    fn rigid_body_modes_give_zero_strain_and_force() {
        let (b, a) = b_matrix(&TRI);
        let k = stiffness(&b, a, &d());
        // Two translations and an infinitesimal rotation about an arbitrary point.
        for u in [
            linear_field([1.0, 0.0], [[0.0; 2]; 2]),
            linear_field([0.0, 1.0], [[0.0; 2]; 2]),
            linear_field([0.3, -0.1], [[0.0, -1.0], [1.0, 0.0]]),
        ] {
            assert!(strain(&b, &u).norm() < 1e-14);
            let f = internal_force(&b, a, &(d() * strain(&b, &u)));
            assert!(f.norm() < 1e-9, "{f}");
            assert!((k * u).norm() < 1e-9 * k.norm());
        }
    }

    #[test]
    fn stiffness_symmetric_with_three_zero_eigenvalues() {
        let (b, a) = b_matrix(&TRI);
        let k = stiffness(&b, a, &d());
        assert!((k - k.transpose()).norm() <= 1e-14 * k.norm());
        let mut eig: Vec<f64> = k.symmetric_eigenvalues().iter().copied().collect();
        eig.sort_by(f64::total_cmp);
        let max = eig[5];
        for &e in &eig[..3] {
            assert!(e.abs() < 1e-12 * max, "{eig:?}");
        }
        for &e in &eig[3..] {
            assert!(e > 1e-3 * max, "{eig:?}");
        }
    }

    #[test]
    fn stiffness_is_derivative_of_internal_force() {
        let (b, a) = b_matrix(&TRI);
        let dm = d();
        let k = stiffness(&b, a, &dm);
        let force = |u: &SVector<f64, 6>| internal_force(&b, a, &(dm * strain(&b, u)));
        let u0 = SVector::<f64, 6>::from_fn(|r, _| 1e-4 * ((r as f64) * 0.7).sin());
        let h = 1e-7;
        let mut kfd = SMatrix::<f64, 6, 6>::zeros();
        for j in 0..6 {
            let mut e = SVector::<f64, 6>::zeros();
            e[j] = h;
            kfd.set_column(j, &((force(&(u0 + e)) - force(&(u0 - e))) / (2.0 * h)));
        }
        let err = (k - kfd).norm() / k.norm();
        assert!(err < 1e-6, "rel err {err:e}");
    }

    #[test]
    fn energy_consistency_and_orientation_independence() {
        // u^T K u = |A| eps^T D eps, also for a clockwise copy.
        let g = [[1e-3, 2e-4], [-3e-4, 5e-4]];
        let u = linear_field([0.0; 2], g);
        let (b, a) = b_matrix(&TRI);
        let k = stiffness(&b, a, &d());
        let eps = strain(&b, &u);
        let w = (u.transpose() * k * u)[0];
        let expected = a.abs() * eps.dot(&(d() * eps));
        assert!((w - expected).abs() < 1e-12 * expected);
        let (bcw, acw) = b_matrix(&[TRI[0], TRI[2], TRI[1]]);
        let kcw = stiffness(&bcw, acw, &d());
        assert!((kcw[(0, 0)] - k[(0, 0)]).abs() < 1e-12 * k.norm());
    }
}

//! Linear isotropic elasticity in two dimensions (paper section 3.1: matrix and aggregates
//! are linear elastic; section 5.1 is plane strain, section 5.2 plane stress).
//!
//! Voigt order `[xx, yy, xy]`, strain with ENGINEERING shear `gamma_xy = 2 eps_xy`
//! (paper: `eps = [eps_x; eps_y; gamma_xy]`), stress `[s_xx, s_yy, s_xy]`, so that
//! `stress = D strain` and `stress . strain` is the strain energy density times two.

use nalgebra::{Matrix3, Vector3};

/// The 2D idealization of the third direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Analysis {
    /// `eps_zz = 0`; `s_zz = nu (s_xx + s_yy)` is reported as an extra output.
    PlaneStrain,
    /// `s_zz = 0`; `eps_zz = -nu/(1-nu) (eps_xx + eps_yy)` is not needed by the RVE.
    PlaneStress,
}

/// Isotropic linear elastic material: Young's modulus `E` and Poisson's ratio `nu`.
///
/// Admissible values: `E > 0` and `-1 < nu < 1/2` (plane strain needs `nu < 1/2` strictly;
/// plane stress alone would tolerate `nu < 1`). See [`IsotropicElastic::is_admissible`].
/// Serialized as `{ young = .., poisson = .. }`; unknown keys are rejected.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IsotropicElastic {
    /// Young's modulus `E` (paper: N/mm^2).
    pub young: f64,
    /// Poisson's ratio `nu` (dimensionless).
    pub poisson: f64,
}

impl IsotropicElastic {
    /// True when the material's 2D stiffness for `analysis` is positive definite
    /// (`E > 0`, `-1 < nu < 1/2` for plane strain, `-1 < nu < 1` for plane stress) and
    /// both values are finite.
    pub fn is_admissible(&self, analysis: Analysis) -> bool {
        let upper = match analysis {
            Analysis::PlaneStrain => 0.5,
            Analysis::PlaneStress => 1.0,
        };
        self.young.is_finite()
            && self.young > 0.0
            && self.poisson.is_finite()
            && self.poisson > -1.0
            && self.poisson < upper
    }

    /// The 2D elasticity matrix `D` (Voigt `[xx, yy, xy]`, engineering shear).
    ///
    /// Plane strain (`eps_zz = 0`):
    /// ```text
    ///              E            | 1-nu   nu        0      |
    /// D = ------------------    |  nu   1-nu       0      |
    ///     (1+nu)(1-2nu)         |  0     0    (1-2nu)/2   |
    /// ```
    /// Plane stress (`s_zz = 0`):
    /// ```text
    ///        E     | 1   nu     0     |
    /// D = -------  | nu   1     0     |
    ///     1-nu^2   | 0    0  (1-nu)/2 |
    /// ```
    /// In both cases `D[2][2] = G = E / (2 (1+nu))`, the shear modulus.
    pub fn stiffness(&self, analysis: Analysis) -> Matrix3<f64> {
        let (e, nu) = (self.young, self.poisson);
        let g = e / (2.0 * (1.0 + nu));
        let (d11, d12) = match analysis {
            Analysis::PlaneStrain => {
                let c = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
                (c * (1.0 - nu), c * nu)
            }
            Analysis::PlaneStress => {
                let c = e / (1.0 - nu * nu);
                (c, c * nu)
            }
        };
        Matrix3::new(d11, d12, 0.0, d12, d11, 0.0, 0.0, 0.0, g)
    }

    /// In-plane stress `D strain` for an in-plane strain `[eps_xx, eps_yy, gamma_xy]`.
    pub fn stress(&self, analysis: Analysis, strain: &Vector3<f64>) -> Vector3<f64> {
        self.stiffness(analysis) * strain
    }

    /// The out-of-plane normal stress `s_zz` that goes with an in-plane stress.
    ///
    /// Plane strain: `eps_zz = (s_zz - nu (s_xx + s_yy)) / E = 0`, hence
    /// `s_zz = nu (s_xx + s_yy)`. Plane stress: `s_zz = 0` by definition.
    pub fn out_of_plane_stress(&self, analysis: Analysis, stress: &Vector3<f64>) -> f64 {
        match analysis {
            Analysis::PlaneStrain => self.poisson * (stress[0] + stress[1]),
            Analysis::PlaneStress => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SMatrix;

    const MAT: IsotropicElastic = IsotropicElastic {
        young: 30000.0,
        poisson: 0.2,
    };

    /// 3D isotropic stiffness, Voigt `[xx, yy, zz, yz, xz, xy]`, engineering shear.
    fn stiffness_3d(m: &IsotropicElastic) -> SMatrix<f64, 6, 6> {
        let (e, nu) = (m.young, m.poisson);
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mu = e / (2.0 * (1.0 + nu));
        let mut c = SMatrix::<f64, 6, 6>::zeros();
        for i in 0..3 {
            for j in 0..3 {
                c[(i, j)] = lambda;
            }
            c[(i, i)] += 2.0 * mu;
            c[(i + 3, i + 3)] = mu;
        }
        c
    }

    fn rel(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
        (a - b).norm() / b.norm()
    }

    #[test]
    fn plane_strain_is_the_in_plane_block_of_3d_hooke() {
        let c = stiffness_3d(&MAT);
        let idx = [0, 1, 5];
        let expected = Matrix3::from_fn(|i, j| c[(idx[i], idx[j])]);
        let d = MAT.stiffness(Analysis::PlaneStrain);
        assert!(rel(&d, &expected) < 1e-14, "{d} vs {expected}");
        // Closed form: E(1-nu)/((1+nu)(1-2nu)) = 30000*0.8/(1.2*0.6).
        assert!((d[(0, 0)] - 30000.0 * 0.8 / 0.72).abs() < 1e-9);
        assert!((d[(0, 1)] - 30000.0 * 0.2 / 0.72).abs() < 1e-9);
        assert!((d[(2, 2)] - 30000.0 / 2.4).abs() < 1e-9);
    }

    #[test]
    fn plane_stress_inverts_the_in_plane_compliance() {
        let (e, nu) = (MAT.young, MAT.poisson);
        let compliance = Matrix3::new(
            1.0 / e,
            -nu / e,
            0.0,
            -nu / e,
            1.0 / e,
            0.0,
            0.0,
            0.0,
            2.0 * (1.0 + nu) / e,
        );
        let d = MAT.stiffness(Analysis::PlaneStress);
        assert!(rel(&(d * compliance), &Matrix3::identity()) < 1e-14);
        assert!((d[(0, 0)] - 30000.0 / 0.96).abs() < 1e-9);
        assert!((d[(0, 1)] - 0.2 * 30000.0 / 0.96).abs() < 1e-9);
        assert!((d[(2, 2)] - 30000.0 / 2.4).abs() < 1e-9);
    }

    #[test]
    fn engineering_shear_convention() {
        // Pure shear gamma_xy = 2 eps_xy = 1e-3 gives s_xy = G gamma_xy.
        let g = MAT.young / (2.0 * (1.0 + MAT.poisson));
        for a in [Analysis::PlaneStrain, Analysis::PlaneStress] {
            let s = MAT.stress(a, &Vector3::new(0.0, 0.0, 1e-3));
            assert!((s[2] - g * 1e-3).abs() < 1e-12);
            assert_eq!((s[0], s[1]), (0.0, 0.0));
        }
    }

    #[test]
    fn out_of_plane_stress_matches_3d_hooke() {
        let c = stiffness_3d(&MAT);
        let strain = Vector3::new(1.3e-4, -0.4e-4, 2.0e-4);
        let strain6 = SMatrix::<f64, 6, 1>::from_column_slice(&[
            strain[0], strain[1], 0.0, 0.0, 0.0, strain[2],
        ]);
        let s3d = c * strain6;
        let s = MAT.stress(Analysis::PlaneStrain, &strain);
        let szz = MAT.out_of_plane_stress(Analysis::PlaneStrain, &s);
        assert!((szz - s3d[2]).abs() < 1e-12 * s3d.norm());
        assert!((s[0] - s3d[0]).abs() < 1e-12 * s3d.norm());
        let sps = MAT.stress(Analysis::PlaneStress, &strain);
        assert_eq!(MAT.out_of_plane_stress(Analysis::PlaneStress, &sps), 0.0);
    }

    #[test]
    fn admissibility() {
        assert!(MAT.is_admissible(Analysis::PlaneStrain));
        let nearly_incompressible = IsotropicElastic {
            young: 1.0,
            poisson: 0.7,
        };
        assert!(!nearly_incompressible.is_admissible(Analysis::PlaneStrain));
        assert!(nearly_incompressible.is_admissible(Analysis::PlaneStress));
        let bad = IsotropicElastic {
            young: f64::NAN,
            poisson: 0.2,
        };
        assert!(!bad.is_admissible(Analysis::PlaneStress));
    }

    #[test]
    fn analysis_serde_names() {
        let json = serde_json::to_string(&Analysis::PlaneStrain).unwrap();
        assert_eq!(json, "\"plane_strain\"");
        let a: Analysis = serde_json::from_str("\"plane_stress\"").unwrap();
        assert_eq!(a, Analysis::PlaneStress);
    }
}

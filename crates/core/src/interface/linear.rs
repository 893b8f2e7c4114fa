//! A linear elastic interface: `t_s = k_s delta_s`, `t_n = k_n delta_n` with constant
//! stiffnesses per unit area, no history, no contact. It models a perfectly bonded but
//! compliant ITZ, and its RVE response has a closed form (a layer of stiffness `k_n` in
//! series with the bulk), which makes it a verification case for the element and the
//! solver independent of the cohesive law.

use std::sync::Arc;

use nalgebra::{Matrix2, Vector2};

use super::law::{Branch, InterfaceLaw, InterfaceLawSpec, LawPoint, TangentKind};
use crate::error::{require_positive, Result};

/// Constant interface stiffnesses per unit area (stress per length).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearInterface {
    /// Shear stiffness `k_s`.
    pub shear: f64,
    /// Normal stiffness `k_n`.
    pub normal: f64,
}

impl InterfaceLaw for LinearInterface {
    fn history_len(&self) -> usize {
        0
    }

    /// `t = diag(k_s, k_n) delta`; the matrix is the same for both kinds.
    fn respond(
        &self,
        _committed: &[f64],
        _trial: &mut [f64],
        jump: [f64; 2],
        _length: f64,
        _kind: TangentKind,
    ) -> LawPoint {
        LawPoint {
            traction: Vector2::new(self.shear * jump[0], self.normal * jump[1]),
            matrix: Matrix2::new(self.shear, 0.0, 0.0, self.normal),
            branch: Branch::Unloading,
        }
    }

    /// The law itself: it is linear.
    fn frozen_secant(&self, _history: &[f64], _closed: bool, _length: f64) -> Option<Matrix2<f64>> {
        Some(Matrix2::new(self.shear, 0.0, 0.0, self.normal))
    }

    /// Always: the law is linear and has no history.
    fn stays_linear(
        &self,
        _history: &[f64],
        _jump: [f64; 2],
        _error: [f64; 2],
        _closed: bool,
    ) -> bool {
        true
    }
}

/// A linear elastic interface `t = diag(k_s, k_n) delta`, stiffnesses per unit area.
#[derive(Clone, Copy, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct LinearItzSpec {
    pub shear_stiffness: f64,
    pub normal_stiffness: f64,
}

impl InterfaceLawSpec for LinearItzSpec {
    fn validate(&self, key: &str) -> Result<()> {
        require_positive(
            &format!("materials.{key}.shear_stiffness"),
            self.shear_stiffness,
        )?;
        require_positive(
            &format!("materials.{key}.normal_stiffness"),
            self.normal_stiffness,
        )
    }

    fn build(&self, _contact: bool) -> Arc<dyn InterfaceLaw> {
        Arc::new(LinearInterface {
            shear: self.shear_stiffness,
            normal: self.normal_stiffness,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn traction_is_linear_and_history_free() {
        let law = LinearInterface {
            shear: 2e3,
            normal: 5e3,
        };
        assert_eq!(law.history_len(), 0);
        let p = law.respond(&[], &mut [], [1e-4, -2e-4], 0.3, TangentKind::Consistent);
        assert_eq!(p.traction, Vector2::new(0.2, -1.0));
        assert_eq!(p.matrix, Matrix2::new(2e3, 0.0, 0.0, 5e3));
        let s = law.respond(&[], &mut [], [1e-4, -2e-4], 0.3, TangentKind::Secant);
        assert_eq!(s.matrix * Vector2::new(1e-4, -2e-4), s.traction);
    }
}

//! IMPL-EX integration of an interface law (Oliver, Huespe & Cante 2008, "An
//! implicit/explicit integration scheme to increase computability of non-linear material
//! and contact/friction problems", CMAME 197).
//!
//! Within a step, every point answers on the linear branch of its law at an
//! *extrapolated* history with the contact status of the last converged state:
//! ```text
//! h_ex = h_n + (dt_{n+1} / dt_n) (h_n - h_{n-1}),     t = S(h_ex, status_n) delta
//! ```
//! For the paper's law `S` is the unloading secant of eq. 24 at `delta_max_ex`
//! (`k(delta_max_ex) diag(beta^2, 1)`) on an open point and the contact penalty of eq. 47
//! on a closed one ([`InterfaceLaw::frozen_secant`]). The RVE is then linear in the macro
//! strain within the step, its tangent symmetric positive definite, and one factorization
//! answers every host iteration of the step. After the host commits, the *implicit*
//! history `h_{n+1}` is formed from the step's converged jumps by the law itself (eq. 25),
//! ready for the next extrapolation: the stress lags the implicit law by a step, an error
//! of first order in the step that the accuracy study measures.
//!
//! [`Implex`] is the law seen by the assembly during such a step: its "committed history"
//! is `h_ex`, and it never changes it.

use nalgebra::Matrix2;

use super::law::{Branch, InterfaceLaw, LawPoint, TangentKind};

/// An interface law answered on its frozen linear branch (see the module docs).
#[derive(Debug)]
pub struct Implex<'a> {
    pub law: &'a dyn InterfaceLaw,
}

impl Implex<'_> {
    fn secant(&self, history: &[f64], closed: bool, length: f64) -> Matrix2<f64> {
        // The model refuses `integration = "implex"` with a law without a frozen branch;
        // NaN here would make the solve fail loudly rather than answer.
        self.law
            .frozen_secant(history, closed, length)
            .unwrap_or_else(|| Matrix2::from_element(f64::NAN))
    }
}

impl InterfaceLaw for Implex<'_> {
    fn history_len(&self) -> usize {
        self.law.history_len()
    }

    fn respond(
        &self,
        committed: &[f64],
        trial: &mut [f64],
        jump: [f64; 2],
        length: f64,
        kind: TangentKind,
    ) -> LawPoint {
        let closed = self.law.is_closed(jump);
        self.respond_as(committed, trial, jump, length, kind, closed)
    }

    fn has_contact_status(&self) -> bool {
        self.law.has_contact_status()
    }

    fn is_closed(&self, jump: [f64; 2]) -> bool {
        self.law.is_closed(jump)
    }

    /// `t = S(h_ex, closed) delta`, matrix `S` for both kinds; the history is unchanged.
    fn respond_as(
        &self,
        committed: &[f64],
        trial: &mut [f64],
        jump: [f64; 2],
        length: f64,
        _kind: TangentKind,
        closed: bool,
    ) -> LawPoint {
        trial.copy_from_slice(committed);
        let s = self.secant(committed, closed, length);
        LawPoint {
            traction: s * nalgebra::Vector2::new(jump[0], jump[1]),
            matrix: s,
            branch: if closed && self.law.has_contact_status() {
                Branch::Contact
            } else {
                Branch::Unloading
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interface::{CohesiveLaw, ContactShear, Penalty};

    fn law(shear: ContactShear) -> CohesiveLaw {
        CohesiveLaw {
            sigma_c: 4.0,
            delta_c: 2e-4,
            beta: 0.707,
            penalty: Penalty::PerLength { lambda_p: 1e7 },
            contact: true,
            contact_shear: shear,
        }
    }

    /// Within a step the traction is linear in the jump, the matrix its exact derivative
    /// (checked by central differences), symmetric positive definite, and the history
    /// stays the extrapolated one.
    #[test]
    fn frozen_branch_is_linear_and_its_matrix_is_the_derivative() {
        for shear in [ContactShear::Penalty, ContactShear::Cohesive] {
            let base = law(shear);
            let implex = Implex { law: &base };
            for (h_ex, closed) in [(0.0, false), (3e-4, false), (3e-4, true), (1e-3, true)] {
                let jump = [1.3e-4, if closed { -2e-5 } else { 7e-5 }];
                let mut trial = [9.0];
                let p = implex.respond_as(
                    &[h_ex],
                    &mut trial,
                    jump,
                    0.5,
                    TangentKind::Consistent,
                    closed,
                );
                assert_eq!(trial, [h_ex]);
                let m = p.matrix;
                assert_eq!(m, m.transpose());
                assert!(m[(0, 0)] > 0.0 && m.determinant() > 0.0);
                for c in 0..2 {
                    let step = 1e-9;
                    let (mut plus, mut minus) = (jump, jump);
                    plus[c] += step;
                    minus[c] -= step;
                    let tp = implex.respond_as(
                        &[h_ex],
                        &mut [0.0],
                        plus,
                        0.5,
                        TangentKind::Consistent,
                        closed,
                    );
                    let tm = implex.respond_as(
                        &[h_ex],
                        &mut [0.0],
                        minus,
                        0.5,
                        TangentKind::Consistent,
                        closed,
                    );
                    let fd = (tp.traction - tm.traction) / (2.0 * step);
                    for r in 0..2 {
                        let scale = m.abs().max();
                        assert!(
                            (fd[r] - m[(r, c)]).abs() <= 1e-7 * scale,
                            "{shear:?} {h_ex} {closed} {r}{c}"
                        );
                    }
                }
            }
        }
    }

    /// An open point's frozen secant is the unloading secant of eq. 24 at `h_ex`, the
    /// implicit law's own traction on that branch; a virgin point has the initial stiffness.
    #[test]
    fn open_branch_is_the_unloading_secant() {
        let base = law(ContactShear::Penalty);
        let implex = Implex { law: &base };
        let h = 5e-4;
        let jump = [1e-4, 2e-4]; // opening below h: the implicit law unloads
        let implicit = base.respond(&[h], &mut [0.0], jump, 0.5, TangentKind::Consistent);
        let frozen = implex.respond_as(&[h], &mut [0.0], jump, 0.5, TangentKind::Consistent, false);
        assert_eq!(implicit.branch, Branch::Unloading);
        assert!((implicit.traction - frozen.traction).norm() <= 1e-15 * implicit.traction.norm());
        let virgin = implex.respond_as(
            &[0.0],
            &mut [0.0],
            jump,
            0.5,
            TangentKind::Consistent,
            false,
        );
        assert!(
            (virgin.matrix[(1, 1)] - base.initial_stiffness()).abs()
                <= 1e-12 * base.initial_stiffness()
        );
    }

    /// The cohesive law's extrapolation never lowers `delta_max`, scales the last
    /// increment by the step ratio and leaves an unloaded point where it is.
    #[test]
    fn extrapolation_follows_the_step_ratio() {
        let base = law(ContactShear::Penalty);
        let mut out = [0.0; 3];
        base.extrapolate(&[3e-4, 2e-4, 0.0], &[2e-4, 2e-4, 0.0], 0.5, &mut out);
        assert_eq!(out, [3e-4 + 0.5 * (3e-4 - 2e-4), 2e-4, 0.0]);
    }
}

//! Viscous regularization of the cohesive law, Duvaut-Lions type (Chaboche, Feyel &
//! Monerie 2001; Gao & Bower 2004; Abaqus' cohesive "viscosity coefficient").
//!
//! The paper's law keeps the largest effective opening `delta_max` (eq. 25). Here that
//! inviscid history is kept, and the traction uses a *regularized* one, `delta_v`, which
//! relaxes towards it with the time `eta` (`materials.itz.viscosity`):
//! ```text
//! d delta_v / dt = (delta_max - delta_v) / eta
//! ```
//! integrated by backward Euler over the host's time increment `dt`, `a = dt / eta`:
//! ```text
//! delta_max' = max(delta_max, delta)                    (eq. 25)
//! delta_v'   = (delta_v + a delta_max') / (1 + a)
//! t          = k(delta_v') diag(beta^2, 1) delta        (eqs. 21, 32-35 with delta_v')
//! ```
//! with the secant `k(x) = (sigma_c/delta_c) exp(1 - x/delta_c)` of eqs. 32-35. With
//! `eta -> 0`, `delta_v' = delta_max'` and this is the paper's law: the envelope on
//! loading, the secant to the origin on unloading. Consistent tangent, with `B =
//! diag(beta^2, 1)` and `k' = -k/delta_c`:
//! ```text
//! C = k B + (a / (1 + a)) k'(delta_v') (B delta)(B delta)^T / delta    (loading: delta >= delta_max)
//! C = k B                                                              (otherwise)
//! ```
//! symmetric (`d delta / d delta_i = (B delta)_i / delta`). The stress lags the law: the
//! damage catches up over a few `eta`, which smooths a snap-back in time at the cost of
//! a rate-dependent stress. Closed points (contact, eqs. 36-37) are those of the paper's
//! law; with [`ContactShear::Cohesive`] the sliding follows the regularized law.
//!
//! Without a time increment (`dt <= 0`) the step is taken as long against `eta`
//! (`delta_v' = delta_max'`): the inviscid law.

use nalgebra::{Matrix2, Vector2};

use super::cohesive::{CohesiveHistory, CohesiveLaw, ContactShear};
use super::law::{Branch, InterfaceLaw, LawPoint, PointMeasures, TangentKind};

/// The paper's cohesive-contact law with a viscous regularization of its history.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViscousCohesive {
    pub law: CohesiveLaw,
    /// The relaxation time `eta` (> 0), in the host's time units.
    pub viscosity: f64,
}

impl ViscousCohesive {
    /// `k(x)`, the envelope's secant at the opening `x`.
    fn secant(&self, x: f64) -> f64 {
        self.law.unloading_secant(&CohesiveHistory { delta_max: x })
    }

    /// The open branch at the jump `[ds, dn]` from history `[delta_max, delta_v]`.
    fn open(&self, history: &[f64], trial: &mut [f64], ds: f64, dn: f64, dt: f64) -> LawPoint {
        let beta = self.law.beta;
        let b_delta = Vector2::new(beta * beta * ds, dn);
        let opening = (beta * ds).hypot(dn);
        let loading = opening >= history[0];
        let delta_max = history[0].max(opening);
        let a = if dt > 0.0 {
            dt / self.viscosity
        } else {
            f64::INFINITY
        };
        let delta_v = if a.is_finite() {
            (history[1] + a * delta_max) / (1.0 + a)
        } else {
            delta_max
        };
        trial[0] = delta_max;
        trial[1] = delta_v;
        let k = self.secant(delta_v);
        let mut tangent = Matrix2::new(k * beta * beta, 0.0, 0.0, k);
        if loading && opening > 0.0 {
            let share = if a.is_finite() { a / (1.0 + a) } else { 1.0 };
            let slope = -k / self.law.delta_c;
            let c = share * slope / opening.max(f64::MIN_POSITIVE);
            let off = c * b_delta.x * b_delta.y;
            tangent += Matrix2::new(
                c * b_delta.x * b_delta.x,
                off,
                off,
                c * b_delta.y * b_delta.y,
            );
        }
        let moved = trial[0] != history[0] || trial[1] != history[1];
        LawPoint {
            traction: k * b_delta,
            matrix: tangent,
            branch: if moved {
                Branch::Loading
            } else {
                Branch::Unloading
            },
        }
    }
}

impl InterfaceLaw for ViscousCohesive {
    /// `[delta_max, delta_v]`: the inviscid history and the regularized one.
    fn history_len(&self) -> usize {
        2
    }

    fn respond(
        &self,
        committed: &[f64],
        trial: &mut [f64],
        jump: [f64; 2],
        length: f64,
        kind: TangentKind,
    ) -> LawPoint {
        self.respond_timed(
            committed,
            trial,
            jump,
            length,
            kind,
            self.is_closed(jump),
            0.0,
        )
    }

    fn respond_as(
        &self,
        committed: &[f64],
        trial: &mut [f64],
        jump: [f64; 2],
        length: f64,
        kind: TangentKind,
        closed: bool,
    ) -> LawPoint {
        self.respond_timed(committed, trial, jump, length, kind, closed, 0.0)
    }

    /// See the module docs; `kind` is ignored: the traction is `k(delta_v') B delta`, a
    /// secant form whose matrix the consistent tangent already is on a non-loading point.
    fn respond_timed(
        &self,
        committed: &[f64],
        trial: &mut [f64],
        jump: [f64; 2],
        length: f64,
        _kind: TangentKind,
        closed: bool,
        dt: f64,
    ) -> LawPoint {
        let [ds, dn] = jump;
        let law = &self.law;
        if !law.contact || !(closed || dn < 0.0) {
            return self.open(committed, trial, ds, dn, dt);
        }
        let kp = law.contact_stiffness(length);
        if closed && law.contact_shear == ContactShear::Penalty {
            trial.copy_from_slice(committed);
            return LawPoint {
                traction: Vector2::new(kp * ds, kp * dn),
                matrix: Matrix2::from_diagonal_element(kp),
                branch: Branch::Contact,
            };
        }
        let mut point = self.open(committed, trial, ds, 0.0, dt);
        point.traction.y = kp * dn;
        point.matrix[(1, 1)] = kp;
        if closed {
            point.branch = Branch::Contact;
        }
        point
    }

    fn uses_time(&self) -> bool {
        true
    }

    fn has_contact_status(&self) -> bool {
        self.law.holds_contact_status()
    }

    fn is_closed(&self, jump: [f64; 2]) -> bool {
        self.law.is_closed(jump)
    }

    fn passes_peak(&self, start: &[f64], trial: &[f64]) -> bool {
        trial[0] >= self.law.delta_c && start[0] < self.law.delta_c
    }

    /// Linear only once relaxed (`delta_v = delta_max`), as the paper's law.
    fn stays_linear(&self, history: &[f64], jump: [f64; 2], error: [f64; 2], closed: bool) -> bool {
        history[1] >= history[0] && self.law.stays_linear(&history[..1], jump, error, closed)
    }

    fn history_is_valid(&self, history: &[f64]) -> bool {
        history.iter().all(|d| d.is_finite() && *d >= 0.0)
    }

    fn measures(&self, history: &[f64], jump: [f64; 2], length: f64) -> Option<PointMeasures> {
        self.law.measures(&history[1..2], jump, length)
    }

    fn failure_hint(&self, closed_points: usize) -> Option<String> {
        self.law.failure_hint(closed_points)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interface::Penalty;

    fn viscous(shear: ContactShear) -> ViscousCohesive {
        ViscousCohesive {
            law: CohesiveLaw {
                sigma_c: 4.0,
                delta_c: 2e-4,
                beta: 0.707,
                penalty: Penalty::PerLength { lambda_p: 1e7 },
                contact: true,
                contact_shear: shear,
            },
            viscosity: 0.3,
        }
    }

    /// The tangent is the derivative of the traction by central differences on every
    /// branch (loading, relaxing while unloading, contact), for both contact shears.
    #[test]
    fn tangent_is_the_derivative_of_the_traction() {
        let dt = 0.1;
        let cases = [
            ([1e-4, 1.5e-4], [0.0, 0.0], false),
            ([1e-4, 3e-4], [2e-4, 1e-4], false),
            ([5e-5, 5e-5], [4e-4, 2e-4], false),
            ([2e-4, -3e-5], [3e-4, 2e-4], true),
        ];
        for shear in [ContactShear::Penalty, ContactShear::Cohesive] {
            let v = viscous(shear);
            for (jump, history, closed) in cases {
                let p = v.respond_timed(
                    &history,
                    &mut [0.0; 2],
                    jump,
                    0.5,
                    TangentKind::Consistent,
                    closed,
                    dt,
                );
                assert_eq!(p.matrix, p.matrix.transpose());
                let scale = p.matrix.abs().max();
                for c in 0..2 {
                    let h = 1e-10;
                    let (mut plus, mut minus) = (jump, jump);
                    plus[c] += h;
                    minus[c] -= h;
                    let tp = v.respond_timed(
                        &history,
                        &mut [0.0; 2],
                        plus,
                        0.5,
                        TangentKind::Consistent,
                        closed,
                        dt,
                    );
                    let tm = v.respond_timed(
                        &history,
                        &mut [0.0; 2],
                        minus,
                        0.5,
                        TangentKind::Consistent,
                        closed,
                        dt,
                    );
                    let fd = (tp.traction - tm.traction) / (2.0 * h);
                    for r in 0..2 {
                        assert!(
                            (fd[r] - p.matrix[(r, c)]).abs() <= 1e-6 * scale,
                            "{shear:?} {jump:?} {history:?}: C{r}{c} {} vs {}",
                            p.matrix[(r, c)],
                            fd[r]
                        );
                    }
                }
            }
        }
    }

    /// A long step (`dt >> eta`) and no time both give the paper's law; a short one lags.
    #[test]
    fn long_steps_give_the_inviscid_law() {
        let v = viscous(ContactShear::Penalty);
        let jump = [1e-4, 3e-4];
        let paper = v
            .law
            .respond(&[1e-4], &mut [0.0], jump, 0.5, TangentKind::Consistent);
        let untimed = v.respond(
            &[1e-4, 1e-4],
            &mut [0.0; 2],
            jump,
            0.5,
            TangentKind::Consistent,
        );
        assert_eq!(untimed.traction, paper.traction);
        let long = v.respond_timed(
            &[1e-4, 1e-4],
            &mut [0.0; 2],
            jump,
            0.5,
            TangentKind::Consistent,
            false,
            1e9,
        );
        assert!((long.traction - paper.traction).norm() <= 1e-8 * paper.traction.norm());
        let short = v.respond_timed(
            &[1e-4, 1e-4],
            &mut [0.0; 2],
            jump,
            0.5,
            TangentKind::Consistent,
            false,
            0.03,
        );
        assert!(
            short.traction.norm() > paper.traction.norm(),
            "less damage, more traction"
        );
    }
}

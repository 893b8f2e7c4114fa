//! Coulomb friction on closed cracks: the return mapping of the shear traction of the
//! damaged part of a closed interface point, with its consistent tangent ([`Coulomb`]),
//! and the law that adds it to the ITZ's or the paste's law ([`Frictional`]).
//!
//! With the normal traction `t_n <= 0` of the closed point (`t_n = k_p delta_n`), the
//! shear stiffness `k` of the stick state and the slip `s` (history), the trial shear
//! traction is `t* = k (delta_s - s)` and (Alfano & Sacco 2006, the frictional part)
//! ```text
//! |t*| <= mu |t_n|:  t_f = t*,                   s unchanged      (stick)
//! |t*| >  mu |t_n|:  t_f = mu |t_n| sign(t*),    s = delta_s - t_f / k   (slip)
//! ```
//! Tangent: stick `d t_f / d delta_s = k`, `d t_f / d delta_n = 0`; slip `d t_f / d delta_s
//! = 0`, `d t_f / d delta_n = -mu sign(t*) d t_n / d delta_n` (`|t_n| = -t_n`). Sliding, the
//! shear depends on the normal jump while the normal traction does not depend on the
//! shear jump: the tangent of a sliding point is not symmetric.
//!
//! OOFEM's `IntMatCoulombContact` maps the same way, written with the shear stress shift
//! `k s` instead of the slip (its tractions equal these along any path, checked below);
//! its stiffness matrix is the elastic `k I` in stick and slip alike, not the consistent
//! tangent, so a host's Newton converges linearly with it where this one's is quadratic.
//!
//! # Friction on the damaged part
//! Alfano & Sacco split a point into an undamaged part `(1 - D)`, which keeps the
//! cohesive law, and a damaged part `D`, which carries friction once closed. The laws here
//! are secant: the undamaged part is the law's own closed response (its normal penalty
//! and its shear on the secant `k(delta_max)`, `contact_shear = "cohesive"`), and the
//! damaged part sticks with the stiffness `D K_s = beta^2 (K_0 - k(delta_max))`
//! ([`InterfaceLaw::damaged_shear_stiffness`]) up to the Coulomb limit: a closed point
//! sticks with the virgin shear stiffness and a fully open crack, closed, slides at
//! `mu |t_n|`. `D` is the committed damage, so the law stays a function of its committed
//! history and the jump, with an exact tangent.
//!
//! An open point carries no friction and keeps its slip; at closure `t_n = 0`, so the
//! Coulomb limit grows from zero and the shear traction stays continuous through the
//! contact switch.

use std::sync::Arc;

use super::law::{Branch, InterfaceLaw, LawPoint, PointMeasures, TangentKind};
use crate::error::{require_positive, Error, Result};

/// Coulomb's law with a stick stiffness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coulomb {
    /// The friction coefficient `mu` (>= 0).
    pub coefficient: f64,
    /// The shear stiffness `k` of the stick state, per unit area.
    pub stiffness: f64,
}

/// The frictional shear of a closed point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionPoint {
    /// The shear traction `t_f`.
    pub traction: f64,
    /// `d t_f / d delta_s`.
    pub d_shear: f64,
    /// `d t_f / d delta_n`.
    pub d_normal: f64,
    /// The trial slip `s`.
    pub slip: f64,
    /// Whether the point slides.
    pub sliding: bool,
}

impl Coulomb {
    /// The frictional shear at the shear jump `shear_jump` from the committed `slip`, with
    /// the normal traction `normal` (compression negative; tension gives no friction) and
    /// its derivative `d_normal` with respect to the normal jump.
    pub fn respond(&self, slip: f64, shear_jump: f64, normal: f64, d_normal: f64) -> FrictionPoint {
        let trial = self.stiffness * (shear_jump - slip);
        let limit = self.coefficient * (-normal).max(0.0);
        if trial.abs() <= limit {
            return FrictionPoint {
                traction: trial,
                d_shear: self.stiffness,
                d_normal: 0.0,
                slip,
                sliding: false,
            };
        }
        let sign = trial.signum();
        let traction = sign * limit;
        FrictionPoint {
            traction,
            d_shear: 0.0,
            d_normal: if normal < 0.0 {
                -self.coefficient * sign * d_normal
            } else {
                0.0
            },
            slip: shear_jump - traction / self.stiffness,
            sliding: true,
        }
    }
}

/// A law with Coulomb friction on the damaged part of its closed points (see the module
/// docs). Its history is the inner law's followed by the slip `s`.
#[derive(Debug)]
pub struct Frictional {
    inner: Arc<dyn InterfaceLaw>,
    coefficient: f64,
}

impl Frictional {
    /// `inner` with friction of coefficient `coefficient` (`key` names it in errors).
    /// The inner law must close in contact and give the stiffness of its damaged part.
    pub fn new(inner: Arc<dyn InterfaceLaw>, coefficient: f64, key: &str) -> Result<Self> {
        if coefficient != 0.0 {
            require_positive(key, coefficient)?;
        }
        let carries = inner.is_closed([0.0, -1.0])
            && inner
                .damaged_shear_stiffness(&vec![0.0; inner.history_len()], 1.0)
                .is_some();
        if !carries {
            return Err(Error::scene(
                key,
                "friction acts on closed cracks: the law needs contact (effects.contact) \
                 with contact_shear = \"cohesive\"",
            ));
        }
        Ok(Frictional { inner, coefficient })
    }

    /// The friction coefficient `mu`.
    pub fn coefficient(&self) -> f64 {
        self.coefficient
    }

    /// The inner law's part of a point's history.
    #[inline]
    fn inner_part<'h>(&self, history: &'h [f64]) -> &'h [f64] {
        &history[..self.inner.history_len()]
    }
}

impl InterfaceLaw for Frictional {
    /// The inner law's history, then the slip.
    fn history_len(&self) -> usize {
        self.inner.history_len() + 1
    }

    fn respond(
        &self,
        committed: &[f64],
        trial: &mut [f64],
        jump: [f64; 2],
        length: f64,
        kind: TangentKind,
    ) -> LawPoint {
        let closed = self.inner.is_closed(jump);
        self.respond_as(committed, trial, jump, length, kind, closed)
    }

    /// As the inner law's: the frictional shear is continuous at closure (the Coulomb
    /// limit is zero at `delta_n = 0`), so friction needs no held status of its own.
    fn has_contact_status(&self) -> bool {
        self.inner.has_contact_status()
    }

    fn is_closed(&self, jump: [f64; 2]) -> bool {
        self.inner.is_closed(jump)
    }

    /// The inner law's response, plus on a closed point the frictional shear `t_f` of
    /// its damaged part: `t_s += t_f`, `C_ss += d t_f/d delta_s`, `C_sn += d t_f/d
    /// delta_n` (the normal traction is the penalty's and does not depend on `delta_s`).
    fn respond_as(
        &self,
        committed: &[f64],
        trial: &mut [f64],
        jump: [f64; 2],
        length: f64,
        kind: TangentKind,
        closed: bool,
    ) -> LawPoint {
        let n = self.inner.history_len();
        let inner_committed = &committed[..n];
        let mut point =
            self.inner
                .respond_as(inner_committed, &mut trial[..n], jump, length, kind, closed);
        let slip = committed[n];
        trial[n] = slip;
        if !closed {
            return point;
        }
        let stiffness = self
            .inner
            .damaged_shear_stiffness(inner_committed, length)
            .unwrap_or(0.0);
        if stiffness <= 0.0 {
            // Nothing is damaged: no friction, and the slip follows the shear jump.
            trial[n] = jump[0];
            return point;
        }
        let coulomb = Coulomb {
            coefficient: self.coefficient,
            stiffness,
        };
        let f = coulomb.respond(slip, jump[0], point.traction.y, point.matrix[(1, 1)]);
        trial[n] = f.slip;
        point.traction.x += f.traction;
        // The frictional part's consistent tangent with either kind of matrix. The secant
        // iterations replace the tangent of the softening laws, whose kinks make Newton
        // cycle; Coulomb's law does not soften, and its secant `t_f / (delta_s - s)` would
        // leave out how the limit `mu |t_n|` follows the normal jump, so that the
        // iterations contract only as far as the sliding points' normal jumps settle.
        point.matrix[(0, 0)] += f.d_shear;
        point.matrix[(0, 1)] += f.d_normal;
        if f.sliding && f.d_normal != 0.0 {
            point.branch = Branch::Sliding;
        }
        point
    }

    fn passes_peak(&self, start: &[f64], trial: &[f64]) -> bool {
        self.inner
            .passes_peak(self.inner_part(start), self.inner_part(trial))
    }

    /// Open points on a linear branch of the inner law (their slip does not change);
    /// never a closed one, whose friction is not linear through the origin.
    fn stays_linear(&self, history: &[f64], jump: [f64; 2], error: [f64; 2], closed: bool) -> bool {
        !closed
            && self
                .inner
                .stays_linear(self.inner_part(history), jump, error, false)
    }

    fn traction_scale(&self) -> f64 {
        self.inner.traction_scale()
    }

    /// Point by point (the slices may hold several points): the inner law's
    /// extrapolation, the slip linearly.
    fn extrapolate(&self, committed: &[f64], previous: &[f64], ratio: f64, out: &mut [f64]) {
        let n = self.inner.history_len();
        for ((c, p), o) in committed
            .chunks(n + 1)
            .zip(previous.chunks(n + 1))
            .zip(out.chunks_mut(n + 1))
        {
            self.inner.extrapolate(&c[..n], &p[..n], ratio, &mut o[..n]);
            o[n] = c[n] + ratio * (c[n] - p[n]);
        }
    }

    /// Point by point (`history` may hold several points): the inner law's part valid,
    /// the slip finite.
    fn history_is_valid(&self, history: &[f64]) -> bool {
        let n = self.inner.history_len();
        history.len() % (n + 1) == 0
            && history
                .chunks(n + 1)
                .all(|p| p[n].is_finite() && self.inner.history_is_valid(&p[..n]))
    }

    fn measures(&self, history: &[f64], jump: [f64; 2], length: f64) -> Option<PointMeasures> {
        self.inner.measures(self.inner_part(history), jump, length)
    }

    fn history_measures(&self, history: &[f64], length: f64) -> Option<(f64, f64)> {
        self.inner
            .history_measures(self.inner_part(history), length)
    }

    fn damaged_shear_stiffness(&self, history: &[f64], length: f64) -> Option<f64> {
        self.inner
            .damaged_shear_stiffness(self.inner_part(history), length)
    }

    fn slip(&self, history: &[f64]) -> Option<f64> {
        history.get(self.inner.history_len()).copied()
    }

    /// The inner law regularized, with the same friction: slip is not softening.
    fn regularized(&self, scale: f64) -> Option<Arc<dyn InterfaceLaw>> {
        let inner = self.inner.regularized(scale)?;
        Some(Arc::new(Frictional {
            inner,
            coefficient: self.coefficient,
        }))
    }

    fn failure_hint(&self, closed_points: usize) -> Option<String> {
        self.inner.failure_hint(closed_points)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAW: Coulomb = Coulomb {
        coefficient: 0.6,
        stiffness: 1e4,
    };
    /// The normal penalty of the tests: `t_n = KP delta_n`.
    const KP: f64 = 2e4;

    fn at(slip: f64, ds: f64, dn: f64) -> FrictionPoint {
        LAW.respond(slip, ds, KP * dn, KP)
    }

    /// Sticks until `|t| = mu |t_n|`, then slides at that traction, its slip the jump
    /// beyond the stick one; no friction in tension.
    #[test]
    fn sticks_until_the_coulomb_limit_then_slides() {
        let dn = -1e-3; // t_n = -20: the limit is 12
        let limit = LAW.coefficient * KP * 1e-3;
        let stuck = at(0.0, 0.5 * limit / LAW.stiffness, dn);
        assert!(!stuck.sliding);
        assert!((stuck.traction - 0.5 * limit).abs() <= 1e-12 * limit);
        let ds = 3.0 * limit / LAW.stiffness;
        let slides = at(0.0, ds, dn);
        assert!(slides.sliding);
        assert!((slides.traction - limit).abs() <= 1e-12 * limit);
        assert!((slides.slip - (ds - limit / LAW.stiffness)).abs() <= 1e-15);
        let back = at(0.0, -ds, dn);
        assert!((back.traction + limit).abs() <= 1e-12 * limit);
        let open = at(0.0, ds, 1e-3);
        assert_eq!((open.traction, open.d_normal), (0.0, 0.0));
    }

    /// The tangent against central differences, stick and slip in both directions.
    #[test]
    fn tangent_matches_central_differences() {
        let h = 1e-9;
        for (slip, ds, dn) in [
            (0.0, 2e-4, -1e-3),
            (1e-4, 2e-4, -1e-3),
            (0.0, 5e-3, -1e-3),
            (2e-3, -4e-3, -2e-3),
        ] {
            let p = at(slip, ds, dn);
            let fd_s = (at(slip, ds + h, dn).traction - at(slip, ds - h, dn).traction) / (2.0 * h);
            let fd_n = (at(slip, ds, dn + h).traction - at(slip, ds, dn - h).traction) / (2.0 * h);
            let scale = LAW.stiffness.max(LAW.coefficient * KP);
            assert!(
                (p.d_shear - fd_s).abs() <= 1e-6 * scale,
                "{p:?}: d/ds {fd_s}"
            );
            assert!(
                (p.d_normal - fd_n).abs() <= 1e-6 * scale,
                "{p:?}: d/dn {fd_n}"
            );
        }
    }

    /// OOFEM's `IntMatCoulombContact` (2D, no clearance): the trial shear stress
    /// `k delta_s - shift`, scaled back to `mu |t_n|`, the shift updated to `k delta_s - t`.
    /// Written from its description, as a second implementation: along a random closed
    /// path its shear tractions equal `Coulomb::respond`'s to round-off.
    #[test]
    fn tractions_equal_oofems_return_mapping() {
        let (k, mu) = (LAW.stiffness, LAW.coefficient);
        let (mut slip, mut shift) = (0.0, 0.0);
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut largest = 0.0f64;
        for _ in 0..2000 {
            let (ds, dn) = (4e-3 * (next() - 0.5), -2e-3 * next());
            let ours = at(slip, ds, dn);
            slip = ours.slip;
            let normal = KP * dn;
            let mut shear = k * ds - shift;
            let limit = (normal.abs()) * mu;
            if shear.abs() > limit {
                shear *= limit / (shear.abs() + 1e-15);
            }
            shift = k * ds - shear;
            largest = largest.max((ours.traction - shear).abs());
        }
        assert!(largest <= 1e-12 * LAW.coefficient * KP * 2e-3, "{largest}");
    }

    /// A shear cycle of amplitude `a` at a constant normal traction dissipates the loop of
    /// an elastic-perfectly plastic spring: `4 tau (a - tau / k)` per cycle after the first
    /// loading, with `tau = mu |t_n|`; the trapezoid rule is exact here (the stick spans
    /// fall on whole steps, the traction is linear between them).
    #[test]
    fn a_shear_cycle_dissipates_the_closed_form_loop() {
        let dn = -1e-3;
        let tau = LAW.coefficient * KP * 1e-3;
        let a = 10.0 * tau / LAW.stiffness;
        let n = 20000;
        // 0 -> a, then a -> -a -> a (one closed cycle), measured on the closed cycle.
        let mut path: Vec<f64> = (0..=n).map(|k| a * k as f64 / n as f64).collect();
        path.extend((1..=2 * n).map(|k| a - 2.0 * a * k as f64 / (2 * n) as f64));
        path.extend((1..=2 * n).map(|k| -a + 2.0 * a * k as f64 / (2 * n) as f64));
        let (mut slip, mut previous, mut work) = (0.0, (0.0, 0.0), 0.0);
        for (k, &ds) in path.iter().enumerate() {
            let p = at(slip, ds, dn);
            slip = p.slip;
            if k > n {
                work += 0.5 * (p.traction + previous.1) * (ds - previous.0);
            }
            previous = (ds, p.traction);
        }
        let exact = 4.0 * tau * (a - tau / LAW.stiffness);
        println!(
            "loop {work} against {exact}: {:.1e}",
            (work - exact).abs() / exact
        );
        assert!(
            (work - exact).abs() <= 1e-6 * exact,
            "loop {work} against {exact}"
        );
    }

    use crate::interface::{ContactShear, CrackLaw};
    use std::sync::Arc;

    /// A paste crack law (cohesive shear when closed) with friction 0.6.
    fn frictional() -> (Frictional, CrackLaw) {
        let crack = CrackLaw {
            strength: 5.0,
            fracture_energy: 0.23,
            stiffness: 6e6,
            beta: 0.707,
            penalty: 6e6,
            contact: true,
            contact_shear: ContactShear::Cohesive,
        };
        let law = Frictional::new(Arc::new(crack), 0.6, "friction").unwrap();
        (law, crack)
    }

    fn respond(law: &Frictional, history: [f64; 2], jump: [f64; 2]) -> LawPoint {
        let mut trial = [0.0; 2];
        law.respond(&history, &mut trial, jump, 1.0, TangentKind::Consistent)
    }

    /// The law's consistent tangent against central differences on every branch: open
    /// loading and unloading, closed and virgin, closed sticking, closed sliding both
    /// ways with damage partial and complete.
    #[test]
    fn frictional_tangent_matches_central_differences() {
        let (law, crack) = frictional();
        let (d0, wc) = (crack.peak_opening(), crack.critical_opening());
        let partial = d0 + 0.2 * wc;
        let full = d0 + 2.0 * wc;
        let cases = [
            ([0.0, 0.0], [0.3 * d0, 0.5 * d0], "open, elastic"),
            ([partial, 0.0], [0.0, 0.5 * partial], "open, unloading"),
            (
                [partial, 0.0],
                [0.2 * partial, 1.1 * partial],
                "open, loading",
            ),
            ([0.0, 0.0], [0.3 * d0, -0.5 * d0], "closed, virgin"),
            ([partial, 1e-4], [1.0e-4 + 1e-7, -2e-5], "closed, sticking"),
            ([partial, 0.0], [0.3 * partial, -2e-5], "closed, sliding +"),
            ([full, 0.0], [-3e-3, -2e-5], "closed, fully open, sliding -"),
        ];
        for (history, jump, what) in cases {
            let p = respond(&law, history, jump);
            let h = 1e-6 * (jump[0].abs() + jump[1].abs());
            for j in 0..2 {
                let mut plus = jump;
                let mut minus = jump;
                plus[j] += h;
                minus[j] -= h;
                let fd = (respond(&law, history, plus).traction
                    - respond(&law, history, minus).traction)
                    / (2.0 * h);
                for i in 0..2 {
                    let scale = p.matrix.abs().max().max(1e-300);
                    let err = (p.matrix[(i, j)] - fd[i]).abs() / scale;
                    assert!(
                        err <= 1e-6,
                        "{what}: C[{i}{j}] {} fd {} ({err:e})",
                        p.matrix[(i, j)],
                        fd[i]
                    );
                }
            }
        }
        let sliding = respond(&law, [partial, 0.0], [0.3 * partial, -2e-5]);
        assert_eq!(sliding.branch, Branch::Sliding);
        assert!(
            sliding.matrix[(0, 1)] != sliding.matrix[(1, 0)],
            "sliding is not symmetric"
        );
    }

    /// A fully open crack, closed at `t_n`, sticks with the virgin shear stiffness until
    /// `|t_s| = mu |t_n|`, then slides there; the slip is the jump beyond the stick one.
    #[test]
    fn a_fully_open_crack_sticks_then_slides_at_mu_t_n() {
        let (law, crack) = frictional();
        let full = crack.peak_opening() + 2.0 * crack.critical_opening();
        let dn = -1e-5;
        let tau = 0.6 * crack.penalty * 1e-5;
        let k = crack.beta * crack.beta * (crack.stiffness - crack.secant(full));
        let stick = respond(&law, [full, 0.0], [0.5 * tau / k, dn]);
        assert_eq!(stick.branch, Branch::Contact);
        let cohesive = crack.secant(full) * crack.beta * crack.beta;
        assert!((stick.traction.x - (k + cohesive) * 0.5 * tau / k).abs() <= 1e-12 * tau);
        let ds = 4.0 * tau / k;
        let mut trial = [0.0; 2];
        let slide = law.respond(
            &[full, 0.0],
            &mut trial,
            [ds, dn],
            1.0,
            TangentKind::Consistent,
        );
        assert_eq!(slide.branch, Branch::Sliding);
        assert!((slide.traction.x - tau - cohesive * ds).abs() <= 1e-9 * tau);
        assert!((trial[1] - (ds - tau / k)).abs() <= 1e-12 * ds);
        // Opened again: no friction, the slip kept.
        let mut reopened = [0.0; 2];
        let open = law.respond(
            &trial,
            &mut reopened,
            [ds, 1e-6],
            1.0,
            TangentKind::Consistent,
        );
        assert!(open.traction.x.abs() <= 1e-6 * tau);
        assert_eq!(reopened[1], trial[1]);
    }

    /// Friction needs a law that closes: contact off is refused.
    #[test]
    fn friction_without_contact_is_refused() {
        let (_, mut crack) = frictional();
        crack.contact = false;
        let err = Frictional::new(Arc::new(crack), 0.6, "materials.friction").unwrap_err();
        assert!(err.to_string().contains("materials.friction"), "{err}");
    }
}

//! The cohesive-contact law of a crack through the cement paste: an interface that is
//! stiff until the paste's tensile strength, then softens along Hordijk's curve to zero
//! traction at the crack's critical opening, unloads to the origin, and closes in contact.
//!
//! Zero-thickness interfaces inserted a priori along the paste's element edges (the
//! approach of the mesoscale concrete studies with cohesive elements) must not make the
//! uncracked cell softer: an intrinsic interface of stiffness `K` per unit area adds the
//! compliance `1/K` across each element, so `K` is taken far above `E/h` (the law's
//! `stiffness`, by default `STIFFNESS_FACTOR E_paste / h`, `docs/fracture.md`). Below the
//! strength the interface is elastic and undamaged; the paper's exponential law of the
//! ITZ ([`super::CohesiveLaw`]) softens from the first opening instead, which is right for
//! the weak ITZ and would make the whole paste compliant.
//!
//! # The law
//!
//! Effective opening and traction vector as the ITZ's (eqs. 20-21 of Pituba & Souza Neto):
//! ```text
//! delta = sqrt(beta^2 delta_s^2 + delta_n^2),   t_s = k beta^2 delta_s,   t_n = k delta_n
//! ```
//! with the secant `k = t(delta)/delta` of the loading envelope
//! ```text
//! t(delta) = K delta                                  delta <= delta_0 = f_t / K
//! t(delta) = f_t h((delta - delta_0) / w_c)           delta >  delta_0
//! h(x) = (1 + (c1 x)^3) exp(-c2 x) - x (1 + c1^3) exp(-c2)   (x < 1),   h(x) = 0 (x >= 1)
//! ```
//! (Hordijk 1991, as DIANA writes it: `c1 = 3`, `c2 = 6.93`, `w_c = 5.136 G_f / f_t`, so
//! that the softening dissipates `G_f` per unit crack area: `f_t w_c int_0^1 h = G_f`).
//! Loading iff `delta >= delta_max` (the committed history); unloading and reloading to the
//! origin on the secant `k(delta_max)` (no damage below the strength: `k = K` while
//! `delta_max <= delta_0`). A fully open crack keeps the residual secant
//! `RESIDUAL K` (the cell's stiffness matrix stays regular when a crack separates it).
//!
//! Consistent tangent on the loading branch, from `dt/d delta = t'`:
//! ```text
//! C = k diag(beta^2, 1) + (t' - k) / delta^2  w w^T,    w = (beta^2 delta_s, delta_n)
//! ```
//! symmetric (the traction derives from the potential `phi(delta)`); on the elastic branch
//! `t' = k = K` and `C = K diag(beta^2, 1)`; unloading `C = k(delta_max) diag(beta^2, 1)`.
//!
//! Contact on closure (`delta_n < 0`, when contact is on): the normal penalty `k_p`; the
//! shear by the law of the sliding alone (`delta = beta |delta_s|`, which may advance the
//! history: a closed crack can be sheared open, and a fully open one slides freely), or
//! stuck at the penalty (`t = k_p [delta_s, delta_n]`, the paper's closed ITZ, history
//! frozen). The history is `delta_max` alone.

use std::sync::Arc;

use nalgebra::{Matrix2, Vector2};

use super::cohesive::ContactShear;
use super::law::{Branch, InterfaceLaw, LawPoint, PointMeasures, TangentKind};
use crate::error::{require_positive, Error, Result};

/// Hordijk's constants (Hordijk 1991; DIANA's `c1`, `c2`).
const C1: f64 = 3.0;
const C2: f64 = 6.93;
/// `1 / int_0^1 h(x) dx` for these constants: `w_c = WC_FACTOR G_f / f_t`.
pub const WC_FACTOR: f64 = 5.136;
/// The secant left to a fully open crack, over the initial stiffness.
pub const RESIDUAL: f64 = 1e-9;
/// The default initial stiffness over the paste's `E / h` (`h` the mesh size): each
/// interface adds about `1 / STIFFNESS_FACTOR` of a paste element's compliance.
pub const STIFFNESS_FACTOR: f64 = 200.0;

/// A crack law: its constants, checked by [`CrackSpec::validate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CrackLaw {
    /// Tensile strength `f_t` (stress).
    pub strength: f64,
    /// Fracture energy `G_f` (energy per unit crack area: N/mm for mm and MPa).
    pub fracture_energy: f64,
    /// Initial stiffness `K` per unit area (stress per length).
    pub stiffness: f64,
    /// Mode-mixity weight `beta`, as the ITZ's.
    pub beta: f64,
    /// Contact penalty `k_p` per unit area on closure.
    pub penalty: f64,
    /// Unilateral contact on closure; off: the law acts on `|delta_n|` in compression too.
    pub contact: bool,
    /// What carries the shear of a closed point: the penalty (stuck), or the crack's own
    /// law of the sliding alone (a fully open crack then slides freely), as the ITZ's
    /// [`super::ContactShear`].
    pub contact_shear: ContactShear,
}

impl CrackLaw {
    /// `delta_0 = f_t / K`: the opening at the strength.
    #[inline]
    pub fn peak_opening(&self) -> f64 {
        self.strength / self.stiffness
    }

    /// `w_c`: the softening's length, the crack opening at zero traction past `delta_0`.
    #[inline]
    pub fn critical_opening(&self) -> f64 {
        WC_FACTOR * self.fracture_energy / self.strength
    }

    /// The loading envelope `t(delta)` and its slope `t'(delta)`.
    pub fn envelope(&self, delta: f64) -> (f64, f64) {
        let d0 = self.peak_opening();
        if delta <= d0 {
            return (self.stiffness * delta, self.stiffness);
        }
        let wc = self.critical_opening();
        let x = (delta - d0) / wc;
        if x >= 1.0 {
            return (0.0, 0.0);
        }
        let (e, e1) = ((-C2 * x).exp(), (-C2).exp());
        let cx3 = (C1 * x).powi(3);
        let h = (1.0 + cx3) * e - x * (1.0 + C1.powi(3)) * e1;
        let dh = (3.0 * C1.powi(3) * x * x - C2 * (1.0 + cx3)) * e - (1.0 + C1.powi(3)) * e1;
        (self.strength * h, self.strength * dh / wc)
    }

    /// `k(delta) = t(delta)/delta`, `K` at and below `delta_0` (finite at 0), at least the
    /// residual secant.
    #[inline]
    pub fn secant(&self, delta: f64) -> f64 {
        let floor = RESIDUAL * self.stiffness;
        if delta <= self.peak_opening() {
            self.stiffness
        } else {
            (self.envelope(delta).0 / delta).max(floor)
        }
    }

    fn open(&self, delta_max: f64, ds: f64, dn: f64) -> (Vector2<f64>, Matrix2<f64>, f64, Branch) {
        let beta2 = self.beta * self.beta;
        let delta = (self.beta * ds).hypot(dn);
        if delta < delta_max {
            let k = self.secant(delta_max);
            let c = Matrix2::new(k * beta2, 0.0, 0.0, k);
            return (
                Vector2::new(k * beta2 * ds, k * dn),
                c,
                delta_max,
                Branch::Unloading,
            );
        }
        let k = self.secant(delta);
        let mut c = Matrix2::new(k * beta2, 0.0, 0.0, k);
        let (t, slope) = self.envelope(delta);
        if delta > self.peak_opening() && t / delta > RESIDUAL * self.stiffness {
            let w = Vector2::new(beta2 * ds, dn);
            c += (slope - k) / (delta * delta) * w * w.transpose();
        }
        (
            Vector2::new(k * beta2 * ds, k * dn),
            c,
            delta,
            Branch::Loading,
        )
    }

    /// The response at `jump` from the committed `delta_max`, the contact status held at
    /// `closed` (contact on): `(traction, tangent, trial delta_max, branch)`.
    pub fn evaluate_as(
        &self,
        delta_max: f64,
        jump: [f64; 2],
        closed: bool,
    ) -> (Vector2<f64>, Matrix2<f64>, f64, Branch) {
        let [ds, dn] = jump;
        if !(self.contact && closed) {
            return self.open(delta_max, ds, dn);
        }
        let kp = self.penalty;
        match self.contact_shear {
            ContactShear::Penalty => (
                Vector2::new(kp * ds, kp * dn),
                Matrix2::from_diagonal_element(kp),
                delta_max,
                Branch::Contact,
            ),
            ContactShear::Cohesive => {
                // The law of the sliding alone (`delta_n` clamped at 0), the normal penalty.
                let (mut t, mut c, trial, _) = self.open(delta_max, ds, 0.0);
                t.y = kp * dn;
                c[(0, 1)] = 0.0;
                c[(1, 0)] = 0.0;
                c[(1, 1)] = kp;
                (t, c, trial, Branch::Contact)
            }
        }
    }
}

impl InterfaceLaw for CrackLaw {
    /// `delta_max`.
    fn history_len(&self) -> usize {
        1
    }

    fn respond(
        &self,
        committed: &[f64],
        trial: &mut [f64],
        jump: [f64; 2],
        length: f64,
        kind: TangentKind,
    ) -> LawPoint {
        let closed = self.is_closed(jump);
        self.respond_as(committed, trial, jump, length, kind, closed)
    }

    fn has_contact_status(&self) -> bool {
        self.contact
    }

    fn is_closed(&self, jump: [f64; 2]) -> bool {
        self.contact && jump[1] < 0.0
    }

    /// The secant of a loading point is `k diag(beta^2, 1)`; unloading and contact are
    /// already secant.
    fn respond_as(
        &self,
        committed: &[f64],
        trial: &mut [f64],
        jump: [f64; 2],
        _length: f64,
        kind: TangentKind,
        closed: bool,
    ) -> LawPoint {
        let (traction, tangent, delta_max, branch) = self.evaluate_as(committed[0], jump, closed);
        trial[0] = delta_max;
        let matrix = match (kind, branch) {
            (TangentKind::Secant, Branch::Loading) => {
                let k = self.secant(delta_max);
                Matrix2::new(k * self.beta * self.beta, 0.0, 0.0, k)
            }
            _ => tangent,
        };
        LawPoint {
            traction,
            matrix,
            branch,
        }
    }

    fn trial_history_as(
        &self,
        committed: &[f64],
        trial: &mut [f64],
        jump: [f64; 2],
        _length: f64,
        closed: bool,
    ) {
        let closed = self.contact && closed;
        let delta = if closed {
            (self.beta * jump[0]).abs()
        } else {
            (self.beta * jump[0]).hypot(jump[1])
        };
        trial[0] = if closed && self.contact_shear == ContactShear::Penalty {
            committed[0]
        } else {
            committed[0].max(delta)
        };
    }

    fn passes_peak(&self, start: &[f64], trial: &[f64]) -> bool {
        let d0 = self.peak_opening();
        trial[0] > d0 && start[0] <= d0
    }

    /// Unloading (an open point strictly below `delta_max`, for every jump within
    /// `error`) and contact are linear through the origin.
    fn stays_linear(&self, history: &[f64], jump: [f64; 2], error: [f64; 2], closed: bool) -> bool {
        let [ds, dn] = jump;
        let [es, en] = error;
        let unloading = (self.beta * (ds.abs() + es)).hypot(dn.abs() + en) < history[0];
        if !self.contact {
            return unloading;
        }
        if closed {
            let sliding = self.beta * (ds.abs() + es);
            dn + en < 0.0 && (self.contact_shear == ContactShear::Penalty || sliding < history[0])
        } else {
            dn - en >= 0.0 && unloading
        }
    }

    fn frozen_secant(&self, history: &[f64], closed: bool, _length: f64) -> Option<Matrix2<f64>> {
        let k = self.secant(history[0]);
        let shear = k * self.beta * self.beta;
        Some(match (self.contact && closed, self.contact_shear) {
            (false, _) => Matrix2::new(shear, 0.0, 0.0, k),
            (true, ContactShear::Penalty) => Matrix2::from_diagonal_element(self.penalty),
            (true, ContactShear::Cohesive) => Matrix2::new(shear, 0.0, 0.0, self.penalty),
        })
    }

    fn traction_scale(&self) -> f64 {
        self.strength
    }

    fn extrapolate(&self, committed: &[f64], previous: &[f64], ratio: f64, out: &mut [f64]) {
        super::law::extrapolate_growth(committed, previous, ratio, out);
    }

    fn history_is_valid(&self, history: &[f64]) -> bool {
        super::law::openings_are_valid(history)
    }

    /// Openings over the softening length `w_c` past the strength, and the damage as the
    /// secant's loss, `1 - k(delta_max)/K`.
    fn measures(&self, history: &[f64], jump: [f64; 2], _length: f64) -> Option<PointMeasures> {
        let delta = (self.beta * jump[0]).hypot(jump[1]);
        let wc = self.critical_opening();
        let (damage, max_opening) = self.history_measures(history, 0.0)?;
        Some(PointMeasures {
            opening_ratio: delta / wc,
            max_opening_ratio: max_opening / wc,
            max_opening,
            damage,
        })
    }

    fn history_measures(&self, history: &[f64], _length: f64) -> Option<(f64, f64)> {
        Some((1.0 - self.secant(history[0]) / self.stiffness, history[0]))
    }

    /// `beta^2 (K - k(delta_max))`: the virgin shear stiffness times the damage.
    fn damaged_shear_stiffness(&self, history: &[f64], _length: f64) -> Option<f64> {
        Some(self.beta * self.beta * (self.stiffness - self.secant(history[0])))
    }

    /// The fracture energy `scale` times larger: Hordijk's softening is stretched alike
    /// (`w_c = 5.136 G_f / f_t`), the strength and initial stiffness stay.
    fn regularized(&self, scale: f64) -> Option<Arc<dyn InterfaceLaw>> {
        Some(Arc::new(CrackLaw {
            fracture_energy: self.fracture_energy * scale,
            ..*self
        }))
    }
}

/// The scene's table of a crack law (`[materials.paste_crack]`): the paste's tensile
/// strength and fracture energy, optionally the initial stiffness and the contact penalty
/// per unit area (both default to `STIFFNESS_FACTOR E_paste / h`, set by the model from
/// the paste's modulus and the mesh size), and `beta`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CrackSpec {
    /// Tensile strength of the paste, `f_t` (stress).
    pub strength: f64,
    /// Fracture energy of the paste, `G_f` (N/mm with mm and MPa).
    pub fracture_energy: f64,
    /// Initial stiffness per unit area; absent: `STIFFNESS_FACTOR E_paste / h`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// Contact penalty per unit area; absent: the initial stiffness.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub penalty: Option<f64>,
    /// Mode-mixity weight; absent: 1 (shear and normal strength alike).
    #[serde(default = "one")]
    pub beta: f64,
    /// The shear of a closed crack: `"cohesive"` (the default: the law of the sliding, so
    /// an open crack slides freely once closed) or `"penalty"` (stuck, as the paper's ITZ).
    #[serde(default = "cohesive_shear")]
    pub contact_shear: ContactShear,
    /// The rectangle `[x0, y0, x1, y1]` whose paste edges may crack (by their midpoint);
    /// absent: the whole paste.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub band: Option<[f64; 4]>,
}

fn one() -> f64 {
    1.0
}

fn cohesive_shear() -> ContactShear {
    ContactShear::Cohesive
}

impl CrackSpec {
    /// Checks the constants; errors name `materials.<key>.<constant>`.
    pub fn validate(&self, key: &str) -> Result<()> {
        require_positive(&format!("materials.{key}.strength"), self.strength)?;
        require_positive(
            &format!("materials.{key}.fracture_energy"),
            self.fracture_energy,
        )?;
        for (name, value) in [("stiffness", self.stiffness), ("penalty", self.penalty)] {
            if let Some(v) = value {
                require_positive(&format!("materials.{key}.{name}"), v)?;
            }
        }
        if let Some([x0, y0, x1, y1]) = self.band {
            if !(x0 < x1 && y0 < y1) || [x0, y0, x1, y1].iter().any(|v| !v.is_finite()) {
                return Err(Error::scene(
                    format!("materials.{key}.band"),
                    format!(
                        "must be [x0, y0, x1, y1] with x0 < x1 and y0 < y1, got {:?}",
                        self.band
                    ),
                ));
            }
        }
        if !(self.beta.is_finite() && self.beta >= 0.0) {
            return Err(Error::scene(
                format!("materials.{key}.beta"),
                format!("must be finite and non-negative, got {}", self.beta),
            ));
        }
        Ok(())
    }

    /// Whether the paste edge of midpoint `p` may crack (inside the band, if any).
    pub fn cracks_at(&self, p: [f64; 2]) -> bool {
        self.band
            .is_none_or(|[x0, y0, x1, y1]| (x0..=x1).contains(&p[0]) && (y0..=y1).contains(&p[1]))
    }

    /// The law, with `default_stiffness` (the model's `STIFFNESS_FACTOR E / h`) where the
    /// table gives none.
    pub fn build(&self, contact: bool, default_stiffness: f64) -> Arc<dyn InterfaceLaw> {
        let stiffness = self.stiffness.unwrap_or(default_stiffness);
        Arc::new(CrackLaw {
            strength: self.strength,
            fracture_energy: self.fracture_energy,
            stiffness,
            beta: self.beta,
            penalty: self.penalty.unwrap_or(stiffness),
            contact,
            contact_shear: self.contact_shear,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law() -> CrackLaw {
        CrackLaw {
            strength: 5.0,
            fracture_energy: 0.1,
            stiffness: 5e6,
            beta: 0.8,
            penalty: 5e6,
            contact: true,
            contact_shear: ContactShear::Cohesive,
        }
    }

    /// The softening dissipates `G_f`: the area under the envelope past `delta_0` (the
    /// elastic part adds `f_t delta_0 / 2`).
    #[test]
    fn the_envelope_dissipates_the_fracture_energy() {
        let l = law();
        let (d0, wc) = (l.peak_opening(), l.critical_opening());
        let n = 200_000;
        let area: f64 = (0..n)
            .map(|i| l.envelope(d0 + wc * (i as f64 + 0.5) / n as f64).0 * wc / n as f64)
            .sum();
        assert!((area / l.fracture_energy - 1.0).abs() < 1e-3, "{area}");
        assert_eq!(l.envelope(d0).0, l.strength);
        assert_eq!(l.envelope(d0 + wc).0, 0.0);
    }

    /// Regularized by `scale`, the softening dissipates `scale G_f` and ends at
    /// `scale w_c` past `delta_0`; the law before the strength is unchanged.
    #[test]
    fn regularization_stretches_the_softening_alone() {
        let l = law();
        let r = l.regularized(2.5).expect("the law softens");
        let (d0, wc) = (l.peak_opening(), l.critical_opening());
        let mut trial = [0.0];
        let at = |jump: [f64; 2], trial: &mut [f64]| {
            r.respond(&[0.0], trial, jump, 1.0, TangentKind::Consistent)
                .traction
        };
        assert_eq!(
            at([0.2 * d0, 0.9 * d0], &mut trial),
            l.evaluate_as(0.0, [0.2 * d0, 0.9 * d0], false).0
        );
        let x = 0.3;
        let stretched = at([0.0, d0 + 2.5 * x * wc], &mut trial).y;
        let original = l.envelope(d0 + x * wc).0;
        assert!(
            (stretched - original).abs() <= 1e-12 * l.strength,
            "{stretched} {original}"
        );
        // Past the stretched end only the residual secant is left.
        let end = d0 + 2.5 * wc;
        assert!(at([0.0, end], &mut trial).y <= RESIDUAL * l.stiffness * end * (1.0 + 1e-12));
        assert!(at([0.0, 0.99 * end], &mut trial).y > RESIDUAL * l.stiffness * end);
    }

    fn fd(l: &CrackLaw, h: f64, jump: [f64; 2], closed: bool) -> Matrix2<f64> {
        let mut c = Matrix2::zeros();
        for j in 0..2 {
            let step = 1e-7 * (jump[0].abs() + jump[1].abs()).max(1e-9);
            let (mut p, mut m) = (jump, jump);
            p[j] += step;
            m[j] -= step;
            let d = (l.evaluate_as(h, p, closed).0 - l.evaluate_as(h, m, closed).0) / (2.0 * step);
            c.set_column(j, &d);
        }
        c
    }

    /// The consistent tangent matches central differences on every branch.
    #[test]
    fn the_tangent_is_the_derivative_of_the_traction() {
        let l = law();
        let (d0, wc) = (l.peak_opening(), l.critical_opening());
        let cases = [
            (0.0, [0.2 * d0, 0.5 * d0], false),
            (0.0, [0.3 * wc, 0.2 * wc], false),
            (0.1 * wc, [0.2 * wc, 0.25 * wc], false),
            (0.5 * wc, [0.1 * wc, 0.2 * wc], false),
            (0.5 * wc, [0.1 * wc, -0.2 * wc], true),
            (0.1 * wc, [0.3 * wc, -0.2 * wc], true),
        ];
        for (h, jump, closed) in cases {
            let c = l.evaluate_as(h, jump, closed).1;
            let e = fd(&l, h, jump, closed);
            let scale = c.amax().max(e.amax());
            assert!((c - e).amax() <= 1e-6 * scale, "{h} {jump:?}: {c} vs {e}");
        }
    }

    /// Below the strength nothing is damaged; past it the secant falls; a closed point
    /// keeps its history.
    #[test]
    fn loading_unloading_and_contact() {
        let l = law();
        let d0 = l.peak_opening();
        let mut trial = [0.0];
        l.trial_history_as(&[0.0], &mut trial, [0.0, 0.9 * d0], 1.0, false);
        assert_eq!(l.history_measures(&trial, 1.0).unwrap().0, 0.0);
        let past = [0.0, d0 + 0.2 * l.critical_opening()];
        l.trial_history_as(&[0.0], &mut trial, past, 1.0, false);
        let damage = l.history_measures(&trial, 1.0).unwrap().0;
        assert!(damage > 0.99, "{damage}");
        let mut closed = [0.0];
        l.trial_history_as(&trial, &mut closed, [0.0, -1e-3], 1.0, true);
        assert_eq!(closed, trial);
    }
}

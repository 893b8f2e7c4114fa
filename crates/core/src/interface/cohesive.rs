//! The cohesive-contact law of the ITZ (paper section 3.2, eqs. 19-25, and the traction
//! and tangent formulas of section 4, eqs. 32-37 and 45-47).
//!
//! Everything here is local to one quadrature point and expressed in the local axes of the
//! interface element: `s` (sliding, along the edge) and `n` (normal, out of the inclusion).
//! The displacement jump is `[delta_s, delta_n]` (matrix side minus inclusion side, see
//! [`crate::mesh`]); `delta_n > 0` is opening.
//!
//! # The law
//!
//! Effective opening (eq. 20):
//! ```text
//! delta = sqrt(beta^2 delta_s^2 + delta_n^2)
//! ```
//! Effective traction: loading envelope (eq. 23) and linear unloading/reloading to the
//! origin (eq. 24):
//! ```text
//! t = e sigma_c (delta/delta_c) exp(-delta/delta_c)     if delta >= delta_max   (loading)
//! t = (t_max/delta_max) delta                           if delta <  delta_max   (unloading)
//! ```
//! Traction vector (eq. 21, components eqs. 32-35), with the secant `k = t/delta`:
//! ```text
//! t_s = k beta^2 delta_s,    t_n = k delta_n
//! k   = (sigma_c/delta_c) exp(1 - delta/delta_c)         loading   (eqs. 32-33)
//! k   = t_max/delta_max                                  unloading (eqs. 34-35)
//! ```
//! Writing the loading secant as `(sigma_c/delta_c) exp(1 - delta/delta_c)` instead of
//! `t(delta)/delta` removes the `0/0` at `delta = 0`: `k(0) = e sigma_c/delta_c` is the
//! initial stiffness, and the law is exact for any tiny opening (1e-300 included; `delta`
//! is computed with `hypot`, which neither underflows nor overflows).
//!
//! Consistent tangent `C = dt/d(delta_s, delta_n)`, loading (eq. 45):
//! ```text
//!         | beta^2 (1 - beta^2 ds^2 /(delta_c delta))    -beta^2 ds dn /(delta_c delta) |
//! C = k   |                                                                             |
//!         | -beta^2 ds dn /(delta_c delta)               1 - dn^2 /(delta_c delta)      |
//! ```
//! computed as `beta^2 ds^2/delta = (beta ds) u_s`, `beta^2 ds dn/delta = beta (beta ds) u_n`,
//! `dn^2/delta = dn u_n` with the unit direction `(u_s, u_n) = (beta ds, dn)/delta`, which is
//! bounded; at `delta = 0` the correction terms vanish and `C = (e sigma_c/delta_c)
//! diag(beta^2, 1)`, the exact derivative there (the correction is `O(delta)`).
//! Unloading (eq. 46): `C = (t_max/delta_max) diag(beta^2, 1)`.
//!
//! Contact, when enabled and `delta_n < 0` (eqs. 36-37, tangent eq. 47): a penalty on both
//! components, `t = k_p [delta_s, delta_n]`, `C = k_p I`, with `k_p` from [`Penalty`]
//! ([`ContactShear::Penalty`], the paper's law). Alternative, [`ContactShear::Cohesive`]
//! (Ortiz & Pandolfi 1999, whom the paper follows for the cohesive part): the penalty acts on
//! the normal component only, and the sliding of a closed crack keeps the cohesive law with
//! the normal opening clamped at zero,
//! ```text
//! t_s = k(delta) beta^2 delta_s,  t_n = k_p delta_n,  delta = beta |delta_s|
//! C   = [[dt_s/d delta_s, 0], [0, k_p]]
//! ```
//! i.e. the potential `phi(sqrt(beta^2 ds^2 + <dn>^2)) + k_p <-dn>^2 / 2`: the traction is
//! continuous at `delta_n = 0` and the tangent symmetric.
//!
//! **The shear jump at closure.** The paper's law is discontinuous in `t_s` at
//! `delta_n = 0`: just open, `t_s = k beta^2 delta_s` with the (possibly damaged) cohesive
//! secant `k`; just closed, `t_s = k_p delta_s`. With the contact status read from the gap
//! at every evaluation, paths that close ITZ points while sliding them (a uniaxial macro
//! stress with its Poisson contraction, the snap after the peak) can leave the discrete RVE
//! without any equilibrium: a point held open closes, held closed it opens
//! (`docs/contact-algorithm.md`). The solver therefore holds the status within a Newton
//! iteration (`solver.contact_status = "active_set"`), evaluating the law with
//! [`CohesiveLaw::evaluate_as`]; [`ContactShear::Cohesive`] is continuous at closure and
//! needs no held status.
//!
//! # Held contact status
//!
//! [`CohesiveLaw::evaluate_as`] takes the status as given. Where it agrees with the gap it
//! is [`CohesiveLaw::evaluate`]. Where it does not, the branch of the status is extended:
//! * held closed with an open gap (`delta_n >= 0`): the contact branch (with
//!   [`ContactShear::Penalty`] eq. 47 on both components; the normal traction is then a
//!   tension `k_p delta_n`);
//! * held open with a closed gap (`delta_n < 0`): the normal penalty and the cohesive law
//!   of the sliding alone, `t_s = k(beta |delta_s|) beta^2 delta_s`, `t_n = k_p delta_n`
//!   (the contact branch of [`ContactShear::Cohesive`]): interpenetration is always
//!   penalized and compression never advances the history. Its branch is that of the
//!   sliding (loading or unloading), since the point is open.
//!
//! Both come from a potential, so the tangent stays symmetric, and with the status held
//! the traction is continuous in the jump (with a kink of the normal stiffness at
//! `delta_n = 0`).
//!
//! The loading secant and tangent derive from the potential `phi(delta)` with
//! `dphi/d delta = t(delta)`, so `C` is symmetric in every branch.
//!
//! # Choices the paper leaves open (made here, fixed)
//!
//! * **Loading test.** Eq. 23 asks `delta = delta_max and d(delta)/dt >= 0`. In an implicit
//!   step this is decided on the trial total opening against the *committed* history:
//!   loading iff `delta >= delta_max` (equality is loading, so a virgin point at
//!   `delta = 0` is on the loading branch and its tangent is the initial stiffness). No rate
//!   enters, so Newton iterates that wander below `delta_max` and back do not matter.
//! * **History update** (eq. 25): only on the loading branch, trial
//!   `delta_max' = delta`, `t_max' = t(delta)` (the envelope value, which decreases after the
//!   peak). Unloading and contact return the committed history unchanged. The caller
//!   commits the trial history when the increment converges.
//! * **Pre-peak unloading.** The envelope is concave on `[0, 2 delta_c]`, so the secant
//!   `t_max/delta_max` lies below it even before the peak: this intrinsic law (Ortiz-Pandolfi)
//!   degrades the secant stiffness from the first opening on. That is the paper's law.
//! * **Sliding** is the total tangential jump measured from the reference configuration
//!   (no plastic slip, no friction). Its sign does not matter for `delta` (isotropy,
//!   eq. 19); `t_s` has the sign of `delta_s`.
//! * **`delta_n == 0` exactly counts as open** (cohesive branch); contact needs
//!   `delta_n < 0` strictly (`-0.0` is open too).
//! * **Contact replaces the cohesive traction** (the two are not added) and acts on both
//!   components: a closed point sticks in shear with the penalty stiffness, as eq. 36 says;
//!   there is no friction law or slip. The history is frozen while in contact, so a closed
//!   point can neither damage nor heal. ([`ContactShear::Cohesive`] instead: the sliding of
//!   a closed point follows the cohesive law of `beta |delta_s|`, which may advance the
//!   history, i.e. shear can damage a closed interface.)
//! * **Contact switched off** (`contact = false`): the cohesive law acts symmetrically for
//!   `delta_n < 0` (the effective opening uses `delta_n^2`, `t_n = k delta_n` is compressive)
//!   and compression can drive `delta_max` up, i.e. damage the interface. Interpenetration is
//!   then resisted only by the cohesive stiffness. This mode is for studies without the
//!   unilateral effect.
//! * **Penalty.** The paper's `t = lambda_p l_e delta` (eqs. 36-37) multiplies a per-length
//!   factor by the element length, so the contact stiffness per unit area grows with the
//!   element size; [`Penalty::PerArea`] is the mesh-independent alternative `t = k delta`.
//! * Non-finite jumps give non-finite tractions (the caller's residual check catches them);
//!   nothing here panics.
//!
//! Preconditions (not checked by the law; [`ItzSpec`], the scene's table, checks them):
//! `sigma_c > 0`, `delta_c > 0`, `beta >= 0`, penalty `> 0`, `length > 0`.

use std::sync::Arc;

use nalgebra::{Matrix2, Vector2};

use super::law::{Branch, InterfaceLaw, InterfaceLawSpec, LawPoint, PointMeasures, TangentKind};
use crate::error::{require_positive, Error, Result};

/// Contact penalty on a closed interface point (eqs. 36-37).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Penalty {
    /// The paper's form: `t = lambda_p * l_e * delta`. The paper gives `lambda_p` in N/mm
    /// (Table 1: 1e7, Table 2: 1e5) and uses `lambda_p l_e` as the traction/jump ratio,
    /// whose units should be N/mm^3: dimensionally odd, kept as published. Mesh
    /// dependent: the contact stiffness per unit area scales with the element length.
    PerLength { lambda_p: f64 },
    /// Mesh-independent stiffness per unit area, `t = stiffness * delta`
    /// (N/mm^3 in the paper's units).
    PerArea { stiffness: f64 },
}

/// What carries the shear of a closed interface point (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactShear {
    /// The paper's eq. 47: the penalty on both components, history frozen (a closed point
    /// sticks). Discontinuous in `t_s` at `delta_n = 0`.
    #[default]
    Penalty,
    /// Ortiz & Pandolfi (1999): the penalty on the normal component only; the sliding keeps
    /// the cohesive law with the opening `beta |delta_s|`. Continuous at `delta_n = 0`.
    Cohesive,
}

/// Parameters of the cohesive-contact law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CohesiveLaw {
    /// Maximum cohesive normal traction `sigma_c` (peak of the envelope, at `delta_c`).
    pub sigma_c: f64,
    /// Characteristic opening `delta_c` (opening at the peak).
    pub delta_c: f64,
    /// Mode-mixity weight `beta`: ratio of shear to normal critical tractions (eq. 22).
    pub beta: f64,
    /// Contact penalty, used only when `contact` is on.
    pub penalty: Penalty,
    /// Unilateral contact on closure (`delta_n < 0`); off: the cohesive law is symmetric.
    pub contact: bool,
    /// What carries the shear of a closed point, when `contact` is on.
    pub contact_shear: ContactShear,
}

/// The internal variable of one quadrature point, `q` of eq. 19. Virgin = zero.
///
/// The paper's pair `(delta_max, t_max)` has one degree of freedom: the history only
/// advances on the loading envelope (eq. 23), so `t_max = t(delta_max)` always
/// ([`CohesiveLaw::t_max`]), and the unloading secant `t_max / delta_max` of eq. 24 is the
/// envelope's secant at `delta_max`. Storing `delta_max` alone halves the history (8 bytes
/// per point) and cannot let the two disagree.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CohesiveHistory {
    /// Largest effective opening reached on the loading branch.
    pub delta_max: f64,
}

/// The response of the law at one point for a trial jump.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CohesivePoint {
    /// Local traction `[t_s, t_n]`.
    pub traction: Vector2<f64>,
    /// Consistent tangent `d[t_s, t_n] / d[delta_s, delta_n]` (eqs. 45-47); symmetric.
    pub tangent: Matrix2<f64>,
    /// Trial history: advanced on the loading branch, the committed one otherwise.
    pub history: CohesiveHistory,
    /// The branch taken.
    pub branch: Branch,
    /// Effective opening `delta` (eq. 20) of the trial jump, in every branch
    /// (`beta |delta_s|` at a closed point with [`ContactShear::Cohesive`]).
    pub opening: f64,
    /// The cohesive secant `k = t/delta` at `opening` (eqs. 32-35); the penalty `k_p` at a
    /// closed point with [`ContactShear::Penalty`].
    pub secant: f64,
    /// Whether the normal traction is the penalty's `k_p delta_n` (a closed gap, or a
    /// point held closed).
    pub penalty_normal: bool,
}

impl Penalty {
    /// Contact stiffness per unit area for an element of reference length `length`.
    #[inline]
    pub fn stiffness(&self, length: f64) -> f64 {
        match *self {
            Penalty::PerLength { lambda_p } => lambda_p * length,
            Penalty::PerArea { stiffness } => stiffness,
        }
    }
}

impl CohesiveLaw {
    /// Contact stiffness per unit area `k_p` (eqs. 36-37, 47): `lambda_p l_e` or the
    /// per-area stiffness.
    #[inline]
    pub fn contact_stiffness(&self, length: f64) -> f64 {
        self.penalty.stiffness(length)
    }

    /// Initial (virgin) stiffness `e sigma_c / delta_c`, the slope of eq. 23 at the origin.
    #[inline]
    pub fn initial_stiffness(&self) -> f64 {
        std::f64::consts::E * self.sigma_c / self.delta_c
    }

    /// The loading envelope (eq. 23): `t(delta) = e sigma_c (delta/delta_c) exp(-delta/delta_c)`.
    /// Its maximum is `sigma_c`, at `delta = delta_c`.
    #[inline]
    pub fn envelope(&self, delta: f64) -> f64 {
        self.loading_secant(delta) * delta
    }

    /// `t(delta)/delta = (sigma_c/delta_c) exp(1 - delta/delta_c)`, finite at 0.
    #[inline]
    fn loading_secant(&self, delta: f64) -> f64 {
        (self.sigma_c / self.delta_c) * (1.0 - delta / self.delta_c).exp()
    }

    /// `t_max = t(delta_max)` of a history (eq. 23).
    #[inline]
    pub fn t_max(&self, history: &CohesiveHistory) -> f64 {
        self.envelope(history.delta_max)
    }

    /// The secant `k = t_max / delta_max` of unloading and reloading to the origin
    /// (eqs. 24, 34-35), as the envelope's secant at `delta_max`: no division, finite for
    /// a virgin history.
    #[inline]
    pub fn unloading_secant(&self, history: &CohesiveHistory) -> f64 {
        self.loading_secant(history.delta_max)
    }

    /// The secant matrix `S` with `t = S delta` at a point evaluated by
    /// [`CohesiveLaw::evaluate`]: on the loading branch `(t/delta) diag(beta^2, 1)` (the
    /// secant of the envelope, eq. 21), elsewhere the consistent tangent (eqs. 46-47 are
    /// already secant). Positive definite; used by the secant iterations of the solver.
    pub fn secant_matrix(&self, point: &CohesivePoint) -> Matrix2<f64> {
        let shear = point.secant * self.beta * self.beta;
        match (point.branch, self.contact_shear) {
            (Branch::Loading, _) if point.penalty_normal => {
                Matrix2::new(shear, 0.0, 0.0, point.tangent[(1, 1)])
            }
            (Branch::Loading, _) => Matrix2::new(shear, 0.0, 0.0, point.secant),
            (Branch::Contact, ContactShear::Cohesive) => {
                Matrix2::new(shear, 0.0, 0.0, point.tangent[(1, 1)])
            }
            (Branch::Unloading | Branch::Sliding, _) | (Branch::Contact, ContactShear::Penalty) => {
                point.tangent
            }
        }
    }

    /// Evaluates the law at a trial local jump `[delta_s, delta_n]` against the committed
    /// `history`; `length` is the element's reference length (used only by
    /// [`Penalty::PerLength`]). See the module documentation for the formulas and choices.
    /// Pure, allocation free.
    pub fn evaluate(
        &self,
        history: &CohesiveHistory,
        jump: [f64; 2],
        length: f64,
    ) -> CohesivePoint {
        self.evaluate_as(history, jump, length, self.is_closed(jump))
    }

    /// The contact status the gap of `jump` gives: closed iff contact is on and
    /// `delta_n < 0` (`delta_n == 0` and `-0.0` count as open).
    #[inline]
    pub fn is_closed(&self, jump: [f64; 2]) -> bool {
        self.contact && jump[1] < 0.0
    }

    /// [`CohesiveLaw::evaluate`] with the contact status held at `closed` instead of read
    /// from the gap of `jump` (see "Held contact status" in the module docs). Contact
    /// off: `closed` is ignored.
    pub fn evaluate_as(
        &self,
        history: &CohesiveHistory,
        jump: [f64; 2],
        length: f64,
        closed: bool,
    ) -> CohesivePoint {
        let [ds, dn] = jump;
        let side = self.side(dn, closed);
        if side == Side::Open {
            return self.open(history, ds, dn);
        }
        let kp = self.contact_stiffness(length);
        if side == Side::Penalty {
            // Eqs. 36-37 and 47.
            return CohesivePoint {
                traction: Vector2::new(kp * ds, kp * dn),
                tangent: Matrix2::from_diagonal_element(kp),
                history: *history,
                branch: Branch::Contact,
                opening: (self.beta * ds).hypot(dn),
                secant: kp,
                penalty_normal: true,
            };
        }
        // The cohesive law of the sliding alone (at delta_n = 0 its off-diagonal tangent
        // terms vanish), plus the normal penalty: a closed point of ContactShear::Cohesive,
        // or a point held open whose gap has closed.
        let mut point = self.open(history, ds, 0.0);
        point.traction.y = kp * dn;
        point.tangent[(1, 1)] = kp;
        point.penalty_normal = true;
        if closed {
            point.branch = Branch::Contact;
        }
        point
    }

    /// Which branch of [`CohesiveLaw::evaluate_as`] a point of normal jump `dn` and held
    /// status `closed` is on.
    fn side(&self, dn: f64, closed: bool) -> Side {
        if !self.contact || !(closed || dn < 0.0) {
            Side::Open
        } else if closed && self.contact_shear == ContactShear::Penalty {
            Side::Penalty
        } else {
            Side::Sliding
        }
    }

    /// Whether holding the contact status changes anything: contact on with
    /// [`ContactShear::Penalty`], whose shear traction jumps at closure. With
    /// [`ContactShear::Cohesive`] the traction is continuous at closure.
    #[inline]
    pub fn holds_contact_status(&self) -> bool {
        self.contact && self.contact_shear == ContactShear::Penalty
    }

    /// The cohesive law of an open (or, with contact off, any) point: loading on the
    /// envelope or unloading to the origin.
    fn open(&self, history: &CohesiveHistory, ds: f64, dn: f64) -> CohesivePoint {
        let beta = self.beta;
        let bs = beta * ds;
        let opening = bs.hypot(dn);
        if opening >= history.delta_max {
            // Loading, eqs. 23, 32-33, tangent eq. 45.
            let k = self.loading_secant(opening);
            // At `opening == 0` both components are 0: dividing by 1 gives the (0, 0)
            // direction without forming 0/0, which a host trapping invalid operations
            // (a debug Fortran build) would stop on even where the value is unused.
            let denominator = if opening > 0.0 { opening } else { 1.0 };
            let (us, un) = (bs / denominator, dn / denominator);
            let inv_dc = 1.0 / self.delta_c;
            let css = k * beta * beta * (1.0 - bs * us * inv_dc);
            let csn = -k * beta * bs * un * inv_dc;
            let cnn = k * (1.0 - dn * un * inv_dc);
            CohesivePoint {
                traction: Vector2::new(k * beta * bs, k * dn),
                tangent: Matrix2::new(css, csn, csn, cnn),
                history: CohesiveHistory { delta_max: opening },
                branch: Branch::Loading,
                opening,
                secant: k,
                penalty_normal: false,
            }
        } else {
            // Unloading/reloading to the origin, eqs. 24, 34-35, tangent eq. 46.
            let k = self.unloading_secant(history);
            CohesivePoint {
                traction: Vector2::new(k * beta * bs, k * dn),
                tangent: Matrix2::new(k * beta * beta, 0.0, 0.0, k),
                history: *history,
                branch: Branch::Unloading,
                opening,
                secant: k,
                penalty_normal: false,
            }
        }
    }
}

/// The branches of [`CohesiveLaw::evaluate_as`]: open (the cohesive law of the whole
/// jump), closed under the paper's penalty (eqs. 36-37, history unchanged), or the
/// cohesive law of the sliding alone plus the normal penalty.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Side {
    Open,
    Penalty,
    Sliding,
}

impl InterfaceLaw for CohesiveLaw {
    /// `delta_max`: the paper's pair `(delta_max, t_max)` has one degree of freedom (see
    /// [`CohesiveHistory`]).
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
        self.respond_as(committed, trial, jump, length, kind, self.is_closed(jump))
    }

    fn has_contact_status(&self) -> bool {
        self.holds_contact_status()
    }

    fn is_closed(&self, jump: [f64; 2]) -> bool {
        CohesiveLaw::is_closed(self, jump)
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
        let history = CohesiveHistory {
            delta_max: committed[0],
        };
        let point = self.evaluate_as(&history, jump, length, closed);
        trial[0] = point.history.delta_max;
        LawPoint {
            traction: point.traction,
            matrix: match kind {
                TangentKind::Consistent => point.tangent,
                TangentKind::Secant => self.secant_matrix(&point),
            },
            branch: point.branch,
        }
    }

    /// `delta_max` of [`CohesiveLaw::evaluate_as`]'s branches ([`Side`]) without their
    /// tractions: unchanged under the penalty, else the larger of `delta_max` and the
    /// effective opening (of the sliding alone on [`Side::Sliding`]), formed as `open`
    /// forms them.
    fn trial_history_as(
        &self,
        committed: &[f64],
        trial: &mut [f64],
        jump: [f64; 2],
        _length: f64,
        closed: bool,
    ) {
        let [ds, dn] = jump;
        let delta_max = committed[0];
        let opening = match self.side(dn, closed) {
            Side::Open => (self.beta * ds).hypot(dn),
            Side::Penalty => {
                trial[0] = delta_max;
                return;
            }
            Side::Sliding => (self.beta * ds).hypot(0.0),
        };
        trial[0] = if opening >= delta_max {
            opening
        } else {
            delta_max
        };
    }

    /// A point passes the peak of the envelope when its `delta_max` crosses `delta_c`.
    fn passes_peak(&self, start: &[f64], trial: &[f64]) -> bool {
        trial[0] >= self.delta_c && start[0] < self.delta_c
    }

    /// The linear branches of the law are unloading to the origin (eq. 24: an open point
    /// with `delta < delta_max`) and contact (eqs. 36-37: a closed point; with
    /// [`ContactShear::Cohesive`] also `beta |delta_s| < delta_max`, the sliding
    /// unloading). Every jump within `error` of `jump` must give the same status as
    /// `closed` (`delta_n < 0` closed, `delta_n >= 0` open) and a strictly smaller effective
    /// opening than `delta_max`: the loading test `delta >= delta_max` is never met.
    fn stays_linear(&self, history: &[f64], jump: [f64; 2], error: [f64; 2], closed: bool) -> bool {
        let delta_max = history[0];
        let [ds, dn] = jump;
        let [es, en] = error;
        let sliding = self.beta * (ds.abs() + es);
        let unloading = sliding.hypot(dn.abs() + en) < delta_max;
        if !self.contact {
            return unloading;
        }
        if closed {
            dn + en < 0.0 && (self.contact_shear == ContactShear::Penalty || sliding < delta_max)
        } else {
            dn - en >= 0.0 && unloading
        }
    }

    /// IMPL-EX's frozen branch: open, the unloading secant of eq. 24 at `delta_max`,
    /// `k(delta_max) diag(beta^2, 1)` (for a virgin point the initial stiffness); closed,
    /// the contact branch (eq. 47: `k_p I`; with [`ContactShear::Cohesive`] the sliding's
    /// secant and the normal penalty). Contact off: always the open secant.
    fn frozen_secant(&self, history: &[f64], closed: bool, length: f64) -> Option<Matrix2<f64>> {
        let k = self.unloading_secant(&CohesiveHistory {
            delta_max: history[0],
        });
        let shear = k * self.beta * self.beta;
        Some(match (self.contact && closed, self.contact_shear) {
            (false, _) => Matrix2::new(shear, 0.0, 0.0, k),
            (true, ContactShear::Penalty) => {
                Matrix2::from_diagonal_element(self.contact_stiffness(length))
            }
            (true, ContactShear::Cohesive) => {
                Matrix2::new(shear, 0.0, 0.0, self.contact_stiffness(length))
            }
        })
    }

    /// `sigma_c`, the peak of the envelope's normal traction.
    fn traction_scale(&self) -> f64 {
        self.sigma_c
    }

    /// `delta_max` extrapolated; it never decreases (`h_n >= h_{n-1}` and `ratio >= 0`).
    fn extrapolate(&self, committed: &[f64], previous: &[f64], ratio: f64, out: &mut [f64]) {
        super::law::extrapolate_growth(committed, previous, ratio, out);
    }

    /// `delta_max` is a non-negative opening.
    fn history_is_valid(&self, history: &[f64]) -> bool {
        super::law::openings_are_valid(history)
    }

    /// `delta/delta_c` with the opening the law uses at `jump` (eq. 20; `beta |delta_s|`
    /// at a closed point with [`ContactShear::Cohesive`]), `delta_max/delta_c`, and the
    /// damage as the loss of secant stiffness of unloading (eq. 24) against the virgin one:
    /// ```text
    /// D = 1 - t_max / (e sigma_c delta_max/delta_c) = 1 - exp(-delta_max/delta_c)
    /// ```
    /// (0 virgin, `1 - 1/e` at the peak of the envelope, tends to 1 as the crack opens).
    fn measures(&self, history: &[f64], jump: [f64; 2], length: f64) -> Option<PointMeasures> {
        let h = CohesiveHistory {
            delta_max: history[0],
        };
        let point = self.evaluate(&h, jump, length);
        let max_ratio = h.delta_max / self.delta_c;
        Some(PointMeasures {
            opening_ratio: point.opening / self.delta_c,
            max_opening_ratio: max_ratio,
            max_opening: h.delta_max,
            damage: -(-max_ratio).exp_m1(),
        })
    }

    /// `1 - exp(-delta_max/delta_c)` and `delta_max`, without evaluating the law.
    fn history_measures(&self, history: &[f64], _length: f64) -> Option<(f64, f64)> {
        let delta_max = history[0];
        Some((-(-delta_max / self.delta_c).exp_m1(), delta_max))
    }

    /// `beta^2 (e sigma_c/delta_c) D`, `D = 1 - exp(-delta_max/delta_c)`: the virgin shear
    /// stiffness less the unloading secant's, `beta^2 (K_0 - k(delta_max))`.
    fn damaged_shear_stiffness(&self, history: &[f64], _length: f64) -> Option<f64> {
        let damage = -(-history[0] / self.delta_c).exp_m1();
        Some(self.beta * self.beta * self.initial_stiffness() * damage)
    }

    /// With the paper's contact law read from the gap at every evaluation, closed points
    /// that slide can leave the RVE without equilibrium (see the module docs); the message
    /// names the remedy. (The solver asks only when it did not hold the status.)
    fn failure_hint(&self, closed_points: usize) -> Option<String> {
        (self.holds_contact_status() && closed_points > 0).then(|| {
            format!(
                "; {closed_points} ITZ points are closed at the last iterate: with the paper's \
                 contact law (materials.itz.contact_shear = \"penalty\") read at every \
                 iteration (solver.contact_status = \"per_iteration\") the shear traction \
                 jumps at closure and sliding closed points can leave the RVE without \
                 equilibrium; solver.contact_status = \"active_set\" (the default) holds \
                 the status within a Newton iteration"
            )
        })
    }
}

/// The cohesive-contact law of the ITZ (paper eqs. 20-25, 36-37).
#[derive(Clone, Copy, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ItzSpec {
    /// Maximum cohesive normal traction.
    pub sigma_c: f64,
    /// Characteristic opening.
    pub delta_c: f64,
    /// Shear-to-normal weight in the effective opening (eq. 20).
    pub beta: f64,
    pub penalty: PenaltySpec,
    /// What carries the shear of a closed point: `"penalty"` (the paper's eq. 47, default)
    /// or `"cohesive"` (Ortiz-Pandolfi: normal penalty only, continuous at closure). See
    /// [`ContactShear`].
    #[serde(default)]
    pub contact_shear: ContactShear,
}

/// Contact penalty, exactly one of:
/// * `{ lambda_p = ... }`: the paper's `t = lambda_p l_e delta` (eqs. 36-37), the form the
///   shipped scenes use, so they reproduce the paper;
/// * `{ stiffness = ... }`: a mesh-independent stiffness per unit area, `t = k delta`.
#[derive(Clone, Copy, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct PenaltySpec {
    #[serde(default)]
    pub lambda_p: Option<f64>,
    #[serde(default)]
    pub stiffness: Option<f64>,
}

impl InterfaceLawSpec for ItzSpec {
    fn validate(&self, key: &str) -> Result<()> {
        let named = |constant: &str| format!("materials.{key}.{constant}");
        require_positive(&named("sigma_c"), self.sigma_c)?;
        require_positive(&named("delta_c"), self.delta_c)?;
        require_positive(&named("beta"), self.beta)?;
        match (self.penalty.lambda_p, self.penalty.stiffness) {
            (Some(l), None) => require_positive(&named("penalty.lambda_p"), l),
            (None, Some(k)) => require_positive(&named("penalty.stiffness"), k),
            _ => Err(Error::scene(
                named("penalty"),
                "give exactly one of `lambda_p` (paper, per length) or `stiffness` (per area)",
            )),
        }
    }

    fn build(&self, contact: bool) -> Arc<dyn InterfaceLaw> {
        Arc::new(CohesiveLaw {
            sigma_c: self.sigma_c,
            delta_c: self.delta_c,
            beta: self.beta,
            penalty: match (self.penalty.lambda_p, self.penalty.stiffness) {
                (Some(lambda_p), _) => Penalty::PerLength { lambda_p },
                (None, Some(stiffness)) => Penalty::PerArea { stiffness },
                (None, None) => Penalty::PerArea { stiffness: 0.0 },
            },
            contact,
            contact_shear: self.contact_shear,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DC: f64 = 2e-4;
    const LEN: f64 = 0.5;

    fn law(contact: bool) -> CohesiveLaw {
        CohesiveLaw {
            sigma_c: 4.0,
            delta_c: DC,
            beta: 0.707,
            penalty: Penalty::PerLength { lambda_p: 1e7 },
            contact,
            contact_shear: ContactShear::Penalty,
        }
    }

    /// `trial_history_as` writes what `respond_as` writes, bit for bit, on every branch:
    /// loading, unloading, closed and held open or closed against the gap, both contact
    /// shear laws, contact off, and a non-finite jump.
    #[test]
    fn trial_history_alone_is_respond_as_history() {
        let jumps = [
            [3e-5, 2e-5],
            [-4e-5, 1e-6],
            [1e-6, -3e-5],
            [2e-4, -1e-7],
            [0.0, 0.0],
            [5e-4, 3e-4],
            [f64::NAN, 1e-5],
        ];
        let mut checked = 0;
        for contact in [false, true] {
            for shear in [ContactShear::Penalty, ContactShear::Cohesive] {
                let l = CohesiveLaw {
                    contact_shear: shear,
                    ..law(contact)
                };
                for delta_max in [0.0, 1e-5, 4e-5, DC, 3.0 * DC] {
                    for jump in jumps {
                        for closed in [false, true] {
                            let (mut full, mut alone) = ([-1.0], [-2.0]);
                            l.respond_as(
                                &[delta_max],
                                &mut full,
                                jump,
                                LEN,
                                TangentKind::Consistent,
                                closed,
                            );
                            l.trial_history_as(&[delta_max], &mut alone, jump, LEN, closed);
                            assert_eq!(
                                full[0].to_bits(),
                                alone[0].to_bits(),
                                "contact {contact}, {shear:?}, delta_max {delta_max}, jump {jump:?}, closed {closed}"
                            );
                            checked += 1;
                        }
                    }
                }
            }
        }
        assert_eq!(checked, 2 * 2 * 5 * 7 * 2);
    }

    /// History committed after loading to effective opening `delta`.
    fn loaded_to(delta: f64) -> CohesiveHistory {
        CohesiveHistory { delta_max: delta }
    }

    /// Central finite difference of the traction, step `h` on each jump component.
    fn fd_tangent(l: &CohesiveLaw, h: &CohesiveHistory, jump: [f64; 2], step: f64) -> Matrix2<f64> {
        let mut c = Matrix2::zeros();
        for j in 0..2 {
            let (mut jp, mut jm) = (jump, jump);
            jp[j] += step;
            jm[j] -= step;
            let tp = l.evaluate(h, jp, LEN).traction;
            let tm = l.evaluate(h, jm, LEN).traction;
            c.set_column(j, &((tp - tm) / (2.0 * step)));
        }
        c
    }

    /// Norm-relative error of the analytic tangent against central FD; also checks the
    /// branch is the expected one at the point and at the perturbed points.
    fn check_tangent(
        l: &CohesiveLaw,
        h: &CohesiveHistory,
        jump: [f64; 2],
        step: f64,
        branch: Branch,
    ) {
        let p = l.evaluate(h, jump, LEN);
        assert_eq!(p.branch, branch, "jump {jump:?}");
        for j in 0..2 {
            for sign in [-1.0, 1.0] {
                let mut jj = jump;
                jj[j] += sign * step;
                assert_eq!(l.evaluate(h, jj, LEN).branch, branch, "FD crosses a branch");
            }
        }
        let fd = fd_tangent(l, h, jump, step);
        let err = (p.tangent - fd).norm() / p.tangent.norm();
        assert!(
            err < 1e-6,
            "jump {jump:?}: rel err {err:e}\n{}\n{fd}",
            p.tangent
        );
        assert!((p.tangent - p.tangent.transpose()).norm() <= 1e-15 * p.tangent.norm());
    }

    #[test]
    fn tangent_virgin_loading_pre_peak() {
        let l = law(true);
        let h = CohesiveHistory::default();
        check_tangent(&l, &h, [0.3 * DC, 0.4 * DC], 1e-6 * DC, Branch::Loading);
        check_tangent(&l, &h, [-0.5 * DC, 0.1 * DC], 1e-6 * DC, Branch::Loading);
        check_tangent(&l, &h, [0.0, 0.7 * DC], 1e-6 * DC, Branch::Loading);
    }

    #[test]
    fn tangent_post_peak_loading() {
        let l = law(true);
        let h = loaded_to(1.2 * DC);
        check_tangent(&l, &h, [1.1 * DC, 1.5 * DC], 1e-6 * DC, Branch::Loading);
        check_tangent(&l, &h, [-3.0 * DC, 0.2 * DC], 1e-6 * DC, Branch::Loading);
        // Softening: the normal stiffness is negative past delta_c in pure mode I.
        let p = l.evaluate(&h, [0.0, 1.5 * DC], LEN);
        assert!(p.tangent[(1, 1)] < 0.0);
    }

    #[test]
    fn tangent_unloading() {
        let l = law(true);
        let h = loaded_to(1.5 * DC);
        check_tangent(&l, &h, [0.4 * DC, 0.5 * DC], 1e-6 * DC, Branch::Unloading);
        check_tangent(&l, &h, [-0.4 * DC, 0.01 * DC], 1e-6 * DC, Branch::Unloading);
        let k = l.envelope(h.delta_max) / h.delta_max; // eq. 24: t_max / delta_max
        let p = l.evaluate(&h, [0.4 * DC, 0.5 * DC], LEN);
        let expected = Matrix2::new(k * 0.707 * 0.707, 0.0, 0.0, k);
        assert!((p.tangent - expected).norm() <= 1e-15 * expected.norm());
    }

    #[test]
    fn tangent_contact_both_penalties() {
        for penalty in [
            Penalty::PerLength { lambda_p: 1e7 },
            Penalty::PerArea { stiffness: 3e6 },
        ] {
            let l = CohesiveLaw {
                penalty,
                ..law(true)
            };
            for h in [CohesiveHistory::default(), loaded_to(2.0 * DC)] {
                check_tangent(&l, &h, [0.2 * DC, -0.1 * DC], 1e-6 * DC, Branch::Contact);
                let p = l.evaluate(&h, [0.2 * DC, -0.1 * DC], LEN);
                let kp = l.contact_stiffness(LEN);
                assert_eq!(p.tangent, Matrix2::from_diagonal_element(kp));
                let expected = Vector2::new(kp * (0.2 * DC), kp * (-0.1 * DC));
                assert!((p.traction - expected).norm() <= 1e-15 * expected.norm());
                assert_eq!(p.history, h);
            }
        }
        let l = law(true);
        assert_eq!(l.contact_stiffness(0.5), 0.5e7);
    }

    /// `ContactShear::Cohesive` at a closed point: normal penalty, sliding on the cohesive
    /// law of `beta |delta_s|` (loading advances the history, unloading keeps it), exact
    /// tangent, and the secant matrix of the solver's secant iterations.
    #[test]
    fn cohesive_contact_shear_tangent_and_history() {
        let l = CohesiveLaw {
            contact_shear: ContactShear::Cohesive,
            ..law(true)
        };
        let kp = l.contact_stiffness(LEN);
        let damaged = loaded_to(1.5 * DC);
        // (history, jump, branch of the sliding)
        for (h, jump, sliding_loads) in [
            (CohesiveHistory::default(), [0.4 * DC, -0.1 * DC], true),
            (damaged, [3.0 * DC, -0.2 * DC], true), // beta |ds| = 2.1 dc > 1.5 dc
            (damaged, [0.5 * DC, -0.2 * DC], false),
        ] {
            check_tangent(&l, &h, jump, 1e-6 * DC, Branch::Contact);
            let p = l.evaluate(&h, jump, LEN);
            let sliding = l.evaluate(&h, [jump[0], 0.0], LEN);
            assert_eq!(p.traction.x, sliding.traction.x);
            assert_eq!(p.traction.y, kp * jump[1]);
            assert_eq!(p.tangent[(0, 1)], 0.0);
            assert_eq!(p.tangent[(1, 0)], 0.0);
            assert_eq!(p.tangent[(1, 1)], kp);
            assert!((p.opening - l.beta * jump[0].abs()).abs() < 1e-18);
            if sliding_loads {
                assert_eq!(p.history.delta_max, p.opening);
            } else {
                assert_eq!(p.history, h);
            }
            let k = l.envelope(p.history.delta_max) / p.history.delta_max;
            let secant = l.secant_matrix(&p);
            assert!((secant[(0, 0)] - k * l.beta * l.beta).abs() <= 1e-12 * k);
            assert_eq!(secant[(1, 1)], kp);
        }
    }

    /// The traction is continuous across closure (`delta_n = 0`) with
    /// `ContactShear::Cohesive`, and jumps in shear with the paper's `Penalty` (by
    /// `(k_p - k beta^2) delta_s`, the reason the option exists).
    #[test]
    fn closure_continuity_of_the_two_contact_shears() {
        let damaged = loaded_to(1.5 * DC);
        let ds = 0.5 * DC;
        let tiny = 1e-12 * DC;
        for (shear, continuous) in [
            (ContactShear::Cohesive, true),
            (ContactShear::Penalty, false),
        ] {
            let l = CohesiveLaw {
                contact_shear: shear,
                ..law(true)
            };
            let open = l.evaluate(&damaged, [ds, tiny], LEN);
            let closed = l.evaluate(&damaged, [ds, -tiny], LEN);
            assert_eq!(open.branch, Branch::Unloading);
            assert_eq!(closed.branch, Branch::Contact);
            let jump = (open.traction - closed.traction).norm() / open.traction.norm();
            if continuous {
                assert!(jump < 1e-6, "{shear:?}: jump {jump:e}");
            } else {
                let k = l.envelope(damaged.delta_max) / damaged.delta_max;
                let expected = (l.contact_stiffness(LEN) - k * l.beta * l.beta) * ds;
                assert!(
                    ((closed.traction.x - open.traction.x) - expected).abs()
                        < 1e-9 * expected.abs()
                );
            }
        }
    }

    /// `evaluate_as` with the status the gap gives is `evaluate`, bit for bit, on every
    /// branch and both contact shears.
    #[test]
    fn held_status_matching_the_gap_is_evaluate() {
        for shear in [ContactShear::Penalty, ContactShear::Cohesive] {
            let l = CohesiveLaw {
                contact_shear: shear,
                ..law(true)
            };
            for h in [CohesiveHistory::default(), loaded_to(1.5 * DC)] {
                for jump in [
                    [0.3 * DC, 0.4 * DC],
                    [3.0 * DC, 0.2 * DC],
                    [0.2 * DC, -0.1 * DC],
                    [-2.5 * DC, -0.3 * DC],
                    [0.1 * DC, 0.0],
                    [0.1 * DC, -0.0],
                ] {
                    let p = l.evaluate(&h, jump, LEN);
                    assert_eq!(l.evaluate_as(&h, jump, LEN, l.is_closed(jump)), p);
                    assert_eq!(l.is_closed(jump), p.branch == Branch::Contact);
                }
            }
        }
        assert!(!law(false).is_closed([0.0, -DC]));
        assert!(law(true).holds_contact_status());
        assert!(!law(false).holds_contact_status());
        let cohesive = CohesiveLaw {
            contact_shear: ContactShear::Cohesive,
            ..law(true)
        };
        assert!(!cohesive.holds_contact_status());
    }

    /// The paper's law held closed with an open gap: the penalty on both components (the
    /// normal one tensile), history frozen; held open with a closed gap: the normal
    /// penalty and the cohesive law of the sliding, on the sliding's branch, whose history
    /// advances with the sliding only (compression does not damage). Exact symmetric
    /// tangents; the secant matrix keeps the normal penalty.
    #[test]
    fn held_status_against_the_gap() {
        let l = law(true);
        let kp = l.contact_stiffness(LEN);
        for h in [CohesiveHistory::default(), loaded_to(1.5 * DC)] {
            let jump = [0.4 * DC, 0.2 * DC];
            let p = l.evaluate_as(&h, jump, LEN, true);
            assert_eq!(p.branch, Branch::Contact);
            assert!(p.penalty_normal);
            assert_eq!(p.traction, Vector2::new(kp * jump[0], kp * jump[1]));
            assert_eq!(p.tangent, Matrix2::from_diagonal_element(kp));
            assert_eq!(p.history, h);

            for (jump, loads) in [
                ([0.4 * DC, -0.2 * DC], false),
                ([3.0 * DC, -0.2 * DC], true),
            ] {
                let p = l.evaluate_as(&h, jump, LEN, false);
                let sliding = l.evaluate(&h, [jump[0], 0.0], LEN);
                assert_eq!(p.branch, sliding.branch);
                assert!(p.penalty_normal);
                assert_eq!(p.traction.x, sliding.traction.x);
                assert_eq!(p.traction.y, kp * jump[1]);
                assert!((p.opening - l.beta * jump[0].abs()).abs() < 1e-18);
                let virgin_loads = h.delta_max == 0.0 || loads;
                if virgin_loads {
                    assert_eq!(p.history.delta_max, p.opening);
                } else {
                    assert_eq!(p.history, h);
                }
                // FD of the held law (the status does not follow the perturbed gap).
                let mut fd = Matrix2::zeros();
                let step = 1e-6 * DC;
                for j in 0..2 {
                    let (mut jp, mut jm) = (jump, jump);
                    jp[j] += step;
                    jm[j] -= step;
                    let tp = l.evaluate_as(&h, jp, LEN, false).traction;
                    let tm = l.evaluate_as(&h, jm, LEN, false).traction;
                    fd.set_column(j, &((tp - tm) / (2.0 * step)));
                }
                assert!((p.tangent - fd).norm() < 1e-6 * p.tangent.norm());
                assert_eq!(p.tangent, p.tangent.transpose());
                let secant = l.secant_matrix(&p);
                assert_eq!(secant[(1, 1)], kp);
            }
        }
    }

    /// With the status held, the traction is continuous across `delta_n = 0` (for either
    /// status), where the status read from the gap jumps in shear.
    #[test]
    fn held_status_is_continuous_at_closure() {
        let l = law(true);
        let damaged = loaded_to(1.5 * DC);
        let (ds, tiny) = (0.5 * DC, 1e-12 * DC);
        for closed in [false, true] {
            let open = l.evaluate_as(&damaged, [ds, tiny], LEN, closed);
            let shut = l.evaluate_as(&damaged, [ds, -tiny], LEN, closed);
            let jump = (open.traction - shut.traction).norm() / open.traction.norm();
            assert!(jump < 1e-6, "held {closed}: jump {jump:e}");
        }
    }

    #[test]
    fn tangent_near_zero_opening() {
        let l = law(true);
        let h = CohesiveHistory::default();
        let d = 1e-9 * DC;
        // Pure sliding, pure opening, and mixed with both signs of shear.
        for jump in [
            [d, 0.0],
            [-d, 0.0],
            [0.0, d],
            [0.6 * d, 0.8 * d],
            [-0.6 * d, 0.8 * d],
        ] {
            let step = 1e-6 * d;
            if jump[1] == 0.0 {
                // The FD in delta_n would enter contact at -step: check the law with
                // contact off there (the open branch is the same function).
                check_tangent(&law(false), &h, jump, step, Branch::Loading);
            } else {
                check_tangent(&l, &h, jump, step, Branch::Loading);
            }
        }
    }

    #[test]
    fn tangent_exactly_zero_opening() {
        let k0 = law(true).initial_stiffness();
        let b2 = 0.707 * 0.707;
        let expected = Matrix2::new(k0 * b2, 0.0, 0.0, k0);
        let h = CohesiveHistory::default();
        // Contact on: delta_n == 0 counts as open, the tangent is the cohesive one.
        let p = law(true).evaluate(&h, [0.0, 0.0], LEN);
        assert_eq!(p.branch, Branch::Loading);
        assert_eq!(p.traction, Vector2::zeros());
        assert!((p.tangent - expected).norm() <= 1e-15 * expected.norm());
        assert_eq!(p.history, CohesiveHistory::default());
        // -0.0 is open too.
        assert_eq!(
            law(true).evaluate(&h, [0.0, -0.0], LEN).branch,
            Branch::Loading
        );
        // Contact off: the law is smooth enough at 0 for a central FD (error O(step)).
        check_tangent(&law(false), &h, [0.0, 0.0], 1e-9 * DC, Branch::Loading);
        // Contact on: one-sided check of the normal column (opening side).
        let step = 1e-9 * DC;
        let tp = law(true).evaluate(&h, [0.0, step], LEN).traction;
        let col = tp / step;
        assert!((col - expected.column(1)).norm() < 1e-6 * expected.norm());
    }

    #[test]
    fn tiny_opening_is_exact() {
        let l = law(true);
        let h = CohesiveHistory::default();
        let k0 = l.initial_stiffness();
        let b2 = 0.707 * 0.707;
        for jump in [
            [1e-300, 0.0],
            [0.0, 1e-300],
            [3e-310, 4e-310],
            [-1e-300, 1e-300],
        ] {
            let p = l.evaluate(&h, jump, LEN);
            assert!(p
                .traction
                .iter()
                .chain(p.tangent.iter())
                .all(|v| v.is_finite()));
            assert_eq!(p.branch, Branch::Loading);
            let t_expected = Vector2::new(k0 * b2 * jump[0], k0 * jump[1]);
            assert!((p.traction - t_expected).norm() <= 1e-14 * t_expected.norm());
            let c_expected = Matrix2::new(k0 * b2, 0.0, 0.0, k0);
            assert!((p.tangent - c_expected).norm() <= 1e-14 * c_expected.norm());
            assert!(p.opening > 0.0 && p.history.delta_max == p.opening);
        }
    }

    #[test]
    fn peak_and_envelope() {
        let l = law(true);
        assert!((l.envelope(DC) - 4.0).abs() < 1e-14);
        assert!(l.envelope(0.999 * DC) < 4.0 && l.envelope(1.001 * DC) < 4.0);
        // Pure mode I loading reproduces the envelope; effective traction eq. 22.
        let p = l.evaluate(&CohesiveHistory::default(), [0.0, DC], LEN);
        assert!((p.traction[1] - 4.0).abs() < 1e-14);
        let p = l.evaluate(&CohesiveHistory::default(), [0.8 * DC, 0.5 * DC], LEN);
        let t_eff = (p.traction[0] * p.traction[0] / (0.707 * 0.707)
            + p.traction[1] * p.traction[1])
            .sqrt();
        assert!((t_eff - l.envelope(p.opening)).abs() < 1e-12 * t_eff);
        assert!((l.t_max(&p.history) - t_eff).abs() < 1e-12 * t_eff);
    }

    #[test]
    fn traction_continuous_at_delta_max() {
        let l = law(true);
        for dmax in [0.3 * DC, DC, 2.5 * DC] {
            let h = loaded_to(dmax);
            // Direction (beta ds, dn) = dmax (0.6, 0.8).
            let dir = [0.6 / 0.707, 0.8];
            let at = |f: f64| {
                let d = dmax * f;
                l.evaluate(&h, [dir[0] * d, dir[1] * d], LEN)
            };
            let (below, on, above) = (at(1.0 - 1e-12), at(1.0), at(1.0 + 1e-12));
            assert_eq!(below.branch, Branch::Unloading);
            assert_eq!(on.branch, Branch::Loading);
            assert_eq!(above.branch, Branch::Loading);
            let scale = on.traction.norm();
            assert!((below.traction - on.traction).norm() < 1e-10 * scale);
            assert!((above.traction - on.traction).norm() < 1e-10 * scale);
            // The history does not move when reloading exactly to delta_max.
            assert!((on.history.delta_max - dmax).abs() <= 1e-15 * dmax);
            assert!((l.t_max(&on.history) - l.t_max(&h)).abs() <= 1e-14 * l.t_max(&h));
        }
    }

    #[test]
    fn load_unload_reload_contact_sequence() {
        let l = law(true);
        let mut committed = CohesiveHistory::default();
        let dir = |d: f64| [0.6 / 0.707 * d, 0.8 * d];
        let mut step = |jump: [f64; 2], expected: Branch| {
            let p = l.evaluate(&committed, jump, LEN);
            assert_eq!(p.branch, expected, "jump {jump:?}");
            committed = p.history;
            (p, committed)
        };
        // Load to 0.5 delta_c and 1.5 delta_c.
        let (_, h) = step(dir(0.5 * DC), Branch::Loading);
        assert!((h.delta_max - 0.5 * DC).abs() < 1e-15);
        let (_, h15) = step(dir(1.5 * DC), Branch::Loading);
        assert!((h15.delta_max - 1.5 * DC).abs() < 1e-15);
        assert!(l.t_max(&h15) < 4.0);
        // Unload to 0.7 delta_c: secant, history unchanged.
        let (p, h) = step(dir(0.7 * DC), Branch::Unloading);
        assert_eq!(h, h15);
        let t_eff = (p.traction[0] / 0.707).hypot(p.traction[1]);
        assert!((t_eff - l.t_max(&h15) / h15.delta_max * 0.7 * DC).abs() < 1e-12);
        // Close the crack with some sliding: contact, history frozen.
        let (p, h) = step([0.5 * DC, -0.01 * DC], Branch::Contact);
        assert_eq!(h, h15);
        assert!(p.traction[1] < 0.0);
        // Reopen below delta_max: secant again; reload past it: the envelope.
        let (_, h) = step(dir(1.2 * DC), Branch::Unloading);
        assert_eq!(h, h15);
        let (p, h) = step(dir(2.0 * DC), Branch::Loading);
        assert!((h.delta_max - 2.0 * DC).abs() < 1e-15);
        assert!((p.opening - 2.0 * DC).abs() < 1e-15);
    }

    #[test]
    fn contact_off_is_symmetric() {
        let l = law(false);
        let h = loaded_to(0.8 * DC);
        for (hist, branch) in [
            (CohesiveHistory::default(), Branch::Loading),
            (h, Branch::Unloading),
        ] {
            let up = l.evaluate(&hist, [0.2 * DC, 0.3 * DC], LEN);
            let down = l.evaluate(&hist, [0.2 * DC, -0.3 * DC], LEN);
            assert_eq!(up.branch, branch);
            assert_eq!(down.branch, branch);
            assert_eq!(down.traction, Vector2::new(up.traction[0], -up.traction[1]));
            check_tangent(&l, &hist, [0.2 * DC, -0.3 * DC], 1e-6 * DC, branch);
        }
        // Compression damages the interface when contact is off.
        let p = l.evaluate(&CohesiveHistory::default(), [0.0, -1.3 * DC], LEN);
        assert!((p.history.delta_max - 1.3 * DC).abs() < 1e-15);
    }

    #[test]
    fn zero_beta_has_no_shear_resistance() {
        let l = CohesiveLaw {
            beta: 0.0,
            ..law(true)
        };
        let p = l.evaluate(&CohesiveHistory::default(), [5.0 * DC, 0.0], LEN);
        assert_eq!(p.traction, Vector2::zeros());
        assert_eq!(p.opening, 0.0);
        assert!(p.tangent.iter().all(|v| v.is_finite()));
        check_tangent(
            &l,
            &CohesiveHistory::default(),
            [0.3 * DC, 0.5 * DC],
            1e-6 * DC,
            Branch::Loading,
        );
    }

    #[test]
    fn damage_is_the_secant_stiffness_loss() {
        let l = law(true);
        for dm in [0.0, 0.3 * DC, DC, 4.0 * DC] {
            let h = loaded_to(dm);
            let m = l.measures(&[dm], [0.0, 0.5 * dm], LEN).unwrap();
            assert_eq!(m.max_opening_ratio, dm / DC);
            assert!((m.opening_ratio - 0.5 * dm / DC).abs() <= 1e-15 * (1.0 + dm / DC));
            let expected = if dm == 0.0 {
                0.0
            } else {
                1.0 - l.t_max(&h) / (l.initial_stiffness() * dm)
            };
            assert!(
                (m.damage - expected).abs() <= 1e-14,
                "{dm}: {} vs {expected}",
                m.damage
            );
        }
    }

    /// `stays_linear` is conservative: wherever it holds for a jump and an error box, every
    /// jump of the box (corners and centre) evaluates on a branch that is not loading, with
    /// the contact status asked for, the history unchanged and the traction linear through
    /// the origin (`t = C delta` with the branch's constant tangent). It refuses the
    /// boundaries: `delta = delta_max`, `delta_n = 0` for a closed status, a box straddling
    /// a boundary, a virgin open point, and non-finite jumps.
    #[test]
    fn stays_linear_is_conservative() {
        let mut checked = 0;
        for contact_shear in [ContactShear::Penalty, ContactShear::Cohesive] {
            for contact in [true, false] {
                let l = CohesiveLaw {
                    contact_shear,
                    ..law(contact)
                };
                for dm in [0.0, 0.5 * DC, 3.0 * DC] {
                    let h = loaded_to(dm);
                    for i in -6..=6 {
                        for k in -6..=6 {
                            let jump = [0.4 * DC * f64::from(i), 0.3 * DC * f64::from(k)];
                            let error = [1e-3 * DC, 2e-3 * DC];
                            for closed in [true, false] {
                                if !l.stays_linear(&[dm], jump, error, closed) {
                                    continue;
                                }
                                for (a, b) in [
                                    (-1.0, -1.0),
                                    (-1.0, 1.0),
                                    (1.0, -1.0),
                                    (1.0, 1.0),
                                    (0.0, 0.0),
                                ] {
                                    let j = [jump[0] + a * error[0], jump[1] + b * error[1]];
                                    let p = l.evaluate(&h, j, LEN);
                                    assert_ne!(p.branch, Branch::Loading, "{j:?} {dm}");
                                    assert_eq!(l.is_closed(j), closed && contact, "{j:?}");
                                    assert_eq!(p.history, h);
                                    let linear = p.tangent * Vector2::new(j[0], j[1]);
                                    assert!(
                                        (linear - p.traction).norm() <= 1e-12 * p.traction.norm()
                                    );
                                    checked += 1;
                                }
                            }
                        }
                    }
                }
            }
        }
        assert!(checked > 1000, "{checked} jumps checked");
        let l = law(true);
        let h = [2.0 * DC];
        let boundary = 2.0 * DC / 0.707;
        assert!(l.stays_linear(&h, [0.99 * boundary, 0.0], [0.0; 2], false));
        assert!(
            !l.stays_linear(&h, [boundary, 0.0], [0.0; 2], false),
            "delta = delta_max"
        );
        assert!(!l.stays_linear(&h, [0.99 * boundary, 0.0], [0.02 * boundary, 0.0], false));
        assert!(
            !l.stays_linear(&h, [0.0, 0.0], [0.0; 2], true),
            "delta_n = 0 is open"
        );
        assert!(l.stays_linear(&h, [0.0, 0.0], [0.0; 2], false));
        assert!(
            !l.stays_linear(&h, [0.0, -1e-9], [0.0, 2e-9], true),
            "box straddles the gap"
        );
        assert!(
            !l.stays_linear(&[0.0], [1e-9, 1e-9], [0.0; 2], false),
            "virgin open point"
        );
        assert!(!l.stays_linear(&h, [f64::NAN, 0.0], [0.0; 2], false));
        assert!(!l.stays_linear(&h, [0.0, f64::NAN], [0.0; 2], true));
    }
}

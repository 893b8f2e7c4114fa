//! The seam between the interface element and its constitutive law.
//!
//! A law sees one quadrature point at a time, in the local axes of the element (`s`
//! sliding, `n` normal, `delta_n > 0` opening), and declares the size of its history per
//! point ([`InterfaceLaw::history_len`], pmsim's `n_int_vars`): the element and the solver
//! keep the history as one flat `f64` slice, element-major then point-major, and never
//! read a law's parameters. A new law is one file in this folder implementing the trait,
//! plus its registration where the model translates the scene (`model::from_scene`).

use std::sync::Arc;

use nalgebra::{Matrix2, Vector2};

/// Which matrix a law returns with its traction.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TangentKind {
    /// The consistent tangent `dt/d delta` (eqs. 45-47 for the paper's law).
    #[default]
    Consistent,
    /// A positive definite matrix for the secant iterations of the solver: `S` with
    /// `t = S delta` for a law without friction; a law with friction adds the consistent
    /// tangent of its frictional shear (not symmetric where a point slides; the residual
    /// always takes the traction).
    Secant,
}

/// Which branch of its law a point is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Branch {
    /// The history advances (the loading envelope, eq. 23).
    Loading,
    /// A reversible branch with the history unchanged (unloading to the origin, eq. 24;
    /// every point of a law without history).
    Unloading,
    /// Contact of a closed point (eqs. 36-37), sticking if the law has friction.
    Contact,
    /// A closed point sliding at the Coulomb limit of a law with friction
    /// ([`super::Frictional`]): its consistent tangent is not symmetric.
    Sliding,
}

/// The response of a law at one point for a trial jump.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LawPoint {
    /// Local traction `[t_s, t_n]`.
    pub traction: Vector2<f64>,
    /// The matrix of the requested [`TangentKind`]: symmetric, but for the consistent
    /// tangent of a [`Branch::Sliding`] point.
    pub matrix: Matrix2<f64>,
    pub branch: Branch,
}

/// Post-processing measures of one point of a law with a characteristic opening.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointMeasures {
    /// Effective opening over the characteristic opening, `delta/delta_c` (eq. 20).
    pub opening_ratio: f64,
    /// Largest effective opening reached over the characteristic one, `delta_max/delta_c`.
    pub max_opening_ratio: f64,
    /// Largest effective opening reached, `delta_max` (length units).
    pub max_opening: f64,
    /// Secant stiffness loss in `[0, 1)`: `1 - k_unloading / k_virgin`.
    pub damage: f64,
}

/// A traction-separation law of a zero-thickness interface.
pub trait InterfaceLaw: std::fmt::Debug + Send + Sync {
    /// Internal variables per quadrature point.
    fn history_len(&self) -> usize;

    /// The traction and matrix at the local jump `[delta_s, delta_n]` from the committed
    /// history `committed` of the point; writes the point's trial history into `trial`
    /// (both of [`InterfaceLaw::history_len`] values). `length` is the element's reference
    /// length. Pure and allocation free; non-finite jumps give non-finite tractions.
    fn respond(
        &self,
        committed: &[f64],
        trial: &mut [f64],
        jump: [f64; 2],
        length: f64,
        kind: TangentKind,
    ) -> LawPoint;

    /// Whether the law switches a point between two laws by the sign of its gap (the
    /// paper's contact: closed iff `delta_n < 0`) with a traction that jumps at the
    /// switch, so that the solver holds that *contact status* within a Newton iteration
    /// and reads it again between iterations (`solver::contact`). `false`: the status is
    /// never held and [`InterfaceLaw::respond_as`] is [`InterfaceLaw::respond`].
    fn has_contact_status(&self) -> bool {
        false
    }

    /// The contact status the gap of `jump` gives: `true` for closed.
    fn is_closed(&self, _jump: [f64; 2]) -> bool {
        false
    }

    /// [`InterfaceLaw::respond`] with the contact status held at `closed` instead of read
    /// from the gap of `jump`; the same as `respond` where `closed == is_closed(jump)`.
    /// With the status held, the traction must be continuous in the jump and the matrix
    /// symmetric.
    fn respond_as(
        &self,
        committed: &[f64],
        trial: &mut [f64],
        jump: [f64; 2],
        length: f64,
        kind: TangentKind,
        _closed: bool,
    ) -> LawPoint {
        self.respond(committed, trial, jump, length, kind)
    }

    /// The trial history [`InterfaceLaw::respond_as`] writes into `trial`, bit for bit,
    /// without its traction and matrix: IMPL-EX forms the implicit history from a step's
    /// jumps and reads nothing else (`solver::implex::finish_step`, at every ITZ point of
    /// every call). The default calls `respond_as`.
    fn trial_history_as(
        &self,
        committed: &[f64],
        trial: &mut [f64],
        jump: [f64; 2],
        length: f64,
        closed: bool,
    ) {
        self.respond_as(
            committed,
            trial,
            jump,
            length,
            TangentKind::Consistent,
            closed,
        );
    }

    /// Whether a point whose history goes from `start` to `trial` within a step passes
    /// the peak of its strength there: the solver then refuses the tangent predictor,
    /// which would carry it past a limit point of the RVE on the pre-peak branch.
    fn passes_peak(&self, _start: &[f64], _trial: &[f64]) -> bool {
        false
    }

    /// Whether every jump within `error` (a bound per component) of `jump` keeps the point
    /// on a *linear branch through the origin* with its history unchanged, and on the
    /// contact status `closed`: then the point's traction is `S delta` with a fixed matrix
    /// `S`, and an RVE whose points all stay so is linear in the macro strain (the fast
    /// path of `solver::fast_path`). `false` when in doubt; the default (a law that does
    /// not say) is always `false`, so the fast path never answers for it.
    fn stays_linear(
        &self,
        _history: &[f64],
        _jump: [f64; 2],
        _error: [f64; 2],
        _closed: bool,
    ) -> bool {
        false
    }

    /// The matrix `S` of the law's linear branch through the origin at `history` with the
    /// contact status `closed` (`t = S delta`): what IMPL-EX integration holds fixed
    /// within a step ([`crate::interface::Implex`]). Symmetric positive definite. `None`:
    /// the law has no such branch and cannot be integrated by IMPL-EX (the default).
    fn frozen_secant(&self, _history: &[f64], _closed: bool, _length: f64) -> Option<Matrix2<f64>> {
        None
    }

    /// The traction below which a difference of tractions is measured in absolute terms
    /// (the law's strength; `solver::implex::error_estimate`). The default, 0, measures
    /// every difference relative to the tractions themselves.
    fn traction_scale(&self) -> f64 {
        0.0
    }

    /// The history after a step, extrapolated from the last two converged ones
    /// (`previous`, then `committed`) for a step `ratio` times as long as the last
    /// (Oliver, Huespe & Cante 2008): `h_ex = h_n + ratio (h_n - h_{n-1})`. Written into
    /// `out`. The default extrapolates every value linearly.
    fn extrapolate(&self, committed: &[f64], previous: &[f64], ratio: f64, out: &mut [f64]) {
        for ((o, &h), &p) in out.iter_mut().zip(committed).zip(previous) {
            *o = h + ratio * (h - p);
        }
    }

    /// Whether a history read from a checkpoint is admissible for this law.
    fn history_is_valid(&self, history: &[f64]) -> bool {
        history.iter().all(|v| v.is_finite())
    }

    /// Opening ratios and damage of a point with history `history` at the local jump
    /// `jump` (for pictures and VTK output); `None` for a law without a characteristic
    /// opening.
    fn measures(&self, _history: &[f64], _jump: [f64; 2], _length: f64) -> Option<PointMeasures> {
        None
    }

    /// `(damage, max_opening)` of [`InterfaceLaw::measures`], which depend on the history
    /// alone: for the UMAT's mirrors, once per call over every point. The default asks
    /// `measures` at a zero jump; a law whose `measures` costs more overrides it.
    fn history_measures(&self, history: &[f64], length: f64) -> Option<(f64, f64)> {
        self.measures(history, [0.0, 0.0], length)
            .map(|m| (m.damage, m.max_opening))
    }

    /// The shear stiffness per unit area that the damaged part of a closed point with
    /// `history` carries while it sticks: `D K_s`, with `D` the damage of
    /// [`InterfaceLaw::history_measures`] and `K_s` the virgin shear stiffness (Alfano &
    /// Sacco 2006: friction acts on the damaged part). `None`: the law cannot carry
    /// friction (the default).
    fn damaged_shear_stiffness(&self, _history: &[f64], _length: f64) -> Option<f64> {
        None
    }

    /// The frictional slip of a point with `history`, for a law with friction.
    fn slip(&self, _history: &[f64]) -> Option<f64> {
        None
    }

    /// This law with its softening stretched `scale` times, its strength and the
    /// stiffness before the peak unchanged: the crack band's regularization by a host
    /// element's size (`scale = L_cell / h`), so that a cell that fails dissipates its
    /// fracture energy per unit crack length over the element's length `h` instead of its
    /// own `L_cell` (Bažant & Oh 1983). `None`: the law has no softening to scale (the
    /// default), and stays as it is.
    fn regularized(&self, _scale: f64) -> Option<Arc<dyn InterfaceLaw>> {
        None
    }

    /// Something to add to the message of a failed solve whose last iterate has
    /// `closed_points` points in contact, if the law knows why that may fail.
    fn failure_hint(&self, _closed_points: usize) -> Option<String> {
        None
    }
}

/// An interface law as a scene gives it, a table under `[materials]`: the value carries
/// its own checks and builds its law. `scene::MaterialsSpec::interface_laws` registers
/// each one under its key; the scene's validation and the model read them through it.
pub trait InterfaceLawSpec: std::fmt::Debug {
    /// Checks the constants; errors name the key `materials.<key>.<constant>`.
    fn validate(&self, key: &str) -> crate::error::Result<()>;
    /// The law; `contact` is the scene's `effects.contact`.
    fn build(&self, contact: bool) -> std::sync::Arc<dyn InterfaceLaw>;
}

/// The extrapolation of a history that never decreases (an opening's `delta_max`):
/// `h_n + ratio max(h_n - h_{n-1}, 0)` value by value, the laws' `extrapolate`.
pub(crate) fn extrapolate_growth(committed: &[f64], previous: &[f64], ratio: f64, out: &mut [f64]) {
    for ((o, &h), &p) in out.iter_mut().zip(committed).zip(previous) {
        *o = h + ratio.max(0.0) * (h - p).max(0.0);
    }
}

/// Whether every history value is a finite non-negative opening.
pub(crate) fn openings_are_valid(history: &[f64]) -> bool {
    history.iter().all(|d| d.is_finite() && *d >= 0.0)
}

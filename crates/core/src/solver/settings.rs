//! The solver's own settings and the types of its API: what a caller asks for and what an
//! update reports. The scene's `[solver]` table is [`Settings`] itself.

/// Settings of the RVE equilibrium solve (see `increment` for the remedy ladder they
/// switch on and off). This is also the scene's `[solver]` table, key by key, with its
/// defaults: a new switch is declared here once.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Settings {
    /// Relative residual tolerance: Newton converges when
    /// `||R|| <= tolerance * max(||G eps||, 1e-8 ||G||)`.
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// Newton iterations per attempt.
    #[serde(default = "default_iterations")]
    pub max_iterations: u32,
    /// Backtracking line search on `||R||` when the full step increases it.
    #[serde(default = "yes")]
    pub line_search: bool,
    /// Maximum bisection depth of the macro strain increment (2^depth sub-steps) before
    /// the update fails.
    #[serde(default = "default_substep_depth")]
    pub max_substep_depth: u32,
    /// Trace the equilibrium path through limit points (arc length) when Newton fails on
    /// a step, before the secant iterations and bisection.
    #[serde(default = "yes")]
    pub path_following: bool,
    /// Iterations allowed to the secant-then-Newton loop that takes over when plain
    /// Newton fails on a step, before the step is bisected; 0 switches it off.
    #[serde(default = "default_secant_iterations")]
    pub max_secant_iterations: u32,
    /// Modified-Newton (chord) corrections: after a Newton correction that cut the
    /// residual at least a hundredfold, the next correction reuses its factorization
    /// instead of factorizing the new tangent (see `newton`). `false` gives plain Newton
    /// with its quadratic rate.
    #[serde(default = "yes")]
    pub reuse_factorization: bool,
    /// Second-order predictor: an increment that keeps the direction of the previous one
    /// starts from `x_n + X_n Delta eps + s^2 e_n`, with the previous increment's
    /// prediction error `e_n` kept in the state (see `state::PathCurvature`); `false`
    /// predicts to first order only (`x_n + X_n Delta eps`) and keeps no curvature.
    #[serde(default = "yes")]
    pub second_order_predictor: bool,
    /// When the contact status of an ITZ point (closed iff its normal jump is negative,
    /// eqs. 36-37) is read: `"active_set"` (default) or `"per_iteration"` (see `contact`
    /// and `docs/contact-algorithm.md`).
    #[serde(default)]
    pub contact_status: ContactStatus,
    /// Answer an update without Newton when every ITZ point provably stays on the linear
    /// branch (unloading or contact) it had at the last full solve: `sigma = D_b eps`,
    /// exact (see `fast_path`); `false` solves every update.
    #[serde(default = "yes")]
    pub fast_path: bool,
    /// How the ITZ history is integrated over a host increment: `"implicit"` (default)
    /// or `"implex"` (see `implex` and `docs/implex.md`).
    #[serde(default)]
    pub integration: Integration,
    /// Check every implicit increment that Newton lands in one step while ITZ points pass
    /// the peak of their law against two half steps, and flag it when they reach another
    /// equilibrium (the answer depends on the host's step: `RveInfo` and the UMAT then
    /// ask for a smaller step, `PNEWDT` 0.5). `false` skips the check (see `step_check`).
    #[serde(default = "yes")]
    pub step_check: bool,
    /// The integration error an IMPL-EX step may make, relative (see
    /// [`super::implex::error_estimate`] and `docs/step_control.md`): each update then
    /// estimates its error and suggests a step ratio, below 1 to redo the step smaller
    /// (`PNEWDT`, `RveInfo`), above 1 when the next step may be larger (`RveInfo`, the
    /// batch report; never `PNEWDT`). Absent (the default): no estimate, ratio 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step_tolerance: Option<f64>,
    /// The smallest time increment the step control asks for, in the host's time units
    /// (`DTIME`, `dt`): a cut is never below it, and a step at or below it is kept (ratio 1)
    /// whatever its estimate. Inside an RVE's snap-back the estimate does not fall with the
    /// step, and a host that halves down to its own minimum stops there (CalculiX's
    /// "increment size smaller than minimum"); see `docs/step_control.md`. Absent: no floor.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub smallest_step: Option<f64>,
    /// Answer sharing (see `crate::model::share` and `docs/sharing.md`): within one host
    /// increment, a point whose committed state and strain lie within this relative
    /// tolerance of a point already solved takes that point's answer corrected to first
    /// order with its tangent, `sigma = sigma_a + D_a (eps - eps_a)`, instead of solving.
    /// In (0, 0.1]. Absent (the default): every point solves its own RVE, bit for bit as
    /// without the key.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub share_tolerance: Option<f64>,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            tolerance: default_tolerance(),
            max_iterations: default_iterations(),
            line_search: true,
            max_substep_depth: default_substep_depth(),
            path_following: true,
            max_secant_iterations: default_secant_iterations(),
            reuse_factorization: true,
            second_order_predictor: true,
            contact_status: ContactStatus::ActiveSet,
            fast_path: true,
            integration: Integration::Implicit,
            step_check: true,
            step_tolerance: None,
            smallest_step: None,
            share_tolerance: None,
        }
    }
}

fn yes() -> bool {
    true
}
fn default_tolerance() -> f64 {
    1e-6
}
fn default_iterations() -> u32 {
    40
}
fn default_substep_depth() -> u32 {
    10
}
fn default_secant_iterations() -> u32 {
    100
}

/// `solver.integration`: how the ITZ law's history is integrated over a host increment.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Integration {
    /// Backward Euler: the history of the step's end, found by Newton with path
    /// following through the RVE's snap-backs.
    #[default]
    Implicit,
    /// IMPL-EX (Oliver, Huespe & Cante 2008): the history extrapolated from the last two
    /// converged steps, the contact status of the last one. The RVE is linear within a
    /// step: one factorization per step, a symmetric positive definite tangent, no
    /// snap-back; the stress lags the implicit law by an error of first order in the step
    /// (see `implex`).
    Implex,
}

/// `solver.contact_status`: when the solver reads the contact status of the ITZ points
/// from their gaps (laws with [`crate::interface::InterfaceLaw::has_contact_status`]; see
/// `contact`). Matters only with the paper's contact law
/// (`materials.itz.contact_shear = "penalty"`), whose shear traction jumps at closure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactStatus {
    /// Held within each Newton iteration and read again between iterations; a point may
    /// switch at most [`super::contact::MAX_SWITCHES`] times per Newton loop, then keeps
    /// its status (an active-set strategy).
    #[default]
    ActiveSet,
    /// Read from the gap at every evaluation of the law. The residual then jumps where a
    /// sliding point closes, and some paths have no equilibrium at all.
    PerIteration,
}

/// What tangent the caller wants back.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TangentRequest {
    /// The consistent homogenized tangent (eq. 18).
    #[default]
    Consistent,
    /// No tangent: stress only (skips the tangent solve).
    None,
    /// The elastic tangent of the virgin RVE (`Model::elastic_tangent`): no tangent
    /// solve; the host's Newton then converges linearly. The solver treats it as `None`;
    /// `model::Instance` puts the elastic tangent and its `s_zz` row in the response.
    Elastic,
}

/// Counters of one update.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IncrementReport {
    /// Newton corrections summed over sub-steps.
    pub iterations: u32,
    /// Accepted sub-steps (1 when the increment converged in one go).
    pub substeps: u32,
    /// Numeric factorizations, including any for the tangent.
    pub factorizations: u32,
    /// How many of them were LU (indefinite tangent, both symmetric factorizations
    /// refused by their check).
    pub lu_factorizations: u32,
    /// How many were the checked LBL^T (indefinite tangent, the LDL^T refused).
    pub lblt_factorizations: u32,
    /// How many were an LDL^T of an indefinite tangent, accepted by its check; the rest
    /// were LDL^T of a positive definite tangent.
    pub indefinite_ldlt_factorizations: u32,
    /// Limit points of the macro strain along the equilibrium paths traced by path
    /// following in this update (a snap-back of the RVE response counts two: the strain
    /// passes a maximum, then a minimum). Non-zero means the strain-controlled equilibrium
    /// is not continuous over the increment: the RVE snapped back (a material instability
    /// at this point of the host), and no strain-controlled Newton loop can be expected to
    /// converge in a few iterations there.
    pub limit_points: u32,
    /// Interface points on the loading / unloading / contact branch at the end.
    pub loading: usize,
    pub unloading: usize,
    pub contact: usize,
    /// Interface points held at the end at a contact status their gap contradicts (see
    /// `contact`): 0 means the converged state is an equilibrium of the law with the
    /// status read from the gaps.
    pub held_points: usize,
    /// How the update was answered.
    pub answer: Answer,
    /// The increment's answer depends on its size: Newton landed it in one step over
    /// interface points passing their peak, and two half steps reach another equilibrium
    /// (see `step_check`). The host should cut the increment (UMAT's `PNEWDT` < 1).
    pub step_too_large: bool,
    /// Factorizations of that check, not counted in `factorizations`.
    pub check_factorizations: u32,
    /// The step's integration error estimate relative to `solver.step_tolerance`
    /// (`eta / tol`, see [`super::implex::error_estimate`]); `None` without a tolerance.
    pub error_estimate: Option<f64>,
    /// The estimate exceeds the tolerance but did not fall when the host redid the step
    /// smaller (see `model::Instance`): the error is not the step's (the RVE snaps back
    /// through it at any step), so the ratio is 1, not a further cut.
    pub irreducible: bool,
    /// `solver.smallest_step / dt`: the step control does not cut below it, and keeps a step
    /// for which it is 1 or more; 0 without `solver.smallest_step`.
    pub smallest_ratio: f64,
}

/// How an update was answered.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Answer {
    /// By the equilibrium solve.
    #[default]
    Solved,
    /// By the fast path: every interface point stays on its linear branch, the response
    /// is `D_b eps` (see `fast_path`).
    FastPath,
    /// The instance's pending trial at the same strain, returned again.
    Repeated,
}

impl IncrementReport {
    /// The ratio of the next macro increment to this one that the update suggests: 1/2
    /// when the answer depends on the step (`step_too_large`), the step control's ratio
    /// ([`step_ratio_for`], not below `smallest_ratio`, 1 at it) under
    /// `solver.step_tolerance`, else 1. Below 1: redo this
    /// increment smaller (UMAT's `PNEWDT`); above 1: the next may be that much larger.
    pub fn suggested_step_ratio(&self) -> f64 {
        if self.step_too_large {
            0.5
        } else if self.irreducible {
            1.0
        } else if let Some(e) = self.error_estimate {
            let ratio = step_ratio_for(e);
            if ratio >= 1.0 {
                ratio
            } else if self.smallest_ratio >= 1.0 - 1e-9 {
                1.0
            } else {
                ratio.max(self.smallest_ratio)
            }
        } else {
            1.0
        }
    }

    /// Whether the step's error estimate exceeds `solver.step_tolerance`.
    pub fn exceeds_tolerance(&self) -> bool {
        self.error_estimate.is_some_and(|e| e > 1.0)
    }

    /// Whether the answer is less reliable than a plain converged increment: it needed
    /// sub-steps, it depends on the step (`step_too_large`), or its error estimate exceeds
    /// `solver.step_tolerance`. MGIS-style reliability.
    pub fn substepped(&self) -> bool {
        self.substeps > 1 || self.step_too_large || self.exceeds_tolerance()
    }
}

/// Smallest ratio the step control asks for: a step whose error is far beyond the
/// tolerance is redone at a tenth, then judged again.
pub const MIN_STEP_RATIO: f64 = 0.1;
/// Largest ratio the step control offers: the next step at most twice this one.
pub const MAX_STEP_RATIO: f64 = 2.0;
/// Safety factor of the step control's ratio.
const STEP_SAFETY: f64 = 0.9;

/// The step control's ratio for an error estimate `e = eta / tol` (see `docs/step_control.md`).
/// IMPL-EX's error in a step is the extrapolation's, of second order in the step where
/// the history grows smoothly, so the step that meets the tolerance is `sqrt(1/e)` times
/// this one:
/// ```text
/// e > 1:   r = clamp(0.9 sqrt(1/e), 0.1, 0.9)   (redo smaller)
/// e <= 1:  r = min(0.9 sqrt(1/e), 2) if that exceeds 1, else 1   (keep; grow when well below)
/// ```
pub fn step_ratio_for(e: f64) -> f64 {
    let r = if e > 0.0 {
        STEP_SAFETY / e.sqrt()
    } else {
        MAX_STEP_RATIO
    };
    if e > 1.0 {
        r.clamp(MIN_STEP_RATIO, STEP_SAFETY)
    } else {
        r.clamp(1.0, MAX_STEP_RATIO)
    }
}

impl Answer {
    /// Answered without an equilibrium solve (fast path or repeated trial).
    pub fn is_fast(self) -> bool {
        self != Answer::Solved
    }
}

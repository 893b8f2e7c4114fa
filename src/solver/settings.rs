//! The solver's own settings and the types of its API: what a caller asks for and what an
//! update reports. The scene's `[solver]` table is translated into [`Settings`] by `model`.

/// Settings of the RVE equilibrium solve (see `increment` for the remedy ladder they
/// switch on and off).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Newton converges when `||R|| <= tolerance * max(||G eps||, 1e-8 ||G||)`.
    pub tolerance: f64,
    /// Newton iterations per attempt.
    pub max_iterations: u32,
    /// Backtracking line search on `||R||` when the full step increases it.
    pub line_search: bool,
    /// Bisections of the macro strain increment before the update fails.
    pub max_substep_depth: u32,
    /// Trace the equilibrium path through limit points when Newton fails on a step.
    pub path_following: bool,
    /// Iterations of the secant-then-Newton remedy; 0 switches it off.
    pub max_secant_iterations: u32,
    /// Chord corrections after a hundredfold Newton contraction (see `newton`).
    pub reuse_factorization: bool,
    /// The second-order term of the predictor (see `predictor`).
    pub second_order_predictor: bool,
    /// When the contact status of the interface points is read (see `contact`).
    pub contact_status: ContactStatus,
    /// Answer updates that keep every interface point on its linear branch without
    /// Newton (see `fast_path`).
    pub fast_path: bool,
    /// How the interface history is integrated over a step (see `implex`).
    pub integration: Integration,
    /// Check an implicit increment that Newton landed over interface points passing
    /// their peak against two half steps (see `step_check`).
    pub step_check: bool,
}

/// How the interface history is integrated over a host increment.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Integration {
    /// Backward Euler, solved by Newton and path following.
    #[default]
    Implicit,
    /// IMPL-EX: the extrapolated history, linear within a step (see `implex`).
    Implex,
}

/// When the solver reads the contact status of the interface points from their gaps
/// (laws with [`crate::interface::InterfaceLaw::has_contact_status`]; see `contact`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ContactStatus {
    /// Held within each Newton iteration, read again between iterations, at most
    /// [`super::contact::MAX_SWITCHES`] switches per point and Newton loop.
    #[default]
    ActiveSet,
    /// Read at every evaluation of the law.
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
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
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
    /// The ratio of the next macro increment to this one that the update suggests (UMAT's
    /// `PNEWDT`): 1, or 1/2 when the answer depends on the step (`step_too_large`).
    pub fn suggested_step_ratio(&self) -> f64 {
        if self.step_too_large {
            0.5
        } else {
            1.0
        }
    }

    /// Whether the answer is less reliable than a plain converged increment: it needed
    /// sub-steps, or it depends on the step (`step_too_large`). MGIS-style reliability.
    pub fn substepped(&self) -> bool {
        self.substeps > 1 || self.step_too_large
    }
}

impl Answer {
    /// Answered without an equilibrium solve (fast path or repeated trial).
    pub fn is_fast(self) -> bool {
        self != Answer::Solved
    }
}

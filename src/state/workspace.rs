//! Scratch memory for one thread: sized once for a model, reused by every update of every
//! instance of that model, so the solve allocates nothing.

use faer::dyn_stack::MemBuffer;

use super::State;
use crate::assembly::{Discretization, SystemEvaluation};
use crate::interface::CohesiveHistory;
use crate::solver::{LinearSolver, NumericFactor};

/// Per-thread scratch for [`crate::model::Model::update`].
pub struct Workspace {
    /// Tangent values on the model's pattern, at the current iterate.
    pub k: Vec<f64>,
    /// Tangent values that `factor` factorizes (to detect an unchanged matrix).
    pub k_factored: Vec<f64>,
    /// True when `factor` holds a valid factorization of `k_factored`.
    pub factored: bool,
    pub factor: NumericFactor,
    pub stack: MemBuffer,
    /// Residual, Newton correction, line-search iterate, scratch.
    pub r: Vec<f64>,
    pub dx: Vec<f64>,
    pub x_try: Vec<f64>,
    pub r_try: Vec<f64>,
    pub k_try: Vec<f64>,
    /// `X_n Delta eps`, the first-order part of the tangent prediction (see
    /// [`crate::state::PathCurvature`]).
    pub tangent_prediction: Vec<f64>,
    /// `K^-1 G` (n x 3, column-major) and its refinement residual.
    pub kg: Vec<f64>,
    /// True when `kg` is `K_f^-1 G` for the factorization in `factor`, solved with the
    /// Newton correction (see `solver::newton`).
    pub kg_of_factor: bool,
    /// Right-hand sides of a Newton correction with the tangent columns: `[-R | G]`.
    pub rhs4: Vec<f64>,
    pub kg_res: Vec<f64>,
    /// Interface histories: start of the sub-step, trial, line-search trial.
    pub hist_base: Vec<CohesiveHistory>,
    pub hist_trial: Vec<CohesiveHistory>,
    pub hist_try: Vec<CohesiveHistory>,
    /// State at the start of the current sub-step (for sub-stepping).
    pub substep_start: State,
    /// Path following: load vector `G Delta eps`, its solution, last arc point, last step.
    pub arc_f: Vec<f64>,
    pub arc_dxf: Vec<f64>,
    pub arc_xa: Vec<f64>,
    pub arc_prev: Vec<f64>,
    pub arc_pred: Vec<f64>,
    /// Branch counts of the evaluation in `r`/`k` and of the one in the `*_try` buffers.
    pub counts: SystemEvaluation,
    pub counts_try: SystemEvaluation,
    /// Residual norms of the last Newton loop (for convergence studies).
    pub residuals: Vec<f64>,
    /// The interface branch signature of each of those iterates
    /// ([`crate::assembly::SystemEvaluation::branch_signature`]): where two successive ones
    /// agree, no point changed branch and the correction between them is a Newton step on
    /// a smooth system.
    pub branch_signatures: Vec<u64>,
    /// Which model this workspace was sized for.
    pub(crate) model_id: u64,
}

impl Workspace {
    /// Sizes a workspace for `disc` (the model's discretization).
    pub fn new(
        disc: &Discretization,
        linear: &LinearSolver,
        max_iterations: usize,
        model_id: u64,
    ) -> Self {
        let n = disc.n();
        let nh = disc.history_len();
        let nnz = disc.pattern.nnz();
        let req = linear.scratch(4);
        Workspace {
            k: vec![0.0; nnz],
            k_factored: vec![0.0; nnz],
            factored: false,
            factor: linear.numeric(),
            stack: MemBuffer::new(req),
            r: vec![0.0; n],
            dx: vec![0.0; n],
            x_try: vec![0.0; n],
            r_try: vec![0.0; n],
            k_try: vec![0.0; nnz],
            tangent_prediction: vec![0.0; n],
            kg: vec![0.0; 3 * n],
            kg_of_factor: false,
            rhs4: vec![0.0; 4 * n],
            kg_res: vec![0.0; 3 * n],
            hist_base: vec![CohesiveHistory::default(); nh],
            hist_trial: vec![CohesiveHistory::default(); nh],
            hist_try: vec![CohesiveHistory::default(); nh],
            substep_start: State::virgin(n, nh),
            arc_f: vec![0.0; n],
            arc_dxf: vec![0.0; n],
            arc_xa: vec![0.0; n],
            arc_prev: vec![0.0; n],
            arc_pred: vec![0.0; n],
            counts: SystemEvaluation::default(),
            counts_try: SystemEvaluation::default(),
            residuals: Vec::with_capacity(max_iterations + 2),
            branch_signatures: Vec::with_capacity(max_iterations + 2),
            model_id,
        }
    }
}

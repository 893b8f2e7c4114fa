//! Scratch memory for one thread: sized once for a model, reused by every update of every
//! instance of that model, so the solve allocates nothing.
//!
//! The factorization and what depends on it live in [`Factorization`], whose methods keep
//! its invariants: the copy of the factorized matrix, whether it was a consistent tangent,
//! and whether `K_f^-1 G` belongs to it change only together with the factors.

use crate::error::LinearAlgebraError;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMat;

use super::sparse_direct::{FactorKind, FactorMethod, LinearSolver, NumericFactor};
use crate::assembly::{Discretization, SystemEvaluation};
use crate::state::State;

/// One evaluation of the discrete system: residual, tangent values on the pattern, trial
/// interface histories and branch counts, all at the same iterate.
pub(super) struct Evaluation {
    pub r: Vec<f64>,
    pub k: Vec<f64>,
    pub history: Vec<f64>,
    pub counts: SystemEvaluation,
}

impl Evaluation {
    fn new(n: usize, nnz: usize, nh: usize) -> Self {
        Evaluation {
            r: vec![0.0; n],
            k: vec![0.0; nnz],
            history: vec![0.0; nh],
            counts: SystemEvaluation::default(),
        }
    }
}

/// What a factorization is for, given to [`Factorization::factorize`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FactorUse {
    /// A consistent tangent: chord corrections and the condensed tangent may reuse its
    /// factors.
    Reusable,
    /// A secant matrix or a path direction: the factors serve one purpose only.
    OneUse,
}

/// The numeric factorization of a workspace and the facts tied to it.
pub struct Factorization {
    numeric: NumericFactor,
    stack: MemBuffer,
    /// The values of the last reusable factorization.
    matrix: Vec<f64>,
    /// True when `numeric` holds a factorization of `matrix`, a consistent tangent that
    /// chord corrections and the condensed tangent may reuse.
    consistent: bool,
    /// `K_f^-1 G` (n x 3, column-major), or the refined `K^-1 G` of the tangent.
    kg: Vec<f64>,
    /// True when `kg` is exactly `K_f^-1 G` for the current factors.
    kg_of_factor: bool,
    /// Whether the factorized matrix is symmetric (no point slides under friction).
    symmetric: bool,
}

impl Factorization {
    fn new(linear: &LinearSolver, n: usize, nnz: usize) -> Self {
        Factorization {
            numeric: linear.numeric(),
            stack: MemBuffer::new(linear.scratch(4)),
            matrix: vec![0.0; nnz],
            consistent: false,
            kg: vec![0.0; 3 * n],
            kg_of_factor: false,
            symmetric: true,
        }
    }

    /// Factorizes `values` (on `pattern`). [`FactorUse::Reusable`]: they are a consistent
    /// tangent whose factors chord corrections and the condensed tangent may reuse (the
    /// values are then kept, to recognise an unchanged tangent); [`FactorUse::OneUse`]: the
    /// factors serve one purpose only (a secant matrix, a path direction). Whatever
    /// depended on the previous factors is invalidated. `symmetric`: whether the matrix
    /// is; LDL^T and LBL^T read its lower triangle only, so a matrix that is not (a point
    /// sliding under friction) is factorized by LU.
    pub fn factorize(
        &mut self,
        linear: &LinearSolver,
        pattern: &SymbolicSparseColMat<usize>,
        values: &[f64],
        use_: FactorUse,
        symmetric: bool,
    ) -> Result<FactorKind, LinearAlgebraError> {
        self.kg_of_factor = false;
        self.consistent = false;
        self.symmetric = symmetric;
        let method = if symmetric {
            FactorMethod::SymmetricFirst
        } else {
            FactorMethod::Lu
        };
        let kind = linear.factorize(
            pattern,
            values,
            &mut self.numeric,
            method,
            MemStack::new(&mut self.stack),
        )?;
        if use_ == FactorUse::Reusable {
            self.matrix.copy_from_slice(values);
            self.consistent = true;
        }
        Ok(kind)
    }

    /// Forgets the factors' meaning (the start of a Newton loop): no chord step and no
    /// tangent may reuse them.
    pub(super) fn invalidate(&mut self) {
        self.consistent = false;
        self.kg_of_factor = false;
    }

    /// Whether the factors are those of a reusable consistent tangent.
    pub(super) fn is_reusable(&self) -> bool {
        self.consistent
    }

    /// Whether the factorized matrix was symmetric.
    pub(super) fn is_symmetric(&self) -> bool {
        self.symmetric
    }

    /// Whether the factors are those of exactly the consistent tangent `k`.
    pub(super) fn factorizes(&self, k: &[f64]) -> bool {
        self.consistent && self.matrix == k
    }

    /// Solves in place for `ncols` right-hand sides (column-major) with the factors.
    pub fn solve(&mut self, linear: &LinearSolver, rhs: &mut [f64], ncols: usize) {
        linear.solve_in_place(
            &mut self.numeric,
            rhs,
            ncols,
            MemStack::new(&mut self.stack),
        );
    }

    /// Solves `[-r | G]` in one 4-column solve (scratch `rhs4`): the Newton correction
    /// into `dx` and `K_f^-1 G`, which then belongs to these factors.
    pub(super) fn solve_with_g(
        &mut self,
        linear: &LinearSolver,
        g: &[f64],
        r: &[f64],
        rhs4: &mut [f64],
        dx: &mut [f64],
    ) {
        let n = r.len();
        let (first, rest) = rhs4.split_at_mut(n);
        first.iter_mut().zip(r).for_each(|(d, r)| *d = -r);
        rest.copy_from_slice(g);
        self.solve(linear, rhs4, 4);
        dx.copy_from_slice(&rhs4[..n]);
        self.kg.copy_from_slice(&rhs4[n..]);
        self.kg_of_factor = true;
    }

    /// Makes `kg` hold `K_f^-1 G` for the current factors (three solves unless it does).
    pub(super) fn solve_g(&mut self, linear: &LinearSolver, g: &[f64]) {
        if !self.kg_of_factor {
            self.kg.copy_from_slice(g);
            linear.solve_in_place(
                &mut self.numeric,
                &mut self.kg,
                3,
                MemStack::new(&mut self.stack),
            );
            self.kg_of_factor = true;
        }
    }

    /// Whether `kg` is exactly `K_f^-1 G` for the current factors (not a refined one).
    pub(super) fn kg_is_of_factor(&self) -> bool {
        self.kg_of_factor
    }

    /// `K^-1 G` (or its best approximation) from the last tangent computation.
    pub fn kg(&self) -> &[f64] {
        &self.kg
    }

    /// Writable `kg`; it no longer counts as `K_f^-1 G` of the factors.
    pub(super) fn kg_mut(&mut self) -> &mut Vec<f64> {
        self.kg_of_factor = false;
        &mut self.kg
    }

    /// The numeric factors and their counters (factorizations, solves by width).
    pub fn numeric(&self) -> &NumericFactor {
        &self.numeric
    }
}

/// Buffers of path following (see `arclength`).
pub(super) struct TraceBuffers {
    /// Load vector `f = G Delta eps` and the path direction `K^-1 f`.
    pub f: Vec<f64>,
    pub dxf: Vec<f64>,
    /// The last arc point, the last step, and the predictor direction.
    pub xa: Vec<f64>,
    pub prev: Vec<f64>,
    pub pred: Vec<f64>,
    /// The path direction at a corrector's converged iterate before its pinned points
    /// were released (see `arclength::correct`).
    pub held_dxf: Vec<f64>,
}

/// The contact status of the interface points within a Newton loop (see `contact`).
pub(super) struct ContactBuffers {
    /// Whether the status is held in this update at all.
    pub held: bool,
    /// The status at the loop's start state, the status held now, how many times each
    /// point has switched in this loop, and scratch for the status the gaps give.
    pub start: Vec<bool>,
    pub now: Vec<bool>,
    pub switches: Vec<u8>,
    pub read: Vec<bool>,
    /// Points the start state holds against their gap: not read again at the loop's
    /// first iterate (see `contact`).
    pub pinned: Vec<bool>,
    /// The held status of the converged iterate `Workspace::pinned_x`.
    pub saved: Vec<bool>,
}

impl ContactBuffers {
    fn new(points: usize) -> Self {
        ContactBuffers {
            held: false,
            start: vec![false; points],
            now: vec![false; points],
            switches: vec![0; points],
            read: vec![false; points],
            pinned: vec![false; points],
            saved: vec![false; points],
        }
    }

    /// The status to evaluate with: the held one, or `None` (read from the gaps).
    pub fn status(&self) -> Option<&[bool]> {
        self.held.then_some(self.now.as_slice())
    }
}

/// What a step check's Newton loops write besides their states: its own copies of the
/// buffers an update leaves for inspection (last evaluation, residual history, branch
/// signatures, start history, held contact status), swapped in for the check and out after
/// it, so the workspace still describes the answered increment.
pub(super) struct StepCheckBuffers {
    pub half_steps: [State; 2],
    current: Evaluation,
    residuals: Vec<f64>,
    branch_signatures: Vec<u64>,
    history_start: Vec<f64>,
    contact: ContactBuffers,
}

/// Per-thread scratch for the updates of one model (`Model::update`).
pub struct Workspace {
    /// The evaluation at the current iterate, and a candidate (line search, predictor).
    pub(super) current: Evaluation,
    pub(super) candidate: Evaluation,
    pub(super) factorization: Factorization,
    /// Newton correction, candidate iterate, and the scratch of 4-column solves.
    pub(super) dx: Vec<f64>,
    pub(super) x_try: Vec<f64>,
    /// A converged iterate with pinned points held, kept while they are released once.
    pub(super) pinned_x: Vec<f64>,
    pub(super) rhs4: Vec<f64>,
    /// `X_n Delta eps`, the first-order part of the tangent prediction (see `predictor`).
    pub(super) tangent_prediction: Vec<f64>,
    /// Refinement residual of `K^-1 G` (see `tangent`).
    pub(super) kg_res: Vec<f64>,
    /// Interface history at the start of the current sub-step.
    pub(super) history_start: Vec<f64>,
    /// State at the start of the current sub-step (for sub-stepping).
    pub(super) substep_start: State,
    /// A lazy committed state with its unknowns formed (see `fast_path::materialize`).
    pub(super) materialized: State,
    /// The two half steps of a step check, and the buffers its Newton loops run in (see
    /// `step_check`).
    pub(super) step_check: StepCheckBuffers,
    pub(super) trace: TraceBuffers,
    pub(super) contact: ContactBuffers,
    /// Relative residual norms of the last Newton loop, and the interface branch signature
    /// ([`SystemEvaluation::branch_signature`]) of each of those iterates: where two
    /// successive ones agree, no point changed branch and the correction between them is
    /// a Newton step on a smooth system.
    pub(super) residuals: Vec<f64>,
    pub(super) branch_signatures: Vec<u64>,
    /// Which model this workspace was sized for.
    model_id: u64,
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
        let zeros = || vec![0.0; n];
        Workspace {
            current: Evaluation::new(n, nnz, nh),
            candidate: Evaluation::new(n, nnz, nh),
            factorization: Factorization::new(linear, n, nnz),
            dx: zeros(),
            x_try: zeros(),
            pinned_x: zeros(),
            rhs4: vec![0.0; 4 * n],
            tangent_prediction: zeros(),
            kg_res: vec![0.0; 3 * n],
            history_start: vec![0.0; nh],
            substep_start: State::with_capacity(n, nh),
            materialized: State::with_capacity(n, nh),
            step_check: StepCheckBuffers {
                half_steps: [State::with_capacity(n, nh), State::with_capacity(n, nh)],
                current: Evaluation::new(n, nnz, nh),
                residuals: Vec::with_capacity(max_iterations + 2),
                branch_signatures: Vec::with_capacity(max_iterations + 2),
                history_start: vec![0.0; nh],
                contact: ContactBuffers::new(disc.interface_points()),
            },
            trace: TraceBuffers {
                f: zeros(),
                dxf: zeros(),
                xa: zeros(),
                prev: zeros(),
                pred: zeros(),
                held_dxf: zeros(),
            },
            contact: ContactBuffers::new(disc.interface_points()),
            residuals: Vec::with_capacity(max_iterations + 2),
            branch_signatures: Vec::with_capacity(max_iterations + 2),
            model_id,
        }
    }

    /// Swaps the answered increment's inspectable buffers with the step check's (twice:
    /// back to the answered increment's).
    pub(super) fn swap_step_check_buffers(&mut self) {
        let spare = &mut self.step_check;
        std::mem::swap(&mut self.current, &mut spare.current);
        std::mem::swap(&mut self.residuals, &mut spare.residuals);
        std::mem::swap(&mut self.branch_signatures, &mut spare.branch_signatures);
        std::mem::swap(&mut self.history_start, &mut spare.history_start);
        std::mem::swap(&mut self.contact, &mut spare.contact);
    }

    /// The model this workspace was sized for.
    pub fn model_id(&self) -> u64 {
        self.model_id
    }

    /// Relative residual norms of the last Newton loop (convergence studies).
    pub fn residual_history(&self) -> &[f64] {
        &self.residuals
    }

    /// The contact status of the interface points held at the end of the last Newton loop
    /// (one entry per point, element-major), or `None` when the last update did not hold
    /// it (see `solver.contact_status`). Where it differs from the status the converged
    /// gaps give, a point was held against its gap (convergence studies).
    pub fn held_contact_status(&self) -> Option<&[bool]> {
        self.contact.status()
    }

    /// The interface history the last Newton loop started from (the last sub-step's or arc
    /// point's; convergence studies).
    pub fn history_start(&self) -> &[f64] {
        &self.history_start
    }

    /// Branch signatures of the iterates of the last Newton loop.
    pub fn branch_signatures(&self) -> &[u64] {
        &self.branch_signatures
    }

    /// The residual and tangent values at the last converged iterate.
    pub fn residual(&self) -> &[f64] {
        &self.current.r
    }
    pub fn tangent_values(&self) -> &[f64] {
        &self.current.k
    }

    /// The factorization (benchmarks and tests factorize and solve with it).
    pub fn factorization(&mut self) -> &mut Factorization {
        &mut self.factorization
    }
}

//! Newton-Raphson on the fluctuation with line search and sub-stepping.
//!
//! # Convergence test
//! An iterate converges when `||R||_2 <= tolerance * max(||G eps||_2, 1e-8 ||G||_F)`:
//! the residual relative to the load the macro strain puts on the RVE (`G eps` is the
//! residual of the zero fluctuation in the absence of interfaces). The floor makes strains
//! below 1e-8 count as 1e-8, so a zero target strain still has a meaningful test.
//!
//! # Line search
//! Backtracking on `||R||`: the full step is accepted when it reduces the residual norm;
//! otherwise the step is halved up to five times, and the step with the smallest residual
//! is taken (the smallest is still taken if none reduces it, so Newton can cross the kinks
//! of the law). Switch off with `solver.line_search = false`.
//!
//! # Secant iterations, then Newton
//! Past the peak, loading/unloading switches at many interface points can make Newton
//! cycle (a semismooth Newton on the kinks of the law), and at an RVE snap-back the
//! equilibrium jumps to another branch, far from the last converged state. When plain
//! Newton fails on a step, the step is solved again from its start with secant
//! iterations: the loading points use the secant `(t/delta) diag(beta^2, 1)` of the
//! envelope instead of its tangent, so every matrix is positive definite and each iterate
//! solves `K_sec(x_k) x_{k+1} = -G eps` (the classical secant / fixed-point iteration of
//! damage mechanics, robust through softening and snap-back). Once the relative residual
//! is below `100 * tolerance` the loop switches to consistent Newton for the final
//! quadratic convergence (and back to secant if Newton makes the residual grow tenfold).
//! Only if that fails too is the step bisected. The converged state satisfies the same
//! equations; only the path to it differs.
//!
//! # Sub-stepping (Somer et al. 2009)
//! If an increment fails (no convergence in `max_iterations`, a singular or non-finite
//! system), it is bisected and the halves are solved in turn, each from the converged
//! state (fluctuation and interface history) of the previous one; after two successes in
//! a row the step doubles again (one level up). Past `max_substep_depth` levels of
//! bisection (a step of `2^-max_substep_depth` of the increment) the update fails
//! with a suggested step ratio (UMAT's PNEWDT), and the committed state is untouched
//! because every iterate lives in the trial state.
//!
//! # Predictor
//! Each step starts from `x_n + X_n Delta eps`, with `X_n = -K_n^-1 G` the sensitivity of
//! the committed state, kept in the state from its tangent computation (8-bit blocks, see
//! [`crate::state::Sensitivity`]): Newton's own first iterate, whose residual is
//! `O(|Delta eps|^2)` (3e-3 relative on the paper RVE's pre-peak increments, against
//! 3e-2 from the elastic sensitivity of the virgin RVE). When the step keeps the
//! direction of the committed state's own increment (`Delta eps = s Delta eps_n`, see
//! [`curvature_scale`]), the second-order term `s^2 e_n` is added, `e_n` being that
//! increment's first-order prediction error (`x_n - x_{n-1} - X_{n-1} Delta eps_n`, kept
//! in the state as [`crate::state::PathCurvature`]): along a smooth path
//! `e_n ~ x''[Delta eps_n, Delta eps_n] / 2`, so the prediction is good to third order.
//! On the paper path (increments 3 to 15, scratch run of `Instance::update` reading
//! `Workspace::residuals`) the predictor's own residual falls only from 3.0e-2 to 1.8e-2
//! of `||G Delta eps||` (median), but the relative residual after the first Newton
//! correction falls from 2.6e-6..1.3e-5 to 6.7e-8..8.8e-7: below the 1e-6 tolerance, where
//! the first-order predictor needed a chord correction after it (one solve and one
//! evaluation fewer per increment). `solver.second_order_predictor = false` switches it
//! off.
//! A prediction is kept only if it lowers the residual and leaves every ITZ point before
//! the envelope's peak; otherwise the elastic predictor is tried (see [`predict`]), and
//! if Newton fails from the tangent prediction the step restarts from the elastic one
//! before any other remedy. Once Newton has failed on a step, the rest of the increment
//! runs plain Newton from elastic predictions (no chord corrections, no committed
//! sensitivity applied to sub-steps that start elsewhere): the speed-ups serve the easy
//! steps, the remedies keep the behaviour they were measured with.
//!
//! # Chord corrections
//! A Newton correction that cuts the residual at least a hundredfold
//! ([`CHORD_CONTRACTION`]) shows that the tangent barely changed over the step; the next
//! correction then reuses the factorization (a chord or modified-Newton step, contracting
//! by the relative change of the tangent, about 1e-2 here) instead of factorizing the new
//! tangent. With the tangent predictor, a pre-peak increment takes one factorization, one
//! Newton and one chord correction. `solver.reuse_factorization = false` gives plain
//! Newton and its quadratic rate (`tests/newton_convergence.rs` checks both).
//!
//! # Tangent
//! `D_hom = D_Taylor - (1/V) G^T K^-1 G` at the converged state (eq. 18), with `K` the
//! consistent tangent there, by condensation with the factorization the Newton loop left
//! (see [`condensed_tangent`]):
//! - if the converged `K` is bitwise the last factorized one (unloading, contact, the
//!   elastic range: piecewise linear branches), `K^-1 G` costs three solves;
//! - otherwise `K_f^-1 G` from the last factorization `K_f` is refined against the
//!   converged `K`, and `G^T K^-1 G` is taken from its variational form, whose error is
//!   quadratic in that of `K^-1 G`: one or two sweeps reach 1e-10 after a chord step;
//! - only when [`TANGENT_SWEEPS`] sweeps cannot reach [`TANGENT_ACCURACY`] (a long last
//!   step, after the peak) is the converged `K` factorized once more.
//!   `IncrementReport::factorizations` counts it.
//!
//! With sub-steps, the tangent is that of the last sub-step.

use faer::dyn_stack::MemStack;

use super::arclength::{trace, Traced};
use super::linear::LinearSolver;
use crate::assembly::Discretization;
use crate::element::TangentKind;
use crate::error::{Error, Result};
use crate::homogenization::Homogenizer;
use crate::interface::ContactShear;
use crate::scene::SolverSpec;
use crate::state::{PathCurvature, State, Workspace};

/// What tangent the caller wants back.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TangentRequest {
    /// The consistent homogenized tangent (eq. 18).
    #[default]
    Consistent,
    /// No tangent: stress only (skips the tangent solve).
    None,
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
    /// How many of them were LU (indefinite tangent, the checked LBL^T refused).
    pub lu_factorizations: u32,
    /// How many were the checked LBL^T (indefinite tangent); the rest were LL^T.
    pub lblt_factorizations: u32,
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
}

/// Why one Newton loop failed.
pub(super) enum Failure {
    NotConverged {
        residual: f64,
        reference: f64,
    },
    Singular(String),
    NonFinite,
    /// Path following could not trace the equilibrium path of the step.
    PathLost,
}

impl Failure {
    fn describe(&self, max_iterations: u32) -> String {
        match self {
            Failure::NotConverged {
                residual,
                reference,
            } => format!(
                "no convergence in {max_iterations} iterations (relative residual {:.3e})",
                residual / reference
            ),
            Failure::Singular(e) => format!("singular RVE tangent ({e})"),
            Failure::NonFinite => "non-finite residual or correction".to_string(),
            Failure::PathLost => {
                "the equilibrium path could not be traced through a limit point".to_string()
            }
        }
    }
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|a| a * a).sum::<f64>().sqrt()
}

/// Residual reference of the convergence test (see module docs).
fn reference(disc: &Discretization, eps: &[f64; 3]) -> f64 {
    let n = disc.n();
    let mut sq = 0.0;
    for i in 0..n {
        let gi = disc.g[i] * eps[0] + disc.g[n + i] * eps[1] + disc.g[2 * n + i] * eps[2];
        sq += gi * gi;
    }
    let g_frob = norm(&disc.g);
    sq.sqrt().max(1e-8 * g_frob)
}

/// Evaluates `R` and `K` at `x` into `ws.r`, `ws.k`, `ws.hist_trial` and `ws.counts`,
/// from the sub-step's history `ws.hist_base`.
pub(super) fn evaluate_current(
    disc: &Discretization,
    x: &[f64],
    eps: &[f64; 3],
    kind: TangentKind,
    ws: &mut Workspace,
) {
    ws.counts = disc.evaluate_with(
        x,
        eps,
        &ws.hist_base,
        &mut ws.hist_trial,
        &mut ws.r,
        Some(&mut ws.k),
        kind,
    );
}

/// Takes the evaluation in the `*_try` buffers as the current one.
fn accept_try(ws: &mut Workspace) {
    std::mem::swap(&mut ws.r, &mut ws.r_try);
    std::mem::swap(&mut ws.k, &mut ws.k_try);
    std::mem::swap(&mut ws.hist_trial, &mut ws.hist_try);
    std::mem::swap(&mut ws.counts, &mut ws.counts_try);
}

/// Factorizes `ws.k` into `ws.factor` (`ws.kg` no longer belongs to it).
pub(super) fn factorize_current(
    disc: &Discretization,
    linear: &LinearSolver,
    ws: &mut Workspace,
) -> std::result::Result<super::FactorKind, String> {
    ws.kg_of_factor = false;
    linear.factorize(
        &disc.pattern.symbolic,
        &ws.k,
        &mut ws.factor,
        true,
        MemStack::new(&mut ws.stack),
    )
}

/// How a Newton loop globalizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Mode {
    /// Consistent Newton with backtracking line search.
    Newton,
    /// The same, giving up early once the residual stagnates (see [`STAGNATION_WINDOW`]):
    /// the first try on a whole increment, where path following comes next.
    NewtonUntilStagnant,
    /// Secant iterations, switching to Newton near convergence (see module docs).
    SecantThenNewton,
}

/// The full Newton step is taken unless it multiplies `||R||` by more than this; smaller
/// steps are tried only then (a non-monotone rule: across the kinks of the cohesive law a
/// temporary rise of the residual is normal, and strict decrease stalls Newton).
const LINE_SEARCH_GROWTH: f64 = 1.0;
/// A Newton correction that multiplies `||R||` by at most this is followed by a chord
/// correction with the same factorization.
const CHORD_CONTRACTION: f64 = 1e-2;
/// Refinement sweeps the condensed tangent may take before a fresh factorization is
/// cheaper: one sweep (a 3-column solve and three products) costs 0.11 ms against 0.43 ms
/// for a factorization and its 3-column solve on the paper RVE, 2.1 ms against 11.2 ms on
/// the fine one (timed with the factorization and solve of `benches/solver.rs`).
const TANGENT_SWEEPS: u32 = 3;
/// Relative accuracy of the condensed term `G^T K^-1 G` the sweeps must reach. The stress
/// it goes with is converged to the Newton tolerance (1e-6 relative residual by default);
/// a tangent error of 1e-10 leaves a host's Newton quadratic down to relative errors of
/// 1e-10, far below any host tolerance, and the finite-difference checks (1e-6) cannot see
/// it. Reaching 1e-13 instead would take one more sweep in most pre-peak increments.
const TANGENT_ACCURACY: f64 = 1e-10;
/// A Newton loop gives up once its residual has not halved over this many iterations.
/// At an RVE snap-back the residual of strain-controlled Newton sits at a local minimum
/// that is no root (1.5e-3 relative for 37 iterations on the paper path), and path
/// following is the remedy. Measured with `scripts/robustness-study` (98 paths), against
/// the full `max_iterations` budget: cohesive-law iterations 7939 -> 6509 and solver time
/// 10.0 -> 8.7 s with no failure either way; paper-law failures 24 -> 25 of 49, which
/// flip with round-off (see the README). (Before path following landed on the target
/// itself, this cut made one cohesive path fail.) Only the first try on a step that has
/// not been bisected gives up early ([`Mode::NewtonUntilStagnant`]): in the sub-steps of a
/// bisection slow Newton is the remedy that works, and cutting it there made the paper-law
/// path `scenes/paper/rve_circles_3e-4.toml` fail (`tests/paper_examples.rs`).
const STAGNATION_WINDOW: u32 = 10;

/// Secant iterations hand over to Newton below this multiple of the tolerance.
const SECANT_HANDOVER: f64 = 100.0;

/// One Newton loop at fixed macro strain `eps` from the unknowns `x`, with interface
/// history `ws.hist_base`. `evaluated`: `ws.r`/`ws.k`/`ws.hist_trial` already hold the
/// consistent evaluation at `x` (from the predictor). On success `x` is converged,
/// `ws.r`/`ws.k`/`ws.hist_trial`/`ws.counts` belong to it (`ws.k` is the consistent
/// tangent), and `ws.factor` holds the last factorization (if any).
#[allow(clippy::too_many_arguments)]
pub(super) fn newton(
    disc: &Discretization,
    linear: &LinearSolver,
    settings: &SolverSpec,
    eps: &[f64; 3],
    x: &mut [f64],
    ws: &mut Workspace,
    mode: Mode,
    evaluated: bool,
) -> std::result::Result<u32, Failure> {
    let reference = reference(disc, eps);
    let tolerance = settings.tolerance * reference;
    let max_iterations = match mode {
        Mode::Newton | Mode::NewtonUntilStagnant => settings.max_iterations,
        Mode::SecantThenNewton => settings.max_secant_iterations,
    };
    let mut kind = match mode {
        Mode::Newton | Mode::NewtonUntilStagnant => TangentKind::Consistent,
        Mode::SecantThenNewton => TangentKind::Secant,
    };
    ws.factored = false;
    ws.kg_of_factor = false;
    ws.residuals.clear();
    ws.branch_signatures.clear();
    if !(evaluated && kind == TangentKind::Consistent) {
        evaluate_current(disc, x, eps, kind, ws);
    }
    let mut rnorm = norm(&ws.r);
    let mut iteration = 0u32;
    let mut chord = false;
    loop {
        if ws.residuals.len() < ws.residuals.capacity() {
            ws.residuals.push(rnorm / reference);
            ws.branch_signatures.push(ws.counts.branch_signature);
        }
        if !rnorm.is_finite() {
            return Err(Failure::NonFinite);
        }
        if rnorm <= tolerance {
            if kind == TangentKind::Secant {
                // Converged on secant matrices: the tangent needs the consistent one.
                evaluate_current(disc, x, eps, TangentKind::Consistent, ws);
                ws.factored = false;
            }
            return Ok(iteration);
        }
        // Stagnation: a Newton loop whose residual has not halved in the last
        // [`STAGNATION_WINDOW`] iterations gives up before its budget and hands over to the
        // next remedy (see the constant).
        let window = STAGNATION_WINDOW as usize;
        let stagnant = mode == Mode::NewtonUntilStagnant && ws.residuals.len() > window && {
            let k = ws.residuals.len();
            ws.residuals[k - 1] > 0.5 * ws.residuals[k - 1 - window]
        };
        if iteration >= max_iterations || stagnant {
            return Err(Failure::NotConverged {
                residual: rnorm,
                reference,
            });
        }
        let fresh = !(chord && ws.factored);
        if fresh {
            factorize_current(disc, linear, ws).map_err(Failure::Singular)?;
            ws.k_factored.copy_from_slice(&ws.k);
            ws.factored = kind == TangentKind::Consistent;
        }
        if fresh && ws.factored {
            // The correction and K_f^-1 G for the tangent in one 4-column solve (fine RVE:
            // 2.0 ms, against 1.1 ms for the correction alone and 1.8 ms for the three
            // tangent columns; paper RVE: 0.11, 0.04 and 0.08 ms): if the increment ends on
            // this factorization (a chord step follows), the tangent starts from it (see
            // `condensed_tangent`). Done whether or not the tangent is wanted, so that the
            // correction, and with it the stress, has the same bits either way.
            let n = disc.n();
            let (first, rest) = ws.rhs4.split_at_mut(n);
            first.iter_mut().zip(&ws.r).for_each(|(d, r)| *d = -r);
            rest.copy_from_slice(&disc.g);
            linear.solve_in_place(
                &mut ws.factor,
                &mut ws.rhs4,
                4,
                MemStack::new(&mut ws.stack),
            );
            ws.dx.copy_from_slice(&ws.rhs4[..n]);
            ws.kg.copy_from_slice(&ws.rhs4[n..]);
            ws.kg_of_factor = true;
        } else {
            ws.dx.iter_mut().zip(&ws.r).for_each(|(d, r)| *d = -r);
            linear.solve_in_place(&mut ws.factor, &mut ws.dx, 1, MemStack::new(&mut ws.stack));
        }
        if ws.dx.iter().any(|d| !d.is_finite()) {
            return Err(Failure::Singular("non-finite Newton correction".into()));
        }
        iteration += 1;

        // The matrix of the next iterate: secant until the hand-over, then consistent.
        let next_kind = match mode {
            Mode::Newton | Mode::NewtonUntilStagnant => TangentKind::Consistent,
            Mode::SecantThenNewton => kind,
        };
        let new_norm = if kind == TangentKind::Consistent {
            line_search(disc, eps, x, rnorm, settings.line_search, next_kind, ws)
        } else {
            try_step(disc, eps, x, 1.0, next_kind, ws);
            norm(&ws.r_try)
        };
        x.copy_from_slice(&ws.x_try);
        accept_try(ws);
        if mode == Mode::SecantThenNewton {
            let wanted = if new_norm <= SECANT_HANDOVER * tolerance {
                TangentKind::Consistent
            } else if kind == TangentKind::Consistent && new_norm > 10.0 * rnorm {
                TangentKind::Secant
            } else {
                kind
            };
            if wanted != kind {
                kind = wanted;
                evaluate_current(disc, x, eps, kind, ws);
            }
        }
        // A correction that contracted the residual this much leaves the tangent almost
        // unchanged: the next one reuses the factorization (see module docs).
        chord = settings.reuse_factorization
            && kind == TangentKind::Consistent
            && new_norm <= CHORD_CONTRACTION * rnorm;
        rnorm = new_norm;
    }
}

/// Backtracking on `||R||` along `ws.dx`: `alpha = 1, 1/2, ..., 1/32`, keeping the best;
/// leaves the chosen iterate in the `*_try` buffers and returns its residual norm.
fn line_search(
    disc: &Discretization,
    eps: &[f64; 3],
    x: &[f64],
    rnorm: f64,
    enabled: bool,
    kind: TangentKind,
    ws: &mut Workspace,
) -> f64 {
    let mut alpha = 1.0;
    let (mut best_alpha, mut best_norm) = (1.0, f64::INFINITY);
    let halvings = if enabled { 5 } else { 0 };
    for trial in 0..=halvings {
        try_step(disc, eps, x, alpha, kind, ws);
        let n_try = norm(&ws.r_try);
        if n_try < best_norm {
            best_norm = n_try;
            best_alpha = alpha;
        }
        if n_try < LINE_SEARCH_GROWTH * rnorm || trial == halvings {
            break;
        }
        alpha *= 0.5;
    }
    if best_alpha != alpha {
        try_step(disc, eps, x, best_alpha, kind, ws);
    }
    best_norm
}

/// Evaluates the system at `x + alpha dx` into the `*_try` buffers.
fn try_step(
    disc: &Discretization,
    eps: &[f64; 3],
    x: &[f64],
    alpha: f64,
    kind: TangentKind,
    ws: &mut Workspace,
) {
    for ((t, xi), di) in ws.x_try.iter_mut().zip(x).zip(&ws.dx) {
        *t = xi + alpha * di;
    }
    ws.counts_try = disc.evaluate_with(
        &ws.x_try,
        eps,
        &ws.hist_base,
        &mut ws.hist_try,
        &mut ws.r_try,
        Some(&mut ws.k_try),
        kind,
    );
}

/// The fixed parts of one RVE problem, borrowed from its model.
#[derive(Clone, Copy)]
pub struct Problem<'a> {
    pub disc: &'a Discretization,
    pub hom: &'a Homogenizer,
    pub linear: &'a LinearSolver,
    pub settings: &'a SolverSpec,
    /// Elastic sensitivity `-K_el^-1 G` (n x 3, column-major), or empty: the fallback
    /// predictor `x_0 = x_n + X_el Delta eps` of a step when the committed state has no
    /// sensitivity of its own or its prediction is refused (see the module docs).
    pub predictor: &'a [f64],
}

/// Predicts the start of a strain step `step` from `from` to `target`: `x += X step` with
/// the committed state's sensitivity `X_n` (the Newton predictor: its residual is
/// `O(|step|^2)`), plus the second-order term `s^2 e` of the committed state's path
/// curvature when `step` is `s` times its step in nearly the same direction (see
/// [`curvature_scale`]), or else the model's elastic `X_el`, whichever first lowers the
/// residual below that of `x` itself. The residual of `x` at `target` is `R_n + G step`
/// with `R_n` the converged residual (below the tolerance), so `||G step||` stands for it.
/// Nothing is predicted when the step goes towards the origin (unloading: the secant
/// response is linear and plain Newton from `x` is exact in one iteration).
/// `ws.hist_base` must hold the step's start history. `committed` is `None` to skip the
/// tangent predictor; otherwise `ws.tangent_prediction` receives `X_n step`. Returns
/// whether a prediction was taken (its consistent evaluation is then in
/// `ws.r`/`ws.k`/`ws.hist_trial`, for Newton to start from) and whether it was the
/// tangent one.
fn predict(
    problem: &Problem,
    committed: Option<&State>,
    x: &mut [f64],
    from: &[f64; 3],
    step: &[f64; 3],
    target: &[f64; 3],
    ws: &mut Workspace,
) -> (bool, bool) {
    let (disc, n) = (problem.disc, problem.disc.n());
    let outward = from[0] * step[0] + from[1] * step[1] + from[2] * step[2] >= 0.0;
    if !outward {
        return (false, false);
    }
    sensitivity_times(&disc.g, step, &mut ws.r_try);
    let before = norm(&ws.r_try);
    if let Some(committed) = committed.filter(|c| c.sensitivity.valid) {
        committed.sensitivity.times(step, &mut ws.x_try);
        ws.tangent_prediction.copy_from_slice(&ws.x_try);
        if problem.settings.second_order_predictor {
            if let Some(s) = curvature_scale(&committed.curvature, step) {
                committed.curvature.add_scaled(s, &mut ws.x_try);
            }
        }
        if take_prediction(disc, x, target, before, true, ws) {
            return (true, true);
        }
    }
    if problem.predictor.len() == 3 * n {
        sensitivity_times(problem.predictor, step, &mut ws.x_try);
        if take_prediction(disc, x, target, before, false, ws) {
            return (true, false);
        }
    }
    (false, false)
}

/// Steps whose direction is within this cosine of the stored curvature's step get the
/// second-order term (a proportional path has 1; the term is exact only along the stored
/// direction, and the cross terms `x''[Delta_par, Delta_perp]` it misses grow with the
/// angle).
const CURVATURE_ALIGNMENT: f64 = 0.99;
/// Largest ratio `s` of a step to the stored one that gets the term: `s^2 e` extrapolates
/// the curvature of the last step, which a much longer step outruns.
const CURVATURE_MAX_SCALE: f64 = 4.0;

/// The ratio `s` with `step ~ s * stored step`, if the committed curvature is valid and
/// `step` keeps its direction ([`CURVATURE_ALIGNMENT`], [`CURVATURE_MAX_SCALE`]).
fn curvature_scale(curvature: &PathCurvature, step: &[f64; 3]) -> Option<f64> {
    let p = &curvature.step;
    let dot = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (pp, sp, ss) = (dot(p, p), dot(step, p), dot(step, step));
    let aligned = pp > 0.0 && sp >= CURVATURE_ALIGNMENT * (pp * ss).sqrt();
    let s = sp / pp;
    (curvature.valid && aligned && s <= CURVATURE_MAX_SCALE).then_some(s)
}

/// Evaluates the prediction `x + ws.x_try` and takes it (into `x` and the current
/// evaluation) if its residual is below `before` and, for a tangent prediction
/// (`tangent`), no ITZ point passes the peak of the envelope (`delta = delta_c`) in this
/// step: a step into softening can pass a limit point of the RVE response, and from the
/// tangent prediction Newton then converges on the continuation of the pre-peak branch
/// beyond it, where the elastic predictor lets it fall onto the post-snap branch
/// (measured on the paper's section 5.2 paths). Points already past the peak at the start
/// of the step do not refuse it: after the snap the committed tangent knows their
/// softening (`scripts/robustness-study`: 6509 -> 6395 iterations on the cohesive-law
/// paths, 120 -> 115 slow increments on the paper-law ones, against refusing whenever a
/// point is past the peak). Before the peak the equilibrium is unique and nothing changes
/// but speed.
fn take_prediction(
    disc: &Discretization,
    x: &mut [f64],
    target: &[f64; 3],
    before: f64,
    tangent: bool,
    ws: &mut Workspace,
) -> bool {
    ws.x_try
        .iter_mut()
        .zip(x.iter())
        .for_each(|(t, xi)| *t += xi);
    ws.counts_try = disc.evaluate(
        &ws.x_try,
        target,
        &ws.hist_base,
        &mut ws.hist_try,
        &mut ws.r_try,
        Some(&mut ws.k_try),
    );
    let softening = tangent
        && disc.law.is_some_and(|law| {
            ws.hist_try
                .iter()
                .zip(&ws.hist_base)
                .any(|(h, b)| h.delta_max >= law.delta_c && b.delta_max < law.delta_c)
        });
    if softening || norm(&ws.r_try) >= before {
        return false;
    }
    x.copy_from_slice(&ws.x_try);
    accept_try(ws);
    true
}

/// Solves the RVE from the committed state to macro strain `eps`, writing the converged
/// state into `trial` (resized like `committed`) and, if asked, the tangent into
/// `tangent`. `committed` is never modified.
pub fn solve_increment(
    problem: &Problem,
    committed: &State,
    eps: [f64; 3],
    request: TangentRequest,
    ws: &mut Workspace,
    trial: &mut State,
    tangent: &mut [f64; 9],
) -> Result<IncrementReport> {
    let Problem {
        disc,
        hom,
        linear,
        settings,
        ..
    } = *problem;
    let (count_before, lu_before, lblt_before) =
        (ws.factor.count, ws.factor.lu_count, ws.factor.lblt_count);
    trial.copy_from(committed);
    let mut report = IncrementReport::default();
    if disc.n() == 0 {
        // Taylor: no fluctuation, no interface opening.
        trial.strain = eps;
        report.substeps = 1;
        if request == TangentRequest::Consistent {
            *tangent = hom.tangent(disc, &[]);
        }
        return Ok(report);
    }
    if disc.interfaces.is_empty() && problem.predictor.len() == 3 * disc.n() {
        // No ITZ (perfect bonding): the RVE is linear and `x = X_el eps` exactly, with the
        // model's elastic sensitivity; no assembly, no factorization (DESIGN.md section 5:
        // effects a scene does not call for cost nothing).
        linear_response(problem, eps, request, ws, trial, tangent);
        report.substeps = 1;
        return Ok(report);
    }
    let start = committed.strain;
    let delta = [eps[0] - start[0], eps[1] - start[1], eps[2] - start[2]];
    let (mut done, mut step) = (0.0f64, 1.0f64);
    let (mut depth, mut successes_in_row) = (0u32, 0u32);
    // The speed-ups (tangent predictor, chord corrections) serve the easy increments. Once
    // plain Newton has failed on a step, the rest of the increment runs without them:
    // plain Newton, as the remedies below were designed and measured with, and no
    // committed-state sensitivity applied to sub-steps that start elsewhere.
    let plain_settings = SolverSpec {
        reuse_factorization: false,
        ..*settings
    };
    let mut hard = false;
    // Whether the increment's first try started from the tangent predictor.
    let mut tangent_start = false;
    while done < 1.0 {
        let settings = if hard { &plain_settings } else { settings };
        let to = (done + step).min(1.0);
        let target = if to >= 1.0 {
            eps
        } else {
            [
                start[0] + to * delta[0],
                start[1] + to * delta[1],
                start[2] + to * delta[2],
            ]
        };
        ws.substep_start.copy_from(trial);
        ws.hist_base.copy_from_slice(&trial.history);
        let step_strain = [
            target[0] - trial.strain[0],
            target[1] - trial.strain[1],
            target[2] - trial.strain[2],
        ];
        let from = trial.strain;
        // The sub-step's predictor and Newton loop, from `trial` at `from` to `target`.
        let predict_step = |committed, trial: &mut State, ws: &mut Workspace| {
            predict(
                problem,
                committed,
                &mut trial.unknowns,
                &from,
                &step_strain,
                &target,
                ws,
            )
        };
        let newton_step = |settings, trial: &mut State, ws: &mut Workspace, mode, evaluated| {
            newton(
                disc,
                linear,
                settings,
                &target,
                &mut trial.unknowns,
                ws,
                mode,
                evaluated,
            )
        };
        let (evaluated, tangent_predicted) = predict_step((!hard).then_some(committed), trial, ws);
        if !hard {
            // The whole increment's first try (the only pass while not `hard`).
            tangent_start = tangent_predicted;
        }
        // 1. Plain Newton.
        let first_mode = if depth == 0 {
            Mode::NewtonUntilStagnant
        } else {
            Mode::Newton
        };
        let mut outcome = newton_step(settings, trial, ws, first_mode, evaluated);
        // 1b. Near a limit point the tangent predictor can overshoot into the basin of
        // another equilibrium; plain Newton then starts again from the elastic predictor.
        // (Retrying after chord corrections alone changed none of the outcomes on an
        // earlier 22-path robustness sample and cost 40 iterations at the snap.)
        let retry = outcome.is_err() && tangent_predicted;
        hard |= outcome.is_err();
        let settings = if hard { &plain_settings } else { settings };
        if retry {
            restart(&mut report, trial, ws);
            let (evaluated, _) = predict_step(None, trial, ws);
            outcome = newton_step(settings, trial, ws, Mode::Newton, evaluated);
        }
        // 2. Path following through a limit point, landing on the target (see
        // `arclength`).
        if outcome.is_err() && settings.path_following {
            restart(&mut report, trial, ws);
            let reference = reference(disc, &target);
            let mut work = Traced::default();
            let landed = trace(
                disc, linear, settings, start, delta, done, to, reference, trial, ws, &mut work,
            );
            report.substeps += work.points;
            outcome = if landed {
                // On the target, from the last arc point's history (the sub-step's).
                report.limit_points += work.limit_points;
                Ok(work.iterations)
            } else {
                report.iterations += work.iterations;
                Err(Failure::PathLost)
            };
        }
        // 3. Secant iterations, then Newton, from the start of the sub-step.
        if outcome.is_err() && settings.max_secant_iterations > 0 {
            restart(&mut report, trial, ws);
            ws.hist_base.copy_from_slice(&trial.history);
            outcome = newton_step(settings, trial, ws, Mode::SecantThenNewton, false);
        }
        match outcome {
            Ok(iterations) => {
                report.iterations += iterations;
                report.substeps += 1;
                trial.history.copy_from_slice(&ws.hist_trial);
                trial.strain = target;
                done = to;
                successes_in_row += 1;
                if successes_in_row >= 2 && step < 1.0 {
                    step *= 2.0;
                    depth = depth.saturating_sub(1);
                    successes_in_row = 0;
                }
            }
            Err(failure) => {
                report.iterations += ws.residuals.len().saturating_sub(1) as u32;
                // The last iterate of a lost path is an arc point at another strain: no hint.
                let final_failure = depth + 1 > settings.max_substep_depth;
                let hint = if final_failure && !matches!(failure, Failure::PathLost) {
                    contact_law_hint(disc, &target, trial, ws)
                } else {
                    String::new()
                };
                trial.copy_from(&ws.substep_start);
                depth += 1;
                successes_in_row = 0;
                if depth > settings.max_substep_depth {
                    let suggested = done.max(step).clamp(0.1, 0.5);
                    return Err(Error::Solve {
                        reason: failure.describe(settings.max_iterations) + &hint,
                        depth: depth - 1,
                        suggested_step_ratio: suggested,
                    });
                }
                step *= 0.5;
            }
        }
    }
    // The branch counts of the last evaluation, at the converged point.
    let counts = ws.counts;
    report.loading = counts.loading;
    report.unloading = counts.unloading;
    report.contact = counts.contact;
    if request == TangentRequest::Consistent {
        let condensed = condensed_tangent(disc, linear, ws)?;
        *tangent = hom.tangent_from_condensed(&condensed);
        trial.sensitivity.store_negated(&ws.kg);
    }
    // The path curvature for the next increment, kept when this one converged from its
    // first-order prediction in one Newton loop and refreshed the sensitivity.
    let smooth = settings.second_order_predictor && tangent_start && !hard;
    if request == TangentRequest::Consistent && smooth {
        store_curvature(committed, delta, ws, trial);
    } else {
        trial.curvature.valid = false;
    }
    report.factorizations = (ws.factor.count - count_before) as u32;
    report.lu_factorizations = (ws.factor.lu_count - lu_before) as u32;
    report.lblt_factorizations = (ws.factor.lblt_count - lblt_before) as u32;
    Ok(report)
}

/// Stores into `trial` the path curvature of the increment `delta` from `committed`: the
/// error `x_conv - x_n - X_n delta` of its first-order prediction (`X_n delta` is in
/// `ws.tangent_prediction`; `ws.x_try` is scratch).
fn store_curvature(committed: &State, delta: [f64; 3], ws: &mut Workspace, trial: &mut State) {
    let (x_conv, x_start) = (&trial.unknowns, &committed.unknowns);
    for (i, e) in ws.x_try.iter_mut().enumerate() {
        *e = x_conv[i] - x_start[i] - ws.tangent_prediction[i];
    }
    trial.curvature.store(&ws.x_try, delta);
}

/// After a failed loop: counts its corrections and puts the trial back at the start of
/// the sub-step, for the next remedy.
fn restart(report: &mut IncrementReport, trial: &mut State, ws: &Workspace) {
    report.iterations += ws.residuals.len().saturating_sub(1) as u32;
    trial.copy_from(&ws.substep_start);
}

/// On a final failure: if the last iterate has closed ITZ points under the paper's contact
/// law, say so and name the remedy. That law's shear traction jumps at closure (eq. 47
/// against eqs. 32-35), and closed points that slide can leave the discrete RVE without an
/// equilibrium (see `ContactShear`); no step size or solver setting helps then.
fn contact_law_hint(
    disc: &Discretization,
    target: &[f64; 3],
    trial: &State,
    ws: &mut Workspace,
) -> String {
    let paper_law = disc
        .law
        .is_some_and(|l| l.contact && l.contact_shear == ContactShear::Penalty);
    if !paper_law || trial.unknowns.iter().any(|v| !v.is_finite()) {
        return String::new();
    }
    let counts = disc.evaluate(
        &trial.unknowns,
        target,
        &ws.hist_base,
        &mut ws.hist_try,
        &mut ws.r_try,
        None,
    );
    if counts.contact == 0 {
        return String::new();
    }
    format!(
        "; {} ITZ points are closed at the last iterate: with the paper's contact law \
         (materials.itz.contact_shear = \"penalty\") the shear traction jumps at closure and \
         sliding closed points can leave the RVE without equilibrium; \
         contact_shear = \"cohesive\" keeps it continuous",
        counts.contact
    )
}

/// `out = X d` for a sensitivity `X` (n x 3, column-major) and a strain `d`.
fn sensitivity_times(sensitivity: &[f64], d: &[f64; 3], out: &mut [f64]) {
    let n = out.len();
    let (x0, rest) = sensitivity.split_at(n);
    let (x1, x2) = rest.split_at(n);
    for (i, o) in out.iter_mut().enumerate() {
        *o = x0[i] * d[0] + x1[i] * d[1] + x2[i] * d[2];
    }
}

/// The exact response of an RVE without interfaces: `x = X_el eps` from the model's
/// elastic sensitivity `X_el = -K^-1 G`, and `D_hom` from `K^-1 G = -X_el` (eq. 18).
fn linear_response(
    problem: &Problem,
    eps: [f64; 3],
    request: TangentRequest,
    ws: &mut Workspace,
    trial: &mut State,
    tangent: &mut [f64; 9],
) {
    sensitivity_times(problem.predictor, &eps, &mut trial.unknowns);
    trial.strain = eps;
    if request == TangentRequest::Consistent {
        for (kg, p) in ws.kg.iter_mut().zip(problem.predictor) {
            *kg = -p;
        }
        *tangent = problem.hom.tangent(problem.disc, &ws.kg);
    }
}

/// Computes the condensed term `C = G^T K^-1 G` (3 x 3, row-major) at the converged state
/// (`ws.k`) and leaves the best `X ~ K^-1 G` in `ws.kg`, reusing the last factorization
/// `K_f` when it can (see module docs).
///
/// With `K_f != K`, `X_0 = K_f^-1 G` is refined by sweeps `X_{k+1} = X_k + K_f^-1 R_k`,
/// `R_k = G - K X_k`, and `C` is taken from the stationary (variational) form
/// `C(X) = G^T X + X^T R(X)`, whose error `-(X - X*)^T K (X - X*)` is quadratic in the
/// error of `X` (`K` is symmetric). The sweeps contract the error by
/// `rho ~ ||R_k|| / ||R_{k-1}||`, so the error of `C_k` is about `|C_k - C_{k-1}| rho^2`;
/// they stop when that is below [`TANGENT_ACCURACY`], and give way to a fresh
/// factorization when [`TANGENT_SWEEPS`] cannot reach it.
fn condensed_tangent(
    disc: &Discretization,
    linear: &LinearSolver,
    ws: &mut Workspace,
) -> Result<[f64; 9]> {
    let n = disc.n();
    let condensed = |x: &[f64], res: Option<&[f64]>| -> [f64; 9] {
        let mut out = [0.0; 9];
        for i in 0..3 {
            for j in 0..3 {
                let (gi, xj) = (&disc.g[i * n..(i + 1) * n], &x[j * n..(j + 1) * n]);
                let mut c: f64 = gi.iter().zip(xj).map(|(a, b)| a * b).sum();
                if let Some(r) = res {
                    let (xi, rj) = (&x[i * n..(i + 1) * n], &r[j * n..(j + 1) * n]);
                    c += xi.iter().zip(rj).map(|(a, b)| a * b).sum::<f64>();
                }
                out[3 * i + j] = c;
            }
        }
        out
    };
    let unchanged = ws.factored && ws.k == ws.k_factored;
    if ws.factored {
        if !ws.kg_of_factor {
            ws.kg.copy_from_slice(&disc.g);
            linear.solve_in_place(&mut ws.factor, &mut ws.kg, 3, MemStack::new(&mut ws.stack));
        }
        if unchanged {
            return Ok(condensed(&ws.kg, None));
        }
        let residual = |ws: &mut Workspace| {
            disc.pattern.mul_symmetric3(&ws.k, &ws.kg, &mut ws.kg_res);
            for (ri, gi) in ws.kg_res.iter_mut().zip(&disc.g) {
                *ri = gi - *ri;
            }
            norm(&ws.kg_res)
        };
        let mut res_norm = residual(ws);
        let mut previous = condensed(&ws.kg, Some(&ws.kg_res));
        let scale = previous
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()))
            .max(f64::MIN_POSITIVE);
        for sweep in 1..=TANGENT_SWEEPS {
            // The correction K_f^-1 R_k, in place: `residual` rewrites `kg_res` next.
            linear.solve_in_place(
                &mut ws.factor,
                &mut ws.kg_res,
                3,
                MemStack::new(&mut ws.stack),
            );
            ws.kg.iter_mut().zip(&ws.kg_res).for_each(|(x, d)| *x += d);
            let new_norm = residual(ws);
            let now = condensed(&ws.kg, Some(&ws.kg_res));
            let change = now
                .iter()
                .zip(&previous)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
                / scale;
            let rho = new_norm / res_norm;
            let error = change * rho * rho;
            if !(error.is_finite() && rho < 1.0) {
                break;
            }
            if error <= TANGENT_ACCURACY || new_norm == 0.0 {
                return Ok(now);
            }
            // Each further sweep multiplies the error by rho^2: give up early if the
            // budget cannot reach the accuracy.
            let left = (TANGENT_SWEEPS - sweep) as i32;
            if error * rho.powi(2 * left) > TANGENT_ACCURACY {
                break;
            }
            previous = now;
            res_norm = new_norm;
        }
    }
    factorize_current(disc, linear, ws).map_err(|e| Error::Solve {
        reason: format!("singular RVE tangent at the converged state ({e:?})"),
        depth: 0,
        suggested_step_ratio: 0.5,
    })?;
    ws.k_factored.copy_from_slice(&ws.k);
    ws.factored = true;
    ws.kg.copy_from_slice(&disc.g);
    linear.solve_in_place(&mut ws.factor, &mut ws.kg, 3, MemStack::new(&mut ws.stack));
    Ok(condensed(&ws.kg, None))
}

//! The Newton kernel: one loop at a fixed macro strain, with a line search, chord
//! corrections and a secant mode.
//!
//! # Convergence test
//! An iterate converges when `||R||_2 <= tolerance * reference` (see
//! [`Problem::reference`]).
//!
//! # Line search
//! Backtracking on `||R||`: the full step is accepted unless it multiplies the residual
//! norm by more than [`LINE_SEARCH_GROWTH`]; otherwise the step is halved up to five times,
//! and the step with the smallest residual is taken (even if none reduces it, so that
//! Newton can cross the kinks of the law). Switched off by `Settings::line_search`.
//!
//! # Chord corrections
//! A Newton correction that cuts the residual at least a hundredfold
//! ([`CHORD_CONTRACTION`]) with every interface point on the branch (and contact status)
//! it had at the factorization shows that the tangent barely changed over the step; the
//! next
//! correction then reuses the factorization (a chord or modified-Newton step, contracting
//! by the relative change of the tangent) instead of factorizing the new tangent.
//! `Settings::reuse_factorization = false` gives plain Newton and its quadratic rate.
//!
//! # Secant iterations, then Newton ([`Mode::SecantThenNewton`])
//! Past the peak, loading/unloading switches at many interface points can make Newton
//! cycle (a semismooth Newton on the kinks of the law). In secant mode the loading points
//! use the secant matrix of the law instead of its tangent, so every matrix is positive
//! definite and each iterate solves `K_sec(x_k) x_{k+1} = -G eps` (the fixed-point
//! iteration of damage mechanics, robust through softening and snap-back). Below
//! [`SECANT_HANDOVER`] times the tolerance the loop switches to consistent Newton for the
//! final quadratic convergence (and back to secant if Newton makes the residual grow
//! tenfold). The converged state satisfies the same equations; only the path differs.
//!
//! # Contact status
//! With a law that has a contact status, the status is held within each iteration and
//! read again at the first iterate and after each accepted one (see `contact`).

use super::contact;
use super::problem::{accept_candidate, norm, Problem, Strain};
use super::settings::Settings;
use super::workspace::{FactorUse, Workspace};
use crate::error::Error;
use crate::interface::TangentKind;
use crate::state::State;

/// How a Newton loop globalizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Mode {
    /// Consistent Newton with backtracking line search.
    Newton,
    /// The same, giving up early once the residual stagnates or the branch sets cycle (see
    /// [`STAGNATION_WINDOW`], [`CYCLE_WINDOW`]).
    NewtonUntilStagnant,
    /// Secant iterations, switching to Newton near convergence.
    SecantThenNewton,
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
    pub(super) fn describe(&self, max_iterations: u32) -> String {
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

/// The full Newton step is taken unless it multiplies `||R||` by more than this; smaller
/// steps are tried only then (a non-monotone rule: across the kinks of the cohesive law a
/// temporary rise of the residual is normal, and strict decrease stalls Newton).
const LINE_SEARCH_GROWTH: f64 = 1.0;
/// A Newton correction that multiplies `||R||` by at most this is followed by a chord
/// correction with the same factorization.
const CHORD_CONTRACTION: f64 = 1e-2;
/// [`Mode::NewtonUntilStagnant`] gives up once its residual has not halved over this many
/// iterations. At an RVE snap-back the residual of strain-controlled Newton sits at a
/// local minimum that is no root, and path following is the remedy; in the sub-steps of
/// a bisection slow Newton is the remedy that works, so only the first try stops early.
const STAGNATION_WINDOW: usize = 10;
/// Points pinned at the status of the loop's start state (`contact`) keep it for this
/// many corrections, and are read from their gaps again after them: a step short enough
/// converges within them, with the start's status, where a switch would throw the iterate
/// out by the traction jump (up to 1e2 of the reference on the hard cases).
const PINNED_CORRECTIONS: u32 = 2;
/// Corrections spent looking for an equilibrium with released pinned points (here and in
/// the path following's corrector).
pub(super) const RELEASE_BUDGET: u32 = 6;
/// [`Mode::NewtonUntilStagnant`] also gives up once an iterate's interface branch set is
/// one of the last this many iterates' without the residual having halved since: a
/// semismooth Newton that comes back to a branch set without progress cycles. The path
/// following's corrector looks back as far.
pub(super) const CYCLE_WINDOW: usize = 4;
/// Secant iterations hand over to Newton below this multiple of the tolerance.
const SECANT_HANDOVER: f64 = 100.0;

/// One Newton loop at the macro strain `strain` from the unknowns `x`, with the interface
/// history `ws.history_start`. `evaluated`: `ws.current` already holds the consistent
/// evaluation at `x` (from the predictor). On success `x` is converged, `ws.current`
/// belongs to it (with the consistent tangent), `ws.factorization` holds the last
/// factorization, and the number of corrections is returned.
pub(super) fn newton(
    problem: &Problem,
    settings: &Settings,
    strain: &Strain,
    x: &mut [f64],
    ws: &mut Workspace,
    mode: Mode,
    evaluated: bool,
) -> Result<u32, Failure> {
    let mut run = NewtonLoop::start(problem, settings, strain, x, ws, mode, evaluated);
    loop {
        run.record();
        if !run.rnorm.is_finite() && run.released.is_none() {
            return Err(Failure::NonFinite);
        }
        if run.rnorm <= run.tolerance {
            if run.released.is_none() && contact::release_pinned(problem, run.x, run.ws) {
                run.release();
                continue;
            }
            return Ok(run.converged());
        }
        if run.out_of_iterations() {
            return run.give_up();
        }
        run.iterate()?;
    }
}

/// The state of one [`newton`] loop between its iterations.
struct NewtonLoop<'a, 'p> {
    problem: &'a Problem<'p>,
    settings: &'a Settings,
    strain: &'a Strain,
    /// The iterate.
    x: &'a mut [f64],
    ws: &'a mut Workspace,
    mode: Mode,
    reference: f64,
    /// `settings.tolerance * reference`, the convergence test on `||R||`.
    tolerance: f64,
    max_iterations: u32,
    /// The matrix of the iterations: secant or consistent.
    kind: TangentKind,
    /// `||R||` at the iterate.
    rnorm: f64,
    /// Corrections so far.
    iteration: u32,
    /// Whether the next correction reuses the factorization (see "Chord corrections").
    chord: bool,
    /// The iteration at which pinned points were released at a converged iterate.
    released: Option<u32>,
    /// The interface branches of the iterate whose tangent is factorized.
    factored_branches: u64,
}

impl<'a, 'p> NewtonLoop<'a, 'p> {
    /// Evaluates the start iterate `x` (unless `evaluated` already did with the
    /// consistent tangent) with the contact status of the first iteration.
    fn start(
        problem: &'a Problem<'p>,
        settings: &'a Settings,
        strain: &'a Strain,
        x: &'a mut [f64],
        ws: &'a mut Workspace,
        mode: Mode,
        evaluated: bool,
    ) -> Self {
        let reference = problem.reference(strain);
        let tolerance = settings.tolerance * reference;
        let (max_iterations, kind) = match mode {
            Mode::Newton | Mode::NewtonUntilStagnant => {
                (settings.max_iterations, TangentKind::Consistent)
            }
            Mode::SecantThenNewton => (settings.max_secant_iterations, TangentKind::Secant),
        };
        ws.factorization.invalidate();
        ws.residuals.clear();
        ws.branch_signatures.clear();
        if !evaluated {
            contact::restore(ws);
        }
        if !(evaluated && kind == TangentKind::Consistent) {
            problem.evaluate(x, strain, kind, ws);
        }
        // The contact status of the first iteration (see `contact`); pinned points keep
        // theirs.
        if contact::update(problem, x, false, ws) > 0 {
            problem.evaluate(x, strain, kind, ws);
        }
        let rnorm = norm(&ws.current.r);
        NewtonLoop {
            problem,
            settings,
            strain,
            x,
            ws,
            mode,
            reference,
            tolerance,
            max_iterations,
            kind,
            rnorm,
            iteration: 0,
            chord: false,
            released: None,
            factored_branches: 0,
        }
    }

    /// Keeps the relative residual and branch set of the iterate (as long as
    /// `ws.residuals` has room).
    fn record(&mut self) {
        let ws = &mut *self.ws;
        if ws.residuals.len() < ws.residuals.capacity() {
            ws.residuals.push(self.rnorm / self.reference);
            ws.branch_signatures
                .push(ws.current.counts.branch_signature);
        }
    }

    /// Converged with points pinned against their gap, now released: look once for an
    /// equilibrium with their gaps' status, from here.
    fn release(&mut self) {
        self.ws.pinned_x.copy_from_slice(self.x);
        self.released = Some(self.iteration);
        self.problem
            .evaluate(self.x, self.strain, self.kind, self.ws);
        self.rnorm = norm(&self.ws.current.r);
        self.chord = false;
        self.ws.factorization.invalidate();
    }

    /// The converged iterate: with the consistent tangent in `ws.current`; returns the
    /// corrections.
    fn converged(&mut self) -> u32 {
        if self.kind == TangentKind::Secant {
            // Converged on secant matrices: the tangent needs the consistent one.
            self.problem
                .evaluate(self.x, self.strain, TangentKind::Consistent, self.ws);
            self.ws.factorization.invalidate();
        }
        self.iteration
    }

    /// Whether the loop stops unconverged: out of iterations, out of the release budget,
    /// or (in [`Mode::NewtonUntilStagnant`]) stagnant or cycling.
    fn out_of_iterations(&self) -> bool {
        let out_of_budget = self
            .released
            .is_some_and(|r| self.iteration >= r + RELEASE_BUDGET)
            || !self.rnorm.is_finite();
        self.iteration >= self.max_iterations
            || out_of_budget
            || (self.mode == Mode::NewtonUntilStagnant && (stagnant(self.ws) || cycling(self.ws)))
    }

    /// The end of an unconverged loop: the pinned equilibrium if points were released
    /// at one, else the failure.
    fn give_up(&mut self) -> Result<u32, Failure> {
        if self.released.is_some() {
            // No equilibrium with the gaps' status found: back to the pinned one.
            self.x.copy_from_slice(&self.ws.pinned_x);
            contact::restore_saved(self.ws);
            self.problem
                .evaluate(self.x, self.strain, TangentKind::Consistent, self.ws);
            self.ws.factorization.invalidate();
            return Ok(self.iteration);
        }
        Err(Failure::NotConverged {
            residual: self.rnorm,
            reference: self.reference,
        })
    }

    /// One correction: solve, line search (consistent) or full step (secant), the
    /// contact status of the next iteration, the matrix of the next iteration and whether
    /// it is a chord step.
    fn iterate(&mut self) -> Result<(), Failure> {
        let (problem, strain, kind) = (self.problem, self.strain, self.kind);
        if correction(problem, kind, self.chord, self.ws)? {
            self.factored_branches = self.ws.current.counts.branch_signature;
        }
        self.iteration += 1;
        let new_norm = if kind == TangentKind::Consistent {
            line_search(
                problem,
                strain,
                self.x,
                self.rnorm,
                self.settings.line_search,
                self.ws,
            )
        } else {
            step(problem, strain, self.x, 1.0, kind, self.ws);
            norm(&self.ws.candidate.r)
        };
        self.x.copy_from_slice(&self.ws.x_try);
        accept_candidate(self.ws);
        // The contact status of the next iteration.
        let release = self.iteration >= PINNED_CORRECTIONS;
        let new_norm = if contact::update(problem, self.x, release, self.ws) > 0 {
            problem.evaluate(self.x, strain, kind, self.ws);
            norm(&self.ws.current.r)
        } else {
            new_norm
        };
        if self.mode == Mode::SecantThenNewton {
            self.switch_matrix(new_norm);
        }
        // A correction that contracted the residual this much, with no interface point
        // changing branch since the factorization, leaves the tangent almost unchanged:
        // the next one reuses the factorization.
        self.chord = self.settings.reuse_factorization
            && self.kind == TangentKind::Consistent
            && new_norm <= CHORD_CONTRACTION * self.rnorm
            && self.ws.current.counts.branch_signature == self.factored_branches;
        self.rnorm = new_norm;
        Ok(())
    }

    /// [`Mode::SecantThenNewton`]: consistent Newton below [`SECANT_HANDOVER`] times the
    /// tolerance, back to secant if Newton made the residual grow tenfold (`new_norm`
    /// against `rnorm`); re-evaluates the iterate on a change.
    fn switch_matrix(&mut self, new_norm: f64) {
        let kind = self.kind;
        let wanted = if new_norm <= SECANT_HANDOVER * self.tolerance {
            TangentKind::Consistent
        } else if kind == TangentKind::Consistent && new_norm > 10.0 * self.rnorm {
            TangentKind::Secant
        } else {
            kind
        };
        if wanted != kind {
            self.kind = wanted;
            self.problem.evaluate(self.x, self.strain, wanted, self.ws);
        }
    }
}

/// Whether the residual has not halved over the last [`STAGNATION_WINDOW`] iterations.
fn stagnant(ws: &Workspace) -> bool {
    let k = ws.residuals.len();
    k > STAGNATION_WINDOW && ws.residuals[k - 1] > 0.5 * ws.residuals[k - 1 - STAGNATION_WINDOW]
}

/// Whether the last iterate's branch set comes back from one of the [`CYCLE_WINDOW`]
/// iterates' before it (see [`comes_back`]).
fn cycling(ws: &Workspace) -> bool {
    let (r, b) = (&ws.residuals, &ws.branch_signatures);
    let Some(k) = r.len().checked_sub(1) else {
        return false;
    };
    let earlier = (k.saturating_sub(CYCLE_WINDOW)..k)
        .rev()
        .map(|j| (b[j], r[j]));
    comes_back(earlier, b[k], r[k])
}

/// Whether an iterate with branch set `branches` and residual norm `residual` comes back
/// to the set of one of the `earlier` iterates (most recent first) with another set in
/// between, the residual not halved since that one: a semismooth Newton cycling between
/// branch sets, which never converges. An unchanged set is no cycle: the iterates then
/// move on one smooth piece of the law (a line search that halves the step halves a
/// linear residual exactly, and round-off would decide), and stagnation judges them.
pub(super) fn comes_back(
    earlier: impl Iterator<Item = (u64, f64)>,
    branches: u64,
    residual: f64,
) -> bool {
    let mut another_between = false;
    for (set, r) in earlier {
        if set == branches && another_between && residual > 0.5 * r {
            return true;
        }
        another_between |= set != branches;
    }
    false
}

/// The Newton correction `dx = -K^-1 R` into `ws.dx`: a chord step with the kept factors
/// when `chord` allows it, else with a fresh factorization of `ws.current.k`. A fresh
/// consistent factorization solves `[-R | G]` in one 4-column solve, so that an increment
/// ending on it (a chord step follows) starts its tangent from `K_f^-1 G` (see
/// `tangent`); done whether or not the tangent is wanted, so that the correction, and with
/// it the stress, has the same bits either way. Returns whether it factorized.
fn correction(
    problem: &Problem,
    kind: TangentKind,
    chord: bool,
    ws: &mut Workspace,
) -> Result<bool, Failure> {
    let fresh = !(chord && ws.factorization.is_reusable());
    if fresh {
        problem
            .factorize(
                ws,
                if kind == TangentKind::Consistent {
                    FactorUse::Reusable
                } else {
                    FactorUse::OneUse
                },
            )
            .map_err(|e| Failure::Singular(e.to_string()))?;
    }
    if fresh && ws.factorization.is_reusable() {
        ws.factorization.solve_with_g(
            problem.linear,
            &problem.disc.g,
            &ws.current.r,
            &mut ws.rhs4,
            &mut ws.dx,
        );
    } else {
        problem.solve_correction(ws);
    }
    if ws.dx.iter().any(|d| !d.is_finite()) {
        return Err(Failure::Singular("non-finite Newton correction".into()));
    }
    Ok(fresh)
}

/// Backtracking on `||R||` along `ws.dx`: `alpha = 1, 1/2, ..., 1/32`, keeping the best;
/// leaves the chosen iterate in `ws.x_try` and `ws.candidate` and returns its residual
/// norm.
fn line_search(
    problem: &Problem,
    strain: &Strain,
    x: &[f64],
    rnorm: f64,
    enabled: bool,
    ws: &mut Workspace,
) -> f64 {
    let kind = TangentKind::Consistent;
    let mut alpha = 1.0;
    let (mut best_alpha, mut best_norm) = (1.0, f64::INFINITY);
    let halvings = if enabled { 5 } else { 0 };
    for trial in 0..=halvings {
        step(problem, strain, x, alpha, kind, ws);
        let n_try = norm(&ws.candidate.r);
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
        step(problem, strain, x, best_alpha, kind, ws);
    }
    best_norm
}

/// Evaluates the system at `x + alpha dx` as the candidate.
fn step(
    problem: &Problem,
    strain: &Strain,
    x: &[f64],
    alpha: f64,
    kind: TangentKind,
    ws: &mut Workspace,
) {
    for ((t, xi), di) in ws.x_try.iter_mut().zip(x).zip(&ws.dx) {
        *t = xi + alpha * di;
    }
    problem.evaluate_candidate(strain, kind, ws);
}

/// The fluctuation in equilibrium at `strain` with `state`'s history as the committed
/// one, by Newton with the line search from the guess in `unknowns`, every point's
/// contact status read from its gap. For a converged state that the secant solve
/// (`implex::secant_unknowns`) cannot rebuild from its history: a closed point sticking
/// under friction is on a branch offset from the origin by its slip, and at the converged
/// jump its committed slip puts it on the Coulomb limit with the converged traction.
pub fn equilibrium_unknowns(
    problem: &Problem,
    state: &State,
    strain: &Strain,
    ws: &mut Workspace,
    unknowns: &mut [f64],
) -> crate::error::Result<()> {
    ws.history_start.copy_from_slice(&state.history);
    ws.contact.held = false;
    let tolerance = problem.settings.tolerance * problem.reference(strain);
    problem.evaluate(unknowns, strain, TangentKind::Consistent, ws);
    let mut rnorm = norm(&ws.current.r);
    for _ in 0..problem.settings.max_iterations {
        if rnorm <= tolerance {
            return Ok(());
        }
        problem.one_use_correction(ws).map_err(|e| Error::Solve {
            reason: format!("singular RVE matrix rebuilding a state ({e:?})"),
            depth: 0,
            suggested_step_ratio: 0.5,
        })?;
        rnorm = line_search(problem, strain, unknowns, rnorm, true, ws);
        unknowns.copy_from_slice(&ws.x_try);
        accept_candidate(ws);
    }
    if rnorm <= tolerance {
        return Ok(());
    }
    Err(Error::Solve {
        reason: format!(
            "rebuilding a state: no equilibrium with its history in {} iterations (relative \
             residual {:.3e})",
            problem.settings.max_iterations,
            rnorm / problem.reference(strain)
        ),
        depth: 0,
        suggested_step_ratio: 0.5,
    })
}

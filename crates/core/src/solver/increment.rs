//! One macro strain increment: sub-stepping (Somer et al. 2009) over a ladder of remedies.
//!
//! # Remedy ladder
//! Each sub-step tries the [`Remedy`]s of [`LADDER`] in order until one converges, each
//! from the start of the sub-step:
//! 1. Newton from the predicted start (see `predictor`);
//! 2. after a failed tangent prediction, Newton again from the elastic prediction: near a
//!    limit point the tangent predictor can overshoot into the basin of another
//!    equilibrium;
//! 3. path following through a limit point, landing on the target (see `arclength`);
//! 4. secant iterations, then Newton (see `newton`).
//!
//! Once a remedy has been needed, the rest of the increment runs *hard*: plain Newton
//! (no chord corrections) from elastic predictions (no committed sensitivity applied to
//! sub-steps that start elsewhere). The speed-ups serve the easy increments; the remedies
//! keep the behaviour they were measured with.
//!
//! # Sub-stepping
//! If every remedy fails on a sub-step (no convergence, a singular or non-finite system),
//! it is bisected and the halves are solved in turn, each from the converged state
//! (fluctuation and interface history) of the previous one; after two successes in a row
//! the step doubles again (one level up). Past `max_substep_depth` levels of bisection the
//! update fails with a suggested step ratio (UMAT's PNEWDT), and the committed state is
//! untouched because every iterate lives in the trial state. With sub-steps, the tangent
//! is that of the last sub-step.

use super::arclength::{trace, StrainLine, Traced};
use super::contact;
use super::fast_path;
use super::newton::{newton, Failure, Mode};
use super::predictor::{predict, store_curvature, Prediction, StrainStep};
use super::problem::{accept_candidate, norm, sensitivity_times, Problem, Strain};
use super::settings::{IncrementReport, Settings, TangentRequest};
use super::tangent::{condensed, condensed_tangent};
use super::workspace::{FactorUse, Workspace};
use crate::error::{Error, Result};
use crate::interface::TangentKind;
use crate::state::State;

/// What a converged increment returns besides the trial state.
#[derive(Clone, Copy, Debug)]
pub struct Solved {
    pub report: IncrementReport,
    /// `G^T K^-1 G` (row-major) at the converged state when the tangent was requested,
    /// zeros otherwise: the caller forms `D_hom = D_Taylor - C / V` from it (eq. 18).
    pub condensed: [f64; 9],
}

/// A remedy of the ladder (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Remedy {
    Newton,
    NewtonFromElastic,
    PathFollowing,
    SecantIterations,
}

/// The order in which the remedies are tried on a sub-step.
const LADDER: [Remedy; 4] = [
    Remedy::Newton,
    Remedy::NewtonFromElastic,
    Remedy::PathFollowing,
    Remedy::SecantIterations,
];

/// One sub-step: the part `[from, to]` of the increment's strain line.
struct SubStep {
    from: f64,
    to: f64,
    /// The target strain, `line.at(to)` (exactly the increment's strain when `to` is 1).
    target: Strain,
}

/// The mutable context of one increment.
struct Increment<'p, 'a> {
    problem: &'p Problem<'a>,
    committed: &'p State,
    line: StrainLine,
    /// The settings without chord corrections, for the hard part of the increment.
    plain: Settings,
    hard: bool,
    /// Whether the increment's first try started from the tangent predictor.
    tangent_start: bool,
    /// The current bisection depth.
    depth: u32,
    report: IncrementReport,
}

/// Solves the RVE from the committed state to the macro strain `strain`, writing the
/// converged state into `trial` (resized like `committed`). `committed` is never
/// modified.
///
/// A committed state left by fast updates (its unknowns at another strain, see
/// `fast_path`) is first given its unknowns at its strain, in the workspace.
pub fn solve_increment(
    problem: &Problem,
    committed: &State,
    strain: Strain,
    request: TangentRequest,
    ws: &mut Workspace,
    trial: &mut State,
) -> Result<Solved> {
    if committed.unknowns_are_current() {
        return solve_from(problem, committed, strain, request, ws, trial);
    }
    let mut start = std::mem::replace(&mut ws.materialized, State::virgin(0, 0));
    let solved = fast_path::materialize(problem, committed, &mut start, ws)
        .and_then(|()| solve_from(problem, &start, strain, request, ws, trial));
    ws.materialized = start;
    // The materialization's factorization counts with the update's.
    solved.map(|mut s| {
        s.report.factorizations += 1;
        s
    })
}

/// [`solve_increment`] from a committed state whose unknowns are current.
fn solve_from(
    problem: &Problem,
    committed: &State,
    strain: Strain,
    request: TangentRequest,
    ws: &mut Workspace,
    trial: &mut State,
) -> Result<Solved> {
    let numeric = ws.factorization.numeric();
    let before = (
        numeric.count,
        numeric.lu_count,
        numeric.lblt_count,
        numeric.indefinite_ldlt_count,
    );
    trial.copy_solution_from(committed);
    contact::configure(problem, ws);
    if problem.n() == 0
        || (problem.disc.interfaces.is_empty() && problem.predictor.len() == 3 * problem.n())
    {
        return Ok(linear_response(problem, strain, request, ws, trial));
    }
    let origin = committed.strain;
    let delta = [
        strain[0] - origin[0],
        strain[1] - origin[1],
        strain[2] - origin[2],
    ];
    let mut increment = Increment {
        problem,
        committed,
        line: StrainLine { origin, delta },
        plain: Settings {
            reuse_factorization: false,
            ..*problem.settings
        },
        hard: false,
        tangent_start: false,
        depth: 0,
        report: IncrementReport::default(),
    };
    increment.substeps(strain, trial, ws)?;
    let polished = polish(problem, &strain, trial, ws);
    let mut report = increment.report;
    report.iterations += u32::from(polished);
    let counts = ws.current.counts;
    (report.loading, report.unloading, report.contact) =
        (counts.loading, counts.unloading, counts.contact);
    report.held_points = contact::record_held(problem, trial, ws);
    let mut solved = [0.0; 9];
    if request == TangentRequest::Consistent {
        solved = condensed_tangent(problem, ws)?;
        trial.sensitivity.store_negated(ws.factorization.kg());
    }
    // The path curvature for the next increment, kept when this one converged from its
    // first-order prediction in one Newton loop and refreshed the sensitivity, and had a
    // loading point: on linear branches only the path is a straight line (`x = X_b eps`,
    // see `fast_path`), whose curvature is zero, and a fast update, which keeps none,
    // leaves the same state.
    let smooth = problem.settings.second_order_predictor
        && increment.tangent_start
        && !increment.hard
        && !(problem.disc.law.is_some() && report.loading == 0);
    if request == TangentRequest::Consistent && smooth {
        store_curvature(committed, delta, ws, trial);
    } else {
        trial.curvature.valid = false;
    }
    let numeric = ws.factorization.numeric();
    report.factorizations = (numeric.count - before.0) as u32;
    report.lu_factorizations = (numeric.lu_count - before.1) as u32;
    report.lblt_factorizations = (numeric.lblt_count - before.2) as u32;
    report.indefinite_ldlt_factorizations = (numeric.indefinite_ldlt_count - before.3) as u32;
    Ok(Solved {
        report,
        condensed: solved,
    })
}

/// On linear branches only (no loading point at the converged iterate) the equilibrium is
/// linear, `K_b x + G eps = 0`, and one correction with the exact `K_b` solves it to
/// round-off. Made after every such increment whose loop stopped within the tolerance at
/// an iterate not reached with the factors of `K_b` (the predictor itself, a chord step
/// with an older tangent): the update then returns
/// `x = X_b eps`, the answer of the fast path (`fast_path`), and the factors of `K_b`
/// are left for the tangent. The corrected iterate is kept when it stays on the branch
/// set and does not raise the residual. Returns whether it was kept.
fn polish(problem: &Problem, strain: &Strain, trial: &mut State, ws: &mut Workspace) -> bool {
    // A loop whose last correction used the factors of exactly this `K_b` (every loop
    // starts with invalidated factors) already solved the linear system.
    if problem.disc.law.is_none()
        || ws.current.counts.loading > 0
        || ws.factorization.factorizes(&ws.current.k)
    {
        return false;
    }
    if problem.factorize(ws, FactorUse::Reusable).is_err() {
        return false;
    }
    ws.dx
        .iter_mut()
        .zip(&ws.current.r)
        .for_each(|(d, r)| *d = -r);
    ws.factorization.solve(problem.linear, &mut ws.dx, 1);
    for ((t, x), d) in ws.x_try.iter_mut().zip(&trial.unknowns).zip(&ws.dx) {
        *t = x + d;
    }
    problem.evaluate_candidate(strain, TangentKind::Consistent, ws);
    let same_branches = ws.candidate.counts.branch_signature == ws.current.counts.branch_signature;
    if !(same_branches && norm(&ws.candidate.r) <= norm(&ws.current.r)) {
        return false;
    }
    trial.unknowns.copy_from_slice(&ws.x_try);
    accept_candidate(ws);
    trial.history.copy_from_slice(&ws.current.history);
    true
}

/// The exact response of a linear RVE: without fluctuation (Taylor) nothing to solve;
/// without interfaces (perfect bonding) `x = X_el eps` with the model's elastic
/// sensitivity `X_el = -K^-1 G`, and `C = G^T K^-1 G = -G^T X_el`; no assembly, no
/// factorization.
fn linear_response(
    problem: &Problem,
    strain: Strain,
    request: TangentRequest,
    ws: &mut Workspace,
    trial: &mut State,
) -> Solved {
    let mut solved = Solved {
        report: IncrementReport {
            substeps: 1,
            ..Default::default()
        },
        condensed: [0.0; 9],
    };
    trial.strain = strain;
    if problem.n() == 0 {
        return solved;
    }
    sensitivity_times(problem.predictor, &strain, &mut trial.unknowns);
    if request == TangentRequest::Consistent {
        let kg = ws.factorization.kg_mut();
        kg.iter_mut()
            .zip(problem.predictor)
            .for_each(|(k, p)| *k = -p);
        solved.condensed = condensed(&problem.disc.g, ws.factorization.kg(), None);
    }
    solved
}

impl Increment<'_, '_> {
    /// The settings of the current part of the increment.
    fn settings(&self) -> Settings {
        if self.hard {
            self.plain
        } else {
            *self.problem.settings
        }
    }

    /// Solves the sub-steps up to the increment's strain (`strain` exactly at the end),
    /// bisecting failed ones.
    fn substeps(&mut self, strain: Strain, trial: &mut State, ws: &mut Workspace) -> Result<()> {
        let (mut done, mut step) = (0.0f64, 1.0f64);
        let mut successes_in_row = 0u32;
        while done < 1.0 {
            let to = (done + step).min(1.0);
            let target = if to >= 1.0 { strain } else { self.line.at(to) };
            let sub = SubStep {
                from: done,
                to,
                target,
            };
            ws.substep_start.copy_from(trial);
            ws.history_start.copy_from_slice(&trial.history);
            contact::hold_state(self.problem, trial, ws);
            match self.solve_substep(&sub, trial, ws) {
                Ok(iterations) => {
                    self.report.iterations += iterations;
                    self.report.substeps += 1;
                    trial.history.copy_from_slice(&ws.current.history);
                    trial.strain = target;
                    contact::record_held(self.problem, trial, ws);
                    done = to;
                    successes_in_row += 1;
                    if successes_in_row >= 2 && step < 1.0 {
                        step *= 2.0;
                        self.depth = self.depth.saturating_sub(1);
                        successes_in_row = 0;
                    }
                }
                Err(failure) => {
                    self.report.iterations += ws.residuals.len().saturating_sub(1) as u32;
                    let last = self.depth + 1 > self.problem.settings.max_substep_depth;
                    // The last iterate of a lost path is an arc point at another strain.
                    let hint = if last && !matches!(failure, Failure::PathLost) {
                        failure_hint(self.problem, &target, trial, ws)
                    } else {
                        String::new()
                    };
                    trial.copy_from(&ws.substep_start);
                    self.depth += 1;
                    successes_in_row = 0;
                    if last {
                        return Err(Error::Solve {
                            reason: failure.describe(self.settings().max_iterations) + &hint,
                            depth: self.depth - 1,
                            suggested_step_ratio: done.max(step).clamp(0.1, 0.5),
                        });
                    }
                    step *= 0.5;
                }
            }
        }
        Ok(())
    }

    /// Tries the remedies of [`LADDER`] on one sub-step until one converges.
    fn solve_substep(
        &mut self,
        sub: &SubStep,
        trial: &mut State,
        ws: &mut Workspace,
    ) -> std::result::Result<u32, Failure> {
        let mut outcome = Err(Failure::NonFinite);
        let mut tangent_predicted = false;
        for remedy in LADDER {
            let applies = match remedy {
                Remedy::Newton => true,
                Remedy::NewtonFromElastic => tangent_predicted,
                Remedy::PathFollowing => self.settings().path_following,
                Remedy::SecantIterations => self.settings().max_secant_iterations > 0,
            };
            if !applies {
                continue;
            }
            if remedy != Remedy::Newton {
                // After a failed loop: count its corrections and start the sub-step again.
                self.report.iterations += ws.residuals.len().saturating_sub(1) as u32;
                trial.copy_from(&ws.substep_start);
            }
            outcome = self.run(remedy, sub, trial, ws, &mut tangent_predicted);
            if remedy == Remedy::Newton {
                self.hard |= outcome.is_err();
            }
            if outcome.is_ok() {
                break;
            }
        }
        outcome
    }

    /// Runs one remedy from the start of the sub-step.
    fn run(
        &mut self,
        remedy: Remedy,
        sub: &SubStep,
        trial: &mut State,
        ws: &mut Workspace,
        tangent_predicted: &mut bool,
    ) -> std::result::Result<u32, Failure> {
        let (problem, settings) = (self.problem, self.settings());
        let step = StrainStep {
            from: trial.strain,
            to: sub.target,
        };
        match remedy {
            Remedy::Newton | Remedy::NewtonFromElastic => {
                let first = remedy == Remedy::Newton;
                let committed = (first && !self.hard).then_some(self.committed);
                let prediction = predict(problem, committed, &mut trial.unknowns, &step, ws);
                let mode = if first && self.depth == 0 {
                    Mode::NewtonUntilStagnant
                } else {
                    Mode::Newton
                };
                if first {
                    *tangent_predicted = prediction == Prediction::Tangent;
                    if !self.hard {
                        self.tangent_start = *tangent_predicted;
                    }
                }
                newton(
                    problem,
                    &settings,
                    &sub.target,
                    &mut trial.unknowns,
                    ws,
                    mode,
                    prediction.evaluated(),
                )
            }
            Remedy::PathFollowing => {
                let reference = problem.reference(&sub.target);
                let mut work = Traced::default();
                let landed = trace(
                    problem, &settings, self.line, sub.from, sub.to, reference, trial, ws,
                    &mut work,
                );
                self.report.substeps += work.points;
                if landed {
                    // On the target, from the last arc point's history (the sub-step's).
                    self.report.limit_points += work.limit_points;
                    Ok(work.iterations)
                } else {
                    self.report.iterations += work.iterations;
                    Err(Failure::PathLost)
                }
            }
            Remedy::SecantIterations => {
                ws.history_start.copy_from_slice(&trial.history);
                contact::hold_state(problem, trial, ws);
                newton(
                    problem,
                    &settings,
                    &sub.target,
                    &mut trial.unknowns,
                    ws,
                    Mode::SecantThenNewton,
                    false,
                )
            }
        }
    }
}

/// On a final failure: what the interface law has to say about the last iterate (for the
/// paper's contact law read at every evaluation, that closed points can leave the RVE
/// without equilibrium; with the status held that does not apply).
fn failure_hint(problem: &Problem, target: &Strain, trial: &State, ws: &mut Workspace) -> String {
    let Some(laws) = problem.disc.law.as_ref() else {
        return String::new();
    };
    if contact::held(ws) {
        return String::new();
    }
    if trial.unknowns.iter().any(|v| !v.is_finite()) {
        return String::new();
    }
    let out = &mut ws.candidate;
    let counts = problem.disc.evaluate(
        &trial.unknowns,
        target,
        &ws.history_start,
        &mut out.history,
        &mut out.r,
        None,
    );
    laws.itz().failure_hint(counts.contact).unwrap_or_default()
}

//! Path following through limit points inside one macro strain increment.
//!
//! Past the peak, debonding around an aggregate can be unstable: the RVE response
//! `sigma(eps)` has a limit point and snaps back, and under strain control the equilibrium
//! beyond it lies on another branch. Newton from the pre-snap state then stalls (the
//! residual norm has a local minimum that is no root), and bisection cannot help, because
//! the jump is in the physics, not in the step size. This module traces the path instead:
//!
//! With the increment `eps(t) = eps_0 + t Delta eps` the residual is
//! `R(x, t) = K_const x + G eps(t) + F_itz(x)`, so `dR/dt = f = G Delta eps`. From a converged
//! point `(x_a, t_a)` an arc-length step (Riks, normal plane) predicts along the tangent
//! `p = dt_0 dx_f` of length `l` and then asks `(x - x_a) . p = l^2`, solving for `(x, t)`
//! together: each iteration solves `K dx_R = -R` and `K dx_f = -f` with one factorization,
//! sets `dx = dx_R + dt dx_f` and takes `dt` from the (linear) constraint. The predictor of
//! the next point reuses the corrector's last `dx_f` (from `K` at an iterate within the
//! tolerance of the new point), so a converged point costs no factorization of its own
//! (`scripts/robustness-study`, cohesive-law paths: factorizations 6545 -> 5816, solver
//! time 8.5 -> 7.6 s, slowest increment 593 -> 374 ms). Every converged arc
//! point is committed into the trial history, exactly like a sub-step, so the interface
//! history follows the traced path. The parameter `t` may decrease along a snap-back.
//!
//! # Landing
//! Once the path has come back and the next point would pass the target `t`, the tracer
//! *lands*: a strain-controlled Newton solve at the target (at most [`MAX_LANDING`]
//! iterations), from the tangent prediction `x_a + (t_target - t_a) dx_f` of the last arc
//! point, which lies on the stable post-snap branch. If the landing does not converge, the
//! arc length is halved and tracing goes on from the same point, so the next landing
//! starts closer to the target, exactly as after a corrector that does not converge; the
//! tracer gives up after [`MAX_CUTS`] failures in a row. (Handing a failed landing back to
//! the caller instead cost a whole bisection of the macro step each time: on the README's
//! robustness sample, one cohesive increment took 2374 iterations that way, see
//! `docs/robustness.md`.)

use faer::dyn_stack::MemStack;

use super::linear::LinearSolver;
use super::newton::{evaluate_current, factorize_current, newton, Mode};
use crate::assembly::Discretization;
use crate::element::TangentKind;
use crate::scene::SolverSpec;
use crate::state::{State, Workspace};

/// Most arc points per call, and corrector iterations per point.
const MAX_POINTS: u32 = 400;
const MAX_CORRECTOR: u32 = 12;
/// Newton iterations of one landing attempt at the target strain.
const MAX_LANDING: u32 = 12;
/// Failed attempts in a row (each halves the arc length) after which the path is lost:
/// the arc length is then 1/256 of the last one that worked.
const MAX_CUTS: u32 = 8;
/// The path is also lost when the arc length falls below this fraction of the first one:
/// the tracer is stuck at a corner of the path, where tiny points converge at once and
/// longer ones do not. (Before these two limits the only one was an arc length of 1e-10
/// of the step: one increment of the robustness sample spent 436 factorizations at such
/// a corner before the secant iterations solved it.)
const MIN_LENGTH: f64 = 1e-4;
// No budget on a trace's total iterations. Tried: giving a trace up after 150 corrector
// and landing iterations (traces that land took 12-79 on the shipped scenes and the
// robustness sample's ellipse paths; lost ones crawled through 127-340 before the limits
// above stopped them, and the secant iterations did the work). `scripts/robustness-study`
// kept every outcome and cut 19 % of the paper-law iterations, but the budget also cut a
// trace that would have landed in the mixed-control host Newton of
// `c_examples/macro_newton.c` (step 16): the secant iterations put the host's iterates on
// different post-peak branches and the host's Newton cycled. Where an increment lands
// matters more to a host than what it costs.

/// `ws.arc_dxf = -K^-1 f` with the factorization in `ws.factor`: the direction of the
/// equilibrium path per unit of the load parameter `t`.
fn load_direction(linear: &LinearSolver, ws: &mut Workspace) {
    ws.arc_dxf
        .iter_mut()
        .zip(&ws.arc_f)
        .for_each(|(d, f)| *d = -f);
    linear.solve_in_place(
        &mut ws.factor,
        &mut ws.arc_dxf,
        1,
        MemStack::new(&mut ws.stack),
    );
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Work and progress of one traced path, counted whether or not it lands.
#[derive(Default)]
pub(super) struct Traced {
    /// Corrector and landing iterations (one linear solve each).
    pub iterations: u32,
    /// Converged arc points.
    pub points: u32,
    /// Limit points of the strain along the traced path: turns of `t` between successive
    /// arc points. A snap-back shows two (a maximum, then a minimum of the strain).
    pub limit_points: u32,
}

/// Traces the path of `eps_0 + t delta` from the converged `trial` at `t = from` and lands
/// on `t = to` (see the module docs). On success (`true`) `trial.unknowns` is converged at
/// `eps_0 + to delta` from the history in `ws.hist_base` (the last arc point's, also in
/// `trial.history`), and `ws.r`/`ws.k`/`ws.hist_trial`/`ws.factor` belong to it, as after
/// a converged Newton loop. Returns `false` when the path cannot be followed (no real
/// root, singular system, [`MAX_CUTS`] failed attempts in a row, an arc length below
/// [`MIN_LENGTH`] of the first, budget exhausted); `trial` then holds the last converged
/// arc point, still valid. `work` counts what was done either way.
#[allow(clippy::too_many_arguments)]
pub(super) fn trace(
    disc: &Discretization,
    linear: &LinearSolver,
    settings: &SolverSpec,
    eps_0: [f64; 3],
    delta: [f64; 3],
    from: f64,
    to: f64,
    reference: f64,
    trial: &mut State,
    ws: &mut Workspace,
    work: &mut Traced,
) -> bool {
    let n = disc.n();
    let tolerance = settings.tolerance * reference;
    let landing = SolverSpec {
        max_iterations: MAX_LANDING,
        ..*settings
    };
    // f = G delta.
    for i in 0..n {
        ws.arc_f[i] =
            disc.g[i] * delta[0] + disc.g[n + i] * delta[1] + disc.g[2 * n + i] * delta[2];
    }
    let eps_at = |t: f64| {
        [
            eps_0[0] + t * delta[0],
            eps_0[1] + t * delta[1],
            eps_0[2] + t * delta[2],
        ]
    };
    let mut t_a = from;
    ws.arc_prev.iter_mut().for_each(|v| *v = 0.0);
    let (mut length, mut first_length) = (0.0, 0.0);
    let mut cuts = 0;
    let mut going_forward = true;

    // Whether `ws.arc_dxf` holds a tangent direction for the arc point `x_a`.
    let mut direction_ready = false;
    for _ in 0..MAX_POINTS {
        ws.hist_base.copy_from_slice(&trial.history);
        ws.arc_xa.copy_from_slice(&trial.unknowns);
        if !direction_ready {
            // Tangent at the arc point: K dx_f = -f.
            evaluate_current(
                disc,
                &trial.unknowns,
                &eps_at(t_a),
                TangentKind::Consistent,
                ws,
            );
            if factorize_current(disc, linear, ws).is_err() {
                return false;
            }
            load_direction(linear, ws);
        }
        let dxf_norm = dot(&ws.arc_dxf, &ws.arc_dxf).sqrt();
        if !(dxf_norm.is_finite() && dxf_norm > 0.0) {
            return false;
        }
        if length == 0.0 {
            // Eight points would cover the rest of the increment on a straight path.
            length = (to - from) * dxf_norm / 8.0;
            first_length = length;
        }
        // Direction: keep going the way the path went (positive t at the start).
        let sign = if work.points == 0 || dot(&ws.arc_dxf, &ws.arc_prev) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        let dt_pred = sign * length / dxf_norm;
        let converged = if t_a + dt_pred >= to {
            // The path has come back past the target: land on it under strain control,
            // from the tangent prediction.
            for i in 0..n {
                trial.unknowns[i] = ws.arc_xa[i] + (to - t_a) * ws.arc_dxf[i];
            }
            let outcome = newton(
                disc,
                linear,
                &landing,
                &eps_at(to),
                &mut trial.unknowns,
                ws,
                Mode::Newton,
                false,
            );
            work.iterations += ws.residuals.len().saturating_sub(1) as u32;
            if outcome.is_ok() {
                return true;
            }
            false
        } else {
            let corrected = correct(
                disc, linear, tolerance, &eps_at, t_a, dt_pred, length, trial, ws, work,
            );
            if let Some(t) = corrected {
                for i in 0..n {
                    ws.arc_prev[i] = trial.unknowns[i] - ws.arc_xa[i];
                }
                trial.history.copy_from_slice(&ws.hist_trial);
                trial.strain = eps_at(t);
                let forward = t > t_a;
                if forward != going_forward {
                    work.limit_points += 1;
                    going_forward = forward;
                }
                t_a = t;
                work.points += 1;
                // Not Crisfield's rule (`sqrt(3 / corrector iterations)`, clamped to
                // [0.5, 2] or [0.5, 1.25]): on `scripts/robustness-study` it cost 12 %
                // more iterations on the cohesive-law paths with the narrow clamp, and with
                // the wide one a snap of `tests/closed_form_interface.rs` landed off the
                // closed-form branch.
                length *= 1.25;
            } else {
                // The corrector overwrote `arc_dxf`: back to the direction at `x_a`.
                ws.arc_dxf.copy_from_slice(&ws.arc_pred);
            }
            corrected.is_some()
        };
        // The next predictor's direction: after a converged point, the corrector's last
        // `K^-1 f`, at an iterate within the tolerance of the new point (saves its
        // factorization); after a failed corrector or landing, the one at `x_a` (a landing
        // leaves `arc_dxf` alone).
        direction_ready = true;
        if converged {
            cuts = 0;
        } else {
            trial.unknowns.copy_from_slice(&ws.arc_xa);
            length *= 0.5;
            cuts += 1;
            if cuts > MAX_CUTS || length < MIN_LENGTH * first_length {
                return false;
            }
        }
    }
    false
}

/// The corrector of one arc step of length `length` from the arc point `ws.arc_xa` at
/// `t_a`, predicted along `dt_pred ws.arc_dxf`: Newton on the residual and Riks' normal
/// plane together. Returns the converged `t` (the unknowns are in `trial`), or `None`.
/// Leaves the predictor direction in `ws.arc_pred`.
#[allow(clippy::too_many_arguments)]
fn correct(
    disc: &Discretization,
    linear: &LinearSolver,
    tolerance: f64,
    eps_at: &impl Fn(f64) -> [f64; 3],
    t_a: f64,
    dt_pred: f64,
    length: f64,
    trial: &mut State,
    ws: &mut Workspace,
    work: &mut Traced,
) -> Option<f64> {
    let n = disc.n();
    // Predictor (its direction stays the normal of the constraint plane).
    ws.arc_pred.copy_from_slice(&ws.arc_dxf);
    for i in 0..n {
        trial.unknowns[i] = ws.arc_xa[i] + dt_pred * ws.arc_dxf[i];
    }
    let mut t = t_a + dt_pred;
    for _ in 0..MAX_CORRECTOR {
        evaluate_current(
            disc,
            &trial.unknowns,
            &eps_at(t),
            TangentKind::Consistent,
            ws,
        );
        let rnorm = dot(&ws.r, &ws.r).sqrt();
        if !rnorm.is_finite() {
            return None;
        }
        if rnorm <= tolerance {
            return Some(t);
        }
        factorize_current(disc, linear, ws).ok()?;
        work.iterations += 1;
        // dx_R into ws.dx, dx_f into ws.arc_dxf (both with this factorization).
        ws.dx.iter_mut().zip(&ws.r).for_each(|(d, r)| *d = -r);
        linear.solve_in_place(&mut ws.factor, &mut ws.dx, 1, MemStack::new(&mut ws.stack));
        load_direction(linear, ws);
        // Riks' normal plane: ((x - x_a) + dx_R + dt dx_f) . p = length^2, with p the
        // predictor step: linear in dt, so always solvable (a circle may miss the
        // linearized path at a kink of the law).
        let (mut cur_p, mut dxf_p) = (0.0, 0.0);
        for i in 0..n {
            let p = dt_pred * ws.arc_pred[i];
            cur_p += (trial.unknowns[i] - ws.arc_xa[i] + ws.dx[i]) * p;
            dxf_p += ws.arc_dxf[i] * p;
        }
        if dxf_p == 0.0 || !dxf_p.is_finite() {
            return None;
        }
        let dt = (length * length - cur_p) / dxf_p;
        for i in 0..n {
            trial.unknowns[i] += ws.dx[i] + dt * ws.arc_dxf[i];
        }
        t += dt;
    }
    None
}

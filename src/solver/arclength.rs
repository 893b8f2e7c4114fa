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
//! sets `dx = dx_R + dt dx_f` and takes `dt` from the (linear) constraint. Every converged arc
//! point is committed into the trial history, exactly like a sub-step, so the interface
//! history follows the traced path. The parameter `t` may decrease along a snap-back; once
//! the path comes back and the next point would pass the target `t`, the remainder is a
//! plain strain-controlled Newton solve at the target, from the last arc point, which lies
//! on the stable post-snap branch.

use faer::dyn_stack::MemStack;

use super::linear::LinearSolver;
use super::newton::{evaluate_current, factorize_current};
use crate::assembly::Discretization;
use crate::element::TangentKind;
use crate::scene::SolverSpec;
use crate::state::{State, Workspace};

/// Most arc points per call, and corrector iterations per point.
const MAX_POINTS: u32 = 400;
const MAX_CORRECTOR: u32 = 12;

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Outcome counters of a traced path.
pub(super) struct Traced {
    pub iterations: u32,
    pub factorizations: u32,
    pub points: u32,
}

/// Traces the path of `eps_0 + t delta` from the converged `trial` at `t = from` until
/// a point short of `to` from which strain control can take over; leaves that point in
/// `trial` (strain, unknowns, history) and returns. The caller then solves at `to`.
/// Returns `None` when the path cannot be followed (no real root, singular system,
/// budget exhausted); `trial` then holds the last converged arc point, still valid.
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
) -> Option<(f64, Traced)> {
    let n = disc.n();
    let tolerance = settings.tolerance * reference;
    let mut out = Traced {
        iterations: 0,
        factorizations: 0,
        points: 0,
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
    let mut length = 0.0;

    for _ in 0..MAX_POINTS {
        ws.hist_base.copy_from_slice(&trial.history);
        ws.arc_xa.copy_from_slice(&trial.unknowns);
        // Tangent at the arc point: K dx_f = -f.
        evaluate_current(
            disc,
            &trial.unknowns,
            &eps_at(t_a),
            TangentKind::Consistent,
            ws,
        );
        if factorize_current(disc, linear, ws).is_err() {
            return None;
        }
        out.factorizations += 1;
        ws.arc_dxf
            .iter_mut()
            .zip(&ws.arc_f)
            .for_each(|(d, f)| *d = -f);
        linear.solve_in_place(&ws.factor, &mut ws.arc_dxf, 1, MemStack::new(&mut ws.stack));
        let dxf_norm = dot(&ws.arc_dxf, &ws.arc_dxf).sqrt();
        if !(dxf_norm.is_finite() && dxf_norm > 0.0) {
            return None;
        }
        if length == 0.0 {
            // Eight points would cover the rest of the increment on a straight path.
            length = (to - from) * dxf_norm / 8.0;
        }
        // Direction: keep going the way the path went (positive t at the start).
        let sign = if out.points == 0 || dot(&ws.arc_dxf, &ws.arc_prev) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        let dt_pred = sign * length / dxf_norm;
        if t_a + dt_pred >= to {
            // The path has come back past the target: hand over to strain control.
            return Some((t_a, out));
        }
        // Predictor (its direction stays the normal of the constraint plane).
        ws.arc_pred.copy_from_slice(&ws.arc_dxf);
        for i in 0..n {
            trial.unknowns[i] = ws.arc_xa[i] + dt_pred * ws.arc_dxf[i];
        }
        let mut t = t_a + dt_pred;
        let mut converged = false;
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
                break;
            }
            if rnorm <= tolerance {
                converged = true;
                break;
            }
            if factorize_current(disc, linear, ws).is_err() {
                break;
            }
            out.factorizations += 1;
            out.iterations += 1;
            // dx_R into ws.dx, dx_f into ws.arc_dxf (both with this factorization).
            ws.dx.iter_mut().zip(&ws.r).for_each(|(d, r)| *d = -r);
            linear.solve_in_place(&ws.factor, &mut ws.dx, 1, MemStack::new(&mut ws.stack));
            ws.arc_dxf
                .iter_mut()
                .zip(&ws.arc_f)
                .for_each(|(d, f)| *d = -f);
            linear.solve_in_place(&ws.factor, &mut ws.arc_dxf, 1, MemStack::new(&mut ws.stack));
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
                break;
            }
            let dt = (length * length - cur_p) / dxf_p;
            for i in 0..n {
                trial.unknowns[i] += ws.dx[i] + dt * ws.arc_dxf[i];
            }
            t += dt;
        }
        if converged {
            for i in 0..n {
                ws.arc_prev[i] = trial.unknowns[i] - ws.arc_xa[i];
            }
            trial.history.copy_from_slice(&ws.hist_trial);
            trial.strain = eps_at(t);
            t_a = t;
            out.points += 1;
            length *= 1.25;
        } else {
            trial.unknowns.copy_from_slice(&ws.arc_xa);
            length *= 0.5;
            if length < 1e-10 * dxf_norm * (to - from) {
                return None;
            }
        }
    }
    None
}

//! Mixed control: some macro strain components prescribed, the others held at zero stress
//! (uniaxial stress, shear at zero normal stress). The free components are found by
//! Newton's method on the RVE's own consistent tangent: with `f` the free components and
//! `p` the prescribed ones,
//! ```text
//! sigma_f(eps) = 0,    D_ff delta_eps_f = -sigma_f,    eps_f <- eps_f + delta_eps_f
//! ```
//! each iterate a trial update of the instance from its committed state (the committed
//! state never changes; the last trial is the answer, committed as any other). Under
//! IMPL-EX the step is linear and one correction is exact.

use super::{Instance, Response};
use crate::error::{Error, Result};
use mesorve_core::solver::{TangentRequest, Workspace};

/// Most Newton corrections of the free components before the update fails (the solver's
/// failure: a smaller increment, the host's remedy, usually mends it).
pub const MAX_ITERATIONS: usize = 25;

/// The smallest tolerance of the zero-stress residual relative to the stress's size (at
/// least `STRESS_FLOOR`, in the scene's stress unit, when the stress vanishes); the
/// scene's `solver.tolerance` when larger (the RVE's stress is no more accurate).
pub const TOLERANCE: f64 = 1e-8;
const STRESS_FLOOR: f64 = 1e-6;
/// The residual accepted when the corrections stall at a kink of the RVE's response:
/// the zero-stress components at most this fraction of the stress.
pub const ACCEPTED: f64 = 1e-3;

/// Trial-updates `instance` to the strain whose prescribed components are `target`'s
/// (those of `free` false) and whose stress components of `free` true vanish; the free
/// components start from the committed strain's. Returns the answer at the solution and
/// its strain.
pub fn update_mixed(
    instance: &mut Instance,
    target: [f64; 3],
    free: [bool; 3],
    dt: f64,
    ws: &mut Workspace,
) -> Result<(Response, [f64; 3])> {
    let committed = instance.committed().strain;
    let mut eps: [f64; 3] = std::array::from_fn(|i| if free[i] { committed[i] } else { target[i] });
    let request = TangentRequest::Consistent;
    let idx: Vec<usize> = (0..3).filter(|&i| free[i]).collect();
    let tolerance = instance.model().solver.tolerance.max(TOLERANCE);
    let mut r = instance.update_timed(eps, dt, ws, request)?;
    let mut best = (f64::INFINITY, eps);
    let size = |r: &Response| {
        let scale = r
            .stress
            .iter()
            .fold(0.0f64, |m, s| m.max(s.abs()))
            .max(STRESS_FLOOR);
        idx.iter().fold(0.0f64, |m, &i| m.max(r.stress[i].abs())) / scale
    };
    for _ in 0..MAX_ITERATIONS {
        if idx.is_empty() || size(&r) <= tolerance {
            return Ok((r, eps));
        }
        if size(&r) < best.0 {
            best = (size(&r), eps);
        }
        let d =
            nalgebra::DMatrix::from_fn(idx.len(), idx.len(), |a, b| r.tangent[3 * idx[a] + idx[b]]);
        let rhs = nalgebra::DVector::from_iterator(idx.len(), idx.iter().map(|&i| -r.stress[i]));
        let Some(step) = d.lu().solve(&rhs) else {
            return Err(singular(&idx, &r));
        };
        // Backtracking: the RVE's response has kinks (branch and contact switches), where
        // a full Newton step on the free components may overshoot.
        let before = size(&r);
        let mut fraction = 1.0;
        loop {
            let trial: [f64; 3] = std::array::from_fn(|i| match idx.iter().position(|&j| j == i) {
                Some(k) => eps[i] + fraction * step[k],
                None => eps[i],
            });
            let candidate = instance.update_timed(trial, dt, ws, request)?;
            if size(&candidate) < before || fraction < 1.0 / 16.0 {
                eps = trial;
                r = candidate;
                break;
            }
            fraction *= 0.5;
        }
    }
    if best.0 <= ACCEPTED {
        // A kink of the RVE's response (a contact switch) where the residual stalls: the
        // best iterate, its residual in the answer's stress for the caller to see.
        let r = instance.update_timed(best.1, dt, ws, request)?;
        return Ok((r, best.1));
    }
    Err(Error::Solve {
        reason: format!(
            "the zero-stress components {} did not vanish in {MAX_ITERATIONS} corrections of \
             their strains (stress {:?})",
            names(&idx),
            r.stress
        ),
        depth: 0,
        suggested_step_ratio: 0.5,
    })
}

fn names(idx: &[usize]) -> String {
    let name = ["xx", "yy", "xy"];
    idx.iter().map(|&i| name[i]).collect::<Vec<_>>().join(", ")
}

fn singular(idx: &[usize], r: &Response) -> Error {
    Error::Solve {
        reason: format!(
            "the RVE's tangent on the zero-stress components {} is singular (tangent {:?})",
            names(idx),
            r.tangent
        ),
        depth: 0,
        suggested_step_ratio: 0.5,
    }
}

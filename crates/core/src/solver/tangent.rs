//! The condensed term of the homogenized tangent, `C = G^T K^-1 G` (3 x 3, row-major), at
//! the converged state: `D_hom = D_Taylor - C / V` (eq. 18, formed by the caller).
//!
//! `K^-1 G` comes from the factorization the Newton loop left (`K_f`):
//! - if the converged `K` is bitwise the factorized one (unloading, contact, the elastic
//!   range: piecewise linear branches), `K^-1 G = K_f^-1 G` costs three solves, or none
//!   when the last correction solved it with the residual;
//! - otherwise `X_0 = K_f^-1 G` is refined by sweeps `X_{k+1} = X_k + K_f^-1 R_k`,
//!   `R_k = G - K X_k`, and `C` is taken from the stationary (variational) form
//!   `C(X) = G^T X + X^T R(X)`, whose error `-(X - X*)^T K (X - X*)` is quadratic in the
//!   error of `X` (`K` is symmetric). The sweeps contract the error by
//!   `rho ~ ||R_k|| / ||R_{k-1}||`, so the error of `C_k` is about `|C_k - C_{k-1}| rho^2`;
//!   they stop when that is below [`TANGENT_ACCURACY`];
//! - only when [`TANGENT_SWEEPS`] sweeps cannot reach it is the converged `K` factorized
//!   once more.
//!
//! With a point sliding under friction `K` is not symmetric: the variational form's
//! quadratic error needs the adjoint `K^-T G`, and the product of the sweeps reads `K`
//! as symmetric, so the sweeps are skipped and a `K` that is not bitwise the factorized
//! one is factorized (by LU). `C = G^T K^-1 G` itself holds for any `K` (the macro strain
//! loads the RVE through the bulk alone, `G`), and is not symmetric then.

use super::problem::{norm, Problem};
use super::workspace::{FactorUse, Workspace};
use crate::error::{Error, Result};

/// Refinement sweeps the condensed tangent may take before a fresh factorization is
/// cheaper (one sweep is a 3-column solve and three products; see `benches/solver.rs`).
const TANGENT_SWEEPS: u32 = 3;
/// Relative accuracy of `G^T K^-1 G` the sweeps must reach. The stress it goes with is
/// converged to the Newton tolerance; a tangent error of 1e-10 leaves a host's Newton
/// quadratic down to relative errors of 1e-10, far below any host tolerance.
const TANGENT_ACCURACY: f64 = 1e-10;

/// `C = G^T X` (with `res`: the variational form `G^T X + X^T res`), row-major, for an
/// n x 3 column-major `X`.
pub(super) fn condensed(g: &[f64], x: &[f64], res: Option<&[f64]>) -> [f64; 9] {
    let n = g.len() / 3;
    let mut out = [0.0; 9];
    for i in 0..3 {
        for j in 0..3 {
            let (gi, xj) = (&g[i * n..(i + 1) * n], &x[j * n..(j + 1) * n]);
            let mut c: f64 = gi.iter().zip(xj).map(|(a, b)| a * b).sum();
            if let Some(r) = res {
                let (xi, rj) = (&x[i * n..(i + 1) * n], &r[j * n..(j + 1) * n]);
                c += xi.iter().zip(rj).map(|(a, b)| a * b).sum::<f64>();
            }
            out[3 * i + j] = c;
        }
    }
    out
}

/// Computes `C = G^T K^-1 G` at the converged state (`ws.current.k`) and leaves the best
/// `X ~ K^-1 G` in the factorization's `kg` (see the module docs).
pub(super) fn condensed_tangent(problem: &Problem, ws: &mut Workspace) -> Result<[f64; 9]> {
    if ws.factorization.is_reusable() {
        if let Some(c) = from_last_factorization(problem, ws) {
            return Ok(c);
        }
    }
    problem
        .factorize(ws, FactorUse::Reusable)
        .map_err(|e| Error::Solve {
            reason: format!("singular RVE tangent at the converged state ({e:?})"),
            depth: 0,
            suggested_step_ratio: 0.5,
        })?;
    let g: &[f64] = &problem.disc.g;
    ws.factorization.solve_g(problem.linear, g);
    Ok(condensed(g, ws.factorization.kg(), None))
}

/// `C` from the kept factorization `K_f`: exact when `K_f` is the converged `K`, else by
/// refinement sweeps; `None` when the sweeps cannot reach [`TANGENT_ACCURACY`].
fn from_last_factorization(problem: &Problem, ws: &mut Workspace) -> Option<[f64; 9]> {
    let (g, linear): (&[f64], _) = (&problem.disc.g, problem.linear);
    let unchanged = ws.factorization.factorizes(&ws.current.k);
    let symmetric = ws.factorization.is_symmetric() && ws.current.counts.sliding == 0;
    if !(unchanged || symmetric) {
        return None;
    }
    ws.factorization.solve_g(linear, g);
    if unchanged {
        return Some(condensed(g, ws.factorization.kg(), None));
    }
    let residual = |ws: &mut Workspace| {
        let kg = ws.factorization.kg();
        problem
            .disc
            .pattern
            .mul_symmetric3(&ws.current.k, kg, &mut ws.kg_res);
        for (ri, gi) in ws.kg_res.iter_mut().zip(g) {
            *ri = gi - *ri;
        }
        norm(&ws.kg_res)
    };
    let mut res_norm = residual(ws);
    let mut previous = condensed(g, ws.factorization.kg(), Some(&ws.kg_res));
    let scale = previous
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    for sweep in 1..=TANGENT_SWEEPS {
        // The correction K_f^-1 R_k, in place: `residual` rewrites `kg_res` next.
        ws.factorization.solve(linear, &mut ws.kg_res, 3);
        let kg = ws.factorization.kg_mut();
        kg.iter_mut().zip(&ws.kg_res).for_each(|(x, d)| *x += d);
        let new_norm = residual(ws);
        let now = condensed(g, ws.factorization.kg(), Some(&ws.kg_res));
        let change = now
            .iter()
            .zip(&previous)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
            / scale;
        let rho = new_norm / res_norm;
        let error = change * rho * rho;
        if !(error.is_finite() && rho < 1.0) {
            return None;
        }
        if error <= TANGENT_ACCURACY || new_norm == 0.0 {
            return Some(now);
        }
        // Each further sweep multiplies the error by rho^2: give up early if the budget
        // cannot reach the accuracy.
        let left = (TANGENT_SWEEPS - sweep) as i32;
        if error * rho.powi(2 * left) > TANGENT_ACCURACY {
            return None;
        }
        previous = now;
        res_norm = new_norm;
    }
    None
}

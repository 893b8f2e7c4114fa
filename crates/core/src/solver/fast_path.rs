//! The fast path: an update answered without Newton while every interface point stays on
//! the linear branch it had at the last full solve.
//!
//! # Why it is exact
//! The paper's law is linear through the origin on two of its branches: unloading and
//! reloading to the origin (eq. 24, tangent eq. 46) and penalty contact (eqs. 36-37,
//! tangent eq. 47); the bulk is elastic. With every interface point held on such a branch
//! (the *branch set* `b`), the discrete equilibrium (eq. 14) is linear,
//! `R(x; eps) = K_b x + G eps`, so
//! ```text
//! x = X_b eps,   X_b = -K_b^-1 G,   sigma = D_b eps,   D_b = D_Taylor - G^T K_b^-1 G / V   (eq. 18)
//! ```
//! and the jump of interface point `q` is `delta_q = A_q eps` with `A_q = J_q X_b`. If
//! every `A_q eps` keeps its point on its branch, `x = X_b eps` is an equilibrium of the
//! law with the contact status read from the gaps and no history change: the full solve's
//! answer, which `D_b` gives without assembly or factorization.
//!
//! # The data and when it is made
//! A full update whose converged state has every point on a linear branch (no loading
//! point, no point held against its gap) and that computed the consistent tangent already
//! holds `K_b^-1 G`: [`build`] keeps `D_b`, the `s_zz` row and every `A_q` (f32) in the
//! trial's [`LinearBranch`] (lazy construction: nothing is made while an instance loads).
//! A fast update then only moves the state's strain; its fluctuation `X_b eps` is formed by
//! [`materialize`] (one factorization of `K_b`) when a full solve or an output needs it.
//!
//! # The check
//! [`answers`] evaluates `A_q eps` for every point and asks the law whether every jump
//! within a bound of it keeps the point on its branch
//! ([`crate::interface::InterfaceLaw::stays_linear`]): strictly below `delta_max`, on the
//! side of `delta_n = 0` of its contact status. The bound, [`JUMP_BOUND`] times
//! `sum_j |A_qj eps_j|` per component, covers the f32 rounding of `A_q` (2^-24 relative)
//! and the round-off of the two solves with a wide margin; a point closer to a branch
//! boundary than that takes the full solve. The contact status is read from the gaps, as
//! the active set reads it at convergence (`contact`): the check asks for the status the
//! full solve would end with.
//!
//! Both the full solve and this path give `X_b eps` on such an increment: the full solve
//! ends a loop on linear branches with an exact correction ([`super::increment`]'s
//! polishing step), so the two agree to round-off.

use super::problem::{Problem, Strain};
use super::workspace::Workspace;
use crate::error::{Error, Result};
use crate::state::{LinearBranch, State, JUMP_OPERATOR_LEN};

/// Relative bound on the error of a jump `A_q eps` against the full solve's jump (see the
/// module docs): 17 times the f32 rounding of `A_q`.
pub const JUMP_BOUND: f64 = 1e-6;

/// `A eps` and its error bound for one component of a point's jump operator.
#[inline]
fn component(a: &[f32], strain: &Strain) -> (f64, f64) {
    let terms = [
        f64::from(a[0]) * strain[0],
        f64::from(a[1]) * strain[1],
        f64::from(a[2]) * strain[2],
    ];
    (
        terms[0] + terms[1] + terms[2],
        JUMP_BOUND * (terms[0].abs() + terms[1].abs() + terms[2].abs()),
    )
}

/// Whether the fast path answers an update of the state with interface history `history`
/// and fast data `linear` at `strain`: every interface point provably stays on its linear
/// branch (see the module docs). Allocates nothing.
pub fn answers(problem: &Problem, history: &[f64], linear: &LinearBranch, strain: &Strain) -> bool {
    let Some(laws) = problem.disc.law.as_ref() else {
        return false;
    };
    if !problem.settings.fast_path || !linear.valid {
        return false;
    }
    let (hl, np) = (laws.history_len(), problem.disc.points_per_interface());
    linear
        .jumps
        .chunks_exact(JUMP_OPERATOR_LEN)
        .zip(&linear.closed)
        .enumerate()
        .all(|(q, (a, &closed))| {
            let (s, es) = component(&a[..3], strain);
            let (n, en) = component(&a[3..], strain);
            laws.of(q / np)
                .stays_linear(&history[q * hl..(q + 1) * hl], [s, n], [es, en], closed)
        })
}

/// `(stress, s_zz)` of the fast path at `strain`: `D_b eps` and `szz . eps`.
pub fn response(linear: &LinearBranch, strain: &Strain) -> ([f64; 3], f64) {
    let d = &linear.tangent;
    let row = |i: usize| d[3 * i] * strain[0] + d[3 * i + 1] * strain[1] + d[3 * i + 2] * strain[2];
    let s_zz = linear.szz[0] * strain[0] + linear.szz[1] * strain[1] + linear.szz[2] * strain[2];
    ([row(0), row(1), row(2)], s_zz)
}

/// After a full update that converged at `state` (the trial, at its strain) with the
/// consistent tangent `tangent`, its `s_zz` row `szz` and `K^-1 G` in the workspace's
/// factorization: fills `state.linear` when every interface point is on a linear branch
/// with the contact status its gap gives (none held against it), `K^-1 G` is exact for
/// the converged tangent, and the check passes at the state itself;
/// otherwise marks it not valid. Allocates only the first time an instance's state holds
/// the data.
pub fn build(
    problem: &Problem,
    state: &mut State,
    tangent: [f64; 9],
    szz: [f64; 3],
    ws: &mut Workspace,
) {
    state.linear.invalidate();
    let Some(laws) = problem.disc.law.as_ref() else {
        return;
    };
    let np = problem.disc.points_per_interface();
    let exact_kg = ws.factorization.factorizes(&ws.current.k) && ws.factorization.kg_is_of_factor();
    if !problem.settings.fast_path || ws.current.counts.loading > 0 || !exact_kg {
        return;
    }
    let points = problem.disc.interface_points();
    let linear = &mut state.linear;
    linear.jumps.resize(JUMP_OPERATOR_LEN * points, 0.0);
    linear.closed.resize(points, false);
    jump_operators(problem, ws.factorization.kg(), &mut linear.jumps);
    let closed = &mut linear.closed;
    problem.disc.for_each_jump(&state.unknowns, |q, jump| {
        closed[q] = laws.of(q / np).is_closed(jump)
    });
    // `K_b` was assembled with the held contact status: it must be the gaps' (no point
    // held against its gap, see `contact`).
    if ws
        .contact
        .status()
        .is_some_and(|held| held != closed.as_slice())
    {
        state.linear.invalidate();
        return;
    }
    linear.tangent = tangent;
    linear.szz = szz;
    linear.unknowns_strain = state.strain;
    linear.valid = true;
    // The anchor itself must pass the check (a closed point sliding on the loading branch
    // of the cohesive shear, a point at a branch boundary): otherwise no fast path.
    if !answers(problem, &state.history, &state.linear, &state.strain) {
        state.linear.invalidate();
    }
}

/// Every interface point's jump operator `A_q = J_q X` into `jumps` (f32, see
/// [`LinearBranch`]) from `kg = K^-1 G`: column j of `X = -K^-1 G` gives the jumps per
/// unit strain component j. Shared with IMPL-EX's step (`implex::store_step`).
pub(super) fn jump_operators(problem: &Problem, kg: &[f64], jumps: &mut [f32]) {
    let n = problem.n();
    for j in 0..3 {
        let column = &kg[j * n..(j + 1) * n];
        problem.disc.for_each_jump(column, |q, [s, nn]| {
            jumps[JUMP_OPERATOR_LEN * q + j] = -s as f32;
            jumps[JUMP_OPERATOR_LEN * q + 3 + j] = -nn as f32;
        });
    }
}

/// Writes into `out` the state `state` (without its fast-path data) with its unknowns at
/// its own strain: a copy when
/// they are current, else `x = x_a - K_b^-1 R(x_a; eps)` from the unknowns `x_a` at the
/// anchor, with `K_b` assembled there on the held branch set (one factorization; the
/// workspace's evaluation and factors are overwritten).
pub fn materialize(
    problem: &Problem,
    state: &State,
    out: &mut State,
    ws: &mut Workspace,
) -> Result<()> {
    out.copy_solution_from(state);
    if state.unknowns_are_current() {
        return Ok(());
    }
    let status = problem
        .disc
        .law
        .as_ref()
        .is_some_and(|laws| laws.has_contact_status())
        .then_some(state.linear.closed.as_slice());
    problem.evaluate_into(
        &state.unknowns,
        &state.strain,
        &state.history,
        status,
        crate::interface::TangentKind::Consistent,
        &mut ws.current,
    );
    problem.one_use_correction(ws).map_err(|e| Error::Solve {
        reason: format!("singular RVE tangent on the linear branch set ({e})"),
        depth: 0,
        suggested_step_ratio: 0.5,
    })?;
    out.unknowns
        .iter_mut()
        .zip(&ws.dx)
        .for_each(|(x, d)| *x += d);
    Ok(())
}

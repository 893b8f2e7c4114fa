//! IMPL-EX integration of the interface history over a host step (Oliver, Huespe & Cante
//! 2008; the law side is [`crate::interface::Implex`]).
//!
//! # The step
//! With the history extrapolated from the last two converged states,
//! ```text
//! h_ex = h_n + r (h_n - h_{n-1}),     r = dt_{n+1} / dt_n       ([`step_ratio`])
//! ```
//! and the contact status of the last converged state held, every interface point is on
//! a linear branch through the origin, so the discrete equilibrium (eq. 14) is linear in
//! the macro strain, `K_ex x + G eps = 0`:
//! ```text
//! x = X eps,   X = -K_ex^-1 G,   sigma = D_ex eps,   D_ex = D_Taylor - G^T K_ex^-1 G / V   (eq. 18)
//! ```
//! `K_ex` is symmetric positive definite (the bulk is, every frozen secant is), so is
//! `D_ex`: a host's Newton loop on such a material converges in one or two iterations,
//! whatever the RVE does. [`factorize_step`] assembles and factorizes `K_ex` once per
//! step and keeps, as the fast path does (`fast_path`, [`LinearBranch`]), `D_ex`, the
//! `s_zz` row and every point's jump operator `A_q = J_q X`: the host's later iterations
//! in the same step are answered from them without a factorization.
//!
//! # The implicit history
//! At every answer, [`finish_step`] forms the trial's *implicit* history from the jumps
//! `A_q eps` by the law itself (eq. 25: `delta_max' = max(delta_max, delta)`, frozen while
//! closed), and the contact status from their gaps. When the host commits, that is the
//! state the next step extrapolates from. (Both the first answer of a step and the later
//! ones use the same f32 operators `A_q`, so the history does not depend on whether a step
//! was answered from its kept data: results are identical with the fast path on or off.)
//!
//! # The step size
//! `dt` is the host's time increment (the UMAT's `DTIME`). A host that passes none (`dt
//! <= 0`, as `rve_update` does) has each update count as one unit step (`r = 1`): it
//! keeps the step within the update, so the RVE stays linear in the step and one
//! factorization answers every iteration. (The norm of the macro strain increment would
//! make `h_ex` depend on the trial strain, the RVE nonlinear within the step and its
//! tangent non-symmetric.) `rve run` passes the norm of each path increment, which is
//! known before the step.

use super::problem::{Problem, Strain};
use super::settings::IncrementReport;
use super::workspace::{FactorUse, Workspace};
use crate::error::{Error, Result};
use crate::state::{held_contact_words, LinearBranch, State, JUMP_OPERATOR_LEN};

/// Whether the step kept in `committed.linear` (the step that led to `committed`) is the
/// next step's too: it froze the history it started from, no point has advanced since
/// (`h_n = h_{n-1}`, so nothing is extrapolated either) and the contact status is the one
/// it held. The matrix `K_ex` is then the same, bit for bit, and so is every kept value:
/// an unloading or closed RVE steps without factorizing.
pub fn carries_over(committed: &State) -> bool {
    let implex = &committed.implex;
    let linear = &committed.linear;
    linear.valid
        && implex.at_start
        && implex.previous == committed.history
        && linear
            .closed
            .iter()
            .enumerate()
            .all(|(q, &closed)| closed == implex.is_closed(q))
}

/// `dt_{n+1} / dt_n` when both time increments are given (positive and finite), else 1.
pub fn step_ratio(previous: f64, dt: f64) -> f64 {
    let given = |t: f64| t.is_finite() && t > 0.0;
    if given(previous) && given(dt) {
        dt / previous
    } else {
        1.0
    }
}

/// The `h_{n-1}` an extrapolation from `history` uses: IMPL-EX's `previous` when it holds
/// one value per history value, else `history` itself (before the first step nothing is
/// extrapolated: `h_ex = h_n`).
pub fn extrapolated_from<'a>(history: &'a [f64], previous: &'a [f64]) -> &'a [f64] {
    if previous.len() == history.len() {
        previous
    } else {
        history
    }
}

/// The step's linear RVE from `committed` for a step `ratio` times the last: the
/// extrapolated history (into the workspace) and the committed contact status held, `K_ex`
/// assembled and factorized once, `X = K_ex^-1 G` solved. Returns the condensed term
/// `G^T K_ex^-1 G` (eq. 18); `X` stays in the workspace's factorization for
/// [`store_step`].
pub fn factorize_step(
    problem: &Problem,
    committed: &State,
    ratio: f64,
    ws: &mut Workspace,
) -> Result<[f64; 9]> {
    let disc = problem.disc;
    if let Some(laws) = disc.law.as_ref() {
        let previous = extrapolated_from(&committed.history, &committed.implex.previous);
        let per_element = laws.history_len() * disc.points_per_interface();
        for e in 0..disc.interfaces.len() {
            let range = e * per_element..(e + 1) * per_element;
            laws.of(e).extrapolate(
                &committed.history[range.clone()],
                &previous[range.clone()],
                ratio,
                &mut ws.history_start[range],
            );
        }
        for (q, closed) in ws.contact.start.iter_mut().enumerate() {
            *closed = committed.implex.is_closed(q);
        }
        disc.frozen_stiffness(&ws.history_start, &ws.contact.start, &mut ws.current.k);
    } else {
        ws.current.k.copy_from_slice(&disc.k_const);
    }
    factorize_frozen(problem, ws, FactorUse::Reusable)?;
    Ok(super::tangent::condensed(
        &disc.g,
        ws.factorization.kg(),
        None,
    ))
}

/// Factorizes the frozen stiffness in `ws.current.k` and solves it for the columns of `G`
/// (`ws.factorization.kg()`, from which `X eps = -kg eps`).
fn factorize_frozen(problem: &Problem, ws: &mut Workspace, use_: FactorUse) -> Result<()> {
    problem.factorize(ws, use_).map_err(|e| Error::Solve {
        reason: format!("singular RVE tangent on the IMPL-EX step's frozen branches ({e})"),
        depth: 0,
        suggested_step_ratio: 0.5,
    })?;
    ws.factorization.solve_g(problem.linear, &problem.disc.g);
    Ok(())
}

/// The fluctuation `X eps = -kg eps` of a factorized step (`kg` = `K^-1 G`, column-major).
fn fluctuation(kg: &[f64], strain: &Strain, unknowns: &mut [f64]) {
    let n = unknowns.len();
    for (i, x) in unknowns.iter_mut().enumerate() {
        *x = -(kg[i] * strain[0] + kg[n + i] * strain[1] + kg[2 * n + i] * strain[2]);
    }
}

/// Writes into `out` the IMPL-EX `state` with its unknowns at its own strain, `X eps`, when
/// its step can be rebuilt from it: a step that extrapolated no growth (`implex.at_start`,
/// as every carried-over step), whose frozen branches are the history it started from
/// (`implex.previous`) and the held contact status (`linear.closed`). Factorizes once (the
/// workspace's factors are overwritten). `Ok(false)` when the step extrapolated a growth,
/// which the state no longer holds. For outputs, not for the hot path.
pub fn materialize(
    problem: &Problem,
    state: &State,
    out: &mut State,
    ws: &mut Workspace,
) -> Result<bool> {
    out.copy_solution_from(state);
    if state.unknowns_are_current() {
        return Ok(true);
    }
    let disc = problem.disc;
    let implex = &state.implex;
    let points = disc.interface_points();
    if !implex.at_start || implex.previous.len() != state.history.len() {
        return Ok(false);
    }
    if disc.law.is_some() {
        if state.linear.closed.len() < points {
            return Ok(false);
        }
        ws.contact.start[..points].copy_from_slice(&state.linear.closed[..points]);
        disc.frozen_stiffness(&implex.previous, &ws.contact.start, &mut ws.current.k);
    } else {
        ws.current.k.copy_from_slice(&disc.k_const);
    }
    factorize_frozen(problem, ws, FactorUse::OneUse)?;
    fluctuation(ws.factorization.kg(), &state.strain, &mut out.unknowns);
    Ok(true)
}

/// Keeps the step of [`factorize_step`] in `trial.linear`: `D_ex` (`tangent`), the `s_zz`
/// row, every point's jump operator `A_q` and the held contact status; writes the
/// fluctuation `X eps` at `strain` into `trial.unknowns`.
pub fn store_step(
    problem: &Problem,
    trial: &mut State,
    strain: &Strain,
    tangent: [f64; 9],
    szz: [f64; 3],
    ws: &Workspace,
) {
    let points = problem.disc.interface_points();
    let linear: &mut LinearBranch = &mut trial.linear;
    linear.jumps.resize(JUMP_OPERATOR_LEN * points, 0.0);
    linear.closed.clear();
    linear.closed.extend_from_slice(&ws.contact.start[..points]);
    let kg = ws.factorization.kg();
    super::fast_path::jump_operators(problem, kg, &mut linear.jumps);
    linear.tangent = tangent;
    linear.szz = szz;
    linear.unknowns_strain = *strain;
    linear.valid = true;
    fluctuation(kg, strain, &mut trial.unknowns);
}

/// The trial at `strain` of the step kept in `trial.linear`, from `committed`: its strain,
/// the implicit history and contact status from the jumps `A_q eps` (see the module docs),
/// and what the next extrapolation needs (`h_n`, `dt`). Returns the branch counts. A
/// trial whose unknowns were formed at another strain of the step keeps them there
/// (`LinearBranch::unknowns_strain`).
pub fn finish_step(
    problem: &Problem,
    committed: &State,
    strain: &Strain,
    dt: f64,
    trial: &mut State,
) -> IncrementReport {
    trial.strain = *strain;
    trial.sensitivity.valid = false;
    trial.curvature.valid = false;
    trial.held_contact.fill(0);
    trial.history.copy_from_slice(&committed.history);
    trial.implex.previous.clone_from(&committed.history);
    trial.implex.step = if dt.is_finite() && dt > 0.0 { dt } else { 0.0 };
    trial.implex.at_start =
        committed.implex.previous.is_empty() || committed.implex.previous == committed.history;
    let mut report = IncrementReport {
        factorizations: 0,
        substeps: 1,
        answer: super::Answer::Solved,
        ..Default::default()
    };
    let Some(laws) = problem.disc.law.as_ref() else {
        trial.implex.closed.clear();
        return report;
    };
    let (hl, np) = (laws.history_len(), problem.disc.points_per_interface());
    let points = problem.disc.interface_points();
    trial.implex.closed.clear();
    trial.implex.closed.resize(held_contact_words(points), 0);
    let linear = &trial.linear;
    for q in 0..points {
        let law = laws.of(q / np);
        let jump = point_jump(linear, q, strain);
        let closed = law.is_closed(jump);
        let range = q * hl..(q + 1) * hl;
        let length = problem.disc.interfaces[q / np].length;
        law.trial_history_as(
            &committed.history[range.clone()],
            &mut trial.history[range.clone()],
            jump,
            length,
            closed,
        );
        if closed {
            trial.implex.closed[q / 64] |= 1 << (q % 64);
            report.contact += 1;
        } else if trial.history[range.clone()] != committed.history[range] {
            report.loading += 1;
        } else {
            report.unloading += 1;
        }
    }
    report
}

/// Whether a trial at `strain` on the step kept in `linear` would leave `committed` as it
/// is: at every interface point the contact status the committed one and the history
/// unchanged, bit for bit ([`finish_step`]'s test, without writing a trial).
pub fn stays_still(
    problem: &Problem,
    committed: &State,
    linear: &LinearBranch,
    strain: &Strain,
) -> bool {
    let Some(laws) = problem.disc.law.as_ref() else {
        return true;
    };
    let (hl, np) = (laws.history_len(), problem.disc.points_per_interface());
    let mut stack = [0.0; 8];
    let mut heap = Vec::new();
    let trial: &mut [f64] = if hl <= stack.len() {
        &mut stack[..hl]
    } else {
        heap.resize(hl, 0.0);
        &mut heap
    };
    (0..problem.disc.interface_points()).all(|q| {
        let law = laws.of(q / np);
        let jump = point_jump(linear, q, strain);
        let closed = law.is_closed(jump);
        let range = q * hl..(q + 1) * hl;
        let length = problem.disc.interfaces[q / np].length;
        law.trial_history_as(
            &committed.history[range.clone()],
            trial,
            jump,
            length,
            closed,
        );
        closed == committed.implex.is_closed(q)
            && trial
                .iter()
                .zip(&committed.history[range])
                .all(|(a, b)| a.to_bits() == b.to_bits())
    })
}

/// The local jump `[delta_s, delta_n] = A_q eps` of interface point `q` on the step kept
/// in `linear`.
fn point_jump(linear: &LinearBranch, q: usize, strain: &Strain) -> [f64; 2] {
    let a = &linear.jumps[JUMP_OPERATOR_LEN * q..JUMP_OPERATOR_LEN * (q + 1)];
    let component = |c: &[f32]| {
        f64::from(c[0]) * strain[0] + f64::from(c[1]) * strain[1] + f64::from(c[2]) * strain[2]
    };
    [component(&a[..3]), component(&a[3..])]
}

/// The step's integration error estimate `eta` (after Oliver, Huespe & Cante 2008: the
/// extrapolated history against the implicit one the step's converged jumps imply): the
/// largest relative traction error over the interface points,
/// ```text
/// eta = max_q |t_ex,q - t_q| / max(|t_ex,q| + |t_q|, t_c),   t_ex,q = S(h_ex, c_n) delta_q,   t_q = S(h_{n+1}, c_n) delta_q
/// ```
/// with `S` the frozen secant of the law ([`InterfaceLaw::frozen_secant`](crate::interface::InterfaceLaw::frozen_secant)),
/// `h_ex` the step's extrapolated history, `c_n` the contact status it held, `h_{n+1}` the
/// implicit history [`finish_step`] formed into `trial`, and
/// `delta_q` the point's converged jump, `t_c` the law's strength
/// ([`InterfaceLaw::traction_scale`](crate::interface::InterfaceLaw::traction_scale)). `t_ex,q` is the traction the step answered with,
/// `t_q` the one the paper's law gives at the same jump. In `[0, 1]`; for the cohesive law
/// `eta ~ (h_{n+1} - h_ex) / (2 delta_c)` at an opening point; the floor `t_c` keeps a
/// point with tiny tractions from counting as a 100 % error. The contact status is the
/// held one on both sides: a status that the step's jumps contradict is IMPL-EX's other
/// lag, but with a stiff penalty it flips back and forth at any step size (measured in
/// `docs/step_control.md`), so it cannot steer the step. The largest over the points,
/// not an energy-weighted mean: a crack starts at a few points, whose weight in the RVE's
/// energy is small while they decide the snap-back (`docs/step_control.md` measures both).
/// 0 without an interface law. Allocates nothing.
pub fn error_estimate(
    problem: &Problem,
    committed: &State,
    trial: &State,
    ratio: f64,
    strain: &Strain,
) -> f64 {
    let Some(laws) = problem.disc.law.as_ref() else {
        return 0.0;
    };
    let disc = problem.disc;
    let (hl, np) = (laws.history_len(), disc.points_per_interface());
    let previous = extrapolated_from(&committed.history, &committed.implex.previous);
    // Every law with a frozen branch keeps one value per point (the cohesive law's delta_max).
    let mut extrapolated = [0.0; 16];
    let h_ex = &mut extrapolated[..hl];
    let mut error = 0.0f64;
    for q in 0..disc.interface_points() {
        let law = laws.of(q / np);
        let scale = law.traction_scale();
        let range = q * hl..(q + 1) * hl;
        law.extrapolate(
            &committed.history[range.clone()],
            &previous[range.clone()],
            ratio,
            h_ex,
        );
        let length = disc.interfaces[q / np].length;
        let closed = committed.implex.is_closed(q);
        let explicit = law.frozen_secant(h_ex, closed, length);
        let implicit = law.frozen_secant(&trial.history[range], closed, length);
        let (Some(explicit), Some(implicit)) = (explicit, implicit) else {
            return 0.0;
        };
        let jump = nalgebra::Vector2::from(point_jump(&trial.linear, q, strain));
        let (t_ex, t) = (explicit * jump, implicit * jump);
        let difference = (t_ex - t).norm();
        if difference > 0.0 {
            error = error.max(difference / (t_ex.norm() + t.norm()).max(scale));
        }
    }
    error
}

/// The fluctuation of a converged state from its history and contact status alone: with
/// every point on the linear branch through the origin its history and status give (the
/// loading envelope meets that branch at `delta = delta_max`, eq. 24), the equilibrium is
/// `K_s x + G eps = 0`, so `x = -K_s^-1 G eps` with one factorization. `state` holds the
/// history, `state.implex.closed` the status and `strain` the macro strain; the result
/// goes into `unknowns`. The converged fluctuation agrees to the solver's tolerance; this
/// one is a function of the core alone (`crate::state::statev`).
pub fn secant_unknowns(
    problem: &Problem,
    state: &State,
    strain: &Strain,
    ws: &mut Workspace,
    unknowns: &mut [f64],
) -> Result<()> {
    factorize_step(problem, state, 0.0, ws)?;
    let (n, kg) = (problem.n(), ws.factorization.kg());
    for (i, x) in unknowns.iter_mut().enumerate() {
        *x = -(kg[i] * strain[0] + kg[n + i] * strain[1] + kg[2 * n + i] * strain[2]);
    }
    Ok(())
}

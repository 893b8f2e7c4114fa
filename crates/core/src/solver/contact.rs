//! The contact status of the interface points within a Newton loop
//! (`Settings::contact_status`, [`ContactStatus::ActiveSet`] by default): an active-set
//! strategy for laws with a contact status
//! ([`crate::interface::InterfaceLaw::has_contact_status`]).
//!
//! The paper detects contact "by the gap at the Gauss points" (section 3.2): a point is
//! closed iff its normal jump `delta_n < 0`, and then carries the penalty on both
//! components (eqs. 36-37, 47) instead of the cohesive traction (eqs. 32-35). The shear
//! traction jumps at that switch, by `(k_p - k beta^2) delta_s`. Read at every evaluation,
//! the switch makes the RVE residual discontinuous, and where closed points slide the
//! discrete equilibrium can lie inside the jump: held open such a point closes, held closed
//! it opens, and no solver converges (`docs/contact-algorithm.md`).
//!
//! Here the status is data of a Newton iteration, as the start history is:
//! 1. a Newton loop starts from the status the gaps give at its start state (the converged
//!    state the step starts from: the committed state, a sub-step's start, an arc point);
//! 2. within one iteration (evaluation, factorization, line search) the status is held,
//!    so the law the iteration sees is continuous and its tangent symmetric;
//! 3. at the loop's first iterate and after each accepted iterate the gaps are read again,
//!    and a point whose gap disagrees with its held status switches, at most
//!    [`MAX_SWITCHES`] times per loop; after that it keeps its status to the end of the
//!    loop (a point whose equilibrium lies inside the jump).
//!
//! Every point that can still switch agrees with its gap at convergence. If all do, the
//! converged state is an equilibrium of the law with the status read from the gaps, the
//! one [`ContactStatus::PerIteration`] looks for. A point held against its gap is evaluated
//! by the branch of its held status ([`crate::interface::InterfaceLaw::respond_as`]).
//!
//! The converged status is part of the converged state: the state records the points it
//! holds against their gap ([`State::held_contact`]), and a loop that starts from a
//! converged state (the committed state, a converged sub-step) starts from the status
//! that state is in equilibrium with, its gaps' status with those points flipped. Those
//! points are *pinned*: they keep that status for the loop's first iterate and its first
//! corrections (`PINNED_CORRECTIONS`, see `newton`), and are read again like any other
//! point after them. So a step short enough for its prediction, or a correction or two,
//! to converge converges with the start's status, and the response is continuous in the
//! step. (Read from the gaps instead, every update after a state with
//! held points would start out of equilibrium by the traction jump of those points,
//! far above the tolerance on the hard cases; `docs/contact-algorithm.md`.) Path following
//! treats its arc points the same way, and an arc-length corrector holds its start's
//! status until it converges (see `arclength`).

use super::problem::Problem;
use super::settings::ContactStatus;
use super::workspace::Workspace;
use crate::state::State;

/// How many times one point may switch its status within one Newton loop: close and
/// reopen (or open and close again). One switch is not enough: a point switched by an
/// early iterate far from equilibrium must be able to switch back (with one, the
/// snap-back of `tests/closed_form_interface.rs`, pure mode I, stays glued on a point an
/// early iterate closed). More cost more for little (`docs/contact-algorithm.md`).
pub(super) const MAX_SWITCHES: u8 = 2;

/// Whether this update holds the status: [`ContactStatus::ActiveSet`] and a law with a
/// contact status.
pub(super) fn configure(problem: &Problem, ws: &mut Workspace) {
    ws.contact.held = problem.settings.contact_status == ContactStatus::ActiveSet
        && problem
            .disc
            .law
            .as_ref()
            .is_some_and(|laws| laws.has_contact_status());
}

/// Holds the status the converged state `start` is in equilibrium with: its gaps' status
/// with the points it holds against their gap flipped, those pinned for the first
/// iterate. Called wherever a loop starts from a converged state.
pub(super) fn hold_state(problem: &Problem, start: &State, ws: &mut Workspace) {
    if ws.contact.held {
        let c = &mut ws.contact;
        problem.disc.contact_status(&start.unknowns, &mut c.start);
        for (i, (status, pinned)) in c.start.iter_mut().zip(&mut c.pinned).enumerate() {
            *pinned = start.is_held(i);
            *status ^= *pinned;
        }
        restore(ws);
    }
}

/// Records in `state.held_contact` the points the last loop holds at a status the gaps at
/// the converged `state.unknowns` contradict, and returns how many there are.
pub(super) fn record_held(problem: &Problem, state: &mut State, ws: &mut Workspace) -> usize {
    state.held_contact.fill(0);
    let c = &mut ws.contact;
    if !c.held {
        return 0;
    }
    problem.disc.contact_status(&state.unknowns, &mut c.read);
    let mut count = 0;
    for (i, (now, read)) in c.now.iter().zip(&c.read).enumerate() {
        if now != read {
            if let Some(word) = state.held_contact.get_mut(i / 64) {
                *word |= 1 << (i % 64);
            }
            count += 1;
        }
    }
    count
}

/// Holds the start state's status again, no point switched (before a loop or a
/// prediction from the start state).
pub(super) fn restore(ws: &mut Workspace) {
    let c = &mut ws.contact;
    if c.held {
        c.now.copy_from_slice(&c.start);
        c.switches.fill(0);
    }
}

/// Reads the gaps at the iterate `x` and switches every point whose gap disagrees with its
/// held status and that has switched fewer than [`MAX_SWITCHES`] times in this loop; the
/// pinned points only with `switch_pinned` (an iterate that has not converged). Returns
/// how many switched (the caller then evaluates `x` again).
pub(super) fn update(
    problem: &Problem,
    x: &[f64],
    switch_pinned: bool,
    ws: &mut Workspace,
) -> usize {
    let c = &mut ws.contact;
    if !c.held {
        return 0;
    }
    problem.disc.contact_status(x, &mut c.read);
    let mut switched = 0;
    for (((held, count), &read), &pinned) in c
        .now
        .iter_mut()
        .zip(&mut c.switches)
        .zip(&c.read)
        .zip(&c.pinned)
    {
        if *held != read && *count < MAX_SWITCHES && (switch_pinned || !pinned) {
            *held = read;
            *count += 1;
            switched += 1;
        }
    }
    switched
}

/// Whether the status is held in this update (a failed solve then owes nothing to the
/// jump of the traction at the switch).
pub(super) fn held(ws: &Workspace) -> bool {
    ws.contact.held
}

/// Whether a pinned point is still held against its gap at `x`; if so, saves the held
/// status, unpins every point and switches those against their gap (returns true: the
/// caller evaluates `x` again).
pub(super) fn release_pinned(problem: &Problem, x: &[f64], ws: &mut Workspace) -> bool {
    release(problem, x, Release::Pinned, ws)
}

/// Whether a point is held closed at `x` while its gap is open; if so, saves the held
/// status, unpins every point and opens those (returns true: the caller evaluates `x`
/// again). An arc-length corrector, which switches no point on its way, does this at its
/// converged iterate. A point held open while its gap closed stays open: it carries the
/// normal penalty either way, and closing it would jump its shear traction (see
/// `arclength`).
pub(super) fn release_opened(problem: &Problem, x: &[f64], ws: &mut Workspace) -> bool {
    release(problem, x, Release::Opened, ws)
}

/// Which points [`release`] switches to their gap's status.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Release {
    /// The pinned points against their gap.
    Pinned,
    /// The points held closed whose gap is open.
    Opened,
}

/// [`release_pinned`] or [`release_opened`].
fn release(problem: &Problem, x: &[f64], which: Release, ws: &mut Workspace) -> bool {
    let c = &mut ws.contact;
    if !c.held || (which == Release::Pinned && !c.pinned.iter().any(|&p| p)) {
        return false;
    }
    problem.disc.contact_status(x, &mut c.read);
    let switches = |now: bool, closed: bool, pinned: bool| {
        now != closed
            && match which {
                Release::Pinned => pinned,
                Release::Opened => !closed,
            }
    };
    let against = c
        .now
        .iter()
        .zip(&c.read)
        .zip(&c.pinned)
        .any(|((&now, &closed), &pinned)| switches(now, closed, pinned));
    if !against {
        return false;
    }
    c.saved.copy_from_slice(&c.now);
    for (((now, &closed), pinned), count) in c
        .now
        .iter_mut()
        .zip(&c.read)
        .zip(&mut c.pinned)
        .zip(&mut c.switches)
    {
        if switches(*now, closed, *pinned) {
            *now = closed;
            *count += 1;
        }
        *pinned = false;
    }
    true
}

/// Holds the status saved by [`release_pinned`] again.
pub(super) fn restore_saved(ws: &mut Workspace) {
    let c = &mut ws.contact;
    c.now.copy_from_slice(&c.saved);
    c.switches.fill(MAX_SWITCHES);
}

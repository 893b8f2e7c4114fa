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
//! by the branch of its held status ([`crate::interface::InterfaceLaw::respond_as`]); the
//! next step reads its status from its gap again. An arc-length corrector holds the
//! status of its arc point throughout. Nothing is stored in the state: the status of a
//! start state is read from its unknowns.

use super::problem::Problem;
use super::settings::ContactStatus;
use super::workspace::Workspace;

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
            .as_deref()
            .is_some_and(|law| law.has_contact_status());
}

/// Reads the status of the start state `x_start` of the next loops from its gaps, and
/// holds it. Called wherever a loop's start history is set.
pub(super) fn hold_start(problem: &Problem, x_start: &[f64], ws: &mut Workspace) {
    if ws.contact.held {
        problem.disc.contact_status(x_start, &mut ws.contact.start);
        restore(ws);
    }
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
/// held status and that has switched fewer than [`MAX_SWITCHES`] times in this loop;
/// returns how many switched (the caller then evaluates `x` again).
pub(super) fn update(problem: &Problem, x: &[f64], ws: &mut Workspace) -> usize {
    let c = &mut ws.contact;
    if !c.held {
        return 0;
    }
    problem.disc.contact_status(x, &mut c.read);
    let mut switched = 0;
    for ((held, count), &read) in c.now.iter_mut().zip(&mut c.switches).zip(&c.read) {
        if *held != read && *count < MAX_SWITCHES {
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

/// How many points the last loop holds at a status that the gaps at its converged iterate
/// `x` contradict.
pub(super) fn held_against_gap(problem: &Problem, x: &[f64], ws: &mut Workspace) -> usize {
    let c = &mut ws.contact;
    if !c.held {
        return 0;
    }
    problem.disc.contact_status(x, &mut c.read);
    c.now.iter().zip(&c.read).filter(|(a, b)| a != b).count()
}

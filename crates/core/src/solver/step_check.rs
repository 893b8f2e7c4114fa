//! Whether an implicit increment's answer depends on its size.
//!
//! Under a monotonic strain step, backward Euler on the paper's law does not depend on
//! the step (the history is the largest opening reached), except where the RVE's
//! equilibrium path branches: at a snap-back, continuous loading jumps to the lower branch
//! at the limit point, while one large step can converge by Newton straight onto the upper
//! branch continued beyond it, which continuous loading never reaches (a higher stress and
//! often a negative tangent). Path following only runs where Newton fails, so such a step
//! lands silently.
//!
//! [`depends_on_step`] solves the same increment in two half steps and compares the
//! fluctuations: equal to well within [`STEP_CHECK_TOLERANCE`] where the step does not
//! matter, apart by the jump of a snap where it does. It runs only on increments that
//! Newton landed in one step (no sub-step, no traced limit point) while some interface
//! point passed the peak of its law, i.e. where a snap may have been skipped. The answer
//! is not changed: the host is told to cut its step (`RveInfo`, `PNEWDT`).

use super::increment::solve_increment;
use super::problem::{norm, Problem, Strain};
use super::settings::TangentRequest;
use super::workspace::Workspace;
use crate::state::State;

/// Relative difference of the fluctuations of one step and two half steps above which the
/// two are different equilibria: far above the solver's tolerance, far below a snap.
pub const STEP_CHECK_TOLERANCE: f64 = 1e-3;

/// Whether the check applies to an increment from `committed` that converged into
/// `trial` in one Newton step (`substeps == 1`, no limit point).
pub fn applies(
    problem: &Problem,
    committed: &State,
    trial: &State,
    substeps: u32,
    limits: u32,
) -> bool {
    problem.settings.step_check
        && substeps == 1
        && limits == 0
        && problem.disc.passes_peak(&committed.history, &trial.history)
}

/// Solves the increment from `committed` to `strain` in two half steps and returns whether
/// they end on another equilibrium than `trial` (a half step that fails counts as no
/// evidence), with the factorizations it took. Overwrites the workspace's factors; its
/// Newton loops run in the check's own buffers, so the residual history and the last
/// evaluation still describe the answered increment.
pub fn depends_on_step(
    problem: &Problem,
    committed: &State,
    strain: Strain,
    trial: &State,
    ws: &mut Workspace,
) -> (bool, u32) {
    ws.swap_step_check_buffers();
    let [mut first, mut second] = std::mem::replace(
        &mut ws.step_check.half_steps,
        [State::virgin(0, 0), State::virgin(0, 0)],
    );
    let middle = std::array::from_fn(|c| 0.5 * (committed.strain[c] + strain[c]));
    let request = TangentRequest::None;
    let mut factorizations = 0;
    let mut other = false;
    if let Ok(a) = solve_increment(problem, committed, middle, request, ws, &mut first) {
        factorizations += a.report.factorizations;
        if let Ok(b) = solve_increment(problem, &first, strain, request, ws, &mut second) {
            factorizations += b.report.factorizations;
            let diff: f64 = second
                .unknowns
                .iter()
                .zip(&trial.unknowns)
                .map(|(x, y)| (x - y) * (x - y))
                .sum::<f64>()
                .sqrt();
            other = diff > STEP_CHECK_TOLERANCE * norm(&trial.unknowns);
        }
    }
    ws.step_check.half_steps = [first, second];
    ws.swap_step_check_buffers();
    (other, factorizations)
}

//! Answer sharing with error control (`[solver] share_tolerance`, `docs/sharing.md`):
//! within one host increment, a point close to a point already solved (its *anchor*)
//! takes the anchor's answer corrected to first order instead of solving its own RVE.
//! The idea is that of the adaptivity of preCICE's Micro-Manager (Desai, Uekermann et
//! al.: micro simulations activated and deactivated by the similarity of their states),
//! here per increment and with a correction.
//!
//! **Similarity.** With `tol` = `share_tolerance`, a point (committed state `C`, strain
//! `eps`) matches an anchor (`C_a`, `eps_a`) of the same model (the same scene, `PROPS`
//! and integration: the same [`Model`], checked by identity and fingerprint) when
//! - the contact status of every ITZ point is the same, bit for bit (the held points of
//!   implicit integration, the closed points and the frozen-start flag of IMPL-EX) and
//!   IMPL-EX's last step `dt_n` is the same;
//! - the interface histories agree: `|h - h_a|_inf <= tol max(|h_a|_inf, H_FLOOR)`, and
//!   so do IMPL-EX's previous histories `h_{n-1}`;
//! - the strains agree: `|eps - eps_a|_inf <= tol max(|eps_a|_inf, STRAIN_FLOOR)`.
//!
//! **Correction.** The follower's answer is the anchor's to first order in the strain,
//! `sigma = sigma_a + D_a (eps - eps_a)`, `s_zz = s_zz,a + d s_zz,a (eps - eps_a)`, its
//! tangent `D_a`; its trial state is the anchor's trial moved to `eps`
//! ([`Instance::adopt_trial`]; in `STATEV` mode with implicit integration the anchor's
//! written core with the follower's strain), so that the state a host keeps carries the
//! point's own strain. In `STATEV` mode under IMPL-EX the UMAT shares the anchor's step
//! instead ([`Instance::adopt_step`]): the follower answers on it and forms its own trial.
//! The error left is of second order in `eps - eps_a` plus first order in the history
//! difference `h - h_a`, both bounded by `tol` above.
//!
//! **Error indicator** ([`Indicator`]): after the anchor is solved, a follower gets its
//! own solve back when the anchor failed or was not [`Reliable`](super::Reliability)
//! (sub-stepped, or its answer depends on the increment's size), and, by default
//! ([`Indicator::FirstOrder`]), when the first-order term is large:
//! `|D_a (eps - eps_a)|_inf > tol max(|sigma_a|_inf, |D_a|_inf STRAIN_FLOOR)`: a softening
//! anchor, whose stress is small against its tangent's reach, does not lend its answer.
//! [`Indicator::Branch`] also refuses an anchor whose increment switched the contact
//! status of an ITZ point (the follower may lie on the other side of the switch).

use super::{Instance, Model, Response};
use crate::state::{Core, State};

/// The strain scale below which strains count as equal to within `tol` times it: a tenth
/// of the paper's concrete's tensile peak strain (about 1.3e-4), so that points near zero
/// strain (a member's neutral axis) share; the stress error it lets through is
/// `tol |D| STRAIN_FLOOR`, 1e-4 of the paper RVE's peak stress at `tol` = 0.005.
pub const STRAIN_FLOOR: f64 = 1e-5;
/// The interface history scale (the paper's law: `delta_max`, mm) below which histories
/// count as equal to within `tol` times it: a hundredth of the ITZ opening at the paper
/// RVE's peak stress (about 4e-4 mm).
pub const H_FLOOR: f64 = 4e-6;

/// Strains closer than this fraction of the anchor's count as the same strain (round-off
/// of a host's sums, as the `STATEV` strain check's `1e-9`): a damaging anchor still
/// lends its answer to a point at its own strain (CalculiX's twin point layers).
pub const ROUND_OFF: f64 = 1e-9;

/// When a follower gets its own solve back (measured in `docs/sharing.md`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Indicator {
    /// Only when the anchor failed or was not reliable.
    Plain,
    /// Also when the first-order term is large against the anchor's stress.
    FirstOrder,
    /// Also when the anchor's increment switched an ITZ point's contact status.
    Branch,
    /// [`Indicator::FirstOrder`], and also when the anchor's increment grew its interface
    /// history by more than `tol` times its size (the anchor is damaging: the follower's
    /// own growth, which the first-order correction does not carry, would differ) and the
    /// strains differ beyond round-off ([`ROUND_OFF`]). The default: the one measured to
    /// stay within `tol` of the exact run (`docs/sharing.md`).
    #[default]
    History,
}

/// The sharing tolerance of `model`'s scene (`None`: no sharing).
pub fn tolerance(model: &Model) -> Option<f64> {
    model.solver.share_tolerance
}

/// Whether two models are the same material (identity and fingerprint).
pub fn same_model(a: &std::sync::Arc<Model>, b: &std::sync::Arc<Model>) -> bool {
    std::sync::Arc::ptr_eq(a, b) && a.fingerprint() == b.fingerprint()
}

fn norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// `|a - b|_inf <= tol max(|b|_inf, floor)` (both empty: true; other lengths: false).
pub fn close(tol: f64, a: &[f64], b: &[f64], floor: f64) -> bool {
    if a.len() != b.len() {
        return false;
    }
    let reach = tol * norm(b).max(floor);
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= reach)
}

/// The strains agree (see the module documentation).
pub fn strains_close(tol: f64, eps: &[f64; 3], anchor: &[f64; 3]) -> bool {
    close(tol, eps, anchor, STRAIN_FLOOR)
}

/// Two committed states agree: same contact status and IMPL-EX step, histories within
/// `tol` (see the module documentation).
pub fn states_close(tol: f64, point: &State, anchor: &State) -> bool {
    point.held_contact == anchor.held_contact
        && point.implex.closed == anchor.implex.closed
        && point.implex.at_start == anchor.implex.at_start
        && point.implex.step.to_bits() == anchor.implex.step.to_bits()
        && close(tol, &point.history, &anchor.history, H_FLOOR)
        && close(
            tol,
            &point.implex.previous,
            &anchor.implex.previous,
            H_FLOOR,
        )
}

/// [`states_close`] for two `STATEV` cores (the UMAT's table, `crate::host`).
pub fn cores_close(tol: f64, point: &Core, anchor: &Core) -> bool {
    point.closed == anchor.closed
        && point.at_start == anchor.at_start
        && point.step.to_bits() == anchor.step.to_bits()
        && close(tol, &point.history, &anchor.history, H_FLOOR)
        && close(tol, &point.previous, &anchor.previous, H_FLOOR)
}

/// The anchor's answer moved to `eps` to first order (see the module documentation).
pub fn corrected(anchor: &Response, anchor_strain: &[f64; 3], eps: &[f64; 3]) -> Response {
    let d: [f64; 3] = std::array::from_fn(|i| eps[i] - anchor_strain[i]);
    let mut r = *anchor;
    for (i, s) in r.stress.iter_mut().enumerate() {
        *s += (0..3)
            .map(|j| anchor.tangent[3 * i + j] * d[j])
            .sum::<f64>();
    }
    r.s_zz += (0..3).map(|j| anchor.s_zz_tangent[j] * d[j]).sum::<f64>();
    r.report.iterations = 0;
    r.report.factorizations = 0;
    r
}

/// Whether a follower at `eps` may keep the anchor's answer (the error indicator; see
/// the module documentation). `switched`: the anchor's increment switched a contact
/// status; `grew`: it grew its history ([`grew`]).
pub fn keeps_share(
    indicator: Indicator,
    tol: f64,
    anchor: &Response,
    anchor_strain: &[f64; 3],
    eps: &[f64; 3],
    switched: bool,
    grew: bool,
) -> bool {
    let report = &anchor.report;
    if report.substepped() || report.step_too_large || report.exceeds_tolerance() {
        return false;
    }
    if indicator == Indicator::Plain {
        return true;
    }
    let d: [f64; 3] = std::array::from_fn(|i| eps[i] - anchor_strain[i]);
    let term: [f64; 3] =
        std::array::from_fn(|i| (0..3).map(|j| anchor.tangent[3 * i + j] * d[j]).sum());
    let reach = tol * norm(&anchor.stress).max(norm(&anchor.tangent) * STRAIN_FLOOR);
    if norm(&term) > reach {
        return false;
    }
    match indicator {
        Indicator::Branch => !switched,
        Indicator::History => !grew || norm(&d) <= ROUND_OFF * norm(anchor_strain),
        _ => true,
    }
}

/// Whether `instance`'s pending trial grew its interface history beyond `tol` times
/// its size ([`H_FLOOR`] at least) against the committed state.
pub fn grew(tol: f64, instance: &Instance) -> bool {
    !close(
        tol,
        instance.trial_history(),
        &instance.committed().history,
        H_FLOOR,
    )
}

/// Whether `instance`'s pending trial switched the contact status of an ITZ point
/// against its committed state (held or, with IMPL-EX, closed points).
pub fn switched(instance: &Instance) -> bool {
    instance.trial_switched()
}

/// Solved and shared points of a batch (from its reports' `shared_from`).
pub fn counts(reports: &[super::PointReport]) -> (usize, usize) {
    let shared = reports.iter().filter(|r| r.shared_from.is_some()).count();
    (reports.len() - shared, shared)
}

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
//! IMPL-EX step sharing in `STATEV` mode compares what the step freezes instead of the
//! histories ([`StepSignature`]): the same contact status, `dt_n` and step ratio, and
//! every ITZ point's frozen secant within `tol` times the virgin ITZ stiffness. No
//! strain condition: the step is linear in the strain.
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
use crate::interface::InterfaceLaw;
use crate::state::statev::CoreView;
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

/// What an IMPL-EX step freezes, for step sharing in `STATEV` mode (`crate::host`): the
/// secant `S_q` of every interface point `q` (`InterfaceLaw::frozen_secant`) at the
/// extrapolated history `h_ex = h + r (h - h_{n-1})` of a committed core for step ratio
/// `r`, under the core's contact status; the step's matrix is
/// `K_ex = K_const + sum_q B_q^T S_q B_q w_q`. Entries as `f32`, point-major.
pub struct StepSignature {
    secants: Vec<f32>,
    /// Mean entry: a first filter of the candidates.
    mean: f64,
}

impl StepSignature {
    /// The signature of `core`'s step at ratio `ratio` in `model`. Allocates its secants
    /// alone: each point's history is extrapolated on the stack.
    pub fn of(model: &Model, core: &CoreView<'_>, ratio: f64) -> Self {
        let previous = crate::solver::implex::extrapolated_from(core.history, core.previous);
        let secants = point_secants(model, |q, law, out| {
            let range = q * out.len()..(q + 1) * out.len();
            law.extrapolate(&core.history[range.clone()], &previous[range], ratio, out);
            core.is_closed(q)
        });
        let mean = secants.iter().map(|&x| f64::from(x)).sum::<f64>() / secants.len().max(1) as f64;
        StepSignature { secants, mean }
    }

    /// Whether every entry of the two signatures is within `tol * scale`: the two steps'
    /// matrices `K_ex` differ by at most that in every point's secant.
    pub fn close(&self, other: &Self, tol: f64, scale: f64) -> bool {
        let reach = tol * scale;
        self.secants.len() == other.secants.len()
            && (self.mean - other.mean).abs() <= reach
            && (self.secants.iter().zip(&other.secants))
                .all(|(&a, &b)| (f64::from(a) - f64::from(b)).abs() <= reach)
    }
}

/// The scale of [`StepSignature::close`]: the largest entry of the virgin RVE's open
/// secants (the ITZ's initial stiffness for the paper's law); 0 without an interface.
pub fn secant_scale(model: &Model) -> f64 {
    let virgin = model.new_state();
    let secants = point_secants(model, |q, _, out| {
        out.copy_from_slice(&virgin.history[q * out.len()..(q + 1) * out.len()]);
        false
    });
    secants
        .iter()
        .fold(0.0f64, |m, &x| m.max(f64::from(x).abs()))
}

/// Interface histories of at most this many values a point are formed on the stack.
const POINT_HISTORY_MAX: usize = 8;

/// The four entries of `S_q` of every point, `point(q, law, h)` writing point `q`'s
/// history into `h` and giving its status (true: closed). Empty without an interface.
fn point_secants(
    model: &Model,
    point: impl Fn(usize, &dyn InterfaceLaw, &mut [f64]) -> bool,
) -> Vec<f32> {
    let disc = &model.disc;
    let Some(law) = disc.law.as_deref() else {
        return Vec::new();
    };
    let (per_point, np) = (law.history_len(), disc.points_per_interface());
    let mut stack = [0.0; POINT_HISTORY_MAX];
    let mut heap = Vec::new();
    let h: &mut [f64] = if per_point <= POINT_HISTORY_MAX {
        &mut stack[..per_point]
    } else {
        heap.resize(per_point, 0.0);
        &mut heap
    };
    let mut out = Vec::with_capacity(4 * np * disc.interfaces.len());
    for (e, geometry) in disc.interfaces.iter().enumerate() {
        for q in e * np..(e + 1) * np {
            let closed = point(q, law, h);
            let secant = law
                .frozen_secant(h, closed, geometry.length)
                .unwrap_or_else(|| nalgebra::Matrix2::from_element(f64::NAN));
            out.extend(secant.iter().map(|&x| x as f32));
        }
    }
    out
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The IMPL-EX host scene (paper law, `delta_c` = 2e-4 mm, penalty contact).
    fn model() -> Model {
        let text = include_str!("../../scenes/paper_rve_host_implex.toml");
        let scene = crate::Scene::from_toml_str(text, env!("CARGO_MANIFEST_DIR")).unwrap();
        Model::from_scene(&scene).unwrap()
    }

    /// Step sharing compares the secants a step freezes, not the histories: two points far
    /// into softening (histories 10 % apart, secants both near zero) match, two near the
    /// peak (a factor 2 apart) do not, and a closed point's history does not count.
    #[test]
    fn step_signatures_compare_the_frozen_secants() {
        let m = model();
        let virgin = m.core_of(&m.new_state());
        let scale = secant_scale(&m);
        assert!(scale > 0.0);
        let at = |values: &[(usize, f64)], closed: bool| {
            let mut core = virgin.clone();
            for &(q, h) in values {
                core.history[q] = h;
                if closed {
                    core.closed[q / 64] |= 1 << (q % 64);
                }
            }
            StepSignature::of(&m, &core.view(), 1.0)
        };
        let base = at(&[], false);
        assert!(base.close(&at(&[], false), 0.0, scale));
        let (tol, peak, soft) = (0.005, 2e-4, 2e-2);
        assert!(at(&[(3, soft)], false).close(&at(&[(3, 1.1 * soft)], false), tol, scale));
        assert!(!at(&[(3, peak)], false).close(&at(&[(3, 2.0 * peak)], false), tol, scale));
        assert!(!at(&[(3, peak)], false).close(&base, tol, scale));
        assert!(at(&[(3, peak)], true).close(&at(&[(3, 2.0 * peak)], true), 0.0, scale));
    }
}

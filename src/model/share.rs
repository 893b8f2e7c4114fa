//! Answer sharing with error control (`[solver] share_tolerance`, `docs/sharing.md`):
//! within one host increment, a point close to a point already solved (its *anchor*)
//! takes the anchor's answer, or the anchor's IMPL-EX step, instead of solving its own
//! RVE. The idea is that of the adaptivity of preCICE's Micro-Manager (Desai, Uekermann
//! et al.: micro simulations activated and deactivated by the similarity of their states),
//! here per increment and with a correction.
//!
//! **The invariant that bounds the error.** A follower never keeps another point's
//! history. Whatever it takes from its anchor, the history and contact status it commits
//! are the ones its own solve would have formed from its own committed state (or, for
//! twins, the same to round-off). So the difference from the point's exact run is that of
//! one increment's answer, bounded by the indicator below, and does not build up over the
//! increments: a follower whose path departs from its neighbours' solves itself again,
//! from its own state.
//!
//! **Implicit integration: answer sharing.** With `tol` = `share_tolerance`, a point
//! (committed state `C`, strain `eps`) matches an anchor (`C_a`, `eps_a`) of the same model
//! (the same scene, `PROPS` and integration: the same [`Model`], checked by identity and
//! fingerprint) when
//! - the contact status of every ITZ point is the same, bit for bit;
//! - the interface histories agree: `|h - h_a|_inf <= tol max(|h_a|_inf, H_FLOOR)`;
//! - the strains agree: `|eps - eps_a|_inf <= tol max(|eps_a|_inf, STRAIN_FLOOR)`.
//!
//! Its answer is the anchor's to first order in the strain, `sigma = sigma_a + D_a (eps -
//! eps_a)`, `s_zz` alike, the tangent `D_a`, when the error indicator ([`follows`]) allows:
//! the anchor converged reliably (not sub-stepped, not above `step_tolerance`), the
//! first-order term is small, `|D_a (eps - eps_a)|_inf <= tol max(|sigma_a|_inf, |D_a|_inf
//! STRAIN_FLOOR)`, and either the anchor's increment left its history and contact status
//! unchanged bit for bit (elastic, unloading or closed: [`Follow::Own`], the follower's
//! trial is its own committed state at `eps`), or the two are twins ([`Follow::Twin`]: the
//! same committed state bit for bit, the same strain to round-off; the follower's trial is
//! the anchor's, [`Instance::adopt_trial`](super::Instance::adopt_trial)). A damaging anchor lends nothing else.
//!
//! **IMPL-EX: step sharing.** Under IMPL-EX the RVE of a step is linear; its matrix
//! `K_ex` is frozen at the extrapolated history. A point whose step freezes what the
//! anchor's froze ([`StepSignature`]: the same contact status, `dt_n` and step ratio, and
//! every ITZ point's frozen secant within `tol` times the virgin ITZ stiffness) takes the
//! anchor's factorized step ([`Instance::adopt_step`](super::Instance::adopt_step)) and answers on it itself: its
//! stress `D_ex eps`, its trial history formed from its own committed history and the
//! jumps at its own strain. No strain condition: the step is linear in the strain.
//!
//! Both are used by the batch ([`super::batch`]) and by the UMAT's `STATEV` mode
//! (`crate::host`).

use super::{Model, Response};
use mesorve_core::interface::InterfaceLaw;
use mesorve_core::state::statev::CoreView;
use mesorve_core::state::{Core, LinearBranch, State, JUMP_OPERATOR_LEN};

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

/// How a follower forms its trial state once the error indicator lets it share
/// ([`follows`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Follow {
    /// The anchor's trial, moved to the follower's strain: the two committed states are
    /// the same bit for bit and the strains the same to round-off ([`ROUND_OFF`]), so the
    /// anchor's trial is the follower's own to round-off, whatever the anchor's increment
    /// did (CalculiX's twin point layers).
    Twin,
    /// The follower's own committed state at its own strain: history and contact status
    /// its own, unchanged, as the anchor's increment left the anchor's unchanged.
    Own,
}

/// The sharing tolerance of `model`'s scene (`None`: no sharing).
pub fn tolerance(model: &Model) -> Option<f64> {
    model.solver.share_tolerance
}

/// Whether two models are the same material (identity and fingerprint).
pub fn same_model(a: &std::sync::Arc<Model>, b: &std::sync::Arc<Model>) -> bool {
    std::sync::Arc::ptr_eq(a, b) && a.fingerprint() == b.fingerprint()
}

/// Whether two slices hold the same values bit for bit.
pub fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
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

/// Whether two committed states' IMPL-EX steps freeze the same discrete part: the same
/// contact status, frozen-start flag and `dt_n`, bit for bit (their secants are compared
/// by [`StepSignature::close`]).
pub fn steps_match(point: &State, anchor: &State) -> bool {
    point.implex.closed == anchor.implex.closed
        && point.implex.at_start == anchor.implex.at_start
        && point.implex.step.to_bits() == anchor.implex.step.to_bits()
}

/// [`states_close`] for two `STATEV` cores (the UMAT's table, `crate::host`).
pub fn cores_close(tol: f64, point: &CoreView<'_>, anchor: &Core) -> bool {
    point.closed == anchor.closed
        && point.at_start == anchor.at_start
        && point.step.to_bits() == anchor.step.to_bits()
        && close(tol, point.history, &anchor.history, H_FLOOR)
        && close(tol, point.previous, &anchor.previous, H_FLOOR)
}

/// What an IMPL-EX step freezes, for step sharing in `STATEV` mode (`crate::host`): the
/// secant `S_q` of every interface point `q` (`InterfaceLaw::frozen_secant`) at the
/// extrapolated history `h_ex = h + r (h - h_{n-1})` of a committed core for step ratio
/// `r`, under the core's contact status; the step's matrix is
/// `K_ex = K_const + sum_q B_q^T S_q B_q w_q`. Entries as `f32`, point-major.
#[derive(Debug)]
pub struct StepSignature {
    secants: Vec<f32>,
    /// Mean entry: a first filter of the candidates.
    mean: f64,
}

impl StepSignature {
    /// The signature of `core`'s step at ratio `ratio` in `model`. Allocates its secants
    /// alone: each point's history is extrapolated on the stack.
    pub fn of(model: &Model, core: &CoreView<'_>, ratio: f64) -> Self {
        let previous = mesorve_core::solver::implex::extrapolated_from(core.history, core.previous);
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

/// The first-order difference between the stress a point answers on an adopted IMPL-EX
/// `step` (the anchor's, whose frozen secants are `anchor`'s) at `strain` and the stress
/// it would answer on its own step (secants `own`): the homogenized stiffness is the
/// minimum of the cell's energy over the fluctuations, so its derivative in one interface
/// point's secant is that point's energy at the minimizer (the envelope theorem), and
/// ```text
/// delta_sigma = 1/V sum_q w_q A_q^T (S_q - S_q,a) A_q eps,   w_q = w_i l_e / 2,
/// ```
/// with `A_q` the step's jump operators (`LinearBranch::jumps`, the jumps per unit
/// macro strain). Of second order in `S - S_a`; exact for one point in series with a
/// stiffer rest. Zeros when the step has no jump operators.
pub fn step_difference(
    model: &Model,
    step: &LinearBranch,
    own: &StepSignature,
    anchor: &StepSignature,
    strain: &[f64; 3],
) -> [f64; 3] {
    let disc = &model.disc;
    let np = disc.points_per_interface();
    let points = disc.interface_points();
    let mut out = [0.0; 3];
    if step.jumps.len() != JUMP_OPERATOR_LEN * points
        || own.secants.len() != 4 * points
        || anchor.secants.len() != 4 * points
    {
        return out;
    }
    let rule = disc.quadrature.rule();
    for q in 0..points {
        let a = &step.jumps[JUMP_OPERATOR_LEN * q..JUMP_OPERATOR_LEN * (q + 1)];
        let row = |r: usize| -> [f64; 3] { std::array::from_fn(|j| f64::from(a[3 * r + j])) };
        let (s_row, n_row) = (row(0), row(1));
        let jump = [
            (0..3).map(|j| s_row[j] * strain[j]).sum::<f64>(),
            (0..3).map(|j| n_row[j] * strain[j]).sum::<f64>(),
        ];
        // Column-major 2 x 2 (nalgebra's order in the signature).
        let d = |k: usize| f64::from(own.secants[4 * q + k]) - f64::from(anchor.secants[4 * q + k]);
        let traction = [
            d(0) * jump[0] + d(2) * jump[1],
            d(1) * jump[0] + d(3) * jump[1],
        ];
        let w = rule[q % np].1 * disc.interfaces[q / np].length / 2.0;
        for (i, o) in out.iter_mut().enumerate() {
            *o += w * (s_row[i] * traction[0] + n_row[i] * traction[1]);
        }
    }
    out.map(|v| v / disc.volume)
}

/// An IMPL-EX step a point took from an anchor ([`Instance::adopt_step`]), with what
/// keeping it is judged by at every answer on it ([`AdoptedStep::keeps`]).
///
/// [`Instance::adopt_step`]: super::Instance::adopt_step
#[derive(Debug)]
pub struct AdoptedStep {
    /// The adopter's own step signature (its committed state at the step's ratio).
    pub own: std::sync::Arc<StepSignature>,
    /// The anchor's.
    pub anchor: std::sync::Arc<StepSignature>,
    /// The strain the anchor answered at.
    pub anchor_strain: [f64; 3],
    /// The two committed states are the same to round-off ([`ROUND_OFF`]).
    pub twin: bool,
}

impl AdoptedStep {
    /// Whether an answer `response` at `strain` on the adopted `step` from `committed` is
    /// kept ([`keeps_step`]). The point's own history counts as kept when the step leaves
    /// it unchanged with a margin, at `(1 + tol) eps` (the jumps on another point's
    /// stiffness are not the point's own: one just under a point's threshold may be just
    /// over it on its own step, and a point past its peak goes on softening on its own
    /// extrapolated step where the anchor's leaves it), and for a twin or a point at the
    /// anchor's strain to round-off (CalculiX's twin point layers), whatever it damages.
    pub fn keeps(
        &self,
        model: &Model,
        committed: &State,
        step: &LinearBranch,
        strain: &[f64; 3],
        response: &Response,
    ) -> bool {
        let Some(tol) = tolerance(model) else {
            return false;
        };
        let d = step_difference(model, step, &self.own, &self.anchor, strain);
        let own_history = self.twin
            || strains_close(ROUND_OFF, strain, &self.anchor_strain)
            || mesorve_core::solver::implex::stays_still(
                &model.problem(),
                committed,
                step,
                &strain.map(|e| e * (1.0 + tol)),
            );
        keeps_step(tol, response, &d, own_history)
    }
}

/// Whether a point keeps the IMPL-EX step it adopted and answered `response` on: its
/// step's first-order difference ([`step_difference`]) is within `tol` of its stress
/// (`|delta_sigma|_inf <= tol max(|sigma|_inf, |D|_inf STRAIN_FLOOR)`), and `own_history`:
/// the step left its history and contact status unchanged, or its committed state is the
/// anchor's to round-off. A damaging step of another point is not kept: the history it
/// would form follows the anchor's stiffness, and over the increments it would drift
/// towards the anchor's path (module documentation).
pub fn keeps_step(tol: f64, response: &Response, difference: &[f64; 3], own_history: bool) -> bool {
    let reach = tol * norm(&response.stress).max(norm(&response.tangent) * STRAIN_FLOOR);
    own_history && norm(difference) <= reach
}

/// The scale of [`StepSignature::close`]: the largest entry of the virgin RVE's open
/// secants (the ITZ's initial stiffness for the paper's law); 0 without an interface.
pub fn secant_scale(model: &Model) -> f64 {
    model.secant_scale
}

/// [`secant_scale`], computed once when the model is built.
pub(super) fn virgin_secant_scale(model: &Model) -> f64 {
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
    let Some(laws) = disc.law.as_ref() else {
        return Vec::new();
    };
    let (per_point, np) = (laws.history_len(), disc.points_per_interface());
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
        let law = laws.of(e);
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

/// The error indicator (see the module documentation): whether a follower at `eps` may
/// take the anchor's answer, and how it forms its trial. `twin`: the follower's committed
/// state is the anchor's bit for bit; `still`: the anchor's increment left its interface
/// history and contact status as they were, bit for bit
/// ([`Instance::trial_is_still`](super::Instance::trial_is_still)).
/// `None`: the follower solves its own RVE.
pub fn follows(
    tol: f64,
    anchor: &Response,
    anchor_strain: &[f64; 3],
    eps: &[f64; 3],
    twin: bool,
    still: bool,
) -> Option<Follow> {
    let report = &anchor.report;
    if report.substepped() || report.step_too_large || report.exceeds_tolerance() {
        return None;
    }
    let d: [f64; 3] = std::array::from_fn(|i| eps[i] - anchor_strain[i]);
    let term: [f64; 3] =
        std::array::from_fn(|i| (0..3).map(|j| anchor.tangent[3 * i + j] * d[j]).sum());
    let reach = tol * norm(&anchor.stress).max(norm(&anchor.tangent) * STRAIN_FLOOR);
    if norm(&term) > reach {
        return None;
    }
    if twin && norm(&d) <= ROUND_OFF * norm(anchor_strain) {
        Some(Follow::Twin)
    } else if still {
        Some(Follow::Own)
    } else {
        None
    }
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

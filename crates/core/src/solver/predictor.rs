//! The start of a strain step: Newton's first iterate, predicted from the committed state.
//!
//! A step from the committed strain starts from `x_n + X_n Delta eps`, with
//! `X_n = dx/d eps = -K_n^-1 G` the sensitivity of the committed state (kept in the state
//! from its tangent computation, see [`crate::state::Sensitivity`]): Newton's own first
//! iterate, whose residual is `O(|Delta eps|^2)`. When the step keeps the direction of the
//! committed state's own increment (`Delta eps = s Delta eps_n`, see [`curvature_scale`]),
//! the second-order term `s^2 e_n` is added, `e_n` being that increment's first-order
//! prediction error `x_n - x_{n-1} - X_{n-1} Delta eps_n` (kept in the state as
//! [`crate::state::PathCurvature`]): along a smooth path
//! `e_n ~ x''[Delta eps_n, Delta eps_n] / 2`, so the prediction is good to third order.
//! `Settings::second_order_predictor = false` switches that term off.
//!
//! A prediction is kept only if it lowers the residual and, for the tangent prediction,
//! no interface point passes the peak of its law within the step (see
//! [`take_prediction`]); otherwise the model's elastic sensitivity `X_el` is tried.
//! Measurements of the predictors are in `docs/accuracy.md` and `docs/robustness.md`.

use super::contact;
use super::problem::{accept_candidate, norm, sensitivity_times, Problem, Strain};
use super::workspace::Workspace;
use crate::interface::TangentKind;
use crate::state::{PathCurvature, State};

/// Steps whose direction is within this cosine of the stored curvature's step get the
/// second-order term (a proportional path has 1; the term is exact only along the stored
/// direction, and the cross terms `x''[Delta_par, Delta_perp]` it misses grow with the
/// angle).
const CURVATURE_ALIGNMENT: f64 = 0.99;
/// Largest ratio `s` of a step to the stored one that gets the term: `s^2 e` extrapolates
/// the curvature of the last step, which a much longer step outruns.
const CURVATURE_MAX_SCALE: f64 = 4.0;

/// What [`predict`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Prediction {
    /// Nothing taken: Newton starts from `x` itself and evaluates there.
    None,
    /// The tangent (and second-order) prediction from the committed state.
    Tangent,
    /// The elastic prediction of the model.
    Elastic,
}

impl Prediction {
    /// Whether `ws.current` holds the consistent evaluation of the prediction.
    pub(super) fn evaluated(self) -> bool {
        self != Prediction::None
    }
}

/// A strain step of a sub-step: from `from` to `to`.
#[derive(Clone, Copy, Debug)]
pub(super) struct StrainStep {
    pub from: Strain,
    pub to: Strain,
}

impl StrainStep {
    pub(super) fn delta(&self) -> Strain {
        [
            self.to[0] - self.from[0],
            self.to[1] - self.from[1],
            self.to[2] - self.from[2],
        ]
    }
}

/// Predicts the start of `step` into `x` (the converged unknowns at `step.from`).
///
/// Tries `x + X_n d + s^2 e_n` with the committed state's sensitivity and curvature (when
/// `committed` is given and has them), then `x + X_el d` with the model's elastic
/// sensitivity, and takes the first whose residual is below that of `x` itself. The
/// residual of `x` at `step.to` is `R_n + G d` with `R_n` the converged residual (below
/// the tolerance), so `||G d||` stands for it. Nothing is predicted when the step goes
/// towards the origin (unloading: the secant response is linear and Newton from `x` is
/// exact in one iteration). `ws.history_start` must hold the step's start history; when
/// the tangent prediction is tried, `ws.tangent_prediction` receives `X_n d`.
pub(super) fn predict(
    problem: &Problem,
    committed: Option<&State>,
    x: &mut [f64],
    step: &StrainStep,
    ws: &mut Workspace,
) -> Prediction {
    let (from, d) = (step.from, step.delta());
    contact::restore(ws);
    let outward = from[0] * d[0] + from[1] * d[1] + from[2] * d[2] >= 0.0;
    if !outward {
        return Prediction::None;
    }
    problem.load(&d, &mut ws.candidate.r);
    let before = norm(&ws.candidate.r);
    if let Some(committed) = committed.filter(|c| c.sensitivity.valid) {
        committed.sensitivity.times(&d, &mut ws.x_try);
        ws.tangent_prediction.copy_from_slice(&ws.x_try);
        if problem.settings.second_order_predictor {
            if let Some(s) = curvature_scale(&committed.curvature, &d) {
                committed.curvature.add_scaled(s, &mut ws.x_try);
            }
        }
        if take_prediction(problem, x, &step.to, before, true, ws) {
            return Prediction::Tangent;
        }
    }
    if problem.predictor.len() == 3 * problem.n() {
        sensitivity_times(problem.predictor, &d, &mut ws.x_try);
        if take_prediction(problem, x, &step.to, before, false, ws) {
            return Prediction::Elastic;
        }
    }
    Prediction::None
}

/// The ratio `s` with `step ~ s * stored step`, if the committed curvature is valid and
/// `step` keeps its direction ([`CURVATURE_ALIGNMENT`], [`CURVATURE_MAX_SCALE`]).
fn curvature_scale(curvature: &PathCurvature, step: &Strain) -> Option<f64> {
    let p = &curvature.step;
    let dot = |a: &Strain, b: &Strain| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (pp, sp, ss) = (dot(p, p), dot(step, p), dot(step, step));
    let aligned = pp > 0.0 && sp >= CURVATURE_ALIGNMENT * (pp * ss).sqrt();
    let s = sp / pp;
    (curvature.valid && aligned && s <= CURVATURE_MAX_SCALE).then_some(s)
}

/// Evaluates the prediction `x + ws.x_try` and takes it (into `x` and the current
/// evaluation) if its residual is below `before` and, for a tangent prediction
/// (`tangent`), no interface point passes the peak of its law in this step: a step into
/// softening can pass a limit point of the RVE response, and from the tangent prediction
/// Newton then converges on the continuation of the pre-peak branch beyond it, where the
/// elastic predictor lets it fall onto the post-snap branch. Points already past the peak
/// at the start of the step do not refuse it: the committed tangent knows their
/// softening. Before the peak the equilibrium is unique and nothing changes but speed.
fn take_prediction(
    problem: &Problem,
    x: &mut [f64],
    to: &Strain,
    before: f64,
    tangent: bool,
    ws: &mut Workspace,
) -> bool {
    ws.x_try
        .iter_mut()
        .zip(x.iter())
        .for_each(|(t, xi)| *t += xi);
    problem.evaluate_candidate(to, TangentKind::Consistent, ws);
    let softening = tangent
        && problem
            .disc
            .passes_peak(&ws.history_start, &ws.candidate.history);
    if softening || norm(&ws.candidate.r) >= before {
        return false;
    }
    x.copy_from_slice(&ws.x_try);
    accept_candidate(ws);
    true
}

/// Stores into `trial` the path curvature of the increment `delta` from `committed`: the
/// error `x_conv - x_n - X_n delta` of its first-order prediction (`X_n delta` is in
/// `ws.tangent_prediction`; `ws.x_try` is scratch).
pub(super) fn store_curvature(
    committed: &State,
    delta: Strain,
    ws: &mut Workspace,
    trial: &mut State,
) {
    let (x_conv, x_start) = (&trial.unknowns, &committed.unknowns);
    for (i, e) in ws.x_try.iter_mut().enumerate() {
        *e = x_conv[i] - x_start[i] - ws.tangent_prediction[i];
    }
    trial.curvature.store(&ws.x_try, delta);
}

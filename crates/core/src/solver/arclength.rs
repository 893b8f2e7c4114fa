//! Path following through limit points inside one macro strain increment.
//!
//! Past the peak, debonding around an aggregate can be unstable: the RVE response
//! `sigma(eps)` has a limit point and snaps back, and under strain control the equilibrium
//! beyond it lies on another branch. Newton from the pre-snap state then stalls (the
//! residual norm has a local minimum that is no root), and bisection cannot help, because
//! the jump is in the physics, not in the step size. This module traces the path instead.
//!
//! With the increment `eps(t) = eps_0 + t Delta eps` the residual is
//! `R(x, t) = K_const x + G eps(t) + F_itz(x)`, so `dR/dt = f = G Delta eps`. From a
//! converged point `(x_a, t_a)` an arc-length step (Riks, normal plane) predicts along the
//! tangent `p = dt_0 dx_f` of length `l` and then asks `(x - x_a) . p = l^2`, solving for
//! `(x, t)` together: each iteration solves `K dx_R = -R` and `K dx_f = -f` with one
//! factorization, sets `dx = dx_R + dt dx_f` and takes `dt` from the (linear) constraint.
//! The predictor of the next point reuses the corrector's last `dx_f` (from `K` at an
//! iterate within the tolerance of the new point), so a converged point costs no
//! factorization of its own. Every converged arc point is committed into the trial
//! history, exactly like a sub-step, so the interface history follows the traced path.
//! The parameter `t` may decrease along a snap-back. The arc grows by 1.25 after each
//! converged point and halves after each failed one.
//!
//! # Landing
//! Once the path has come back and the next point would pass the target `t`, the tracer
//! *lands*: a strain-controlled Newton solve at the target (at most [`MAX_LANDING`]
//! iterations), from the tangent prediction `x_a + (t_target - t_a) dx_f` of the last arc
//! point, which lies on the stable post-snap branch. If the landing does not converge, the
//! arc length is halved and tracing goes on from the same point, so the next landing
//! starts closer to the target, exactly as after a corrector that does not converge; the
//! tracer gives up after [`MAX_CUTS`] failures in a row. A trace has no budget on its
//! total iterations: where an increment lands matters more to a host than what it costs.
//! A failed landing is not tried again from the same arc point (it would start from the
//! same prediction): the next attempt is an arc step short of the target.
//! A corrector that converges past the target (`t > t_target`, the path crossed it
//! between two arc points) is not accepted: the tracer lands from the interpolation
//! between the two points instead, so no history beyond the step's strain is committed.
//!
//! # Contact status along a trace
//! An arc point is a converged state like a sub-step's end, and carries its contact status
//! the same way (see `contact`): the points it holds against their gap are recorded in
//! `trial.held_contact`, and the next corrector starts from the status the arc point is
//! in equilibrium with. A corrector switches no point on its way (its status stays that
//! of its start). At a converged iterate with points held closed whose gap opened, it
//! opens them and looks, for at most [`RELEASE_BUDGET`] iterations, for the point of the
//! same arc with them open; it keeps the held-status point if there is none, as a Newton
//! loop does with its pinned points. Points held open whose gap closed stay open to the
//! landing, which reads every gap (they carry the normal penalty either way; closing them
//! jumps their shear traction by the paper's law). Measured choices (`docs/solver.md`):
//! read from the gaps at each arc point, a sliding point whose gap closed on the way
//! makes the arc point no equilibrium and the path was lost; held at the trace's start
//! status with no release, the cycle of the penalty study lands on another post-snap
//! equilibrium; releasing the closed points as well costs more factorizations.
//!
//! # Corners
//! The sign of each step keeps the way the path went (`direction`): right at a smooth
//! limit point, where `t` turns with the tangent. But the law has kinks (a point leaves
//! the loading envelope, eq. 23, for its unloading secant, eq. 24), and the path can turn
//! at a *corner*: there `t` reverses through a kink, the tangent at the arc point belongs
//! to the path coming in, and every corrector along it cycles between two branch sets, at
//! any arc length. After [`CORNER_CUTS`] failed attempts in a row at one arc point, the
//! next attempt goes the other way. Its point is accepted only if interface points still
//! load there (the path goes on dissipating), at least [`CORNER_LOADING`] of those loading
//! at the arc point: otherwise it is the (nearly) elastic unloading branch of the arc
//! point, which leads back past the start of the strain history, and the attempt counts
//! as failed. `docs/solver.md` measures what it saves: the paper-law increments that lost
//! their trace at such a corner fell back to secant iterations.
//!
//! If that fails too, the next attempt goes forward again over a long arc,
//! [`CORNER_JUMP`] times the last one that converged at the arc point. Short arcs end
//! near the corner, where the points about to change branch sit on `delta = delta_max`
//! and the corrector cannot settle on a branch set; a long arc ends where the set is
//! clear again. Its point is accepted like any other; one past the target lands from the
//! interpolation. Measured in `docs/solver.md`: on the robustness paths it fires three
//! times (tension along y with both laws, a uniaxial stress with the cohesive shear),
//! every time reaching past the target and landing, where a lost trace would fall back
//! to secant iterations.
//!
//! # When a trace stops
//! Besides the cuts below, a corrector gives up once its iterates cycle: an interface
//! branch set it had within the last [`CYCLE_WINDOW`] iterations comes back, after another
//! set, without the residual having halved since (`newton::comes_back`: a semismooth Newton
//! cycling between branch sets never converges; the arc is halved at once instead of
//! after [`MAX_CORRECTOR`] iterations). A
//! path traced back past the start of the whole strain history
//! (`t < -(|eps_0| / |Delta eps| + 1)`) is lost: it has left the snap-back for a branch
//! that runs away (an unloading branch followed far back, `docs/solver.md`).
//! So is a trace that only creeps on: more than [`CRAWL_ATTEMPTS`] attempts in a row on
//! arcs under [`CRAWL_FRACTION`] of the first.

use super::contact;
use super::newton::{comes_back, newton, Mode, CYCLE_WINDOW};
use super::problem::{dot, Problem, Strain};
use super::settings::Settings;
use super::workspace::{FactorUse, TraceBuffers, Workspace};
use crate::interface::TangentKind;
use crate::state::State;

/// Most arc points per call, and corrector iterations per point.
const MAX_POINTS: u32 = 400;
const MAX_CORRECTOR: usize = 12;
/// Newton iterations of one landing attempt at the target strain.
const MAX_LANDING: u32 = 12;
/// Failed attempts in a row (each halves the arc length) after which the path is lost:
/// the arc length is then 1/256 of the last one that worked.
const MAX_CUTS: u32 = 8;
/// The path is also lost when the arc length falls below this fraction of the first one:
/// the tracer is stuck at a corner of the path, where tiny points converge at once and
/// longer ones do not.
const MIN_LENGTH: f64 = 1e-4;
/// The path is lost, too, after more than `CRAWL_ATTEMPTS` attempts in a row (converged
/// or not) on arcs shorter than `CRAWL_FRACTION` of the first: converged points reset the
/// cuts, so a trace can creep along a corner of the path, alternating tiny points and
/// failures, without ever reaching [`MIN_LENGTH`] (`docs/solver.md`, "Path-following
/// limits").
const CRAWL_FRACTION: f64 = 0.1;
const CRAWL_ATTEMPTS: u32 = 8;
/// Failed attempts in a row at one arc point after which the next attempt goes the other
/// way, once, and the one after it forward over a long arc (see "Corners" in the module
/// docs).
const CORNER_CUTS: u32 = 3;
/// The long arc over a corner, as a multiple of the last arc that converged there.
const CORNER_JUMP: f64 = 4.0;
/// A point reached the other way round a corner is kept only if at least this fraction
/// of the arc point's loading points still load there (and at least one): fewer, and it
/// lies on the nearly elastic unloading branch of the arc point (`docs/solver.md`,
/// "Path-following limits").
const CORNER_LOADING: f64 = 0.1;
/// Growth of the arc length after a converged point.
const GROWTH: f64 = 1.25;
/// Corrector iterations spent looking for an arc point with released points.
const RELEASE_BUDGET: usize = super::newton::RELEASE_BUDGET as usize;

/// Work and progress of one traced path, counted whether or not it lands.
#[derive(Default)]
pub(super) struct Traced {
    /// Corrector and landing iterations (one linear solve each).
    pub iterations: u32,
    /// Converged arc points.
    pub points: u32,
    /// Limit points of the strain along the traced path: turns of `t` between successive
    /// arc points. A snap-back shows two (a maximum, then a minimum of the strain).
    pub limit_points: u32,
}

/// The straight strain path `eps_0 + t delta` of an increment.
#[derive(Clone, Copy, Debug)]
pub(super) struct StrainLine {
    pub origin: Strain,
    pub delta: Strain,
}

impl StrainLine {
    pub(super) fn at(&self, t: f64) -> Strain {
        let (o, d) = (self.origin, self.delta);
        [o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]]
    }
}

/// `ws.trace.dxf = -K^-1 f` with the current factors: the direction of the equilibrium
/// path per unit of the load parameter `t`.
fn load_direction(problem: &Problem, ws: &mut Workspace) {
    let trace = &mut ws.trace;
    trace
        .dxf
        .iter_mut()
        .zip(&trace.f)
        .for_each(|(d, f)| *d = -f);
    ws.factorization.solve(problem.linear, &mut trace.dxf, 1);
}

/// Traces the path of `line` from the converged `trial` at `t = from` and lands on
/// `t = to` (see the module docs), with the convergence reference `reference` of the
/// step's target. On success (`true`) `trial.unknowns` is converged at
/// `line.at(to)` from the history in `ws.history_start` (the last arc point's, also in
/// `trial.history`), and `ws.current`/`ws.factorization` belong to it, as after a
/// converged Newton loop. Returns `false` when the path cannot be followed (singular
/// system, [`MAX_CUTS`] failed attempts in a row, an arc length below [`MIN_LENGTH`] of
/// the first, a crawl ([`CRAWL_ATTEMPTS`]), [`MAX_POINTS`] exhausted, an arc point back past
/// the start of the strain history); `trial` then holds the last converged arc point,
/// still valid. `work` counts what was done either way.
#[allow(clippy::too_many_arguments)]
pub(super) fn trace(
    problem: &Problem,
    settings: &Settings,
    line: StrainLine,
    from: f64,
    to: f64,
    reference: f64,
    trial: &mut State,
    ws: &mut Workspace,
    work: &mut Traced,
) -> bool {
    let mut tracer = Tracer::new(
        problem,
        settings,
        line,
        (from, to),
        reference,
        trial,
        ws,
        work,
    );
    for _ in 0..MAX_POINTS {
        let Some(dxf_norm) = tracer.at_arc_point() else {
            return false;
        };
        let step = tracer.plan(dxf_norm);
        let converged = match tracer.attempt(&step) {
            Attempt::Landed => return true,
            Attempt::Lost => return false,
            Attempt::Point => true,
            Attempt::Failed => false,
        };
        if !tracer.after_attempt(converged, &step) {
            return false;
        }
    }
    false
}

/// How one attempt from an arc point ended.
enum Attempt {
    /// Converged at the target: the trace is done.
    Landed,
    /// A converged point past the start of the strain history: the path is lost.
    Lost,
    /// A new arc point.
    Point,
    /// No point (corrector, landing, or a point rejected at a corner).
    Failed,
}

/// One attempt from the arc point, as [`Tracer::plan`] sets it.
struct ArcStep {
    /// The attempt goes the other way round a corner.
    reverse: bool,
    /// The attempt goes forward over a long arc past a corner.
    jump: bool,
    /// The arc length before the jump lengthened it.
    cut_length: f64,
    /// The predictor's step of `t`.
    dt_pred: f64,
}

/// A trace in progress (see [`trace`]): the path, the last arc point `x_a` at `t_a`, and
/// the arc length and counters that decide the next attempt.
struct Tracer<'a, 'p> {
    problem: &'a Problem<'p>,
    settings: &'a Settings,
    line: StrainLine,
    /// The start and target of `t`.
    from: f64,
    to: f64,
    /// The convergence test on `||R||` of the corrector.
    tolerance: f64,
    /// A point at `t` below this is back past the start of the strain history.
    back_limit: f64,
    trial: &'a mut State,
    ws: &'a mut Workspace,
    work: &'a mut Traced,
    t_a: f64,
    length: f64,
    first_length: f64,
    /// Failed attempts in a row at the arc point.
    cuts: u32,
    going_forward: bool,
    /// Whether `ws.trace.dxf` holds a tangent direction for the arc point `x_a`.
    direction_ready: bool,
    /// Whether a landing from the current arc point has failed.
    landing_failed: bool,
    /// Attempts in a row on arcs under `CRAWL_FRACTION` of the first.
    crawl: u32,
    /// Interface points loading at the arc point `x_a`.
    point_loading: usize,
}

impl<'a, 'p> Tracer<'a, 'p> {
    /// A trace from `trial` at `t = span.0` to `t = span.1`: the load vector `f` of the
    /// line and the back limit (see "When a trace stops").
    #[allow(clippy::too_many_arguments)]
    fn new(
        problem: &'a Problem<'p>,
        settings: &'a Settings,
        line: StrainLine,
        (from, to): (f64, f64),
        reference: f64,
        trial: &'a mut State,
        ws: &'a mut Workspace,
        work: &'a mut Traced,
    ) -> Self {
        let tolerance = settings.tolerance * reference;
        problem.load(&line.delta, &mut ws.trace.f);
        let magnitude = |e: &Strain| (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
        let back_limit = -(magnitude(&line.origin) / magnitude(&line.delta) + 1.0);
        ws.trace.prev.iter_mut().for_each(|v| *v = 0.0);
        Tracer {
            problem,
            settings,
            line,
            from,
            to,
            tolerance,
            back_limit,
            trial,
            ws,
            work,
            t_a: from,
            length: 0.0,
            first_length: 0.0,
            cuts: 0,
            going_forward: true,
            direction_ready: false,
            landing_failed: false,
            crawl: 0,
            point_loading: 0,
        }
    }

    /// Starts an attempt from the arc point `trial` (its history, held contact status
    /// and unknowns `x_a`, and the path direction there if not ready); returns
    /// `|dx_f|`, or `None` when the path is lost (singular `K`, no direction). The first
    /// call sets the first arc length.
    fn at_arc_point(&mut self) -> Option<f64> {
        let (problem, trial, ws) = (self.problem, &mut *self.trial, &mut *self.ws);
        ws.history_start.copy_from_slice(&trial.history);
        contact::hold_state(problem, trial, ws);
        ws.trace.xa.copy_from_slice(&trial.unknowns);
        if !self.direction_ready {
            if !tangent_at(problem, &self.line.at(self.t_a), trial, ws) {
                return None;
            }
            self.point_loading = ws.current.counts.loading;
        }
        let dxf_norm = dot(&ws.trace.dxf, &ws.trace.dxf).sqrt();
        if !(dxf_norm.is_finite() && dxf_norm > 0.0) {
            return None;
        }
        if self.length == 0.0 {
            // Eight points would cover the rest of the increment on a straight path.
            self.length = (self.to - self.from) * dxf_norm / 8.0;
            self.first_length = self.length;
        }
        Some(dxf_norm)
    }

    /// The next attempt's way, arc length and predictor step, from `|dx_f|`.
    fn plan(&mut self, dxf_norm: f64) -> ArcStep {
        // Round a corner: once the other way, then once forward over a long arc (see
        // "Corners" in the module docs). `length` has been halved at every cut.
        let reverse = self.cuts == CORNER_CUTS;
        let jump = self.cuts == CORNER_CUTS + 1;
        let cut_length = self.length;
        if jump {
            self.length *= CORNER_JUMP * f64::from(1u32 << self.cuts);
        }
        let sign = if reverse { -1.0 } else { 1.0 };
        let mut dt_pred =
            sign * direction(self.work.points, &self.ws.trace) * self.length / dxf_norm;
        if self.landing_failed && self.t_a + dt_pred >= self.to && !reverse {
            // Not the same landing again: an arc step half way to the target.
            self.length = 0.5 * (self.to - self.t_a) * dxf_norm;
            dt_pred = 0.5 * (self.to - self.t_a);
        }
        ArcStep {
            reverse,
            jump,
            cut_length,
            dt_pred,
        }
    }

    /// A landing when `step` would pass the target, else a corrector along `step`.
    fn attempt(&mut self, step: &ArcStep) -> Attempt {
        if self.t_a + step.dt_pred >= self.to && !step.reverse {
            predict_along_tangent(self.t_a, self.to, self.trial, self.ws);
            if self.land() {
                return Attempt::Landed;
            }
            self.landing_failed = true;
            return Attempt::Failed; // a failed landing leaves `dxf` alone
        }
        match self.correct(step.dt_pred) {
            Some(t) => self.corrected(t, step.reverse),
            None => {
                // The corrector overwrote `dxf`: back to the direction at `x_a`.
                self.ws.trace.dxf.copy_from_slice(&self.ws.trace.pred);
                Attempt::Failed
            }
        }
    }

    /// What the corrector's converged point at `t` is: no point round a corner
    /// (`reverse`) where nothing loads any more, a landing when it passed the target,
    /// else the next arc point.
    fn corrected(&mut self, t: f64, reverse: bool) -> Attempt {
        let loading = self.ws.current.counts.loading;
        if reverse
            && (loading == 0 || (loading as f64) < CORNER_LOADING * self.point_loading as f64)
        {
            // Back along an elastic branch, not round a corner: a failed attempt.
            self.ws.trace.dxf.copy_from_slice(&self.ws.trace.pred);
            Attempt::Failed
        } else if t > self.to {
            // The path crossed the target between the two arc points: land there from
            // the interpolation, rather than commit history the step never reaches.
            interpolate(self.t_a, t, self.to, self.trial, self.ws);
            if self.land() {
                return Attempt::Landed;
            }
            self.ws.trace.dxf.copy_from_slice(&self.ws.trace.pred);
            Attempt::Failed
        } else {
            self.accept(t)
        }
    }

    /// Commits the converged point at `t` as the next arc point, counting limit points;
    /// lost if it lies back past the start of the strain history.
    fn accept(&mut self, t: f64) -> Attempt {
        self.point_loading = self.ws.current.counts.loading;
        accept_point(&self.line.at(t), self.trial, self.ws);
        contact::record_held(self.problem, self.trial, self.ws);
        let forward = t > self.t_a;
        if forward != self.going_forward {
            self.work.limit_points += 1;
            self.going_forward = forward;
        }
        if t < self.back_limit {
            return Attempt::Lost;
        }
        self.t_a = t;
        self.landing_failed = false;
        self.work.points += 1;
        self.length *= GROWTH;
        Attempt::Point
    }

    /// The arc length after an attempt (`converged`: it gave a point): reset cuts after a
    /// point, else back to `x_a` with half the arc. Returns `false` when the path is lost
    /// (a crawl, too many cuts, too short an arc).
    fn after_attempt(&mut self, converged: bool, step: &ArcStep) -> bool {
        // The next predictor's direction: after a converged point, the corrector's last
        // `K^-1 f`, at an iterate within the tolerance of the new point (saves its
        // factorization); after a failed corrector or landing, the one at `x_a` (a landing
        // leaves `dxf` alone).
        self.direction_ready = true;
        // A trace that only creeps on (at a corner of the path where every longer arc
        // fails) is lost as well.
        self.crawl = if self.length < CRAWL_FRACTION * self.first_length {
            self.crawl + 1
        } else {
            0
        };
        if self.crawl > CRAWL_ATTEMPTS {
            return false;
        }
        if converged {
            self.cuts = 0;
        } else {
            self.trial.unknowns.copy_from_slice(&self.ws.trace.xa);
            if step.jump {
                self.length = step.cut_length;
            }
            self.length *= 0.5;
            self.cuts += 1;
            if self.cuts > MAX_CUTS || self.length < MIN_LENGTH * self.first_length {
                return false;
            }
        }
        true
    }
}

/// The sign of the next arc step along `dxf`: keep going the way the path went (positive
/// `t` at the first point).
fn direction(points: u32, trace: &TraceBuffers) -> f64 {
    if points == 0 || dot(&trace.dxf, &trace.prev) >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// The path direction at the arc point `trial` (strain `strain`): `K dx_f = -f` with a
/// fresh factorization; false if `K` is singular.
fn tangent_at(problem: &Problem, strain: &Strain, trial: &State, ws: &mut Workspace) -> bool {
    problem.evaluate(&trial.unknowns, strain, TangentKind::Consistent, ws);
    if problem.factorize(ws, FactorUse::OneUse).is_err() {
        return false;
    }
    load_direction(problem, ws);
    true
}

/// Commits the converged arc point (at `strain`) into `trial`, as a sub-step would, and
/// keeps the step from the last point for the direction test.
fn accept_point(strain: &Strain, trial: &mut State, ws: &mut Workspace) {
    let trace = &mut ws.trace;
    for (p, (x, xa)) in trace
        .prev
        .iter_mut()
        .zip(trial.unknowns.iter().zip(&trace.xa))
    {
        *p = x - xa;
    }
    trial.history.copy_from_slice(&ws.current.history);
    trial.strain = *strain;
}

/// The tangent prediction `x_a + (to - t_a) dx_f` of the arc point `x_a` at `t_a`, into
/// `trial.unknowns`.
fn predict_along_tangent(t_a: f64, to: f64, trial: &mut State, ws: &Workspace) {
    let trace = &ws.trace;
    for (x, (xa, dxf)) in trial
        .unknowns
        .iter_mut()
        .zip(trace.xa.iter().zip(&trace.dxf))
    {
        *x = xa + (to - t_a) * dxf;
    }
}

/// The interpolation at `to` between the arc point `x_a` at `t_a` and the converged
/// corrector point `trial.unknowns` at `t`, into `trial.unknowns`.
fn interpolate(t_a: f64, t: f64, to: f64, trial: &mut State, ws: &Workspace) {
    let s = (to - t_a) / (t - t_a);
    for (x, xa) in trial.unknowns.iter_mut().zip(&ws.trace.xa) {
        *x = xa + s * (*x - xa);
    }
}

/// The iterations of one corrector (see [`Tracer::correct`]).
struct Corrector {
    /// The predictor's step of `t`: `dt_pred ws.trace.pred` is the normal of the
    /// constraint plane.
    dt_pred: f64,
    /// The `t` of the iterate.
    t: f64,
    /// The branch signature and residual of the last iterates (see "When a trace stops").
    recent: [(u64, f64); CYCLE_WINDOW],
    /// The iteration at which the points held against their gap were released at a
    /// converged iterate, and that iterate's `t` (its unknowns are in `ws.pinned_x`).
    released: Option<(usize, f64)>,
    iteration: usize,
}

impl Corrector {
    /// Whether the corrector gives up at an iterate with branch set `branches` and
    /// residual norm `rnorm`: its iterates cycle, its budget is spent, or the residual is
    /// not finite.
    fn stops(&self, branches: u64, rnorm: f64) -> bool {
        let iteration = self.iteration;
        let earlier = (1..=CYCLE_WINDOW.min(iteration))
            .map(|back| self.recent[(iteration - back) % CYCLE_WINDOW]);
        let cycling = comes_back(earlier, branches, rnorm);
        let out_of_budget = match self.released {
            Some((at, _)) => iteration >= at + RELEASE_BUDGET,
            None => iteration >= MAX_CORRECTOR,
        };
        cycling || out_of_budget || !rnorm.is_finite()
    }
}

impl Tracer<'_, '_> {
    /// Lands on `t = to` under strain control from the prediction in `trial.unknowns`;
    /// returns whether Newton converged there.
    fn land(&mut self) -> bool {
        let landing = Settings {
            max_iterations: MAX_LANDING,
            ..*self.settings
        };
        let outcome = newton(
            self.problem,
            &landing,
            &self.line.at(self.to),
            &mut self.trial.unknowns,
            self.ws,
            Mode::Newton,
            false,
        );
        self.work.iterations += self.ws.residuals.len().saturating_sub(1) as u32;
        outcome.is_ok()
    }

    /// The corrector of one arc step of length `length` from the arc point `ws.trace.xa`
    /// at `t_a`, predicted along `dt_pred ws.trace.dxf`: Newton on the residual and Riks'
    /// normal plane together. Returns the converged `t` (the unknowns are in `trial`), or
    /// `None`. Leaves the predictor direction in `ws.trace.pred`.
    fn correct(&mut self, dt_pred: f64) -> Option<f64> {
        let mut c = self.predict(dt_pred);
        loop {
            let (problem, ws) = (self.problem, &mut *self.ws);
            problem.evaluate(
                &self.trial.unknowns,
                &self.line.at(c.t),
                TangentKind::Consistent,
                ws,
            );
            let rnorm = dot(&ws.current.r, &ws.current.r).sqrt();
            if rnorm <= self.tolerance {
                if c.released.is_none()
                    && contact::release_opened(problem, &self.trial.unknowns, ws)
                {
                    // Converged with points held closed whose gap opened: look once for
                    // the point of this arc with them open, from here (as `newton` does).
                    ws.pinned_x.copy_from_slice(&self.trial.unknowns);
                    ws.trace.held_dxf.copy_from_slice(&ws.trace.dxf);
                    c.released = Some((c.iteration, c.t));
                    c.recent = [(0u64, f64::INFINITY); CYCLE_WINDOW];
                    continue;
                }
                return Some(c.t);
            }
            let branches = ws.current.counts.branch_signature;
            if c.stops(branches, rnorm) {
                let (_, t_held) = c.released?;
                return Some(self.back_to_held(t_held));
            }
            c.recent[c.iteration % CYCLE_WINDOW] = (branches, rnorm);
            c.iteration += 1;
            c.t += self.riks_step(c.dt_pred)?;
        }
    }

    /// The predictor `x_a + dt_pred dx_f` into `trial.unknowns`, its direction kept in
    /// `ws.trace.pred` (it stays the normal of the constraint plane).
    fn predict(&mut self, dt_pred: f64) -> Corrector {
        let trace = &mut self.ws.trace;
        trace.pred.copy_from_slice(&trace.dxf);
        for (x, (xa, p)) in self
            .trial
            .unknowns
            .iter_mut()
            .zip(trace.xa.iter().zip(&trace.pred))
        {
            *x = xa + dt_pred * p;
        }
        Corrector {
            dt_pred,
            t: self.t_a + dt_pred,
            recent: [(0u64, f64::INFINITY); CYCLE_WINDOW],
            released: None,
            iteration: 0,
        }
    }

    /// No point with the gaps' status: back to the one with the held status, at
    /// `t_held`, re-evaluated; returns `t_held`.
    fn back_to_held(&mut self, t_held: f64) -> f64 {
        let ws = &mut *self.ws;
        self.trial.unknowns.copy_from_slice(&ws.pinned_x);
        ws.trace.dxf.copy_from_slice(&ws.trace.held_dxf);
        contact::restore_saved(ws);
        self.problem.evaluate(
            &self.trial.unknowns,
            &self.line.at(t_held),
            TangentKind::Consistent,
            ws,
        );
        t_held
    }

    /// One corrector iteration with a fresh factorization: `dx = dx_R + dt dx_f` added to
    /// `trial.unknowns`, `dt` from the constraint of the predictor `dt_pred
    /// ws.trace.pred`; returns `dt`, or `None` (singular `K`, no solution of the
    /// constraint).
    fn riks_step(&mut self, dt_pred: f64) -> Option<f64> {
        let (problem, ws) = (self.problem, &mut *self.ws);
        problem.factorize(ws, FactorUse::OneUse).ok()?;
        self.work.iterations += 1;
        // dx_R into ws.dx, dx_f into ws.trace.dxf (both with this factorization).
        ws.dx
            .iter_mut()
            .zip(&ws.current.r)
            .for_each(|(d, r)| *d = -r);
        ws.factorization.solve(problem.linear, &mut ws.dx, 1);
        load_direction(problem, ws);
        // Riks' normal plane: ((x - x_a) + dx_R + dt dx_f) . p = length^2, with p the
        // predictor step: linear in dt, so always solvable (a circle may miss the
        // linearized path at a kink of the law).
        let (mut cur_p, mut dxf_p) = (0.0, 0.0);
        let trace = &ws.trace;
        for i in 0..trace.xa.len() {
            let p = dt_pred * trace.pred[i];
            cur_p += (self.trial.unknowns[i] - trace.xa[i] + ws.dx[i]) * p;
            dxf_p += trace.dxf[i] * p;
        }
        if dxf_p == 0.0 || !dxf_p.is_finite() {
            return None;
        }
        let dt = (self.length * self.length - cur_p) / dxf_p;
        for (x, (d, f)) in self
            .trial
            .unknowns
            .iter_mut()
            .zip(ws.dx.iter().zip(&trace.dxf))
        {
            *x += d + dt * f;
        }
        Some(dt)
    }
}

//! One material point: the committed state plus the last trial, over a shared model. The
//! one trial/commit lifecycle of the crate: `rve run`, the tests and the C interface (one
//! `Instance` behind each handle) all go through it, and so does checkpointing (the bytes
//! of [`mesorve_core::state::persist`]).

use std::borrow::Cow;
use std::cell::RefCell;
use std::sync::Arc;

use super::rve_model::{Model, Response};
use super::share::AdoptedStep;
use crate::error::{Error, Result};
use mesorve_core::solver::{implex, Answer, Integration, TangentRequest, Workspace};
use mesorve_core::state::persist::{self, StateSizes};
use mesorve_core::state::{Core, CoreView, State};

/// An RVE instance: what a host keeps per integration point.
///
/// Lifecycle: [`update`](Self::update) computes a trial from the committed state and
/// never changes the committed one; [`commit`](Self::commit) accepts the last successful
/// trial, [`revert`](Self::revert) discards it, [`reset`](Self::reset) returns to the
/// virgin state. The committed state is only ever replaced whole (a swap or an
/// assignment), so a panic inside an update leaves it intact.
///
/// Updates that need no solve: the fast path ([`Model::fast_update`]), and a trial
/// repeated at the same strain (bit for bit) before it is committed or discarded, which
/// returns the stored trial's response. Both allocate nothing and are counted by
/// [`fast_updates`](Self::fast_updates).
///
/// Memory: the trial state is allocated by the first full update, so an instance that has
/// never been updated holds one state, not two (a host may create 10^5 of them). A fast
/// trial needs no buffers: committing one releases the trial state, so that an instance
/// that stays on its linear branches (unloaded, or closed in compression) holds one
/// state plus the fast path's data; its next full update allocates the trial again.
///
/// A *lean* instance ([`set_lean`](Self::set_lean)) is for a host that keeps the
/// committed state itself (the UMAT's `STATEV` mode). With implicit integration it solves
/// its trial in a per-thread scratch state and keeps only the trial's core (strain,
/// history, contact status), 2.3 KB instead of a second full state, and never commits it.
/// With IMPL-EX it keeps no unknowns (the step's operators give the answers), one step
/// (the committed state's moves to the trial), and between the host's calls
/// ([`park`](Self::park)) the trial's step only: its history and status are formed again
/// from the committed state, the step and the last strain when read
/// ([`unpark`](Self::unpark)), the same bits as the update formed them.
#[derive(Debug)]
pub struct Instance {
    model: Arc<Model>,
    committed: State,
    /// The last full trial's buffers; `None` until the first full update, and in a lean
    /// instance.
    trial: Option<Box<State>>,
    /// A lean instance: full trials are solved in [`SCRATCH`] and kept as `lean_core`.
    lean: bool,
    /// The pending lean trial's core.
    lean_core: Option<Box<Core>>,
    /// A lean IMPL-EX trial whose history, previous history and contact status are in
    /// this thread's [`BODIES`] (see [`park`](Self::park)).
    parked: bool,
    /// A lean IMPL-EX trial's step is the committed state's, carried over
    /// (`solver::implex::carries_over`): the committed state no longer holds it, and a
    /// later step of the same committed state (a cut-back) carries it again.
    carried: bool,
    /// The next IMPL-EX update factorizes its own step ([`Self::refactor_step`]).
    refactor: bool,
    /// The trial awaiting commit or revert, if any.
    pending: Pending,
    /// The response of the pending trial, for a repeated call.
    last: Option<LastTrial>,
    /// Updates answered without a solve (fast path and repeats) since creation.
    fast_updates: u64,
    /// With IMPL-EX integration: the step ratio (bits) whose step of the committed state
    /// `trial.linear` holds, if any (see [`Model::implex_update`]).
    implex_step: Option<u64>,
    /// The step `trial.linear` holds (or, after a commit, the committed state's) was
    /// another point's ([`adopt_step`](Self::adopt_step)): every answer on it is judged by
    /// sharing's indicator. It carries over to the next increment only while this point's
    /// history and status stay as they were (an unloading or closed point), its own
    /// signature then unchanged; otherwise a commit drops it.
    adopted: Option<Box<AdoptedStep>>,
    /// Commits of a trial whose error estimate exceeded `solver.step_tolerance` (the host
    /// kept an increment it was asked to redo smaller), and the last one's estimate.
    ignored_redos: (u64, f64),
    /// The last update whose error estimate exceeded `solver.step_tolerance`: the bits of
    /// its committed strain and step, its `dt` and its estimate (see [`Instance::judge`]).
    exceeded: Option<([u64; 4], f64, f64)>,
}

/// The trial awaiting [`Instance::commit`].
#[derive(Clone, Copy, Debug, PartialEq)]
enum Pending {
    Nothing,
    /// A solved trial, in `Instance::trial`.
    Solved,
    /// A fast trial: the committed state at this strain (same history).
    Fast([f64; 3]),
}

/// What a repeated update returns.
#[derive(Clone, Copy, Debug)]
struct LastTrial {
    strain: [f64; 3],
    dt: f64,
    request: TangentRequest,
    response: Response,
}

impl Instance {
    /// A virgin instance of `model` (zero strain, undamaged).
    pub fn new(model: Arc<Model>) -> Self {
        let committed = model.new_state();
        Instance {
            model,
            committed,
            trial: None,
            lean: false,
            lean_core: None,
            parked: false,
            carried: false,
            refactor: false,
            pending: Pending::Nothing,
            last: None,
            fast_updates: 0,
            implex_step: None,
            adopted: None,
            ignored_redos: (0, 0.0),
            exceeded: None,
        }
    }

    pub fn model(&self) -> &Arc<Model> {
        &self.model
    }

    /// The last committed state. After fast updates its unknowns may lag behind its
    /// strain ([`State::unknowns_are_current`]); [`Model::current_state`] forms them.
    pub fn committed(&self) -> &State {
        &self.committed
    }

    /// How many committed increments had an error estimate above `solver.step_tolerance`
    /// (their update asked for a redo with a ratio below 1, and the host kept them), and
    /// the last one's estimate relative to the tolerance. (0, 0) without a tolerance.
    pub fn ignored_redos(&self) -> (u64, f64) {
        self.ignored_redos
    }

    /// Whether a successful trial awaits [`commit`](Self::commit).
    pub fn has_trial(&self) -> bool {
        self.pending != Pending::Nothing
    }

    /// Updates answered without a solve (fast path and repeated trials) since creation.
    pub fn fast_updates(&self) -> u64 {
        self.fast_updates
    }

    /// Trial update at `strain` from the committed state: a repeat of the pending trial,
    /// the fast path, or a solve ([`Model::update`]). On failure the trial is discarded
    /// and the committed state is unchanged. No time increment: see
    /// [`update_timed`](Self::update_timed).
    pub fn update(
        &mut self,
        strain: [f64; 3],
        ws: &mut Workspace,
        request: TangentRequest,
    ) -> Result<Response> {
        self.update_timed(strain, 0.0, ws, request)
    }

    /// [`update`](Self::update) over a host time increment `dt` (`DTIME`; 0 or negative:
    /// none given). Implicit integration ignores it; IMPL-EX scales its extrapolation by
    /// the ratio of this step's `dt` to the last committed one's (see
    /// `mesorve_core::solver::implex`).
    pub fn update_timed(
        &mut self,
        strain: [f64; 3],
        dt: f64,
        ws: &mut Workspace,
        request: TangentRequest,
    ) -> Result<Response> {
        let refactor = std::mem::take(&mut self.refactor);
        if let Some(response) = (!refactor)
            .then(|| self.repeated(strain, dt, request))
            .flatten()
        {
            self.unpark();
            self.fast_updates += 1;
            return Ok(response);
        }
        self.pending = Pending::Nothing;
        self.last = None;
        let mut response = if self.model.solver.integration == Integration::Implex {
            self.implex(strain, dt, ws, request, refactor)?
        } else {
            self.implicit(strain, ws, request)?
        };
        if request == TangentRequest::Elastic {
            response.tangent = self.model.elastic_tangent;
            response.s_zz_tangent = self.model.elastic_s_zz_tangent;
        }
        self.last = Some(LastTrial {
            strain,
            dt,
            request,
            response,
        });
        Ok(response)
    }

    /// The implicit update: the fast path or a solve.
    fn implicit(
        &mut self,
        strain: [f64; 3],
        ws: &mut Workspace,
        request: TangentRequest,
    ) -> Result<Response> {
        let model = &self.model;
        Ok(match model.fast_update(&self.committed, strain, request)? {
            Some(response) => {
                self.fast_updates += 1;
                self.pending = Pending::Fast(strain);
                response
            }
            None if self.lean => {
                let (response, core) = with_scratch(model, |trial| {
                    let response = model.update(&self.committed, strain, ws, trial, request)?;
                    Ok((response, model.core_of(trial)))
                })?;
                self.lean_core = Some(Box::new(core));
                self.pending = Pending::Solved;
                response
            }
            None => {
                let trial = self
                    .trial
                    .get_or_insert_with(|| Box::new(model.new_state()));
                let response = model.update(&self.committed, strain, ws, trial, request)?;
                self.pending = Pending::Solved;
                response
            }
        })
    }

    /// Makes this instance lean (see [`Instance`]) or not; the pending trial, if any, is
    /// discarded when that changes. A lean implicit instance's solved trial cannot be
    /// committed ([`commit`](Self::commit) answers `NoTrial`): its host keeps the state,
    /// which [`load_core`](Self::load_core) expands. A lean IMPL-EX instance's trial can
    /// (the `STATEV` host hands its values back, and its step carries over), but neither
    /// state has unknowns: outputs that need the fluctuation refuse.
    pub(crate) fn set_lean(&mut self, lean: bool) {
        if self.lean != lean {
            self.revert();
            self.trial = None;
            self.lean_core = None;
            self.lean = lean;
            if self.lean_implex() {
                self.committed.unknowns = Vec::new();
            } else if self.committed.unknowns.is_empty() {
                self.committed.unknowns = self.model.new_state().unknowns;
            }
        }
    }

    /// A lean instance of an IMPL-EX model.
    fn lean_implex(&self) -> bool {
        self.lean && self.model.solver.integration == Integration::Implex
    }

    /// Between two calls of a host that keeps the committed state (a lean IMPL-EX
    /// instance): moves the pending trial's history, previous history and contact status
    /// to this thread's [`BODIES`], keeping its step and its response (4.6 KB less per
    /// point). Reads of the trial's state refuse (`NoTrial`) until
    /// [`unpark`](Self::unpark); an update, a commit and a repeated call unpark it
    /// themselves. Nothing happens to other instances.
    pub(crate) fn park(&mut self) {
        if !self.lean_implex() || self.parked || self.pending != Pending::Solved {
            return;
        }
        let Some(trial) = self.trial.as_deref_mut() else {
            return;
        };
        bodies::put(trial);
        self.parked = true;
    }

    /// Forms a parked trial again ([`park`](Self::park)): its history and contact status
    /// from the committed state, the step and the last update's strain and step size
    /// (`solver::implex::finish_step`, the function the update formed them with, so the
    /// bits are the update's).
    pub(crate) fn unpark(&mut self) {
        if !std::mem::take(&mut self.parked) {
            return;
        }
        let (Some(trial), Some(last)) = (self.trial.as_deref_mut(), self.last.as_ref()) else {
            return;
        };
        bodies::take(trial, self.committed.history.len());
        implex::finish_step(
            &self.model.problem(),
            &self.committed,
            &last.strain,
            last.dt,
            trial,
        );
    }

    /// Gives a parked trial its buffers back without forming them: for an update, which
    /// forms them, and a revert, which drops the trial.
    fn unpark_unformed(&mut self) {
        if std::mem::take(&mut self.parked) {
            if let Some(trial) = self.trial.as_deref_mut() {
                bodies::take(trial, self.committed.history.len());
            }
        }
    }

    /// The IMPL-EX update: the step kept from an earlier update of this step (same
    /// committed state, same step ratio; only with `solver.fast_path`), or a new step.
    /// `own_step`: factorize this point's own step (an adopted one was refused).
    fn implex(
        &mut self,
        strain: [f64; 3],
        dt: f64,
        ws: &mut Workspace,
        request: TangentRequest,
        own_step: bool,
    ) -> Result<Response> {
        self.unpark_unformed();
        let model = &self.model;
        let ratio = implex::step_ratio(self.committed.implex.step, dt).to_bits();
        let reuse = !own_step && model.solver.fast_path && self.implex_step == Some(ratio);
        let lean = self.lean_implex();
        let carry = !reuse
            && !own_step
            && model.solver.fast_path
            && ((lean && self.carried) || implex::carries_over(&self.committed));
        let trial = (self.trial).get_or_insert_with(|| Box::new(new_state(model, lean)));
        if lean && !reuse {
            // One step per lean instance: the committed state's is the trial's when it
            // carries over, and its buffers the new step's otherwise.
            if !self.carried {
                std::mem::swap(&mut trial.linear, &mut self.committed.linear);
                self.committed.linear.clear();
            }
            self.carried = carry;
        } else if carry {
            trial.linear.copy_from(&self.committed.linear);
            trial.unknowns.copy_from_slice(&self.committed.unknowns);
        }
        if !reuse && !carry {
            self.adopted = None;
        }
        let reuse = reuse || carry;
        self.implex_step = None;
        let mut response = model.implex_update(&self.committed, strain, dt, ws, trial, reuse)?;
        self.implex_step = Some(ratio);
        if let Some(adopted) = self.adopted.as_deref() {
            if !adopted.keeps(model, &self.committed, &trial.linear, &strain, &response) {
                // The anchor's step is refused here: this point factorizes its own (a
                // lean instance's carried step was the refused one).
                self.adopted = None;
                self.implex_step = None;
                self.carried = false;
                trial.linear.invalidate();
                return self.implex(strain, dt, ws, request, true);
            }
        }
        self.judge(dt, &mut response.report);
        if reuse {
            self.fast_updates += 1;
        }
        if request != TangentRequest::Consistent {
            response.tangent = [0.0; 9];
            response.s_zz_tangent = [0.0; 3];
        }
        self.pending = Pending::Solved;
        Ok(response)
    }

    /// Under `solver.step_tolerance`: an estimate above the tolerance that did not fall
    /// at all since the last such update from the same committed state at a longer step is
    /// `irreducible` (ratio 1): IMPL-EX's error falls with the step where it is the
    /// step's, so cutting the step did not touch this one (the RVE snapping back through
    /// the step; docs/step_control.md).
    fn judge(&mut self, dt: f64, report: &mut mesorve_core::solver::IncrementReport) {
        let Some(e) = report.error_estimate.filter(|&e| e > 1.0) else {
            return;
        };
        let c = &self.committed;
        let key = [c.strain[0], c.strain[1], c.strain[2], c.implex.step].map(f64::to_bits);
        if let Some((k, longer, before)) = self.exceeded {
            if k == key && dt > 0.0 && dt < longer && e >= before {
                report.irreducible = true;
            }
        }
        if !report.irreducible {
            self.exceeded = Some((key, dt, e));
        }
    }

    /// The pending trial's response when `strain` and `request` repeat its own, the strain
    /// bit for bit. (Only the same request: a trial with the tangent also stored the
    /// predictor's sensitivity and the fast path's data, which one without does not, and
    /// the trial a commit accepts must be the one the last call would have computed.)
    fn repeated(&self, strain: [f64; 3], dt: f64, request: TangentRequest) -> Option<Response> {
        let last = self.last.as_ref().filter(|_| self.has_trial())?;
        let same = last.strain.map(f64::to_bits) == strain.map(f64::to_bits)
            && last.dt.to_bits() == dt.to_bits();
        if !(same && last.request == request) {
            return None;
        }
        let mut response = last.response;
        response.report.answer = Answer::Repeated;
        Some(response)
    }

    /// Accepts the last successful trial as the new converged state; `NoTrial` when
    /// there is none (no successful update since the last commit, revert, reset or load).
    pub fn commit(&mut self) -> Result<()> {
        if let Some(report) = self.last.as_ref().map(|l| l.response.report) {
            let asked = report.exceeds_tolerance() && report.suggested_step_ratio() < 1.0;
            if asked && self.pending != Pending::Nothing {
                let e = report.error_estimate.unwrap_or(0.0);
                self.ignored_redos = (self.ignored_redos.0 + 1, e);
            }
        }
        self.unpark();
        match (self.pending, &mut self.trial) {
            (Pending::Solved, _) if self.lean_core.is_some() => return Err(Error::NoTrial),
            (Pending::Solved, Some(trial)) => {
                std::mem::swap(&mut self.committed, trial);
                self.implex_step = None;
                self.carried = false;
                if self.adopted.is_some() && !implex::carries_over(&self.committed) {
                    // Another point's step whose history it froze is not this point's
                    // any more: the next step is this point's own, or adopted again.
                    self.adopted = None;
                    self.committed.linear.invalidate();
                }
            }
            (Pending::Fast(strain), _) => {
                // The state at the new strain: same history, unknowns lazy (see
                // `LinearBranch`), no path curvature (a full update on linear branches
                // keeps none either). The trial's buffers are released.
                self.committed.strain = strain;
                self.committed.curvature.valid = false;
                self.committed.curvature.data = Default::default();
                self.trial = None;
            }
            _ => return Err(Error::NoTrial),
        }
        self.pending = Pending::Nothing;
        self.last = None;
        Ok(())
    }

    /// Discards the last trial; the committed state stays.
    pub fn revert(&mut self) {
        self.pending = Pending::Nothing;
        self.last = None;
        self.lean_core = None;
        self.unpark_unformed();
    }

    /// Back to the virgin state, as a new instance (the trial's buffers are released).
    pub fn reset(&mut self) {
        self.committed = new_state(&self.model, self.lean_implex());
        self.trial = None;
        self.implex_step = None;
        self.adopted = None;
        self.carried = false;
        self.revert();
    }

    /// The sizes the model's states have, as recorded in the state bytes.
    fn sizes(&self) -> StateSizes {
        StateSizes {
            unknowns: self.model.disc.n(),
            history: self.model.disc.history_len(),
        }
    }

    /// Bytes [`save_state`](Self::save_state) writes now. It depends on the state: the
    /// first updates with a tangent add the predictor's sensitivity and path curvature
    /// (see [`State`]).
    pub fn state_size(&self) -> Result<usize> {
        persist::encoded_len(&self.committed)
    }

    /// The committed state (not the trial) as versioned bytes, for checkpoint/restart:
    /// [`load_state`](Self::load_state) on an instance of the same scene, in this process
    /// or another, continues bit-identically.
    pub fn save_state(&self) -> Result<Vec<u8>> {
        persist::encode(&self.committed, self.sizes(), self.model.fingerprint)
    }

    /// Replaces the committed state by the one in `bytes` (from
    /// [`save_state`](Self::save_state), this format version or an older readable one) and
    /// discards the trial. Refused with `BadState`, `StateVersion`, `StateMismatch` (a
    /// model of other sizes, or a history the model's interface law does not admit) or
    /// `StateOwner` (another fingerprint: another scene, `PROPS`, mesh file or
    /// integration; formats before 10 carry none and load unverified); a
    /// refused load changes nothing, the trial included.
    pub fn load_state(&mut self, bytes: &[u8]) -> Result<()> {
        let state = persist::decode(bytes, self.sizes(), self.model.fingerprint)?;
        if let Some(laws) = &self.model.disc.law {
            if !laws.history_is_valid(&state.history, self.model.disc.points_per_interface()) {
                return Err(Error::BadState {
                    reason: "an interface history value the interface law does not admit \
                             (for the cohesive law: a negative delta_max)"
                        .into(),
                });
            }
        }
        let points = self.model.disc.interface_points();
        if state.linear.valid
            && (self.model.disc.law.is_none() || !state.linear.is_consistent(points))
        {
            return Err(Error::BadState {
                reason: format!(
                    "fast-path data for another number of interface points than the \
                     model's {points}"
                ),
            });
        }
        // Any bit past the points, the spare bits of the last word included.
        let held_beyond = (points..64 * state.held_contact.len()).any(|i| state.is_held(i));
        if held_beyond {
            return Err(Error::BadState {
                reason: format!(
                    "contact status held at a point beyond the model's {points} interface \
                     points"
                ),
            });
        }
        if !state
            .implex
            .is_consistent(state.history.len(), self.model.disc.interface_points())
        {
            return Err(Error::BadState {
                reason: "IMPL-EX history of another size than the model's, or not finite".into(),
            });
        }
        self.committed = state;
        self.adopted = None;
        self.implex_step = None;
        self.carried = false;
        self.revert();
        Ok(())
    }

    /// The committed core of the pending trial (see `mesorve_core::state::statev`): what a host
    /// keeping the state in its own variables stores after this update. `NoTrial` when
    /// there is no pending trial.
    pub fn trial_core(&self) -> Result<Core> {
        self.trial_core_view().map(|view| view.to_core())
    }

    /// [`trial_core`](Self::trial_core) borrowing the state's buffers (no copy of the
    /// histories: what a `STATEV` write needs).
    pub fn trial_core_view(&self) -> Result<CoreView<'_>> {
        if self.parked {
            return Err(Error::NoTrial);
        }
        match (self.pending, &self.trial) {
            (Pending::Solved, _) if self.lean_core.is_some() => {
                Ok(self.lean_core.as_deref().ok_or(Error::NoTrial)?.view())
            }
            (Pending::Solved, Some(trial)) => Ok(self.model.core_view_of(trial)),
            (Pending::Fast(strain), _) => {
                let mut core = self.model.core_view_of(&self.committed);
                core.strain = strain;
                Ok(core)
            }
            _ => Err(Error::NoTrial),
        }
    }

    /// The state of the pending trial, `None` without one: borrowed after a solve, a copy
    /// of the committed state at the trial's strain after a fast update (its unknowns then
    /// lag: [`Model::current_state`] forms them). For outputs, not for the hot path.
    pub fn trial_state(&self) -> Option<Cow<'_, State>> {
        if self.parked {
            return None;
        }
        match (self.pending, &self.trial) {
            (Pending::Solved, Some(trial)) => Some(Cow::Borrowed(trial)),
            (Pending::Fast(strain), _) => {
                let mut state = self.committed.clone();
                state.strain = strain;
                Some(Cow::Owned(state))
            }
            _ => None,
        }
    }

    /// Whether the pending trial holds its unknowns at its own strain (an IMPL-EX step
    /// reused at another strain of it, or a fast update, leaves them at the other one);
    /// `true` without a trial.
    pub fn trial_unknowns_are_current(&self) -> bool {
        self.trial_state()
            .is_none_or(|state| state.unknowns_are_current())
    }

    /// The next IMPL-EX update factorizes its step again (or carries the committed one
    /// over) instead of reusing the pending trial's, so that it forms its unknowns at its
    /// own strain: for outputs after a trial whose unknowns lag
    /// ([`Self::trial_unknowns_are_current`]). The same answer, at one factorization.
    pub fn refactor_step(&mut self) {
        self.refactor = true;
    }

    /// Replaces the committed state by the one `core` stands for (`None`: virgin), rebuilt
    /// by [`Model::expand_core`], and discards the trial. A refused core changes nothing.
    pub fn load_core(&mut self, core: Option<&Core>, ws: &mut Workspace) -> Result<()> {
        self.committed = self.model.expand_core(core, ws)?;
        self.carried = false;
        if self.lean_implex() {
            // Expanded with zero unknowns, which no IMPL-EX answer reads.
            self.committed.unknowns = Vec::new();
        }
        self.implex_step = None;
        self.adopted = None;
        self.revert();
        Ok(())
    }

    /// The interface history of the pending trial, or of the committed state when there is
    /// none: the history of the state a host keeps after this update (as
    /// [`trial_core`](Self::trial_core) writes it). Allocates nothing.
    pub fn trial_history(&self) -> &[f64] {
        debug_assert!(!self.parked, "the history of a parked trial is not held");
        match (self.pending, &self.lean_core, &self.trial) {
            (Pending::Solved, Some(core), _) => &core.history,
            (Pending::Solved, None, Some(trial)) => &trial.history,
            _ => &self.committed.history,
        }
    }

    /// The committed state's core (see `mesorve_core::state::statev`), at the strain the state
    /// is committed at.
    pub fn committed_core(&self) -> Core {
        self.model.core_of(&self.committed)
    }

    /// [`committed_core`](Self::committed_core) borrowing the state's buffers.
    pub fn committed_core_view(&self) -> CoreView<'_> {
        self.model.core_view_of(&self.committed)
    }

    /// Answer sharing between twins (`crate::model::share::Follow::Twin`): makes
    /// `anchor`'s pending trial this instance's, moved to this point's own `strain` (and its
    /// answer `response`, the anchor's corrected to first order), as if this instance had
    /// solved it: a commit accepts it, a revert drops it. The state is the anchor's trial
    /// with `strain`, and the fluctuation moved along the anchor's sensitivity,
    /// `x = x_a + X_a (eps - eps_a)` (kept as it is when the fast path's data says at which
    /// strain it holds). `NoTrial` when the anchor has no pending trial; nothing changes
    /// then.
    pub fn adopt_trial(
        &mut self,
        anchor: &Instance,
        strain: [f64; 3],
        dt: f64,
        request: TangentRequest,
        response: Response,
    ) -> Result<()> {
        let (source, from) = match (anchor.pending, &anchor.trial) {
            (Pending::Solved, Some(trial)) => (&**trial, trial.strain),
            (Pending::Fast(s), _) => (&anchor.committed, s),
            _ => return Err(Error::NoTrial),
        };
        let fast = matches!(anchor.pending, Pending::Fast(_));
        trial_from(&self.model, &mut self.trial, source, (from, strain), fast);
        self.pending_shared(LastTrial {
            strain,
            dt,
            request,
            response,
        });
        Ok(())
    }

    /// Answer sharing with a still anchor (`crate::model::share::Follow::Own`): a trial of
    /// this instance's own committed state at `strain`, history and contact status
    /// unchanged (as the anchor's increment left the anchor's), the fluctuation moved along
    /// the committed state's sensitivity, answered by `response` (the anchor's answer
    /// corrected to first order).
    pub fn keep_own_trial(
        &mut self,
        strain: [f64; 3],
        dt: f64,
        request: TangentRequest,
        response: Response,
    ) {
        let committed = &self.committed;
        let from = committed.strain;
        trial_from(
            &self.model,
            &mut self.trial,
            committed,
            (from, strain),
            true,
        );
        self.pending_shared(LastTrial {
            strain,
            dt,
            request,
            response,
        });
    }

    /// A shared trial is pending, answered by `last`.
    fn pending_shared(&mut self, last: LastTrial) {
        self.pending = Pending::Solved;
        self.implex_step = None;
        self.last = Some(last);
    }

    /// Whether the pending trial left the interface history and the contact status of the
    /// committed state as they were, bit for bit (a fast trial does by construction): the
    /// increment did not damage, open or close anything. False without a trial.
    pub fn trial_is_still(&self) -> bool {
        if !self.has_trial() {
            return false;
        }
        !self.trial_switched()
            && super::share::same_bits(self.trial_history(), &self.committed.history)
    }

    /// The IMPL-EX step the pending trial was answered on (`D_ex`, the jump operators
    /// `A_q`, the frozen contact status: `mesorve_core::state::LinearBranch`), with the step ratio
    /// `dt / dt_n` it was factorized for; `None` without a pending IMPL-EX trial that holds
    /// one. What [`adopt_step`](Self::adopt_step) gives another instance.
    pub fn implex_step(&self) -> Option<(&mesorve_core::state::LinearBranch, u64)> {
        match (self.pending, &self.trial, self.implex_step) {
            (Pending::Solved, Some(trial), Some(ratio)) if trial.linear.valid => {
                Some((&trial.linear, ratio))
            }
            _ => None,
        }
    }

    /// Takes `step`, an IMPL-EX step another instance factorized (its
    /// [`implex_step`](Self::implex_step)) from a committed state close to this one's, as
    /// the step of this instance's committed state for `dt`: the next
    /// [`update_timed`](Self::update_timed) at `dt` answers on it without a factorization,
    /// `sigma = D_ex eps`, and forms this instance's own trial history from the jumps
    /// `A_q eps` and its own committed history (`mesorve_core::solver::implex::finish_step`). The
    /// trial's fluctuation is not formed (outputs that need it refuse, as after any
    /// reused step at another strain). `false` (nothing changes): not an IMPL-EX model,
    /// no fast path, a step of another ratio than `dt`'s from this committed state, or a
    /// committed state whose own step carries over (exact, and free).
    pub fn adopt_step(
        &mut self,
        step: &mesorve_core::state::LinearBranch,
        ratio: u64,
        dt: f64,
        adopted: AdoptedStep,
    ) -> bool {
        let own = implex::step_ratio(self.committed.implex.step, dt).to_bits();
        let carries = (self.lean_implex() && self.carried) || implex::carries_over(&self.committed);
        if self.model.solver.integration != Integration::Implex
            || !self.model.solver.fast_path
            || !step.valid
            || own != ratio
            || carries
        {
            return false;
        }
        self.revert();
        if self.lean_implex() {
            // The committed state's own step (a carry) is not needed any more.
            self.committed.linear.clear();
            self.carried = false;
        }
        let model = &self.model;
        let trial = self
            .trial
            .get_or_insert_with(|| Box::new(model.new_state()));
        trial.linear.clone_from(step);
        // The unknowns are not the step's at any strain.
        trial.linear.unknowns_strain = [f64::NAN; 3];
        self.implex_step = Some(ratio);
        self.adopted = Some(Box::new(adopted));
        true
    }

    /// Whether the pending trial was answered on a step adopted from another point and
    /// kept ([`adopt_step`](Self::adopt_step)).
    pub fn on_adopted_step(&self) -> bool {
        self.adopted.is_some() && self.implex_step.is_some() && self.has_trial()
    }

    /// Whether the pending solved trial holds another contact status than the committed
    /// state at some ITZ point (held points, or IMPL-EX's closed points); false without
    /// one, and for a fast trial (same status by construction).
    pub fn trial_switched(&self) -> bool {
        debug_assert!(!self.parked, "the status of a parked trial is not held");
        match (self.pending, &self.trial) {
            (Pending::Solved, Some(t)) => {
                t.held_contact != self.committed.held_contact
                    || t.implex.closed != self.committed.implex.closed
            }
            _ => false,
        }
    }

    /// Bytes owned by this instance (committed and, once allocated, trial states).
    pub fn state_bytes(&self) -> usize {
        self.committed.bytes()
            + self.trial.as_deref().map_or(0, State::bytes)
            + self.lean_core.as_deref().map_or(0, Core::bytes)
    }
}

/// A trial made from `source` (a state at strain `from`; `fast`: a committed state, whose
/// path curvature is not the trial's) in `trial`'s buffers, its fluctuation moved to
/// `to` along `source`'s sensitivity unless the fast path's data says at which strain it
/// holds.
fn trial_from(
    model: &Model,
    trial: &mut Option<Box<State>>,
    source: &State,
    (from, to): ([f64; 3], [f64; 3]),
    fast: bool,
) {
    let trial = trial.get_or_insert_with(|| Box::new(model.new_state()));
    trial.copy_from(source);
    if fast {
        trial.curvature.valid = false;
    }
    if !trial.linear.valid {
        let step: [f64; 3] = std::array::from_fn(|i| to[i] - from[i]);
        let mut moved = vec![0.0; trial.unknowns.len()];
        if trial.sensitivity.times(&step, &mut moved) {
            trial
                .unknowns
                .iter_mut()
                .zip(&moved)
                .for_each(|(x, d)| *x += d);
        }
    }
    trial.strain = to;
}

thread_local! {
    /// This thread's trial states of lean instances, one per model (the most recently
    /// used [`SCRATCH_MODELS`] models).
    static SCRATCH: RefCell<Vec<(u64, State)>> = const { RefCell::new(Vec::new()) };
}

/// Models whose scratch trial a thread keeps.
const SCRATCH_MODELS: usize = 4;

/// `f` on this thread's scratch trial state of `model` (a new state when the thread has
/// none). Its content is another instance's last trial: an update overwrites all of it
/// (`State::copy_solution_from`, the fast path's data marked not valid) before it reads
/// any. The state is out of [`SCRATCH`] while `f` runs, so a panic drops it.
fn with_scratch<T>(model: &Model, f: impl FnOnce(&mut State) -> Result<T>) -> Result<T> {
    let take = |states: &mut Vec<(u64, State)>| {
        let at = states.iter().position(|(id, _)| *id == model.id)?;
        Some(states.remove(at).1)
    };
    let kept = SCRATCH
        .try_with(|s| take(&mut s.borrow_mut()))
        .ok()
        .flatten();
    let mut state = kept.unwrap_or_else(|| model.new_state());
    let result = f(&mut state);
    let _ = SCRATCH.try_with(|s| {
        let mut states = s.borrow_mut();
        if states.len() >= SCRATCH_MODELS {
            states.remove(0);
        }
        states.push((model.id, state));
    });
    result
}

/// A new state of `model`; without unknowns for a lean IMPL-EX instance (`lean`).
fn new_state(model: &Model, lean: bool) -> State {
    let mut state = model.new_state();
    if lean {
        state.unknowns = Vec::new();
    }
    state
}

/// This thread's parked trial bodies ([`Instance::park`]): the buffers of the trials of
/// lean IMPL-EX instances between the host's calls, so that parking and unparking
/// allocate nothing once a thread has a few.
mod bodies {
    use std::cell::RefCell;

    use mesorve_core::state::State;

    /// The buffers of one trial's history, previous history and contact status.
    type Body = (Vec<f64>, Vec<f64>, Vec<u64>);

    /// Bodies a thread keeps; more are dropped.
    const KEPT: usize = 8;

    thread_local! {
        static BODIES: RefCell<Vec<Body>> = const { RefCell::new(Vec::new()) };
    }

    /// Moves `trial`'s body to this thread's pool (dropped when it is full).
    pub(super) fn put(trial: &mut State) {
        let body = (
            std::mem::take(&mut trial.history),
            std::mem::take(&mut trial.implex.previous),
            std::mem::take(&mut trial.implex.closed),
        );
        let _ = BODIES.try_with(|b| {
            let mut bodies = b.borrow_mut();
            if bodies.len() < KEPT {
                bodies.push(body);
            }
        });
    }

    /// Gives `trial` a body from this thread's pool (or new buffers), its history
    /// `n_history` values long; the values are the caller's to form.
    pub(super) fn take(trial: &mut State, n_history: usize) {
        let body = BODIES.try_with(|b| b.borrow_mut().pop()).ok().flatten();
        let (history, previous, closed) = body.unwrap_or_default();
        (trial.history, trial.implex.previous, trial.implex.closed) = (history, previous, closed);
        trial.history.resize(n_history, 0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::cache;
    use crate::scene::DEFAULT_SCENE_TOML;

    /// A lean instance answers bit for bit as a full one along a loading path followed as
    /// a `STATEV` host does (each increment's trial core expanded as the next committed
    /// state, with a second iteration from the same committed state), writes the same
    /// cores, and holds no second full state.
    #[test]
    fn a_lean_instance_answers_as_a_full_one_with_less_memory() {
        let model = cache::model_for_text(DEFAULT_SCENE_TOML, None).unwrap();
        let mut ws = model.workspace();
        let (mut full, mut lean) = (Instance::new(model.clone()), Instance::new(model.clone()));
        lean.set_lean(true);
        for k in 1..=4 {
            let mut cores = Vec::new();
            for inst in [&mut full, &mut lean] {
                let mut answers = Vec::new();
                for x in [0.9, 1.0] {
                    let strain = [x * 4e-5 * k as f64, -1e-5 * k as f64, 2e-5];
                    let r = inst
                        .update(strain, &mut ws, TangentRequest::Consistent)
                        .unwrap();
                    answers.push((r.stress.map(f64::to_bits), r.tangent.map(f64::to_bits)));
                }
                cores.push((
                    answers,
                    inst.trial_core().unwrap(),
                    inst.trial_history().to_vec(),
                ));
            }
            assert_eq!(cores[0], cores[1], "increment {k}");
            assert!(lean.state_bytes() + 5000 < full.state_bytes());
            assert!(matches!(lean.commit(), Err(Error::NoTrial)));
            for inst in [&mut full, &mut lean] {
                inst.load_core(Some(&cores[0].1), &mut ws).unwrap();
            }
        }
    }

    /// A lean IMPL-EX instance, parked between calls as the UMAT parks its points,
    /// answers bit for bit as a full one (stress, tangent, trial core, factorizations)
    /// along a path through loading, unloading (the step carries over) and a cut-back,
    /// with repeated calls and commits, and holds half the memory or less.
    #[test]
    fn a_lean_implex_instance_answers_as_a_full_one_with_less_memory() {
        let text = DEFAULT_SCENE_TOML.replace("[solver]\n", "[solver]\nintegration = \"implex\"\n");
        let model = cache::model_for_text(&text, None).unwrap();
        let mut ws = model.workspace();
        let (mut full, mut lean) = (Instance::new(model.clone()), Instance::new(model.clone()));
        lean.set_lean(true);
        let consistent = TangentRequest::Consistent;
        let mut carried = 0;
        for (k, level) in [1.0, 2.0, 3.0, 4.0, 3.0, 2.0, 2.0, 5.0]
            .into_iter()
            .enumerate()
        {
            let (mut seen, mut bytes) = (Vec::new(), Vec::new());
            for inst in [&mut full, &mut lean] {
                let mut answers = Vec::new();
                // Two iterations and a repeated call at dt = 1, then a cut-back to dt = 0.5.
                for (x, dt) in [(0.9, 1.0), (1.0, 1.0), (1.0, 1.0), (0.5, 0.5)] {
                    let strain = [x * 4e-5 * level, -1e-5 * level, 2e-5];
                    let r = inst.update_timed(strain, dt, &mut ws, consistent).unwrap();
                    let f = r.report.factorizations;
                    answers.push((r.stress.map(f64::to_bits), r.tangent.map(f64::to_bits), f));
                    inst.park();
                }
                assert!(inst.trial_core().is_err() == inst.parked);
                bytes.push(inst.state_bytes());
                inst.unpark();
                seen.push((answers, Some(inst.trial_core().unwrap())));
                // The host keeps the increment at the cut-back's size.
                inst.commit().unwrap();
                seen.push((Vec::new(), None));
            }
            assert_eq!(seen[0], seen[2], "increment {k}");
            assert_eq!(
                full.committed_core(),
                lean.committed_core(),
                "increment {k}"
            );
            carried += seen[0].0.iter().filter(|a| a.2 == 0).count();
            // Between calls: the committed history and h_{n-1}, and the step.
            assert!(2 * bytes[1] < bytes[0], "increment {k}: {bytes:?}");
            assert!(lean.committed().unknowns.is_empty());
        }
        assert!(full.committed().history.iter().any(|&h| h > 0.0));
        assert!(carried > 8, "no step carried over or reused: {carried}");
    }

    /// An IMPL-EX instance that adopts another's step, factorized from the same committed
    /// state, answers and writes its trial bit for bit as if it had factorized the step
    /// itself, without a factorization; a step of another ratio is refused.
    #[test]
    fn an_adopted_implex_step_answers_as_the_own_one() {
        let text = DEFAULT_SCENE_TOML.replace(
            "[solver]\n",
            "[solver]\nintegration = \"implex\"\nshare_tolerance = 0.005\n",
        );
        let model = cache::model_for_text(&text, None).unwrap();
        let mut ws = model.workspace();
        let consistent = TangentRequest::Consistent;
        let (mut anchor, mut own) = (Instance::new(model.clone()), Instance::new(model.clone()));
        let mut follower = Instance::new(model.clone());
        for k in 1..=6 {
            let strain = |x: f64| [x * 4e-5 * k as f64, -1e-5 * k as f64, 2e-5];
            anchor
                .update_timed(strain(0.9), 1.0, &mut ws, consistent)
                .unwrap();
            let (step, ratio) = anchor.implex_step().unwrap();
            let adopted = twin_of(
                &model,
                follower.committed(),
                anchor.committed(),
                strain(0.9),
            );
            assert!(!follower.adopt_step(step, ratio ^ 1, 1.0, adopted));
            let adopted = twin_of(
                &model,
                follower.committed(),
                anchor.committed(),
                strain(0.9),
            );
            assert!(follower.adopt_step(step, ratio, 1.0, adopted));
            let r = follower
                .update_timed(strain(1.0), 1.0, &mut ws, consistent)
                .unwrap();
            let e = own
                .update_timed(strain(1.0), 1.0, &mut ws, consistent)
                .unwrap();
            assert_eq!(r.report.factorizations, 0, "increment {k}");
            assert!(follower.on_adopted_step());
            assert_eq!(e.report.factorizations, 1, "increment {k}");
            assert_eq!(r.stress.map(f64::to_bits), e.stress.map(f64::to_bits));
            assert_eq!(r.tangent.map(f64::to_bits), e.tangent.map(f64::to_bits));
            assert_eq!(follower.trial_core().unwrap(), own.trial_core().unwrap());
            let core = own.trial_core().unwrap();
            for inst in [&mut anchor, &mut own, &mut follower] {
                inst.load_core(Some(&core), &mut ws).unwrap();
            }
        }
        assert!(own.committed().history.iter().any(|&h| h > 0.0));
    }

    /// The twin-by-core `AdoptedStep` of `point` taking `anchor`'s step.
    fn twin_of(
        model: &Model,
        point: &State,
        anchor: &State,
        anchor_strain: [f64; 3],
    ) -> AdoptedStep {
        use super::super::share::{self, StepSignature};
        let sig = |s: &State| {
            let view = model.core_view_of(s);
            Arc::new(StepSignature::of(
                model,
                &view,
                implex::step_ratio(s.implex.step, 1.0),
            ))
        };
        AdoptedStep {
            own: sig(point),
            anchor: sig(anchor),
            anchor_strain,
            twin: share::states_close(share::ROUND_OFF, point, anchor),
        }
    }

    /// A point of another state that takes a step it damages on is refused it: its answer
    /// is its own step's, bit for bit, in the same update; a point that stays still on it
    /// keeps it, within the tolerance of its own answer.
    #[test]
    fn an_adopted_step_is_refused_where_the_point_damages_and_kept_where_it_is_still() {
        let text = DEFAULT_SCENE_TOML.replace(
            "[solver]\n",
            "[solver]\nintegration = \"implex\"\nshare_tolerance = 0.05\n",
        );
        let model = cache::model_for_text(&text, None).unwrap();
        let mut ws = model.workspace();
        let consistent = TangentRequest::Consistent;
        let mut anchor = Instance::new(model.clone());
        let (mut follower, mut own) = (Instance::new(model.clone()), Instance::new(model.clone()));
        // Loading: the follower at 1.02 of the anchor's strain damages on its step.
        let strain = |x: f64, a: f64| [x * a, -0.2 * x * a, 0.0];
        let (mut kept, mut refused) = (0, 0);
        for (k, a) in [1e-5, 4e-5, 8e-5, 1.2e-4, 1.6e-4, 1e-4, 5e-5, 2e-5]
            .iter()
            .enumerate()
        {
            anchor
                .update_timed(strain(1.0, *a), 1.0, &mut ws, consistent)
                .unwrap();
            if let Some((step, ratio)) = anchor.implex_step() {
                let adopted = AdoptedStep {
                    twin: false,
                    ..twin_of(
                        &model,
                        follower.committed(),
                        anchor.committed(),
                        strain(1.0, *a),
                    )
                };
                follower.adopt_step(step, ratio, 1.0, adopted);
            }
            let adopted_before = follower.adopted.is_some();
            let r = follower
                .update_timed(strain(1.02, *a), 1.0, &mut ws, consistent)
                .unwrap();
            let e = own
                .update_timed(strain(1.02, *a), 1.0, &mut ws, consistent)
                .unwrap();
            if follower.on_adopted_step() {
                kept += 1;
                assert!(
                    follower.trial_is_still(),
                    "increment {k}: a damaging step was kept"
                );
                let d = (0..3).fold(0.0f64, |m, i| m.max((r.stress[i] - e.stress[i]).abs()));
                let s = e.stress.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                assert!(d <= 0.05 * s, "increment {k}: {d} against {s}");
            } else {
                refused += usize::from(adopted_before);
                assert_eq!(
                    r.stress.map(f64::to_bits),
                    e.stress.map(f64::to_bits),
                    "increment {k}"
                );
                assert_eq!(follower.trial_core().unwrap(), own.trial_core().unwrap());
            }
            for inst in [&mut anchor, &mut follower, &mut own] {
                inst.commit().unwrap();
            }
        }
        assert!(kept > 0 && refused > 0, "kept {kept}, refused {refused}");
    }
}

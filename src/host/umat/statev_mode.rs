//! `STATEV` mode: the point's committed state is the host's `STATEV`, and the point's
//! instance only caches the state those values stand for (see the module documentation of
//! [`crate::host::umat`]).

use std::cell::RefCell;
use std::sync::atomic::Ordering;
use std::sync::Arc;

use super::call::{trim, HostSignal, Outcome, UmatCall, UmatOutputs};
use super::point::{call_strain, lock, MaterialKey, Point, TIME_ROUNDOFF};
use super::table::{write_outputs, Failed, Umat};
use crate::error::Error;
use crate::host::diagnostics::{note_once, Note};
use crate::host::material::Material;
use crate::host::share_table::{Anchor, IncrementKey, Step};
use crate::host::values_hash::values_hash;
use crate::host::vtk_dump;
use crate::model::share::{self, StepSignature};
use crate::model::workspaces::with_workspace;
use crate::model::Response;
use crate::scene::ZeroAtStrain;
use mesorve_core::solver::TangentRequest;
use mesorve_core::solver::{Answer, Integration};
use mesorve_core::state::statev::{self, CoreView};

/// `STRAN` and the state's committed strain agree when they differ by at most this
/// fraction of the larger of the two (infinity norms) plus [`STRAIN_MATCH_FLOOR`]. A host
/// that adds `DSTRAN` to `STRAN`, as Abaqus and CalculiX do, hands back the library's own
/// sum (docs/statev.md has the agreement measured over a CalculiX analysis); a total
/// strain recomputed from displacements differs by round-off; a state one increment old
/// differs by the increment.
pub const STRAIN_MATCH_RELATIVE: f64 = 1e-9;
/// The absolute floor of the strain match (at zero strain), strain units.
pub const STRAIN_MATCH_FLOOR: f64 = 1e-12;

const STALE_STATE_REMEDY: &str = ". Check that the host hands every call of an increment \
    the STATEV kept at the end of this point's previous converged increment, with that \
    increment's total strain in STRAN (a state of another point, or of an earlier \
    increment, is not this one's). A host whose STRAN is not the total strain at the start \
    of the increment sets [statev] check_strain = false in the scene";
const EARLIER_STATE_REMEDY: &str = ". CalculiX 2.20 hands an element re-added by *MODEL \
    CHANGE, ADD the STATEV of its last call before the removal: such an element cannot \
    continue from its old state (see docs/statev.md: do not remove and re-add RVE \
    elements, or set [statev] check_time = false in the scene to continue the old state \
    as ccx does). Otherwise the host handed a state kept from an earlier increment; a \
    host whose TIME(2) is not the total time at the start of the increment sets [statev] \
    check_time = false";
const LOST_STATE_REMEDY: &str = ". CalculiX 2.20 writes STATEV to its restart file only \
    when the model has a contact pair: add a node-to-surface pair that never closes (see \
    docs/calculix.md) and run the analysis again from its start. A host that zeroes \
    STATEV on purpose to restart the point from a virgin RVE (an element re-added with \
    its state reset) sets [statev] zero_at_strain = \"virgin\" in the scene";

/// `Some((difference, tolerance))` when a state committed at `stored` does not belong to
/// the start of an increment at `host` (infinity norms; see [`STRAIN_MATCH_RELATIVE`]).
pub fn strain_mismatch(stored: [f64; 3], host: [f64; 3]) -> Option<(f64, f64)> {
    let norm = |e: &[f64; 3]| e.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let difference = norm(&std::array::from_fn(|i| stored[i] - host[i]));
    let tolerance = STRAIN_MATCH_RELATIVE * norm(&stored).max(norm(&host)) + STRAIN_MATCH_FLOOR;
    (difference > tolerance).then_some((difference, tolerance))
}

/// Refuses a state that is not this point's at this increment: its committed strain must
/// be the host's `STRAN` to [`STRAIN_MATCH_RELATIVE`] of the larger of the two, plus
/// [`STRAIN_MATCH_FLOOR`]; an all-zero `STATEV` (`virgin`) at a strained point is a lost
/// state unless the scene says the host zeroes it on purpose (`[statev]`).
fn check_start_strain(p: &Point, c: &UmatCall, virgin: bool, timed: bool) -> crate::Result<()> {
    let spec = p.material.model.scene().spec.statev;
    if !spec.check_strain {
        return Ok(());
    }
    let host = c.hypothesis.rve_strain(c.stran)?;
    let stored = p.instance.committed().strain;
    let Some((difference, tolerance)) = strain_mismatch(stored, host) else {
        return check_start_time(p, c, spec.check_time && timed);
    };
    if virgin {
        if spec.zero_at_strain == ZeroAtStrain::Virgin {
            return Ok(());
        }
        return Err(Error::StateLost {
            host,
            remedy: LOST_STATE_REMEDY.into(),
        });
    }
    Err(Error::StateStrain {
        stored,
        host,
        difference,
        tolerance,
        remedy: STALE_STATE_REMEDY.into(),
    })
}

/// Refuses a state committed at the end of another time than this increment's start
/// (`TIME(2)`, to [`TIME_ROUNDOFF`] of the time plus the increment): a state of an earlier
/// increment, such as the one CalculiX 2.20 hands an element re-added by `*MODEL CHANGE`.
fn check_start_time(p: &Point, c: &UmatCall, check: bool) -> crate::Result<()> {
    let (Some(end), true) = (p.statev.core_time, check) else {
        return Ok(());
    };
    let start = c.time[1];
    let tolerance = TIME_ROUNDOFF * (end.abs() + c.dtime.abs());
    if (start - end).abs() <= tolerance {
        return Ok(());
    }
    Err(Error::StateTime {
        stored: end,
        host: start,
        remedy: EARLIER_STATE_REMEDY.into(),
    })
}

/// Says once per process that a point's `STATEV` is of state format 1 (no fingerprint):
/// accepted, since an upgrade may find an analysis mid-way, but it cannot be verified to be
/// this material's; the point's next write is verified.
fn unverified_note(c: &UmatCall) {
    note_once(Note::Unverified, || {
        format!(
            "mesorve: element {}, point {}, material `{}`: STATEV written by an earlier \
             mesorve (state format 1, no fingerprint): accepted, but it cannot be verified \
             to be this material's state; the values written from now on can (printed \
             once)",
            c.noel,
            c.npt,
            trim(c.cmname)
        )
    });
}

impl Umat {
    /// `STATEV` mode. A host that passes `PNEWDT` (CalculiX, Abaqus) numbers its points:
    /// the table's point `(NOEL, NPT)` is the cache of its state, rebuilt at most once per
    /// increment. A host that does not (Kratos: every point 0) gets this thread's
    /// point for the values (see [`SLOTS`]); with more points on a thread than slots that
    /// rebuilds the state at every call (one factorization), which is why a numbering
    /// host keeps its table.
    pub(super) fn statev_call(
        &self,
        c: &UmatCall,
        out: &mut UmatOutputs,
        material: Arc<Material>,
        signal: HostSignal,
    ) -> Result<Outcome, Failed> {
        let failed = Failed::of(&material);
        if signal == HostSignal::Pnewdt {
            let point = self.point(c).map_err(Failed::unresolved)?;
            let mut p = lock(&point, c).map_err(failed)?;
            if !Arc::ptr_eq(&p.material, &material) {
                *p = Point::new(p.id, MaterialKey::of(c), material.clone());
            }
            let outcome = self.statev_outcome(&mut p, c, out, true);
            // Between calls a lean IMPL-EX point holds its step, not its trial's body.
            p.instance.park();
            return outcome.map_err(failed);
        }
        let n = material.model.statev_len();
        let mut p = take_slot(self.id, &material, &out.statev[..n]).unwrap_or_else(|| {
            let id = self.next_id.fetch_add(1, Ordering::Relaxed);
            Point::new(id, MaterialKey::of(c), material.clone())
        });
        let result = self.statev_outcome(&mut p, c, out, false);
        put_slot(self.id, p);
        result.map_err(failed)
    }

    /// The `STATEV`-mode answer of point `p` written to `out` (`timed`: the host's
    /// `TIME(2)` is meaningful).
    fn statev_outcome(
        &self,
        p: &mut Point,
        c: &UmatCall,
        out: &mut UmatOutputs,
        timed: bool,
    ) -> crate::Result<Outcome> {
        let n = p.material.model.statev_len();
        // The host keeps the committed state: points are lean (implicit: no full trial;
        // IMPL-EX: no unknowns, one step), unless `MESORVE_UMAT_VTK` writes the point's
        // fields from its full states.
        let dumped = self.vtk.as_ref().is_some_and(|v| v.chooses(c.noel, c.npt));
        p.instance.set_lean(!dumped);
        // A point whose fields are written solves its own answer.
        let implex = p.material.model.solver.integration == Integration::Implex;
        if timed && !dumped && !implex {
            if let Some((r, core)) = self.shared_answer(p, c, &out.statev[..n])? {
                let model = &p.material.model;
                with_written(n, |written| {
                    statev::write(
                        &core.view(),
                        model.state_sizes(),
                        model.fingerprint(),
                        written,
                    )?;
                    write_outputs(p, c, &r, out, written, Some(&core.history))
                })?;
                return Ok(Outcome {
                    solved: false,
                    committed: false,
                    reverted: false,
                    iterations: 0,
                });
            }
        }
        let may_share = timed && !dumped;
        let (r, solved) = self.statev_answer(p, c, &out.statev[..n], (timed, may_share))?;
        with_written(n, |written| {
            p.write_trial(written)?;
            write_outputs(p, c, &r, out, written, None)
        })?;
        vtk_dump::at_answer(&self.vtk, &p.instance, &c.dump_at());
        Ok(Outcome {
            solved,
            committed: false,
            reverted: false,
            iterations: r.report.iterations,
        })
    }

    /// `STATEV` mode with answer sharing (`share_table`): the answer of an anchor of
    /// this increment that the point's committed core (decoded from `statev`) and strain
    /// match, corrected to first order, with the anchor's trial core at the point's own
    /// strain and time (the values to write, and the history for the mirrors); `None`: the
    /// point solves (no sharing, no anchor, or values the normal path refuses with its
    /// message). The point's instance is not rebuilt: its pending trial is dropped, so
    /// the next increment rebuilds it from the values if it solves.
    fn shared_answer(
        &self,
        p: &mut Point,
        c: &UmatCall,
        statev: &[f64],
    ) -> crate::Result<Option<(Response, statev::Core)>> {
        let Some(tol) = sharing(p) else {
            return Ok(None);
        };
        if p.instance.has_trial() && p.holds_core(statev) {
            return Ok(None);
        }
        let model = p.material.model.clone();
        let strain = call_strain(p, c)?;
        let sizes = model.state_sizes();
        let core = match statev::read(statev, sizes, model.interface_points(), model.fingerprint())
        {
            Ok(Some(s)) if s.verified => s.core,
            Ok(None) => model.core_of(&model.new_state()),
            _ => return Ok(None),
        };
        if !start_matches(&model, c, &core)? {
            return Ok(None);
        }
        let time = Some(c.time[1] + c.dtime);
        let found = self
            .share
            .follow(&model, increment_key(c), tol, (&core, strain, time));
        let Some((r, written_core)) = found else {
            return Ok(None);
        };
        p.instance.revert();
        p.statev.trial_hash = None;
        p.statev.trial_time = time;
        self.shared.fetch_add(1, Ordering::Relaxed);
        Ok(Some((r, written_core)))
    }

    /// `STATEV` mode: the answer from the committed state `statev` holds (the host's
    /// start-of-increment values). The point's instance is a cache of that state, rebuilt
    /// from the values whenever they differ from the ones it was rebuilt from, so the
    /// answer is a function of `statev`, the strain and `DTIME` alone: a cut-back, a
    /// restart, a new analysis or a re-added element gets what the host hands over. A
    /// call that repeats the pending trial (same values, same strain) is not solved again.
    fn statev_answer(
        &self,
        p: &mut Point,
        c: &UmatCall,
        statev: &[f64],
        (timed, may_share): (bool, bool),
    ) -> crate::Result<(Response, bool)> {
        let strain = call_strain(p, c)?;
        let model = p.material.model.clone();
        if !p.holds_core(statev) {
            p.statev.core_hash = None;
            let implex = model.solver.integration == Integration::Implex;
            // IMPL-EX: the host kept the point's last trial, which is the state those values
            // expand to plus the step kept for carrying over (whose answers are the same
            // bit for bit): it is committed instead of rebuilt.
            if implex && p.takes_trial_back(statev) && p.instance.commit().is_ok() {
                p.statev.core_time = p.statev.trial_time;
            } else {
                let stored = statev::read(
                    statev,
                    model.state_sizes(),
                    model.interface_points(),
                    model.fingerprint(),
                )?;
                if stored.as_ref().is_some_and(|s| !s.verified) {
                    unverified_note(c);
                }
                let core = stored.map(|s| s.core);
                p.statev.core_time = core.as_ref().and_then(|c| c.time);
                with_workspace(&model, |ws| p.instance.load_core(core.as_ref(), ws))?;
                self.loads.fetch_add(1, Ordering::Relaxed);
            }
            p.statev.core_hash = Some(values_hash(statev));
        }
        let virgin = statev.iter().all(|&v| v == 0.0);
        check_start_strain(p, c, virgin, timed)?;
        p.statev.trial_hash = None;
        let request = p.material.tangent;
        let step = may_share.then(|| self.shared_step(p, c)).flatten();
        let r = with_workspace(&model, |ws| {
            p.instance.update_timed(strain, c.dtime, ws, request)
        })?;
        p.statev.trial_time = timed.then(|| c.time[1] + c.dtime);
        let trial_hash = with_written(statev.len(), |written| {
            p.write_trial(written).map(|()| values_hash(written))
        })?;
        p.statev.trial_hash = Some(trial_hash);
        let solved = r.report.answer != Answer::Repeated;
        if let Some(step) = step {
            return Ok((r, self.step_shared(p, c, step, (&strain, &r))));
        }
        if solved && timed && sharing(p).is_some() && !implex_model(p) {
            let mut trial = p.instance.trial_core()?;
            trial.time = p.statev.trial_time;
            let anchor = Anchor {
                committed: p.instance.committed_core(),
                strain,
                response: r,
                trial,
            };
            self.share.insert(&model, increment_key(c), anchor);
        }
        let counter = if solved { &self.solves } else { &self.repeats };
        counter.fetch_add(1, Ordering::Relaxed);
        Ok((r, solved))
    }

    /// IMPL-EX step sharing (`docs/sharing.md`): before the point's update, the step of
    /// this increment factorized from the point's committed core (an earlier call of the
    /// point), else from a core within the tolerance (another point), taken as the point's
    /// own ([`Instance::adopt_step`](crate::model::Instance::adopt_step)), so the update
    /// answers without a factorization.
    /// `Some`: the point shares (a step adopted or not); `None`: no sharing (not IMPL-EX,
    /// no tolerance, or the point already holds its step).
    fn shared_step(&self, p: &mut Point, c: &UmatCall) -> Option<StepLookup> {
        let tol = sharing(p).filter(|_| implex_model(p))?;
        let ratio =
            mesorve_core::solver::implex::step_ratio(p.instance.committed().implex.step, c.dtime);
        if p.instance
            .implex_step()
            .is_some_and(|(_, r)| r == ratio.to_bits())
        {
            return None;
        }
        let model = p.material.model.clone();
        let core = p.instance.committed_core_view();
        let signature = Arc::new(StepSignature::of(&model, &core, ratio));
        let ratio = ratio.to_bits();
        let found =
            (self.share).follow_step(&model, increment_key(c), tol, (&core, ratio, &signature));
        if let Some(found) = found {
            let twin = core.is(&found.committed)
                || share::cores_close(share::ROUND_OFF, &core, &found.committed);
            let adopted = share::AdoptedStep {
                own: signature.clone(),
                anchor: found.signature.clone(),
                anchor_strain: found.strain,
                twin,
            };
            p.instance.adopt_step(&found.step, ratio, c.dtime, adopted);
        }
        Some(StepLookup { signature })
    }

    /// After an update of [`Umat::shared_step`]: counts the call, and records the step a
    /// call that factorized it solved; returns whether the call solved.
    fn step_shared(
        &self,
        p: &Point,
        c: &UmatCall,
        lookup: StepLookup,
        (strain, r): (&[f64; 3], &Response),
    ) -> bool {
        if p.instance.on_adopted_step() {
            self.shared.fetch_add(1, Ordering::Relaxed);
            self.share.count_shared(&p.material.model, increment_key(c));
            return false;
        }
        let counter = match r.report.answer {
            Answer::Repeated => &self.repeats,
            _ => &self.solves,
        };
        counter.fetch_add(1, Ordering::Relaxed);
        let Some((step, ratio)) = p.instance.implex_step() else {
            return true;
        };
        if r.report.factorizations > 0 {
            // The update left the committed state as the lookup saw it.
            let step = Step {
                committed: p.instance.committed_core(),
                strain: *strain,
                step: step.clone(),
                ratio,
                signature: lookup.signature,
            };
            self.share
                .insert_step(&p.material.model, increment_key(c), step);
        }
        r.report.answer != Answer::Repeated
    }
}

/// What [`Umat::shared_step`] looked up: the signature of the point's step (recorded with
/// the step and the committed core if the point factorizes it).
struct StepLookup {
    signature: Arc<StepSignature>,
}

/// The sharing tolerance of the point's material, when it shares: `[solver]
/// share_tolerance` and the consistent tangent returned (the first-order correction needs
/// it; `PROPS(6)` may ask for another).
fn sharing(p: &Point) -> Option<f64> {
    let tol = share::tolerance(&p.material.model)?;
    (p.material.tangent == TangentRequest::Consistent).then_some(tol)
}

/// Whether the point's material integrates by IMPL-EX (step sharing).
fn implex_model(p: &Point) -> bool {
    p.material.model.solver.integration == Integration::Implex
}

/// The share table's increment of a call.
fn increment_key(c: &UmatCall) -> IncrementKey {
    (c.time[1].to_bits(), c.dtime.to_bits(), c.kstep)
}

/// Whether a decoded core passes the checks of the start of the increment (strain and
/// time, as [`check_start_strain`]); a core that does not is left to the normal path,
/// which refuses it with its message.
fn start_matches(model: &crate::Model, c: &UmatCall, core: &statev::Core) -> crate::Result<bool> {
    let spec = model.scene().spec.statev;
    let host = c.hypothesis.rve_strain(c.stran)?;
    if spec.check_strain && strain_mismatch(core.strain, host).is_some() {
        return Ok(false);
    }
    let late = core
        .time
        .is_some_and(|end| (c.time[1] - end).abs() > TIME_ROUNDOFF * (end.abs() + c.dtime.abs()));
    Ok(!(spec.check_time && late))
}

impl Point {
    /// Whether `statev` are the values the committed state stands for: they hash as the
    /// ones it was loaded from, and its core (at
    /// [`StatevTrack::core_time`](super::point::StatevTrack::core_time)) encodes to them
    /// bit for bit (values of state format 1 never do: they are expanded again).
    /// All-zero values (a virgin RVE) are held by a committed state whose core is the
    /// virgin state's.
    fn holds_core(&self, statev: &[f64]) -> bool {
        if self.statev.core_hash != Some(values_hash(statev)) {
            return false;
        }
        let committed = self.instance.committed_core_view();
        if statev.iter().all(|&v| v == 0.0) {
            let model = &self.material.model;
            let virgin = model.core_of(&model.new_state());
            let mut values = vec![0.0; statev.len()];
            let (sizes, fingerprint) = (model.state_sizes(), model.fingerprint());
            return statev::write(&virgin.view(), sizes, fingerprint, &mut values).is_ok()
                && encodes_to(committed, self, None, &values);
        }
        encodes_to(committed, self, self.statev.core_time, statev)
    }

    /// Whether `statev` are the values written for the pending trial.
    fn holds_trial(&self, statev: &[f64]) -> bool {
        self.statev.trial_hash == Some(values_hash(statev)) && self.trial_encodes_to(statev)
    }

    /// [`holds_trial`](Self::holds_trial) for a point whose trial may be parked
    /// (`Instance::park`): a trial whose values hash as `statev` is formed again first.
    fn takes_trial_back(&mut self, statev: &[f64]) -> bool {
        if self.statev.trial_hash != Some(values_hash(statev)) {
            return false;
        }
        self.instance.unpark();
        self.trial_encodes_to(statev)
    }

    /// Whether the pending trial's core encodes to `statev` bit for bit.
    fn trial_encodes_to(&self, statev: &[f64]) -> bool {
        (self.instance.trial_core_view())
            .is_ok_and(|core| encodes_to(core, self, self.statev.trial_time, statev))
    }

    /// The pending trial's values (at
    /// [`StatevTrack::trial_time`](super::point::StatevTrack::trial_time)) into `out`.
    pub(super) fn write_trial(&self, out: &mut [f64]) -> crate::Result<()> {
        let model = &self.material.model;
        let mut core = self.instance.trial_core_view()?;
        core.time = self.statev.trial_time;
        statev::write(&core, model.state_sizes(), model.fingerprint(), out)
    }
}

thread_local! {
    /// This thread's buffer for re-encoded `STATEV` values ([`encodes_to`]).
    static VALUES: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
    /// This thread's buffer for the `STATEV` values a call writes ([`with_written`]).
    static WRITTEN: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

/// `f` on `len` zeros in this thread's buffer, which a call's `STATEV` values are written
/// to before they are hashed or copied to the host: no allocation once the buffer has
/// grown to the state's length. The buffer is taken for the duration of `f` and put back
/// after, so a nested call (or one while the thread exits) works on a fresh one.
fn with_written<R>(len: usize, f: impl FnOnce(&mut [f64]) -> R) -> R {
    let mut buffer = WRITTEN.try_with(RefCell::take).unwrap_or_default();
    buffer.clear();
    buffer.resize(len, 0.0);
    let result = f(&mut buffer);
    let _ = WRITTEN.try_with(|b| b.replace(buffer));
    result
}

/// Whether `core` at `time`, encoded for point `p`'s model, is `statev` bit for bit.
fn encodes_to(mut core: CoreView<'_>, p: &Point, time: Option<f64>, statev: &[f64]) -> bool {
    let model = &p.material.model;
    core.time = time;
    VALUES
        .try_with(|v| {
            let mut v = v.borrow_mut();
            v.clear();
            v.resize(statev.len(), 0.0);
            statev::write(&core, model.state_sizes(), model.fingerprint(), &mut v).is_ok()
                && v.iter()
                    .map(|x| x.to_bits())
                    .eq(statev.iter().map(|x| x.to_bits()))
        })
        .unwrap_or(false)
}

/// `STATEV`-mode points kept per thread, at most this many (all tables together).
const SLOTS_PER_THREAD: usize = 4;

/// A `STATEV`-mode point of a thread: a cache of the state some `STATEV` values stand
/// for, keyed by nothing but those values (and the table and material), never by `NOEL`
/// or `NPT`. Two calls with the same values, strain and `DTIME` (a host's stress call
/// then its tangent call) are answered by one solve, bit for bit.
struct Slot {
    table: u64,
    /// Last use, for replacing the least recently used slot.
    stamp: u64,
    point: Point,
}

thread_local! {
    /// This thread's `STATEV`-mode points ([`Slot`]): no lock, no point shared with
    /// another thread.
    static SLOTS: RefCell<(u64, Vec<Slot>)> = const { RefCell::new((0, Vec::new())) };
}

/// The material of a call whose table and name this thread has a slot of.
pub(super) fn slot_material(table: u64, c: &UmatCall) -> Option<Arc<Material>> {
    SLOTS
        .try_with(|slots| {
            let slots = slots.borrow();
            let found = slots
                .1
                .iter()
                .find(|s| s.table == table && s.point.key.matches(c));
            found.map(|s| s.point.material.clone())
        })
        .ok()
        .flatten()
}

/// Takes this thread's point of `material` whose committed values are `statev` (else
/// whose pending trial's values are, else the least recently used one), or `None`. The
/// caller puts it back with [`put_slot`]; a panic in between drops it.
fn take_slot(table: u64, material: &Arc<Material>, statev: &[f64]) -> Option<Point> {
    SLOTS
        .try_with(|slots| {
            let slots = &mut slots.borrow_mut().1;
            let ours = |s: &Slot| s.table == table && Arc::ptr_eq(&s.point.material, material);
            let find = |f: &dyn Fn(&Slot) -> bool| slots.iter().position(|s| ours(s) && f(s));
            let pick = find(&|s| s.point.holds_core(statev))
                .or_else(|| find(&|s| s.point.holds_trial(statev)))
                .or_else(|| {
                    let mine = slots.iter().enumerate().filter(|(_, s)| ours(s));
                    mine.min_by_key(|(_, s)| s.stamp).map(|(i, _)| i)
                })?;
            Some(slots.swap_remove(pick).point)
        })
        .ok()
        .flatten()
}

/// Gives `point` back to this thread's slots, dropping the least recently used one
/// beyond [`SLOTS_PER_THREAD`].
fn put_slot(table: u64, point: Point) {
    let _ = SLOTS.try_with(|slots| {
        let (clock, slots) = &mut *slots.borrow_mut();
        *clock += 1;
        slots.push(Slot {
            table,
            stamp: *clock,
            point,
        });
        if slots.len() > SLOTS_PER_THREAD {
            let oldest = slots.iter().enumerate().min_by_key(|(_, s)| s.stamp);
            if let Some((i, _)) = oldest {
                slots.swap_remove(i);
            }
        }
    });
}

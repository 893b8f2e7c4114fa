//! `STATEV` mode ([`StatevMode`]): the point's committed state is the host's `STATEV`, and
//! the point's instance only caches the state those values stand for (see the module
//! documentation of [`crate::host::umat`]).

use std::sync::Arc;

use super::call::{Books, Failed, HostSignal, Outcome, UmatCall, UmatOutputs};
use super::point::{lock, PointMap};
use super::slots::{put_slot, take_slot};
use super::statev_checks::{check_start, start_matches, unverified_note};
use super::statev_point::{with_written, StatevPoint};
use crate::host::material::Material;
use crate::host::share_table::{Anchor, IncrementKey, ShareTable, Step};
use crate::host::values_hash::values_hash;
use crate::model::share::{self, StepSignature};
use crate::model::workspaces::with_workspace;
use crate::model::Response;
use mesorve_core::solver::TangentRequest;
use mesorve_core::solver::{Answer, Integration};
use mesorve_core::state::statev;

/// `STATEV` mode of a table: the points of the hosts that number them (`PNEWDT` given:
/// CalculiX, Abaqus), by `(NOEL, NPT)`, each the cache of its state, rebuilt at most once
/// per increment; and answer sharing's per-increment tables. A host that does not number
/// its points (Kratos: every point 0) gets this thread's point for the values instead
/// (`slots.rs`); with more points on a thread than slots that rebuilds the state at every
/// call (one factorization), which is why a numbering host keeps its points here.
pub(super) struct StatevMode {
    points: PointMap<StatevPoint>,
    /// Answer sharing's per-increment tables (`share_table`).
    share: ShareTable,
}

impl StatevMode {
    pub(super) fn new() -> Self {
        StatevMode {
            points: PointMap::new(),
            share: ShareTable::default(),
        }
    }

    /// Points kept by `(NOEL, NPT)`.
    pub(super) fn points(&self) -> usize {
        self.points.len()
    }

    /// The hot path of a numbering host: the call's point, when it exists, is free and
    /// was last called with the call's material (name and `PROPS`, compared in place),
    /// gives that material without resolving it, and `in_mode` (the table's choice of
    /// mode for that material) says whether the call is in `STATEV` mode; then the point
    /// answers. `None`: the call goes the general way (a new point, another material, a
    /// point busy or poisoned, table mode), which resolves the material.
    pub(super) fn answer_held(
        &self,
        books: &Books,
        c: &UmatCall,
        out: &mut UmatOutputs,
        in_mode: impl FnOnce(&Arc<Material>, usize) -> Result<bool, Failed>,
    ) -> Option<Result<Outcome, Failed>> {
        let point = self.points.get(c)?;
        let mut p = point.try_lock().ok()?;
        if !p.point.key.matches(c) {
            return None;
        }
        match in_mode(&p.point.material, out.statev.len()) {
            Ok(true) => {
                let answered = self.answer_point(books, &mut p, c, out);
                Some(answered.map_err(|e| Failed::of(&p.point.material)(e)))
            }
            Ok(false) => None,
            Err(f) => Some(Err(f)),
        }
    }

    /// A `STATEV`-mode call of `material`: the point `(NOEL, NPT)` of a numbering host
    /// (made a virgin point of the call's material when it had another), or this thread's
    /// point for the values of a host without `PNEWDT`.
    pub(super) fn call(
        &self,
        books: &Books,
        c: &UmatCall,
        out: &mut UmatOutputs,
        material: Arc<Material>,
        signal: HostSignal,
    ) -> Result<Outcome, Failed> {
        let failed = Failed::of(&material);
        if signal == HostSignal::Pnewdt {
            let point = (self.points)
                .get_or_insert(c, || StatevPoint::new(books.new_id(), c, material.clone()));
            let mut p = lock(&point, c, StatevPoint::recover).map_err(failed)?;
            if !Arc::ptr_eq(&p.point.material, &material) {
                *p = StatevPoint::new(p.point.id, c, material.clone());
            }
            return self.answer_point(books, &mut p, c, out).map_err(failed);
        }
        let n = material.model.statev_len();
        let mut p = take_slot(books.table, &material, &out.statev[..n])
            .unwrap_or_else(|| StatevPoint::new(books.new_id(), c, material.clone()));
        let result = self.outcome(books, &mut p, c, out, false);
        put_slot(books.table, p);
        result.map_err(failed)
    }

    /// The answer of a numbering host's point, locked; between calls a lean IMPL-EX point
    /// holds its step, not its trial's body.
    fn answer_point(
        &self,
        books: &Books,
        p: &mut StatevPoint,
        c: &UmatCall,
        out: &mut UmatOutputs,
    ) -> crate::Result<Outcome> {
        let outcome = self.outcome(books, p, c, out, true);
        p.point.instance.park();
        outcome
    }

    /// The answer of point `p` written to `out` (`timed`: the host's `TIME(2)` is
    /// meaningful). The trial's values are encoded once, into this thread's buffer, and
    /// copied to `STATEV` when the whole answer is written.
    fn outcome(
        &self,
        books: &Books,
        p: &mut StatevPoint,
        c: &UmatCall,
        out: &mut UmatOutputs,
        timed: bool,
    ) -> crate::Result<Outcome> {
        let n = p.point.material.model.statev_len();
        // The host keeps the committed state: points are lean (implicit: no full trial;
        // IMPL-EX: no unknowns, one step), unless `MESORVE_UMAT_VTK` writes the point's
        // fields from its full states.
        let dumped = books.dumps(c);
        p.point.instance.set_lean(!dumped);
        // A point whose fields are written solves its own answer.
        let implex = implex_model(p);
        if timed && !dumped && !implex {
            if let Some((r, core)) = self.shared_answer(books, p, c, &out.statev[..n])? {
                let model = &p.point.material.model;
                with_written(n, |written| {
                    let (sizes, fingerprint) = (model.state_sizes(), model.fingerprint());
                    statev::write(&core.view(), sizes, fingerprint, written)?;
                    p.point
                        .write_outputs(c, &r, out, written, Some(&core.history))
                })?;
                return Ok(Outcome::answered(false, 0));
            }
        }
        let may_share = timed && !dumped;
        let (r, solved) = with_written(n, |written| {
            let answer = self.answer(books, p, c, &out.statev[..n], written, (timed, may_share))?;
            p.point.write_outputs(c, &answer.0, out, written, None)?;
            crate::Result::Ok(answer)
        })?;
        books.dump(&p.point.instance, c);
        Ok(Outcome::answered(solved, r.report.iterations))
    }

    /// With answer sharing (`share_table`): the answer of an anchor of this increment that
    /// the point's committed core (decoded from `statev`) and strain match, corrected to
    /// first order, with the anchor's trial core at the point's own strain and time (the
    /// values to write, and the history for the mirrors); `None`: the point solves (no
    /// sharing, no anchor, or values the normal path refuses with its message). The
    /// point's instance is not rebuilt: its pending trial is dropped, so the next
    /// increment rebuilds it from the values if it solves.
    fn shared_answer(
        &self,
        books: &Books,
        p: &mut StatevPoint,
        c: &UmatCall,
        statev: &[f64],
    ) -> crate::Result<Option<(Response, statev::Core)>> {
        let Some(tol) = sharing(p) else {
            return Ok(None);
        };
        if p.point.instance.has_trial() && p.holds_core(statev) {
            return Ok(None);
        }
        let model = p.point.material.model.clone();
        let strain = p.point.strain(c)?;
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
        p.point.instance.revert();
        p.trial_hash = None;
        p.trial_time = time;
        Books::count(&books.shared);
        Ok(Some((r, written_core)))
    }

    /// The answer from the committed state `statev` holds (the host's start-of-increment
    /// values), its trial's values encoded into `written`. The point's instance is a cache
    /// of that state, rebuilt from the values whenever they differ from the ones it was
    /// rebuilt from, so the answer is a function of `statev`, the strain and `DTIME`
    /// alone: a cut-back, a restart, a new analysis or a re-added element gets what the
    /// host hands over. A call that repeats the pending trial (same values, same strain)
    /// is not solved again.
    fn answer(
        &self,
        books: &Books,
        p: &mut StatevPoint,
        c: &UmatCall,
        statev: &[f64],
        written: &mut [f64],
        (timed, may_share): (bool, bool),
    ) -> crate::Result<(Response, bool)> {
        let strain = p.point.strain(c)?;
        if !p.holds_core(statev) {
            self.load(books, p, c, statev)?;
        }
        let virgin = statev.iter().all(|&v| v == 0.0);
        check_start(&p.point, p.core_time, c, (virgin, timed))?;
        p.trial_hash = None;
        let request = p.point.material.tangent;
        let step = may_share.then(|| self.shared_step(p, c)).flatten();
        let r = with_workspace(&p.point.material.model, |ws| {
            (p.point.instance).update_timed(strain, c.dtime, ws, request)
        })?;
        p.trial_time = timed.then(|| c.time[1] + c.dtime);
        p.encode_trial(written)?;
        let solved = r.report.answer != Answer::Repeated;
        if let Some(step) = step {
            return Ok((r, self.step_shared(books, p, c, step, (&strain, &r))));
        }
        if solved && timed && sharing(p).is_some() && !implex_model(p) {
            let instance = &p.point.instance;
            let mut trial = instance.trial_core()?;
            trial.time = p.trial_time;
            let anchor = Anchor {
                committed: instance.committed_core(),
                strain,
                response: r,
                trial,
            };
            (self.share).insert(&p.point.material.model, increment_key(c), anchor);
        }
        books.count_answer(solved);
        Ok((r, solved))
    }

    /// Makes the point's committed state the one `statev` stands for. IMPL-EX: the host
    /// kept the point's last trial, which is the state those values expand to plus the
    /// step kept for carrying over (whose answers are the same bit for bit): it is
    /// committed instead of rebuilt. Otherwise the values are read (`statev::read`: the
    /// checks, the fingerprint, the decoding) and expanded (`Instance::load_core`).
    fn load(
        &self,
        books: &Books,
        p: &mut StatevPoint,
        c: &UmatCall,
        statev: &[f64],
    ) -> crate::Result<()> {
        p.core_hash = None;
        let model = p.point.material.model.clone();
        if implex_model(p) && p.takes_trial_back(statev) && p.point.instance.commit().is_ok() {
            p.core_time = p.trial_time;
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
            p.core_time = core.as_ref().and_then(|c| c.time);
            with_workspace(&model, |ws| p.point.instance.load_core(core.as_ref(), ws))?;
            Books::count(&books.loads);
        }
        p.core_hash = Some(values_hash(statev));
        Ok(())
    }

    /// IMPL-EX step sharing (`docs/sharing.md`): before the point's update, the step of
    /// this increment factorized from the point's committed core (an earlier call of the
    /// point), else from a core within the tolerance (another point), taken as the point's
    /// own ([`Instance::adopt_step`](crate::model::Instance::adopt_step)), so the update
    /// answers without a factorization.
    /// `Some`: the point shares (a step adopted or not); `None`: no sharing (not IMPL-EX,
    /// no tolerance, or the point already holds its step).
    fn shared_step(&self, p: &mut StatevPoint, c: &UmatCall) -> Option<StepLookup> {
        let tol = sharing(p).filter(|_| implex_model(p))?;
        let instance = &mut p.point.instance;
        let ratio =
            mesorve_core::solver::implex::step_ratio(instance.committed().implex.step, c.dtime);
        if instance
            .implex_step()
            .is_some_and(|(_, r)| r == ratio.to_bits())
        {
            return None;
        }
        let model = p.point.material.model.clone();
        let core = instance.committed_core_view();
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
            instance.adopt_step(&found.step, ratio, c.dtime, adopted);
        }
        Some(StepLookup { signature })
    }

    /// After an update of [`StatevMode::shared_step`]: counts the call, and records the
    /// step a call that factorized it solved; returns whether the call solved.
    fn step_shared(
        &self,
        books: &Books,
        p: &StatevPoint,
        c: &UmatCall,
        lookup: StepLookup,
        (strain, r): (&[f64; 3], &Response),
    ) -> bool {
        let (instance, model) = (&p.point.instance, &p.point.material.model);
        if instance.on_adopted_step() {
            Books::count(&books.shared);
            self.share.count_shared(model, increment_key(c));
            return false;
        }
        books.count_answer(r.report.answer != Answer::Repeated);
        let Some((step, ratio)) = instance.implex_step() else {
            return true;
        };
        if r.report.factorizations > 0 {
            // The update left the committed state as the lookup saw it.
            let step = Step {
                committed: instance.committed_core(),
                strain: *strain,
                step: step.clone(),
                ratio,
                signature: lookup.signature,
            };
            self.share.insert_step(model, increment_key(c), step);
        }
        r.report.answer != Answer::Repeated
    }
}

/// What [`StatevMode::shared_step`] looked up: the signature of the point's step
/// (recorded with the step and the committed core if the point factorizes it).
struct StepLookup {
    signature: Arc<StepSignature>,
}

/// The sharing tolerance of the point's material, when it shares: `[solver]
/// share_tolerance` and the consistent tangent returned (the first-order correction needs
/// it; `PROPS(6)` may ask for another).
fn sharing(p: &StatevPoint) -> Option<f64> {
    let material = &p.point.material;
    let tol = share::tolerance(&material.model)?;
    (material.tangent == TangentRequest::Consistent).then_some(tol)
}

/// Whether the point's material integrates by IMPL-EX (step sharing).
fn implex_model(p: &StatevPoint) -> bool {
    p.point.material.model.solver.integration == Integration::Implex
}

/// The share table's increment of a call.
fn increment_key(c: &UmatCall) -> IncrementKey {
    (c.time[1].to_bits(), c.dtime.to_bits(), c.kstep)
}

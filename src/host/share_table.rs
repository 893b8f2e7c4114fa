//! Answer sharing in the UMAT's `STATEV` mode (`[solver] share_tolerance`,
//! [`crate::model::share`], `docs/sharing.md`): a table per material and host increment,
//! shared by the host's threads, of the answers of the points solved so far in the
//! increment (anchors). A point whose committed `STATEV` core and strain match an anchor
//! takes its answer corrected to first order and writes its own committed core (or, for a
//! twin, the anchor's trial core) with its own strain and time, without rebuilding or
//! solving its RVE, when the error indicator allows ([`share::follows`]). Under IMPL-EX
//! the table holds the increment's steps instead (step sharing).
//!
//! The increment is `(TIME(2), DTIME, KSTEP)` of the calls: a new one (or a cut-back's
//! smaller `DTIME`) starts an empty table. The answers then depend on which points of the
//! increment the host called first, which with several threads changes from run to run
//! (docs/sharing.md bounds the difference on the member).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};

use super::values_hash::values_hash;
use crate::model::share::{self, Follow, StepSignature};
use crate::model::{Model, Response};
use mesorve_core::state::statev::{Core, CoreView};
use mesorve_core::state::LinearBranch;

/// The increment a table belongs to: the bits of `TIME(2)` and `DTIME`, and `KSTEP`.
pub(super) type IncrementKey = (u64, u64, i32);

/// A point solved in the increment.
pub(super) struct Anchor {
    /// The committed core it solved from.
    pub committed: Core,
    pub strain: [f64; 3],
    pub response: Response,
    /// The trial core it wrote (its strain and time are the anchor's).
    pub trial: Core,
}

/// An IMPL-EX step factorized in the increment (step sharing): the committed core it was
/// factorized from, the step (`Instance::implex_step`) and what it froze.
pub(super) struct Step {
    pub committed: Core,
    /// The strain of the call that factorized it.
    pub strain: [f64; 3],
    pub step: LinearBranch,
    /// The step ratio `dt / dt_n` (bits) it was factorized for.
    pub ratio: u64,
    pub signature: Arc<StepSignature>,
}

/// The key of a core's discrete part (contact status, `at_start`, `dt_n`): the steps of
/// one key are the candidates of a core of that key.
fn status_key(core: &CoreView<'_>) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    core.closed.hash(&mut h);
    core.at_start.hash(&mut h);
    core.step.to_bits().hash(&mut h);
    h.finish()
}

/// The key of a whole core bit for bit (the point's own earlier calls of the increment):
/// [`status_key`] and [`values_hash`] of the strain and histories (a filter: the
/// candidate is compared in full).
fn core_key(core: &CoreView<'_>) -> u64 {
    let parts = [
        status_key(core),
        values_hash(&core.strain),
        values_hash(core.history),
        values_hash(core.previous),
    ];
    values_hash(&parts.map(f64::from_bits))
}

/// A core's [`core_key`] and [`status_key`], computed before the table is locked.
#[derive(Clone, Copy)]
struct Keys {
    core: u64,
    status: u64,
}

impl Keys {
    fn of(core: &CoreView<'_>) -> Self {
        Keys {
            core: core_key(core),
            status: status_key(core),
        }
    }
}

struct Increment {
    model: Arc<Model>,
    key: IncrementKey,
    anchors: Vec<Anchor>,
    /// IMPL-EX steps by [`core_key`] and by [`status_key`].
    exact: HashMap<u64, Arc<Step>>,
    steps: HashMap<u64, Vec<Arc<Step>>>,
    /// The model's [`share::secant_scale`], the unit of the steps' similarity.
    secant_scale: f64,
    solved: u64,
    shared: u64,
}

impl Increment {
    fn new(model: &Arc<Model>, key: IncrementKey) -> Self {
        Increment {
            model: model.clone(),
            key,
            anchors: Vec::new(),
            exact: HashMap::new(),
            steps: HashMap::new(),
            secant_scale: share::secant_scale(model),
            solved: 0,
            shared: 0,
        }
    }

    /// The step of the same committed core, else the first of the same contact status,
    /// `dt_n` and step ratio `ratio` whose frozen secants are within `tol` times the virgin
    /// ITZ stiffness of `signature`'s ([`StepSignature::close`]). The status is compared
    /// again after the bucket: [`status_key`] is a hash.
    fn find_step(
        &self,
        tol: f64,
        (core, ratio, signature): (&CoreView<'_>, u64, &StepSignature),
        keys: Keys,
    ) -> Option<Arc<Step>> {
        let same = |s: &&Arc<Step>| s.ratio == ratio && core.is(&s.committed);
        if let Some(s) = self.exact.get(&keys.core).filter(same) {
            return Some(s.clone());
        }
        let candidates = self.steps.get(&keys.status)?;
        candidates
            .iter()
            .find(|s| {
                s.ratio == ratio
                    && *s.committed.closed == *core.closed
                    && s.committed.at_start == core.at_start
                    && s.committed.step.to_bits() == core.step.to_bits()
                    && signature.close(&s.signature, tol, self.secant_scale)
            })
            .cloned()
    }
}

/// The tables of a UMAT, one per material, each of its current increment.
#[derive(Default)]
pub(super) struct ShareTable {
    increments: Mutex<Vec<Increment>>,
}

/// Prints each increment's counts on stderr when `MESORVE_SHARE_LOG` is set.
fn log(inc: &Increment) {
    static LOG: std::sync::LazyLock<bool> =
        std::sync::LazyLock::new(|| std::env::var_os("MESORVE_SHARE_LOG").is_some());
    if *LOG && inc.solved + inc.shared > 0 {
        super::diagnostics::say(&format!(
            "mesorve: sharing: increment at TIME(2) = {}, DTIME = {}: {} calls solved, {} shared",
            f64::from_bits(inc.key.0),
            f64::from_bits(inc.key.1),
            inc.solved,
            inc.shared
        ));
    }
}

impl ShareTable {
    /// The table of `model` at `key`, emptied when the increment changed.
    fn with<R>(
        &self,
        model: &Arc<Model>,
        key: IncrementKey,
        f: impl FnOnce(&mut Increment) -> R,
    ) -> R {
        let mut all = self
            .increments
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        let i = match all.iter().position(|t| share::same_model(&t.model, model)) {
            Some(i) => i,
            None => {
                all.push(Increment::new(model, key));
                all.len() - 1
            }
        };
        let inc = &mut all[i];
        if inc.key != key {
            log(inc);
            *inc = Increment::new(model, key);
        }
        f(inc)
    }

    /// The answer and the core to write for a point of committed core `core` at
    /// `strain`, from the first anchor that matches it and whose error indicator allows
    /// (`None`: the point solves). `time`: the host's time at the increment's end.
    pub fn follow(
        &self,
        model: &Arc<Model>,
        key: IncrementKey,
        tol: f64,
        (core, strain, time): (&Core, [f64; 3], Option<f64>),
    ) -> Option<(Response, Core)> {
        self.with(model, key, |inc| {
            // The first anchor that matches and whose indicator lets the point follow.
            let (anchor, follow) = inc.anchors.iter().find_map(|a| {
                let matches = share::strains_close(tol, &strain, &a.strain)
                    && share::cores_close(tol, &core.view(), &a.committed);
                let still = a.trial.closed == a.committed.closed
                    && share::same_bits(&a.trial.history, &a.committed.history);
                let twin = share::cores_close(0.0, &core.view(), &a.committed);
                let follow = share::follows(tol, &a.response, &a.strain, &strain, twin, still);
                follow.filter(|_| matches).map(|f| (a, f))
            })?;
            let response = share::corrected(&anchor.response, &anchor.strain, &strain);
            let mut written = match follow {
                Follow::Twin => anchor.trial.clone(),
                Follow::Own => core.clone(),
            };
            written.strain = strain;
            written.time = time;
            inc.shared += 1;
            Some((response, written))
        })
    }

    /// Records a point solved in the increment.
    pub fn insert(&self, model: &Arc<Model>, key: IncrementKey, anchor: Anchor) {
        self.with(model, key, |inc| {
            inc.solved += 1;
            inc.anchors.push(anchor);
        });
    }

    /// IMPL-EX step sharing: the step factorized in this increment from the committed core
    /// `core` (bit for bit), else one that froze secants within `tol` of `signature` (the
    /// core's at step ratio `ratio`; [`Increment::find_step`]) (`None`: the point
    /// factorizes its own); [`count_shared`](Self::count_shared) counts it once kept.
    pub fn follow_step(
        &self,
        model: &Arc<Model>,
        key: IncrementKey,
        tol: f64,
        wanted: (&CoreView<'_>, u64, &StepSignature),
    ) -> Option<Arc<Step>> {
        let keys = Keys::of(wanted.0);
        self.with(model, key, |inc| inc.find_step(tol, wanted, keys))
    }

    /// Counts a call that kept a step found by [`follow_step`](Self::follow_step).
    pub fn count_shared(&self, model: &Arc<Model>, key: IncrementKey) {
        self.with(model, key, |inc| inc.shared += 1);
    }

    /// Records a step factorized in the increment (a solved call).
    pub fn insert_step(&self, model: &Arc<Model>, key: IncrementKey, step: Step) {
        let step = Arc::new(step);
        let keys = Keys::of(&step.committed.view());
        self.with(model, key, |inc| {
            inc.solved += 1;
            inc.exact.entry(keys.core).or_insert_with(|| step.clone());
            inc.steps.entry(keys.status).or_default().push(step);
        });
    }
}

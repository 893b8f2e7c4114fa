//! A `STATEV`-mode point ([`StatevPoint`]): a [`Point`] whose instance caches the state
//! some `STATEV` values stand for, and which values those are (their hashes and times).
//! The values themselves are not kept: a point compares the host's values with its state
//! encoded again, in this thread's buffers ([`with_written`]).

use std::cell::RefCell;

use super::call::UmatCall;
use super::point::Point;
use crate::host::material::Material;
use crate::host::values_hash::values_hash;
use mesorve_core::state::statev::{self, CoreView};
use std::sync::Arc;

/// A `STATEV`-mode point: which of the host's values its instance's committed state and
/// pending trial stand for; all `None` before the first call.
pub(super) struct StatevPoint {
    pub(super) point: Point,
    /// Hashes ([`values_hash`]) of the values the committed state stands for (the ones it
    /// was loaded from) and of the values written for the pending trial.
    pub(super) core_hash: Option<u64>,
    pub(super) trial_hash: Option<u64>,
    /// The host's time the committed state and the pending trial were written at the end
    /// of (`statev::Core::time`).
    pub(super) core_time: Option<f64>,
    pub(super) trial_time: Option<f64>,
}

impl StatevPoint {
    /// A virgin point of `material`, which `c` names.
    pub(super) fn new(id: u64, c: &UmatCall, material: Arc<Material>) -> Self {
        StatevPoint {
            point: Point::new(id, c, material),
            core_hash: None,
            trial_hash: None,
            core_time: None,
            trial_time: None,
        }
    }

    /// After a panic in a call of this point: the trial dropped, no values held.
    pub(super) fn recover(&mut self) {
        self.point.instance.revert();
        self.forget();
    }

    /// Holds no values: the next call rebuilds the state from the host's.
    pub(super) fn forget(&mut self) {
        (self.core_hash, self.trial_hash) = (None, None);
        (self.core_time, self.trial_time) = (None, None);
    }

    /// Whether `statev` are the values the committed state stands for: they hash as the
    /// ones it was loaded from, and its core (at [`core_time`](Self::core_time)) encodes
    /// to them bit for bit (values of state format 1 never do: they are expanded again).
    /// All-zero values (a virgin RVE) are held by a committed state whose core is the
    /// virgin state's.
    pub(super) fn holds_core(&self, statev: &[f64]) -> bool {
        if self.core_hash != Some(values_hash(statev)) {
            return false;
        }
        let committed = self.point.instance.committed_core_view();
        if statev.iter().all(|&v| v == 0.0) {
            let model = &self.point.material.model;
            let virgin = model.core_of(&model.new_state());
            let mut values = vec![0.0; statev.len()];
            let (sizes, fingerprint) = (model.state_sizes(), model.fingerprint());
            return statev::write(&virgin.view(), sizes, fingerprint, &mut values).is_ok()
                && encodes_to(committed, &self.point, None, &values);
        }
        encodes_to(committed, &self.point, self.core_time, statev)
    }

    /// Whether `statev` are the values written for the pending trial.
    pub(super) fn holds_trial(&self, statev: &[f64]) -> bool {
        self.trial_hash == Some(values_hash(statev)) && self.trial_encodes_to(statev)
    }

    /// [`holds_trial`](Self::holds_trial) for a point whose trial may be parked
    /// (`Instance::park`): a trial whose values hash as `statev` is formed again first.
    pub(super) fn takes_trial_back(&mut self, statev: &[f64]) -> bool {
        if self.trial_hash != Some(values_hash(statev)) {
            return false;
        }
        self.point.instance.unpark();
        self.trial_encodes_to(statev)
    }

    /// Whether the pending trial's core encodes to `statev` bit for bit.
    fn trial_encodes_to(&self, statev: &[f64]) -> bool {
        (self.point.instance.trial_core_view())
            .is_ok_and(|core| encodes_to(core, &self.point, self.trial_time, statev))
    }

    /// Encodes the pending trial (at [`trial_time`](Self::trial_time)) into `written`,
    /// the values the call gives the host, and keeps their hash: the one encoding of the
    /// trial a call makes.
    pub(super) fn encode_trial(&mut self, written: &mut [f64]) -> crate::Result<()> {
        let model = &self.point.material.model;
        let mut core = self.point.instance.trial_core_view()?;
        core.time = self.trial_time;
        statev::write(&core, model.state_sizes(), model.fingerprint(), written)?;
        self.trial_hash = Some(values_hash(written));
        Ok(())
    }
}

thread_local! {
    /// This thread's buffer for re-encoded `STATEV` values ([`encodes_to`]).
    static VALUES: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
    /// This thread's buffer for the `STATEV` values a call writes ([`with_written`]).
    static WRITTEN: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

/// `f` on `len` zeros in this thread's buffer, which a call's `STATEV` values are encoded
/// into before they are copied to the host (after the call has succeeded): no allocation
/// once the buffer has grown to the state's length. The buffer is taken for the duration
/// of `f` and put back after, so a nested call (or one while the thread exits) works on a
/// fresh one.
pub(super) fn with_written<R>(len: usize, f: impl FnOnce(&mut [f64]) -> R) -> R {
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

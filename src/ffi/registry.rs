//! Handles: int64 ids into a process-wide table of instances, with a generation counter
//! per slot so that a freed id never becomes valid again.
//!
//! Layout of an id: `generation << 32 | slot`, `generation` in `1..=MAX_GENERATION`
//! (2^20 - 1). Every id is therefore in `[2^32, 2^52)`: positive, never 0, and exactly
//! representable in a double (a UMAT STATEV slot). A slot whose generation is exhausted
//! is retired, never reused.

use std::sync::{Arc, Mutex, MutexGuard, RwLock, TryLockError};

use super::guard::{Failure, FfiResult};
use super::status::RveStatus;
use crate::model::{Instance, Model};

const MAX_GENERATION: u32 = (1 << 20) - 1;

/// One material point behind a handle: a [`model::Instance`](Instance), which owns the
/// trial/commit lifecycle, behind a lock that gives one thread at a time, and its model,
/// kept beside it too so that `rve_clone_model`, the strain path and the per-thread
/// workspaces read it without taking the lock.
pub(crate) struct Entry {
    pub model: Arc<Model>,
    instance: Mutex<Instance>,
}

impl Entry {
    pub fn new(model: Arc<Model>) -> Self {
        let instance = Mutex::new(Instance::new(model.clone()));
        Entry { model, instance }
    }

    /// Exclusive access, or `InstanceBusy` when another thread holds the instance. A
    /// panic during an earlier call poisons the lock; the committed state is only ever
    /// replaced whole (see [`Instance`]), so it is intact, and only the trial is dropped.
    pub fn lock(&self) -> FfiResult<MutexGuard<'_, Instance>> {
        match self.instance.try_lock() {
            Ok(g) => Ok(g),
            Err(TryLockError::WouldBlock) => Err(Failure::new(
                RveStatus::InstanceBusy,
                "the instance is being used by another thread (an instance may be used by \
                 one thread at a time)",
            )),
            Err(TryLockError::Poisoned(p)) => {
                self.instance.clear_poison();
                let mut g = p.into_inner();
                g.revert();
                Ok(g)
            }
        }
    }

    /// Whether another thread holds the instance right now.
    fn busy(&self) -> bool {
        matches!(self.instance.try_lock(), Err(TryLockError::WouldBlock))
    }
}

struct Slot {
    generation: u32,
    entry: Option<Arc<Entry>>,
}

struct Table {
    slots: Vec<Slot>,
    free: Vec<u32>,
}

static TABLE: RwLock<Table> = RwLock::new(Table {
    slots: Vec::new(),
    free: Vec::new(),
});

fn read() -> std::sync::RwLockReadGuard<'static, Table> {
    TABLE.read().unwrap_or_else(|e| e.into_inner())
}

fn write() -> std::sync::RwLockWriteGuard<'static, Table> {
    TABLE.write().unwrap_or_else(|e| e.into_inner())
}

fn encode(slot: u32, generation: u32) -> i64 {
    (i64::from(generation) << 32) | i64::from(slot)
}

fn decode(handle: i64) -> Option<(usize, u32)> {
    let generation = handle >> 32;
    if !(1..=i64::from(MAX_GENERATION)).contains(&generation) {
        return None;
    }
    Some(((handle & 0xffff_ffff) as usize, generation as u32))
}

fn bad_handle(handle: i64) -> Failure {
    Failure::new(
        RveStatus::BadHandle,
        format!("handle {handle} is not a live instance (0, freed, or not from rve_init)"),
    )
}

/// Registers an instance and returns its new id.
pub(crate) fn insert(entry: Entry) -> FfiResult<i64> {
    let entry = Arc::new(entry);
    let mut t = write();
    let index = match t.free.pop() {
        Some(i) => i,
        None => {
            let i = u32::try_from(t.slots.len())
                .map_err(|_| Failure::new(RveStatus::Internal, "too many instances"))?;
            t.slots.push(Slot {
                generation: 1,
                entry: None,
            });
            i
        }
    };
    let slot = &mut t.slots[index as usize];
    slot.entry = Some(entry);
    Ok(encode(index, slot.generation))
}

/// The live instance behind `handle`.
pub(crate) fn get(handle: i64) -> FfiResult<Arc<Entry>> {
    let (index, generation) = decode(handle).ok_or_else(|| bad_handle(handle))?;
    let t = read();
    match t.slots.get(index) {
        Some(Slot {
            generation: g,
            entry: Some(e),
        }) if *g == generation => Ok(e.clone()),
        _ => Err(bad_handle(handle)),
    }
}

/// Unregisters `handle`; its id never becomes valid again. Refused with `InstanceBusy`
/// while another thread uses the instance.
pub(crate) fn remove(handle: i64) -> FfiResult<Arc<Entry>> {
    let (index, generation) = decode(handle).ok_or_else(|| bad_handle(handle))?;
    let mut t = write();
    let slot = match t.slots.get_mut(index) {
        Some(s) if s.generation == generation && s.entry.is_some() => s,
        _ => return Err(bad_handle(handle)),
    };
    if slot.entry.as_ref().is_some_and(|e| e.busy()) {
        return Err(Failure::new(
            RveStatus::InstanceBusy,
            "cannot free an instance that another thread is using",
        ));
    }
    let entry = slot.entry.take().expect("checked above");
    slot.generation += 1;
    if slot.generation <= MAX_GENERATION {
        t.free.push(index as u32);
    }
    Ok(entry)
}

/// Number of live instances.
pub fn live_instances() -> usize {
    read().slots.iter().filter(|s| s.entry.is_some()).count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;
    use crate::scene::Scene;
    use mesorve_core::solver::TangentRequest;

    #[test]
    fn ids_are_positive_double_exact_and_never_zero() {
        for (slot, generation) in [(0, 1), (u32::MAX, MAX_GENERATION), (7, 3)] {
            let id = encode(slot, generation);
            assert!(id > 0 && id < (1i64 << 53));
            assert_eq!(id as f64 as i64, id);
            assert_eq!(decode(id), Some((slot as usize, generation)));
        }
        for bad in [0, 1, -1, 12345, i64::MAX, i64::MIN, 1i64 << 52] {
            assert_eq!(decode(bad), None, "{bad}");
        }
    }

    /// A panic while an instance is locked poisons the lock; the next call gets the
    /// instance with its committed state intact and without the trial it had.
    #[test]
    fn a_poisoned_instance_keeps_its_committed_state_and_drops_the_trial() {
        let model = Arc::new(Model::from_scene(&Scene::embedded_default().unwrap()).unwrap());
        let entry = Entry::new(model.clone());
        let mut ws = model.workspace();
        let committed = {
            let mut i = entry.lock().unwrap();
            i.update([1e-4, 0.0, 0.0], &mut ws, TangentRequest::Consistent)
                .unwrap();
            i.commit().unwrap();
            i.update([2e-4, 0.0, 0.0], &mut ws, TangentRequest::Consistent)
                .unwrap();
            assert!(i.has_trial());
            i.committed().clone()
        };
        let panicked = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let _held = entry.lock().unwrap();
            panic!("a panic while the instance is locked");
        }));
        assert!(panicked.is_err() && entry.instance.is_poisoned());
        let mut i = entry.lock().unwrap();
        assert!(!entry.instance.is_poisoned());
        assert!(!i.has_trial());
        assert_eq!(i.committed(), &committed);
        assert!(matches!(i.commit(), Err(Error::NoTrial)));
    }
}

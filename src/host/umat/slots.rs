//! The `STATEV`-mode points of a host without `PNEWDT` (Kratos: every point numbered 0),
//! kept per thread and keyed by nothing but the values they hold (and the table and
//! material), never by `NOEL` or `NPT`: no lock, no point shared with another thread. Two
//! calls with the same values, strain and `DTIME` (a host's stress call then its tangent
//! call) are answered by one solve, bit for bit.

use std::cell::RefCell;
use std::sync::Arc;

use super::call::UmatCall;
use super::statev_point::StatevPoint;
use crate::host::material::Material;

/// `STATEV`-mode points kept per thread, at most this many (all tables together).
const SLOTS_PER_THREAD: usize = 4;

/// A point of a thread, with its table and last use.
struct Slot {
    table: u64,
    /// Last use, for replacing the least recently used slot.
    stamp: u64,
    point: StatevPoint,
}

thread_local! {
    /// This thread's points ([`Slot`]) and its clock of uses.
    static SLOTS: RefCell<(u64, Vec<Slot>)> = const { RefCell::new((0, Vec::new())) };
}

/// The material of a call whose table and name (and `PROPS`) this thread has a slot of:
/// found without resolving the name or allocating.
pub(super) fn slot_material(table: u64, c: &UmatCall) -> Option<Arc<Material>> {
    SLOTS
        .try_with(|slots| {
            let slots = slots.borrow();
            let found = slots
                .1
                .iter()
                .find(|s| s.table == table && s.point.point.key.matches(c));
            found.map(|s| s.point.point.material.clone())
        })
        .ok()
        .flatten()
}

/// Takes this thread's point of `material` whose committed values are `statev` (else
/// whose pending trial's values are, else the least recently used one), or `None`. The
/// caller puts it back with [`put_slot`]; a panic in between drops it.
pub(super) fn take_slot(
    table: u64,
    material: &Arc<Material>,
    statev: &[f64],
) -> Option<StatevPoint> {
    SLOTS
        .try_with(|slots| {
            let slots = &mut slots.borrow_mut().1;
            let ours =
                |s: &Slot| s.table == table && Arc::ptr_eq(&s.point.point.material, material);
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
pub(super) fn put_slot(table: u64, point: StatevPoint) {
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

//! One integration point: the material a host names ([`MaterialKey`]), its RVE instance,
//! and what each mode keeps of it: the increments of table mode ([`TableTrack`]) and the
//! hashes and times of `STATEV` mode ([`StatevTrack`]). Both modes lock a point of the
//! `(NOEL, NPT)` table with [`lock`].

use std::sync::{Arc, Mutex, MutexGuard, TryLockError};

use super::call::{trim, UmatCall};
use crate::error::Error;
use crate::host::material::Material;
use crate::model::{Instance, Response};

/// Relative round-off of `TIME(2)` tolerated within one increment: CalculiX computes it
/// as `(t + dt) - dt`, which moves by an ulp when a cut-back changes `dt`.
pub(super) const TIME_ROUNDOFF: f64 = 1e-9;

/// A material as a host names it: `CMNAME` without padding and the bits of `PROPS`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(super) struct MaterialKey {
    pub(super) cmname: String,
    props: Vec<u64>,
}

impl MaterialKey {
    pub(super) fn of(c: &UmatCall) -> Self {
        MaterialKey {
            cmname: trim(c.cmname).to_string(),
            props: c.props.iter().map(|v| v.to_bits()).collect(),
        }
    }

    pub(super) fn matches(&self, c: &UmatCall) -> bool {
        self.cmname == trim(c.cmname)
            && self
                .props
                .iter()
                .copied()
                .eq(c.props.iter().map(|v| v.to_bits()))
    }
}

/// The increment a call belongs to (table mode).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Increment {
    pub(super) kstep: i32,
    pub(super) kinc: i32,
    /// `TIME(2)`.
    pub(super) start: f64,
}

impl Increment {
    /// Whether this increment comes before `prev`: an earlier step, an earlier total time
    /// (beyond round-off) in the same step, or an earlier `KINC` at the same time.
    pub(super) fn goes_back_from(&self, prev: &Increment) -> bool {
        let roundoff = TIME_ROUNDOFF * prev.start.abs();
        self.kstep < prev.kstep
            || (self.kstep == prev.kstep
                && (self.start < prev.start - roundoff
                    || (self.start <= prev.start + roundoff && self.kinc < prev.kinc)))
    }
}

/// One integration point: its material and RVE instance, and what each mode keeps of it.
pub(super) struct Point {
    pub(super) id: u64,
    pub(super) key: MaterialKey,
    pub(super) material: Arc<Material>,
    pub(super) instance: Instance,
    /// Table mode: the host's increments as the point saw them.
    pub(super) table: TableTrack,
    /// `STATEV` mode: which of the host's values the instance caches.
    pub(super) statev: StatevTrack,
}

/// What table mode follows of a point (`table_mode.rs`): the increments, which commit or
/// revert the instance's trial.
#[derive(Default)]
pub(super) struct TableTrack {
    /// The increment of the last call.
    pub(super) increment: Option<Increment>,
    /// `DTIME` of the last call.
    pub(super) dtime: f64,
    /// The strain and answer of the instance's trial (`Some` exactly when it has one).
    pub(super) last: Option<([f64; 3], Response)>,
    /// The last call failed.
    pub(super) failed: bool,
}

/// What `STATEV` mode keeps of a point (`statev_mode.rs`): which values of the host the
/// instance's committed state and pending trial stand for; all `None` in table mode and
/// before the first call.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct StatevTrack {
    /// Hashes (`values_hash`, `statev_mode.rs`) of the values the committed state stands
    /// for (see [`Umat::statev_answer`](super::table::Umat::statev_answer)) and of the
    /// values written for the pending trial. The values themselves are not kept:
    /// [`Point::holds_core`] and [`Point::holds_trial`] re-encode the state.
    pub(super) core_hash: Option<u64>,
    pub(super) trial_hash: Option<u64>,
    /// The host's time the committed state and the pending trial were written at the end
    /// of (`statev::Core::time`).
    pub(super) core_time: Option<f64>,
    pub(super) trial_time: Option<f64>,
}

impl Point {
    /// A virgin point of `material`.
    pub(super) fn new(id: u64, key: MaterialKey, material: Arc<Material>) -> Self {
        Point {
            id,
            key,
            instance: Instance::new(material.model.clone()),
            material,
            table: TableTrack::default(),
            statev: StatevTrack::default(),
        }
    }
}

pub(super) type PointRef = Arc<Mutex<Point>>;

/// The point's lock; a point poisoned by a panic in an earlier call keeps its committed
/// state (only ever replaced whole) and drops its trial.
pub(super) fn lock<'p>(point: &'p PointRef, c: &UmatCall) -> crate::Result<MutexGuard<'p, Point>> {
    match point.try_lock() {
        Ok(p) => Ok(p),
        Err(TryLockError::WouldBlock) => Err(Error::HostConvention(format!(
            "element {}, point {} is being updated by another thread",
            c.noel, c.npt
        ))),
        Err(TryLockError::Poisoned(poisoned)) => {
            point.clear_poison();
            let mut p = poisoned.into_inner();
            p.instance.revert();
            p.table.last = None;
            p.table.failed = true;
            p.statev = StatevTrack::default();
            Ok(p)
        }
    }
}

/// The call's total strain `STRAN + DSTRAN` as the RVE's, for the point's model. The
/// lengths are `NTENS`, at most 6 (checked before a mode is chosen), so the sum is on the
/// stack; a longer `STRAN` goes as it is to the length check of
/// [`Hypothesis::rve_strain`](crate::host::Hypothesis::rve_strain).
pub(super) fn call_strain(p: &Point, c: &UmatCall) -> crate::Result<[f64; 3]> {
    let h = c.hypothesis;
    h.check_model(&p.material.model)?;
    let mut total = [0.0; 6];
    let n = c.stran.len().min(c.dstran.len());
    for (t, (a, b)) in total.iter_mut().zip(c.stran.iter().zip(c.dstran)) {
        *t = a + b;
    }
    h.rve_strain(total.get(..n).unwrap_or(c.stran))
}

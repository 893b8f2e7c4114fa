//! One integration point as both modes keep it ([`Point`]: the material a host names,
//! [`MaterialKey`], and its RVE instance), what a call writes of its answer
//! ([`Point::write_outputs`]), and the host's points by `(NOEL, NPT)` ([`PointMap`]),
//! each behind its own lock ([`lock`]).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError, RwLock, TryLockError};

use super::call::{request_step_ratio, trim, UmatCall, UmatOutputs};
use crate::error::Error;
use crate::host::diagnostics::{note_once, Note};
use crate::host::hypothesis::PlaneResponse;
use crate::host::material::Material;
use crate::host::mirrors::{mirrors, mirrors_of};
use crate::model::{Instance, Response};

/// Relative round-off of `TIME(2)` tolerated within one increment: CalculiX computes it
/// as `(t + dt) - dt`, which moves by an ulp when a cut-back changes `dt`.
pub(super) const TIME_ROUNDOFF: f64 = 1e-9;

/// The largest `PNEWDT` asked for an increment whose error exceeds `solver.step_tolerance`.
const TOLERANCE_CUT: f64 = 0.5;

/// A material as a host names it: `CMNAME` without padding, the bits of `PROPS`, and the
/// bits of `CELENT` (the element's length, which a regularized scene reads).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(super) struct MaterialKey {
    pub(super) cmname: String,
    props: Vec<u64>,
    celent: Option<u64>,
}

impl MaterialKey {
    pub(super) fn of(c: &UmatCall) -> Self {
        MaterialKey {
            cmname: trim(c.cmname).to_string(),
            props: c.props.iter().map(|v| v.to_bits()).collect(),
            celent: c.celent.map(f64::to_bits),
        }
    }

    /// This key without `CELENT`: the material before its element's length.
    pub(super) fn without_length(&self) -> Self {
        MaterialKey {
            celent: None,
            ..self.clone()
        }
    }

    /// Whether `c` names this material (compared in place: no allocation).
    pub(super) fn matches(&self, c: &UmatCall) -> bool {
        self.cmname == trim(c.cmname)
            && self.celent == c.celent.map(f64::to_bits)
            && self
                .props
                .iter()
                .copied()
                .eq(c.props.iter().map(|v| v.to_bits()))
    }
}

/// One integration point: its material (as the host named it) and RVE instance.
pub(super) struct Point {
    /// The point's id in the process (the first mirror).
    pub(super) id: u64,
    pub(super) key: MaterialKey,
    pub(super) material: Arc<Material>,
    pub(super) instance: Instance,
}

impl Point {
    /// A virgin point of `material`, which `c` names.
    pub(super) fn new(id: u64, c: &UmatCall, material: Arc<Material>) -> Self {
        Point {
            id,
            key: MaterialKey::of(c),
            instance: Instance::new(material.model.clone()),
            material,
        }
    }

    /// The call's total strain `STRAN + DSTRAN` as the RVE's, for the point's model. The
    /// lengths are `NTENS`, at most 6 (checked before a mode is chosen), so the sum is on
    /// the stack; a longer `STRAN` goes as it is to the length check of
    /// [`Hypothesis::rve_strain`](crate::host::Hypothesis::rve_strain).
    pub(super) fn strain(&self, c: &UmatCall) -> crate::Result<[f64; 3]> {
        let h = c.hypothesis;
        h.check_model(&self.material.model)?;
        let mut total = [0.0; 6];
        let n = c.stran.len().min(c.dstran.len());
        for (t, (a, b)) in total.iter_mut().zip(c.stran.iter().zip(c.dstran)) {
            *t = a + b;
        }
        h.rve_strain(total.get(..n).unwrap_or(c.stran))
    }

    /// Writes `STRESS`, `DDSDDE` and `STATEV`: `written` in `STATEV(1:len)` (in `STATEV`
    /// mode the values of the trial's core, or of a core shared from another point,
    /// encoded once by the mode; empty in table mode) and the inspection mirrors
    /// ([`crate::host::mirrors`]) after it, of the instance's trial or of
    /// `shared_history` (the shared core's history); `PNEWDT` < 1 when the answer depends
    /// on the increment's size.
    pub(super) fn write_outputs(
        &self,
        c: &UmatCall,
        r: &Response,
        out: &mut UmatOutputs,
        written: &[f64],
        shared_history: Option<&[f64]>,
    ) -> crate::Result<()> {
        let material = &self.material;
        let plane = PlaneResponse::from(r);
        let h = c.hypothesis;
        h.host_stress(&plane, out.stress)?;
        h.host_tangent(&plane, &material.elastic.tangent, out.ddsdde)?;
        out.statev[..written.len()].copy_from_slice(written);
        let mirrors_at = written.len();
        let room = out.statev.len() - mirrors_at;
        let (iterations, substeps) = (r.report.iterations, r.report.substeps);
        let mirrors = match shared_history {
            Some(history) => mirrors_of(
                self.id,
                iterations,
                substeps,
                (&material.model, history),
                room,
            ),
            None => mirrors(self.id, iterations, substeps, &self.instance, room),
        };
        for (s, m) in out.statev[mirrors_at..].iter_mut().zip(mirrors) {
            *s = m;
        }
        ask_for_smaller_step(c, r, out);
        Ok(())
    }
}

/// `PNEWDT` < 1 when the answer depends on the increment's size (`solver.step_check`) or
/// its integration error exceeds `solver.step_tolerance`, said once per process on
/// stderr. A ratio of 1 or more is never written: ccx takes any positive `PNEWDT` as a
/// request to redo the increment (`docs/calculix.md`); growth is the host's own rule.
fn ask_for_smaller_step(c: &UmatCall, r: &Response, out: &mut UmatOutputs) {
    let ratio = r.report.suggested_step_ratio();
    if r.report.exceeds_tolerance() && ratio < 1.0 {
        // At most half the increment: ccx allows few cut-backs of one increment (`*CONTROLS`,
        // 5 by default), which ratios of 0.8 or 0.9 spend without reaching the tolerance;
        // but not below `solver.smallest_step`, where ccx would grow back into a cut.
        let ratio = ratio.min(TOLERANCE_CUT).max(r.report.smallest_ratio);
        request_step_ratio(out.pnewdt, ratio);
        note_once(Note::Tolerance, || {
            format!(
                "mesorve: element {}, point {}: the increment's integration error is {:.3} \
                 times solver.step_tolerance: PNEWDT = {ratio:.3} asks for a smaller step \
                 (printed once)",
                c.noel,
                c.npt,
                r.report.error_estimate.unwrap_or(0.0)
            )
        });
    }
    if !r.report.step_too_large {
        return;
    }
    request_step_ratio(out.pnewdt, ratio);
    note_once(Note::StepSize, || {
        format!(
            "mesorve: element {}, point {}: the RVE's answer depends on the size of this \
             increment (one step landed beyond a snap-back that half steps take; \
             solver.step_check): PNEWDT = {ratio} asks for a smaller step (printed once)",
            c.noel, c.npt
        )
    });
}

/// A point of a [`PointMap`], locked by the call that answers it.
pub(super) type PointRef<P> = Arc<Mutex<P>>;

/// Shards of a [`PointMap`]: enough that threads on distinct points rarely take the same
/// shard's lock.
const SHARDS: usize = 64;

/// A host's points by `(NOEL, NPT)`. Points are only ever added, each behind its own
/// lock; the map is split into [`SHARDS`] shards by the key, so a lookup takes one
/// shard's read lock for the time of a hash lookup and threads calling distinct points
/// do not line up on one lock.
pub(super) struct PointMap<P> {
    shards: Box<[Shard<P>]>,
}

/// One shard of a [`PointMap`].
type Shard<P> = RwLock<HashMap<(i32, i32), PointRef<P>>>;

impl<P> PointMap<P> {
    pub(super) fn new() -> Self {
        PointMap {
            shards: (0..SHARDS).map(|_| RwLock::default()).collect(),
        }
    }

    /// The shard of `(noel, npt)`: the top bits of a multiplicative hash, which spreads
    /// consecutive element numbers over the shards.
    fn shard(&self, (noel, npt): (i32, i32)) -> &Shard<P> {
        let bits = (u64::from(noel as u32) << 32) | u64::from(npt as u32);
        let hash = bits.wrapping_mul(0x9e37_79b9_7f4a_7c15);
        &self.shards[(hash >> (64 - SHARDS.trailing_zeros())) as usize]
    }

    /// The point of the call's `(NOEL, NPT)`, if it exists.
    pub(super) fn get(&self, c: &UmatCall) -> Option<PointRef<P>> {
        let key = (c.noel, c.npt);
        let shard = self.shard(key).read();
        shard
            .unwrap_or_else(PoisonError::into_inner)
            .get(&key)
            .cloned()
    }

    /// The point of the call's `(NOEL, NPT)`, made by `make` if it does not exist.
    pub(super) fn get_or_insert(&self, c: &UmatCall, make: impl FnOnce() -> P) -> PointRef<P> {
        if let Some(p) = self.get(c) {
            return p;
        }
        let point = make();
        let key = (c.noel, c.npt);
        let mut shard = self
            .shard(key)
            .write()
            .unwrap_or_else(PoisonError::into_inner);
        shard
            .entry(key)
            .or_insert_with(|| Arc::new(Mutex::new(point)))
            .clone()
    }

    /// Points in the map.
    pub(super) fn len(&self) -> usize {
        self.shards
            .iter()
            .map(|s| s.read().unwrap_or_else(PoisonError::into_inner).len())
            .sum()
    }
}

/// The point's lock. Another thread holding it is refused (a host calls a point from one
/// thread at a time); a point poisoned by a panic in an earlier call is given back after
/// `recover`, which drops its trial (its committed state is only ever replaced whole).
pub(super) fn lock<'p, P>(
    point: &'p PointRef<P>,
    c: &UmatCall,
    recover: fn(&mut P),
) -> crate::Result<MutexGuard<'p, P>> {
    match point.try_lock() {
        Ok(p) => Ok(p),
        Err(TryLockError::WouldBlock) => Err(Error::HostConvention(format!(
            "element {}, point {} is being updated by another thread",
            c.noel, c.npt
        ))),
        Err(TryLockError::Poisoned(poisoned)) => {
            point.clear_poison();
            let mut p = poisoned.into_inner();
            recover(&mut p);
            Ok(p)
        }
    }
}

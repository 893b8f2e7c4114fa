//! The batch entry points: many instances updated in parallel with rayon, for hosts that
//! have no threads of their own. A translation over [`crate::model::batch`], the safe
//! batch API.

use std::ffi::c_char;

use super::guard::{copy_message, guard, slice, slice_mut, Failure, FfiResult};
use super::instance::{update_entry, RveHandle, RveReliability, RveTangentRequest};
use super::registry;
use super::status::RveStatus;
use crate::model::batch::{
    update_batch, BatchOutputs, BatchPoint, BatchStep, Failures, PointReport,
};
use crate::model::{Instance, Response};
use mesorve_core::solver::TangentRequest;

/// Per-point report of `rve_update_batch_timed`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RvePointReport {
    /// This point's `RveStatus` (`OK`, `SOLVER_FAILED`, ...).
    pub status: u32,
    /// Newton corrections, summed over sub-steps (as `RveInfo`).
    pub iterations: u32,
    /// Accepted sub-steps (as `RveInfo`).
    pub substeps: u32,
    /// Numeric factorizations of the RVE stiffness (as `RveInfo`).
    pub factorizations: u32,
    /// An `RveReliability` value.
    pub reliability: i32,
    /// 0: this point was solved itself; `k + 1`: its answer was taken from point `k` of
    /// this batch, corrected to first order (answer sharing: the scene's `[solver]
    /// share_tolerance` and a consistent tangent asked for; docs/sharing.md).
    pub shared_from: u32,
    /// < 1: redo the increment smaller; > 1: the next may be larger; 1 otherwise (on a
    /// failure: the solver's suggestion, 1 for a failure a smaller step does not mend).
    pub suggested_step_ratio: f64,
    /// The IMPL-EX step's integration error estimate relative to the step tolerance
    /// (`solver.step_tolerance`; above 1 the step exceeds it), 0 when none is estimated.
    pub error_estimate: f64,
    /// Out-of-plane stress `s_zz` (as `RveInfo`).
    pub s_zz: f64,
}

impl RvePointReport {
    fn new(r: &PointReport, status: RveStatus) -> Self {
        RvePointReport {
            status: status as u32,
            iterations: r.iterations,
            substeps: r.substeps,
            factorizations: r.factorizations,
            reliability: RveReliability::from(r.reliability) as i32,
            shared_from: r
                .shared_from
                .map_or(0, |k| u32::try_from(k + 1).unwrap_or(u32::MAX)),
            suggested_step_ratio: r.suggested_step_ratio,
            error_estimate: r.error_estimate,
            s_zz: r.s_zz,
        }
    }
}

/// A batch point named by a handle: looked up and locked when its turn comes.
struct HandlePoint(RveHandle);

impl BatchPoint for HandlePoint {
    type Error = Failure;
    fn with_instance<R>(&mut self, f: impl FnOnce(&mut Instance) -> R) -> Option<R> {
        let entry = registry::get(self.0).ok()?;
        let mut instance = entry.lock().ok()?;
        Some(f(&mut instance))
    }
    fn update_point(
        &mut self,
        strain: [f64; 3],
        dtime: f64,
        request: TangentRequest,
    ) -> FfiResult<Response> {
        let entry = registry::get(self.0)?;
        update_entry(&entry, strain, dtime, request)
    }
}

/// The checked arguments of a batch call.
struct Batch<'a> {
    points: Vec<HandlePoint>,
    strains: &'a [[f64; 3]],
    stresses: &'a mut [[f64; 3]],
    tangents: Option<&'a mut [[f64; 9]]>,
    step: BatchStep,
}

/// Checks the arguments common to both batch entries.
///
/// # Safety
/// As the entries: each non-NULL pointer points to memory of the documented size.
unsafe fn checked<'a>(
    handles: *const RveHandle,
    n: usize,
    strains: *const f64,
    stresses: *mut f64,
    tangents: *mut f64,
    (dtime, tangent_request, threads): (f64, i32, usize),
) -> FfiResult<Batch<'a>> {
    let request = RveTangentRequest::from_i32(tangent_request)?;
    if !dtime.is_finite() {
        return Err(Failure::new(
            RveStatus::InvalidArgument,
            format!("dtime {dtime} is not finite"),
        ));
    }
    let handles = slice(handles, n, "handles")?;
    let tangents = if request == RveTangentRequest::None {
        None
    } else {
        Some(slice_mut(tangents.cast::<[f64; 9]>(), n, "tangents")?)
    };
    Ok(Batch {
        points: handles.iter().map(|&h| HandlePoint(h)).collect(),
        strains: slice(strains.cast::<[f64; 3]>(), n, "strains")?,
        stresses: slice_mut(stresses.cast::<[f64; 3]>(), n, "stresses")?,
        tangents,
        step: BatchStep {
            dtime,
            request: request.into(),
            threads,
        },
    })
}

impl Batch<'_> {
    /// Runs the batch; each point's status and report, and the failures in index order.
    fn run(mut self) -> FfiResult<(Vec<PointReport>, Failures<Failure>)> {
        let mut reports = vec![PointReport::default(); self.points.len()];
        let out = BatchOutputs {
            stresses: self.stresses,
            tangents: self.tangents,
            reports: &mut reports,
        };
        let failures = update_batch(&mut self.points, self.strains, self.step, out)?;
        Ok((reports, failures))
    }
}

/// `BATCH_FAILED` with the first failed point's message (prefixed with its index), if any
/// failed.
fn outcome(failures: &[(usize, Failure)]) -> FfiResult<()> {
    match failures.first() {
        None => Ok(()),
        Some((k, f)) => Err(Failure::new(
            RveStatus::BatchFailed,
            format!("item {k}: {}", f.message),
        )),
    }
}

/// Each point's status: `OK` but for the failures.
fn statuses(n: usize, failures: &[(usize, Failure)]) -> Vec<RveStatus> {
    let mut s = vec![RveStatus::Ok; n];
    for (k, f) in failures {
        s[*k] = f.status;
    }
    s
}

/// Trial-updates `n` distinct instances: item `k` is `rve_update(handles[k],
/// &strains[3k], &stresses[3k], &tangents[9k], tangent_request)`, with the same units,
/// conventions and per-item rules (each item's outputs written only when `statuses[k]`
/// is `RVE_STATUS_OK`). `statuses[k]` receives each item's status. `tangents` may be
/// NULL only with `RVE_TANGENT_REQUEST_NONE`. Commit each item with `rve_commit`.
///
/// `nthreads`: 1 runs on the calling thread; `k > 1` uses a pool of `k` threads created
/// on first use and kept for the process; 0 uses rayon's global pool (one thread per
/// core, or `RAYON_NUM_THREADS`). The handles must be distinct: a handle given twice may
/// get `INSTANCE_BUSY`. Results do not depend on `nthreads` (bit-identical).
///
/// Returns `OK` when every item succeeded, `BATCH_FAILED` when at least one failed (its
/// message, prefixed with the item index, is the thread's last error), and
/// `NULL_ARGUMENT`, `INVALID_ARGUMENT` or `PANIC` when nothing was run (then
/// `statuses` is not written).
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_update_batch(
    handles: *const RveHandle,
    n: usize,
    strains: *const f64,
    stresses: *mut f64,
    tangents: *mut f64,
    statuses: *mut u32,
    tangent_request: i32,
    nthreads: usize,
) -> u32 {
    guard("rve_update_batch", || {
        let args = (0.0, tangent_request, nthreads);
        let batch = checked(handles, n, strains, stresses, tangents, args)?;
        let out = slice_mut(statuses, n, "statuses")?;
        let (_, failures) = batch.run()?;
        for (o, s) in out.iter_mut().zip(self::statuses(n, &failures)) {
            *o = s as u32;
        }
        outcome(&failures)
    }) as u32
}

/// Trial-updates `n` distinct instances over one host time increment `dtime` (as
/// `rve_update_timed`): `rve_update_batch` with `dtime` and a report per point.
///
/// - `reports`: `n` entries or NULL. Entry `k` receives point `k`'s status, its
///   iterations, sub-steps, factorizations, reliability, `suggested_step_ratio` and
///   `s_zz` (as `RveInfo`), and `error_estimate`: the IMPL-EX step's error estimate
///   relative to `solver.step_tolerance` (0 without one); `shared_from`: 0, or `k + 1`
///   when the point took point `k`'s answer (answer sharing, docs/sharing.md).
/// - `messages`: `n` buffers of `message_len` bytes each, point `k`'s at
///   `messages + k * message_len`: its failure's message, NUL-terminated and truncated
///   to `message_len - 1` bytes, or "" for a point that succeeded; or NULL (then
///   `message_len` is ignored). Nothing is written when `message_len` is 0.
///
/// Each point's stress and tangent are written only when it succeeded. `nthreads` and
/// the handles as `rve_update_batch`; the results do not depend on `nthreads` (bit for
/// bit) and, without `[solver] share_tolerance` in the instances' scene, equal
/// `rve_update_timed` of each point (bit for bit).
///
/// Returns `OK`, `BATCH_FAILED` (at least one point failed; the first one's message,
/// prefixed with its index, is the thread's last error), or `NULL_ARGUMENT`,
/// `INVALID_ARGUMENT` (tangent request, non-finite `dtime`) or `PANIC` when nothing was
/// run (then neither `reports` nor `messages` is written).
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn rve_update_batch_timed(
    handles: *const RveHandle,
    n: usize,
    strains: *const f64,
    dtime: f64,
    stresses: *mut f64,
    tangents: *mut f64,
    tangent_request: i32,
    reports: *mut RvePointReport,
    messages: *mut c_char,
    message_len: usize,
    nthreads: usize,
) -> u32 {
    guard("rve_update_batch_timed", || {
        let args = (dtime, tangent_request, nthreads);
        let batch = checked(handles, n, strains, stresses, tangents, args)?;
        let message_bytes = n
            .checked_mul(message_len)
            .ok_or_else(|| Failure::new(RveStatus::InvalidArgument, "n * message_len overflows"))?;
        let reports = (!reports.is_null())
            .then(|| slice_mut(reports, n, "reports"))
            .transpose()?;
        let messages = (!messages.is_null() && message_len > 0)
            .then(|| slice_mut(messages.cast::<u8>(), message_bytes, "messages"))
            .transpose()?;
        let (point_reports, failures) = batch.run()?;
        let status = statuses(n, &failures);
        if let Some(reports) = reports {
            for ((out, r), s) in reports.iter_mut().zip(&point_reports).zip(&status) {
                *out = RvePointReport::new(r, *s);
            }
        }
        if let Some(messages) = messages {
            write_messages(messages, message_len, &failures);
        }
        outcome(&failures)
    }) as u32
}

/// Writes "" to every point's message buffer, then each failure's message into its own.
fn write_messages(messages: &mut [u8], message_len: usize, failures: &[(usize, Failure)]) {
    for buf in messages.chunks_mut(message_len) {
        buf[0] = 0;
    }
    for (k, f) in failures {
        let buf = &mut messages[k * message_len..(k + 1) * message_len];
        // SAFETY: `buf` is `message_len` writable bytes of the checked buffer.
        unsafe { copy_message(&f.message, buf.as_mut_ptr(), message_len) };
    }
}

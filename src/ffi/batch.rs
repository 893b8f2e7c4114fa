//! The batch entry point: many instances updated in parallel with rayon, for hosts that
//! have no threads of their own.

use std::collections::HashMap;
use std::sync::{Arc, LazyLock, Mutex};

use rayon::prelude::*;

use super::boundary::{guard, slice, slice_mut, Failure, FfiResult};
use super::instance::{update_entry, RveHandle, RveTangentRequest};
use super::registry;
use super::status::RveStatus;

static POOLS: LazyLock<Mutex<HashMap<usize, Arc<rayon::ThreadPool>>>> =
    LazyLock::new(|| Mutex::new(HashMap::new()));

/// A pool of `n` threads, built once per size and kept for the process.
fn pool(n: usize) -> FfiResult<Arc<rayon::ThreadPool>> {
    let mut pools = POOLS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(p) = pools.get(&n) {
        return Ok(p.clone());
    }
    let p = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .thread_name(|i| format!("rve-batch-{i}"))
        .build()
        .map_err(|e| Failure::new(RveStatus::Internal, format!("thread pool: {e}")))?;
    let p = Arc::new(p);
    pools.insert(n, p.clone());
    Ok(p)
}

/// One item: the status and, on success, the outputs.
fn one(
    handle: RveHandle,
    strain: &[f64],
    stress: &mut [f64],
    tangent: Option<&mut [f64]>,
    request: RveTangentRequest,
) -> Result<(), Failure> {
    let entry = registry::get(handle)?;
    let strain: [f64; 3] = strain.try_into().expect("chunks of 3");
    let r = update_entry(&entry, strain, 0.0, request)?;
    stress.copy_from_slice(&r.stress);
    if let Some(t) = tangent {
        t.copy_from_slice(&r.tangent);
    }
    Ok(())
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
        let request = request_of(tangent_request)?;
        let too_long = || Failure::new(RveStatus::InvalidArgument, format!("n = {n} too large"));
        let n3 = n.checked_mul(3).ok_or_else(too_long)?;
        let n9 = n.checked_mul(9).ok_or_else(too_long)?;
        if n == 0 {
            return Ok(());
        }
        let items = Items {
            handles: slice(handles, n, "handles")?,
            strains: slice(strains, n3, "strains")?,
            request,
        };
        let stresses = slice_mut(stresses, n3, "stresses")?;
        let statuses = slice_mut(statuses, n, "statuses")?;
        let tangents = if request == RveTangentRequest::None {
            None
        } else {
            Some(slice_mut(tangents, n9, "tangents")?)
        };
        let results = items.run_all(stresses, tangents, nthreads)?;
        report(&results, statuses)
    }) as u32
}

/// The `tangent_request` argument of [`rve_update_batch`].
fn request_of(tangent_request: i32) -> FfiResult<RveTangentRequest> {
    match tangent_request {
        0 => Ok(RveTangentRequest::Consistent),
        1 => Ok(RveTangentRequest::None),
        2 => Ok(RveTangentRequest::Elastic),
        v => Err(Failure::new(
            RveStatus::InvalidArgument,
            format!("tangent_request {v} is not an RveTangentRequest"),
        )),
    }
}

/// The inputs of a batch: item `k` updates `handles[k]` to `strains[3k..3k + 3]`.
struct Items<'a> {
    handles: &'a [RveHandle],
    strains: &'a [f64],
    request: RveTangentRequest,
}

impl Items<'_> {
    /// Item `k` into its outputs; a panic in it becomes its status.
    fn run(
        &self,
        k: usize,
        stress: &mut [f64],
        tangent: Option<&mut [f64]>,
    ) -> Result<(), Failure> {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            one(
                self.handles[k],
                &self.strains[3 * k..3 * k + 3],
                stress,
                tangent,
                self.request,
            )
        }))
        .unwrap_or_else(|_| Err(Failure::new(RveStatus::Panic, "panic in batch item")))
    }

    /// Every item, on the calling thread (`nthreads` 1), rayon's global pool (0) or a
    /// pool of `nthreads`, into the chunks of `stresses` and `tangents` (3 and 9 values
    /// an item); the results in item order.
    fn run_all(
        &self,
        stresses: &mut [f64],
        mut tangents: Option<&mut [f64]>,
        nthreads: usize,
    ) -> FfiResult<Vec<Result<(), Failure>>> {
        let mut results: Vec<Result<(), Failure>> = Vec::with_capacity(self.handles.len());
        match nthreads {
            1 => {
                for (k, stress) in stresses.chunks_mut(3).enumerate() {
                    let t = tangents.as_deref_mut().map(|t| &mut t[9 * k..9 * k + 9]);
                    results.push(self.run(k, stress, t));
                }
            }
            _ => {
                let mut work = || {
                    let stress_chunks = stresses.par_chunks_mut(3).enumerate();
                    match tangents.as_deref_mut() {
                        Some(t) => stress_chunks
                            .zip(t.par_chunks_mut(9))
                            .map(|((k, s), t)| self.run(k, s, Some(t)))
                            .collect_into_vec(&mut results),
                        None => stress_chunks
                            .map(|(k, s)| self.run(k, s, None))
                            .collect_into_vec(&mut results),
                    }
                };
                if nthreads == 0 {
                    work();
                } else {
                    pool(nthreads)?.install(work);
                }
            }
        }
        Ok(results)
    }
}

/// Writes each item's status into `statuses`; `BATCH_FAILED` with the first failed item's
/// message (prefixed with its index) if any failed.
fn report(results: &[Result<(), Failure>], statuses: &mut [u32]) -> FfiResult<()> {
    let mut first = None;
    for (k, (r, s)) in results.iter().zip(statuses.iter_mut()).enumerate() {
        *s = match r {
            Ok(()) => RveStatus::Ok as u32,
            Err(f) => {
                first.get_or_insert((k, f));
                f.status as u32
            }
        };
    }
    match first {
        None => Ok(()),
        Some((k, f)) => Err(Failure::new(
            RveStatus::BatchFailed,
            format!("item {k}: {}", f.message),
        )),
    }
}

//! The material-point entry points: init, update, commit, revert, reset, free, state
//! save/load and the scene's strain path. Each translates its arguments and calls the
//! `model::Instance` behind the handle (trial/commit, checkpoint bytes) or its model.

use std::ffi::{c_char, CStr};
use std::path::Path;
use std::sync::Arc;

use super::guard::{guard, out, slice, slice_mut, Failure, FfiResult};
use super::registry::{self, Entry};
use super::status::RveStatus;
use crate::model::batch::{BatchPoint, PointReport, Reliability};
use crate::model::cache;
use crate::model::{Instance, Model, Response};
use mesorve_core::solver::TangentRequest;

/// An RVE instance handle: a 64-bit integer id into a process-wide table, not a pointer.
///
/// Why an id: it fits a Fortran `integer(c_int64_t)` and, being in `[2^32, 2^52)`, is
/// stored exactly in a `double` (a UMAT STATEV slot); and a stale or foreign value can
/// be checked instead of dereferenced. Every id carries a generation counter, so a freed
/// id never becomes valid again: using it gives `RVE_STATUS_BAD_HANDLE`, never undefined
/// behaviour. 0 is never a valid handle (`rve_free(0)` is a no-op). Ids are valid in the
/// process that created them only (save the state bytes to move an instance).
pub type RveHandle = i64;

/// What tangent `rve_update` returns (passed as an `int32_t`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RveTangentRequest {
    /// The consistent homogenized tangent `d stress / d strain` of the converged trial.
    Consistent = 0,
    /// No tangent: stress only (cheaper); `tangent` may be NULL and is not written.
    None = 1,
    /// The elastic tangent of the virgin RVE (shared by the model, costs nothing).
    Elastic = 2,
}

impl RveTangentRequest {
    pub(crate) fn from_i32(v: i32) -> FfiResult<Self> {
        Ok(match v {
            0 => RveTangentRequest::Consistent,
            1 => RveTangentRequest::None,
            2 => RveTangentRequest::Elastic,
            _ => {
                return Err(Failure::new(
                    RveStatus::InvalidArgument,
                    format!("tangent_request {v} is not an RveTangentRequest (0, 1 or 2)"),
                ))
            }
        })
    }
}

/// How far to trust an update (MGIS-style).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RveReliability {
    /// The update failed; only `suggested_step_ratio` is meaningful.
    Failed = 0,
    /// Converged to the scene's tolerance in one step.
    Reliable = 1,
    /// Converged to the scene's tolerance, but only after bisecting the increment
    /// (`substeps > 1`), or to an answer that depends on the increment's size (a step
    /// beyond a snap-back that half steps take, `solver.step_check`; then
    /// `suggested_step_ratio` is 0.5), or with an integration error above
    /// `solver.step_tolerance` (`suggested_step_ratio` < 1): the host's increments are
    /// large for this material state.
    Substepped = 2,
}

/// Extra outputs of `rve_update_ex`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RveInfo {
    /// Newton corrections, summed over sub-steps.
    pub iterations: u32,
    /// Accepted sub-steps (1 when the increment converged in one go).
    pub substeps: u32,
    /// Numeric factorizations of the RVE stiffness, including the tangent's.
    pub factorizations: u32,
    /// An `RveReliability` value.
    pub reliability: i32,
    /// Suggested ratio of the next macro increment to this one: < 1 after a solver
    /// failure, for an answer that depends on the step, or (`solver.step_tolerance`) for an
    /// increment whose integration error exceeds the tolerance: redo it that much
    /// smaller; > 1 (at most 2) under `solver.step_tolerance` when the error is well below
    /// it: the next increment may be that much larger; 1.0 otherwise.
    pub suggested_step_ratio: f64,
    /// Out-of-plane stress `s_zz` (plane strain; 0 in plane stress), stress units.
    pub s_zz: f64,
}

impl From<Reliability> for RveReliability {
    fn from(r: Reliability) -> Self {
        match r {
            Reliability::Failed => RveReliability::Failed,
            Reliability::Reliable => RveReliability::Reliable,
            Reliability::Substepped => RveReliability::Substepped,
        }
    }
}

impl RveInfo {
    fn from_report(r: &PointReport) -> Self {
        RveInfo {
            iterations: r.iterations,
            substeps: r.substeps,
            factorizations: r.factorizations,
            reliability: RveReliability::from(r.reliability) as i32,
            suggested_step_ratio: r.suggested_step_ratio,
            s_zz: r.s_zz,
        }
    }
}

impl From<RveTangentRequest> for TangentRequest {
    fn from(r: RveTangentRequest) -> Self {
        match r {
            RveTangentRequest::Consistent => TangentRequest::Consistent,
            RveTangentRequest::None => TangentRequest::None,
            RveTangentRequest::Elastic => TangentRequest::Elastic,
        }
    }
}

/// Safe core of an update, shared with the batch entry point.
pub(crate) fn update_entry(
    entry: &Arc<Entry>,
    strain: [f64; 3],
    dtime: f64,
    request: TangentRequest,
) -> FfiResult<Response> {
    Ok(entry.lock()?.update_point(strain, dtime, request)?)
}

fn new_instance(model: Arc<Model>, handle: &mut RveHandle) -> FfiResult {
    *handle = registry::insert(Entry::new(model))?;
    Ok(())
}

unsafe fn c_str<'a>(p: *const c_char, name: &str) -> FfiResult<&'a CStr> {
    if p.is_null() {
        Err(Failure::null(name))
    } else {
        Ok(CStr::from_ptr(p))
    }
}

#[cfg(unix)]
fn c_path(s: &CStr) -> FfiResult<&Path> {
    use std::os::unix::ffi::OsStrExt;
    Ok(Path::new(std::ffi::OsStr::from_bytes(s.to_bytes())))
}

#[cfg(not(unix))]
fn c_path(s: &CStr) -> FfiResult<&Path> {
    s.to_str()
        .map(Path::new)
        .map_err(|_| Failure::new(RveStatus::BadScene, "the path is not UTF-8"))
}

/// Creates an instance from the scene file `path` (NUL-terminated; TOML) and writes its
/// handle to `*out_handle`. Relative paths inside the scene (`geometry.file`) resolve
/// against the scene file's directory. Instances of one scene share one immutable model
/// (mesh, factorization pattern, elastic tangent): the scene is meshed once per process
/// while any of its instances lives. The new instance is in the virgin state.
///
/// Returns `RVE_STATUS_OK`, `NULL_ARGUMENT`, `BAD_SCENE` (unreadable, unparsable or
/// invalid scene), `MESH_FAILED`, or `PANIC`. `*out_handle` is written only on success.
/// The caller owns the instance and releases it with `rve_free`.
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_init_file(path: *const c_char, out_handle: *mut RveHandle) -> u32 {
    guard("rve_init_file", || {
        let path = c_path(c_str(path, "path")?)?;
        let out_handle = out(out_handle, "out_handle")?;
        new_instance(cache::model_for_file(path)?, out_handle)
    }) as u32
}

/// Creates an instance from scene text `toml_text` (NUL-terminated UTF-8 TOML, the
/// format of a scene file). Relative paths inside it resolve against `base_dir`
/// (NUL-terminated), or against the working directory when `base_dir` is NULL.
/// Instances created from the same text and base directory share one model.
///
/// Returns as `rve_init_file`; `*out_handle` is written only on success.
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_init_text(
    toml_text: *const c_char,
    base_dir: *const c_char,
    out_handle: *mut RveHandle,
) -> u32 {
    guard("rve_init_text", || {
        let text = c_str(toml_text, "toml_text")?
            .to_str()
            .map_err(|e| Failure::new(RveStatus::BadScene, format!("scene text: {e}")))?;
        let base = if base_dir.is_null() {
            None
        } else {
            Some(c_path(CStr::from_ptr(base_dir))?)
        };
        let out_handle = out(out_handle, "out_handle")?;
        new_instance(cache::model_for_text(text, base)?, out_handle)
    }) as u32
}

/// Creates a new virgin instance of the same model as `h` (no parsing, no meshing).
/// `*out_handle` is written only on success.
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_clone_model(h: RveHandle, out_handle: *mut RveHandle) -> u32 {
    guard("rve_clone_model", || {
        let out_handle = out(out_handle, "out_handle")?;
        let entry = registry::get(h)?;
        new_instance(entry.model.clone(), out_handle)
    }) as u32
}

/// Creates a new virgin instance of `h`'s scene regularized for a host element of
/// characteristic length `element_length` (the scene's length unit): the softening of the
/// cell's cracks is stretched by `L_cell / element_length`, so that an element crossed by
/// one crack dissipates the cell's fracture energy per unit crack length whatever its
/// size (docs/fracture.md). The scene must have `effects.regularization`. The instances
/// of one scene and length share one model; every length shares the scene's mesh and
/// per-thread workspaces. `*out_handle` is written only on success.
///
/// Returns `OK`, `NULL_ARGUMENT`, `BAD_HANDLE`, `BAD_SCENE` (a scene without
/// `effects.regularization`, a length that is not a positive number) or `PANIC`.
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size for the
/// duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_clone_for_element(
    h: RveHandle,
    element_length: f64,
    out_handle: *mut RveHandle,
) -> u32 {
    guard("rve_clone_for_element", || {
        let out_handle = out(out_handle, "out_handle")?;
        let entry = registry::get(h)?;
        new_instance(
            cache::regularized(&entry.model, element_length)?,
            out_handle,
        )
    }) as u32
}

/// Trial update with full outputs. Solves the RVE at the macro strain
/// `strain[3] = [eps_xx, eps_yy, gamma_xy]` (Voigt order, ENGINEERING shear
/// `gamma_xy = 2 eps_xy`, dimensionless) starting from the instance's committed state.
/// It never changes the committed state; calling it twice with the same strain gives
/// bit-identical results. `rve_commit` accepts it, a new `rve_update` replaces it.
///
/// Outputs (caller-owned):
/// - `stress[3]` = `[s_xx, s_yy, s_xy]` in the scene's stress units (paper: N/mm^2);
/// - `tangent[9]`, row-major: `tangent[3*i + j] = d stress_i / d strain_j`. A Fortran
///   caller reading it as `D(3,3)` sees the transpose (equal when symmetric). Its content
///   follows `tangent_request` (an `RveTangentRequest`): consistent, elastic, or not
///   written at all (`NONE`; then `tangent` may be NULL);
/// - `info` (may be NULL): iterations, sub-steps, reliability, PNEWDT and `s_zz`.
///
/// `stress` and `tangent` are written only on success. `info` is written on success and
/// on `RVE_STATUS_SOLVER_FAILED` (reliability `FAILED`, `suggested_step_ratio` < 1);
/// otherwise it is left untouched.
///
/// Returns `OK`, `NULL_ARGUMENT`, `BAD_HANDLE`, `INVALID_ARGUMENT` (tangent request),
/// `NON_FINITE_STRAIN`, `ABSURD_STRAIN` (`|component| > 0.1`), `SOLVER_FAILED`,
/// `INSTANCE_BUSY` (another thread is using this instance) or `PANIC`. After any failure
/// there is no trial to commit; the committed state is unchanged.
///
/// Starts no threads. Distinct instances may be updated concurrently from any threads;
/// each thread keeps one workspace per model.
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_update_ex(
    h: RveHandle,
    strain: *const f64,
    stress: *mut f64,
    tangent: *mut f64,
    tangent_request: i32,
    info: *mut RveInfo,
) -> u32 {
    update_core(
        "rve_update_ex",
        h,
        strain,
        0.0,
        stress,
        tangent,
        tangent_request,
        info,
    )
}

/// `rve_update_ex` over a host time increment `dtime` (the UMAT's `DTIME`, in the host's
/// time units). Same units, conventions, outputs, statuses and rules.
///
/// Implicit integration (`solver.integration = "implicit"`, the default) ignores `dtime`.
/// IMPL-EX (`"implex"`) extrapolates the interface history over this step in proportion to
/// `dtime / dtime_n`, `dtime_n` being the time increment of the step that led to the
/// committed state. `dtime <= 0` means "no time": the step counts as long as the last,
/// which is what `rve_update` and `rve_update_ex` pass. Non-finite `dtime`:
/// `INVALID_ARGUMENT`.
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn rve_update_timed(
    h: RveHandle,
    strain: *const f64,
    dtime: f64,
    stress: *mut f64,
    tangent: *mut f64,
    tangent_request: i32,
    info: *mut RveInfo,
) -> u32 {
    update_core(
        "rve_update_timed",
        h,
        strain,
        dtime,
        stress,
        tangent,
        tangent_request,
        info,
    )
}

/// The body of `rve_update_ex` and `rve_update_timed`.
#[allow(clippy::too_many_arguments)]
unsafe fn update_core(
    name: &str,
    h: RveHandle,
    strain: *const f64,
    dtime: f64,
    stress: *mut f64,
    tangent: *mut f64,
    tangent_request: i32,
    info: *mut RveInfo,
) -> u32 {
    guard(name, || {
        let args = (|| {
            let request = RveTangentRequest::from_i32(tangent_request)?;
            if !dtime.is_finite() {
                return Err(Failure::new(
                    RveStatus::InvalidArgument,
                    format!("dtime {dtime} is not finite"),
                ));
            }
            let strain: [f64; 3] = slice(strain, 3, "strain")?.try_into().expect("3");
            let stress = slice_mut(stress, 3, "stress")?;
            let tangent = if request == RveTangentRequest::None {
                None
            } else {
                Some(slice_mut(tangent, 9, "tangent")?)
            };
            Ok((request, strain, stress, tangent))
        })();
        let entry = registry::get(h);
        let (request, strain, stress, tangent) = match args {
            Ok(args) => args,
            Err(f) => {
                // After any failure there is no trial to commit, bad arguments included.
                if let Ok(mut instance) = entry
                    .as_ref()
                    .map_err(|_| ())
                    .and_then(|e| e.lock().map_err(|_| ()))
                {
                    instance.revert();
                }
                return Err(f);
            }
        };
        let entry = entry?;
        match update_entry(&entry, strain, dtime, request.into()) {
            Ok(r) => {
                stress.copy_from_slice(&r.stress);
                if let Some(t) = tangent {
                    t.copy_from_slice(&r.tangent);
                }
                if let Some(info) = info.as_mut() {
                    *info = RveInfo::from_report(&PointReport::from_response(&r));
                }
                Ok(())
            }
            Err(f) => {
                if let (Some(ratio), Some(info)) = (f.step_ratio, info.as_mut()) {
                    *info = RveInfo::from_report(&PointReport::failed(ratio));
                }
                Err(f)
            }
        }
    }) as u32
}

/// Trial update: `rve_update_ex` without `info`. Same units, conventions, statuses and
/// rules (stress and tangent written only on success; `tangent` may be NULL only with
/// `RVE_TANGENT_REQUEST_NONE`).
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_update(
    h: RveHandle,
    strain: *const f64,
    stress: *mut f64,
    tangent: *mut f64,
    tangent_request: i32,
) -> u32 {
    rve_update_ex(
        h,
        strain,
        stress,
        tangent,
        tangent_request,
        std::ptr::null_mut(),
    )
}

/// Runs `f` on the instance behind `h`, locked, inside the panic boundary.
fn with_instance(name: &str, h: RveHandle, f: impl FnOnce(&mut Instance) -> FfiResult) -> u32 {
    guard(name, || {
        let entry = registry::get(h)?;
        let mut instance = entry.lock()?;
        f(&mut instance)
    }) as u32
}

/// Accepts the last successful trial (`rve_update`) as the instance's new committed
/// state: the end of a macro increment. Returns `OK`, `BAD_HANDLE`, `NO_TRIAL` (no
/// successful update since the last commit, revert, reset or load; nothing changes),
/// `INSTANCE_BUSY` or `PANIC`.
#[no_mangle]
pub extern "C" fn rve_commit(h: RveHandle) -> u32 {
    with_instance("rve_commit", h, |i| {
        let ignored = i.ignored_redos().0;
        i.commit()?;
        if i.ignored_redos().0 > ignored {
            crate::host::umat::note_ignored_redo(i.ignored_redos().1);
        }
        Ok(())
    })
}

/// Discards the last trial; the committed state stays. Returns `OK`, `BAD_HANDLE`,
/// `INSTANCE_BUSY` or `PANIC`.
#[no_mangle]
pub extern "C" fn rve_revert(h: RveHandle) -> u32 {
    with_instance("rve_revert", h, |i| {
        i.revert();
        Ok(())
    })
}

/// Returns the instance to the virgin state (zero strain, undamaged) and discards the
/// trial. Returns `OK`, `BAD_HANDLE`, `INSTANCE_BUSY` or `PANIC`.
#[no_mangle]
pub extern "C" fn rve_reset(h: RveHandle) -> u32 {
    with_instance("rve_reset", h, |i| {
        i.reset();
        Ok(())
    })
}

/// Frees an instance; its handle never becomes valid again. `rve_free(0)` is a no-op
/// that returns `OK`. Returns `OK`, `BAD_HANDLE` (already freed or foreign),
/// `INSTANCE_BUSY` (another thread is using it; not freed) or `PANIC`. The model is
/// released with the last instance of its scene.
#[no_mangle]
pub extern "C" fn rve_free(h: RveHandle) -> u32 {
    guard("rve_free", || {
        if h != 0 {
            registry::remove(h)?;
        }
        Ok(())
    }) as u32
}

/// Writes to `*size` the number of bytes `rve_state_save` needs for the instance's
/// committed state. It depends on the state (the first updates with a tangent add the
/// predictor's sensitivity and path curvature): query it before each save. Returns `OK`,
/// `NULL_ARGUMENT`, `BAD_HANDLE`, `INSTANCE_BUSY` or `PANIC`; `*size` written on success.
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_state_size(h: RveHandle, size: *mut usize) -> u32 {
    guard("rve_state_size", || {
        let size = out(size, "size")?;
        let entry = registry::get(h)?;
        *size = entry.lock()?.state_size()?;
        Ok(())
    }) as u32
}

/// Writes to `*count` how many updates of the instance were answered without an RVE
/// solve since it was created: by the fast path (every interface point stays on the
/// linear branch of its last full solve: unloading to the origin or contact, the stress
/// is exactly `D_b eps`) or as a repeat of the pending trial at the same strain, bit for
/// bit. (`RveInfo` keeps its 0.2.0 layout, ABI 0; the difference of this count before
/// and after an update tells whether that update was fast.) Returns `OK`,
/// `NULL_ARGUMENT`, `BAD_HANDLE`, `INSTANCE_BUSY` or `PANIC`; `*count` written on success.
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_fast_updates(h: RveHandle, count: *mut u64) -> u32 {
    guard("rve_fast_updates", || {
        let count = out(count, "count")?;
        let entry = registry::get(h)?;
        *count = entry.lock()?.fast_updates();
        Ok(())
    }) as u32
}

/// Serialises the instance's committed state (not the trial) into `buf[0..len)`, in a
/// versioned byte format (checkpoint/restart; see `rve_state_load`), and writes the
/// byte count to `*written`. When `len` is too small nothing is written to `buf`,
/// `*written` receives the required size and the status is `BUFFER_TOO_SMALL`.
/// Returns `OK`, `NULL_ARGUMENT`, `BAD_HANDLE`, `BUFFER_TOO_SMALL`, `INSTANCE_BUSY` or
/// `PANIC`. The caller owns `buf`.
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_state_save(
    h: RveHandle,
    buf: *mut u8,
    len: usize,
    written: *mut usize,
) -> u32 {
    guard("rve_state_save", || {
        let written = out(written, "written")?;
        let entry = registry::get(h)?;
        let bytes = entry.lock()?.save_state()?;
        if bytes.len() > len {
            *written = bytes.len();
            return Err(Failure::new(
                RveStatus::BufferTooSmall,
                format!(
                    "the state needs {} bytes, the buffer has {len}",
                    bytes.len()
                ),
            ));
        }
        slice_mut(buf, bytes.len(), "buf")?.copy_from_slice(&bytes);
        *written = bytes.len();
        Ok(())
    }) as u32
}

/// Replaces the instance's committed state by the state in `buf[0..len)` (written by
/// `rve_state_save` for an instance of the same scene) and discards the trial. Refused,
/// with the instance unchanged, when the bytes are not a state or were corrupted (a
/// checksum covers every byte: `BAD_STATE`), come from an unsupported format version
/// (`STATE_VERSION`) or from a model of another scene (`STATE_MISMATCH`). Also
/// `NULL_ARGUMENT`, `BAD_HANDLE`, `INSTANCE_BUSY`, `PANIC`.
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_state_load(h: RveHandle, buf: *const u8, len: usize) -> u32 {
    guard("rve_state_load", || {
        let bytes = slice(buf, len, "buf")?;
        let entry = registry::get(h)?;
        entry.lock()?.load_state(bytes)?;
        Ok(())
    }) as u32
}

/// Writes the committed state of the instance (not the trial) as a VTK unstructured grid
/// (`.vtu`, ParaView) to the file `path` (NUL-terminated UTF-8; created or truncated):
/// the displacement, the strain and stress of each triangle, and the openings,
/// `delta/delta_c`, `delta_max/delta_c`, damage and branch of each ITZ element (the
/// arrays of `rve run --vtk`, see the README). Reads the instance only: its committed
/// state and trial are unchanged. Returns `OK`, `NULL_ARGUMENT`, `BAD_HANDLE`,
/// `WRITE_FAILED` (the file could not be created or written, e.g. an empty path or a
/// missing directory; `rve_last_error` names the path and the reason), `INSTANCE_BUSY`
/// or `PANIC`.
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_write_vtk(h: RveHandle, path: *const c_char) -> u32 {
    guard("rve_write_vtk", || {
        let path = c_path(c_str(path, "path")?)?;
        let entry = registry::get(h)?;
        let instance = entry.lock()?;
        instance
            .model()
            .write_vtu(instance.committed(), path)
            .map_err(|e| Failure::new(RveStatus::WriteFailed, e.to_string()))
    }) as u32
}

/// Writes to `*n` the number of increments of the scene's strain path (`[[path]]`
/// segments; 0 when the scene has none). Returns `OK`, `NULL_ARGUMENT`, `BAD_HANDLE` or
/// `PANIC`.
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_path_len(h: RveHandle, n: *mut usize) -> u32 {
    guard("rve_path_len", || {
        let n = out(n, "n")?;
        let entry = registry::get(h)?;
        *n = crate::scene::path_points(&entry.model.scene.spec.path).len();
        Ok(())
    }) as u32
}

/// Writes to `strain[3]` the macro strain of increment `i` (0-based, `i < rve_path_len`)
/// of the scene's strain path, exactly as `rve run` computes it (Voigt order, engineering
/// shear). Returns `OK`, `NULL_ARGUMENT`, `BAD_HANDLE`, `INVALID_ARGUMENT` (`i` out of
/// range) or `PANIC`; `strain` written only on success.
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_path_point(h: RveHandle, i: usize, strain: *mut f64) -> u32 {
    guard("rve_path_point", || {
        let strain = slice_mut(strain, 3, "strain")?;
        let entry = registry::get(h)?;
        let points = crate::scene::path_points(&entry.model.scene.spec.path);
        let p = points.get(i).ok_or_else(|| {
            Failure::new(
                RveStatus::InvalidArgument,
                format!(
                    "path increment {i} out of range (the path has {})",
                    points.len()
                ),
            )
        })?;
        strain.copy_from_slice(p);
        Ok(())
    }) as u32
}

/// Number of RVE models (meshes) this process has built through `rve_init_*`: a
/// diagnostic showing that instances of one scene share one model.
#[no_mangle]
pub extern "C" fn rve_model_builds() -> u64 {
    cache::model_builds()
}

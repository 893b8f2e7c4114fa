//! `rve_init`, the design card's name for creating an instance: a scene file, or the
//! embedded paper RVE when the path is NULL. A thin call to `rve_init_file` or
//! `rve_init_text`.

use std::ffi::{c_char, CString};
use std::sync::LazyLock;

use super::instance::{rve_init_file, rve_init_text, RveHandle};
use crate::scene::DEFAULT_SCENE_TOML;

/// The embedded scene as a C string (the TOML text has no NUL byte).
static DEFAULT_SCENE: LazyLock<CString> =
    LazyLock::new(|| CString::new(DEFAULT_SCENE_TOML).expect("scene text has no NUL byte"));

/// Creates an instance and writes its handle to `*out_handle`: from the scene file
/// `scene_path` (NUL-terminated; exactly `rve_init_file`), or, when `scene_path` is NULL,
/// from the paper's RVE embedded in the library (`scenes/paper_rve.toml`: section 5.2,
/// plane stress, periodic; the scene `rve run` uses by default). Instances of one scene
/// share one model.
///
/// Returns `OK`, `NULL_ARGUMENT` (`out_handle` is NULL), `BAD_SCENE`, `MESH_FAILED` or
/// `PANIC`. `*out_handle` is written only on success; release the instance with
/// `rve_free`.
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_init(scene_path: *const c_char, out_handle: *mut RveHandle) -> u32 {
    if scene_path.is_null() {
        rve_init_text(DEFAULT_SCENE.as_ptr(), std::ptr::null(), out_handle)
    } else {
        rve_init_file(scene_path, out_handle)
    }
}

//! The C interface: a thin translation layer over the safe Rust API. This is the only
//! module with `unsafe` code or `extern "C"` functions. A handle names one
//! [`crate::Instance`] in a process-wide table (`registry`); the entry points check their
//! arguments, call its methods and map [`crate::Error`] to an [`RveStatus`]. Every entry
//! point of `rve.h` is re-exported here, with `umat_` and `UMAT` (the UMAT's aliases).
//!
//! Conventions (also in the README and the header): handle first, then inputs, then
//! outputs; every function returns an `RveStatus` as `uint32_t` (except queries that
//! cannot fail); outputs are written only on success; every pointer is checked; every
//! function runs inside a panic boundary; the detailed message of the last failure on a
//! thread is `rve_last_error`.

mod abi_version;
mod batch;
mod guard;
mod init;
mod instance;
mod registry;
mod status;
mod umat;
mod version;

pub use crate::model::cache::model_builds;
pub use batch::{rve_update_batch, rve_update_batch_timed};
pub use guard::rve_last_error;
pub use init::rve_init;
pub use instance::{
    rve_clone_for_element, rve_clone_model, rve_commit, rve_fast_updates, rve_free, rve_init_file,
    rve_init_text, rve_model_builds, rve_path_len, rve_path_point, rve_reset, rve_revert,
    rve_state_load, rve_state_save, rve_state_size, rve_update, rve_update_ex, rve_update_timed,
    rve_write_vtk, RveHandle, RveInfo, RveReliability, RveTangentRequest,
};
pub use mesorve_core::state::STATE_FORMAT_VERSION;
pub use registry::live_instances;
pub use status::{rve_status_message, RveStatus, ALL_STATUSES};
pub use umat::{rve_umat, umat_, UMAT};
pub use version::{rve_abi_version, rve_version, rve_version_number};

pub use abi_version::ABI_VERSION;

/// The detailed message of the last failed call on this thread (Rust tests).
pub fn last_error_message() -> String {
    guard::last_error()
}

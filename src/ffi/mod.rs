//! The C interface: a thin translation layer over the safe Rust API. This is the only
//! module with `unsafe` code or `extern "C"` functions.

mod status;
mod version;

pub use status::{rve_status_message, RveStatus};
pub use version::{rve_version, rve_version_number};

/// ABI version: the suffix of the soname `librve.so.<ABI_VERSION>`, also the header's
/// `RVE_ABI_VERSION`. Bump on any incompatible change of the C interface.
pub const ABI_VERSION: u32 = 0;

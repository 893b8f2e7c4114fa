// The ABI version, declared once: `rve::ffi::ABI_VERSION` includes this file as a module
// and `build.rs` with `include!` (for the soname and the header's `RVE_ABI_VERSION`).

/// ABI version: the suffix of the soname `librve.so.<ABI_VERSION>`, also the header's
/// `RVE_ABI_VERSION`. Bump on any incompatible change of the C interface.
pub const ABI_VERSION: u32 = 0;

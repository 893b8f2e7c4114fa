//! Version queries.

use std::ffi::c_char;

/// NUL-terminated copy of the crate version for C.
static VERSION_CSTR: &str = concat!(env!("CARGO_PKG_VERSION"), "\0");

/// Returns the library version as a static NUL-terminated string `"major.minor.patch"`.
/// The pointer is valid for the lifetime of the process; the caller must not free it.
#[no_mangle]
pub extern "C" fn rve_version() -> *const c_char {
    VERSION_CSTR.as_ptr().cast()
}

/// Returns the version packed as `major * 10000 + minor * 100 + patch`.
#[no_mangle]
pub extern "C" fn rve_version_number() -> u32 {
    let parse = |s: &str| s.parse::<u32>().unwrap_or(0);
    parse(env!("CARGO_PKG_VERSION_MAJOR")) * 10000
        + parse(env!("CARGO_PKG_VERSION_MINOR")) * 100
        + parse(env!("CARGO_PKG_VERSION_PATCH"))
}

/// Returns the ABI version of the library (the soname suffix). A host compiled against
/// a header whose `RVE_ABI_VERSION` differs must not use this library.
#[no_mangle]
pub extern "C" fn rve_abi_version() -> u32 {
    super::ABI_VERSION
}

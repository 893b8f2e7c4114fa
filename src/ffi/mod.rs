//! The C interface: a thin translation layer over the safe Rust API. This is the only
//! module with `unsafe` code or `extern "C"` functions.

mod status;
mod version;

pub use status::RveStatus;

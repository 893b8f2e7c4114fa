//! The safe Rust API: a shared immutable [`Model`] per scene, a small [`Instance`] per
//! material point (its trial/commit lifecycle and its checkpoint bytes), and a per-thread
//! [`crate::state::Workspace`].

mod instance;
mod rve_model;

pub use instance::Instance;
pub use rve_model::{Model, Response};

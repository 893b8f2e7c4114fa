//! The safe Rust API: a shared immutable [`Model`] per scene, a small [`Instance`] per
//! material point, and a per-thread [`crate::state::Workspace`].

pub mod cache;
mod instance;
mod rve_model;
pub(crate) mod workspaces;

pub use instance::Instance;
pub use rve_model::{Model, Response, MAX_STRAIN};

//! The safe Rust API: a shared immutable [`Model`] per scene, a small [`Instance`] per
//! material point (its trial/commit lifecycle and its checkpoint bytes), and a per-thread
//! [`mesorve_core::solver::Workspace`]. `from_scene` is the edge where the scene schema becomes
//! the numerical modules' own types.

pub mod batch;
pub mod cache;
mod fingerprint;
mod from_scene;
mod instance;
mod microstructure;
pub mod mixed;
mod post;
mod rve_model;
pub mod share;
mod statev;
pub(crate) mod workspaces;

pub use batch::{update_batch, BatchOutputs, BatchPoint, BatchStep, PointReport, Reliability};
pub use instance::Instance;
pub use microstructure::build_microstructure;
pub use rve_model::{Model, Response};

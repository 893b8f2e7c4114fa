//! Per-instance state and per-thread workspace.

mod instance_state;
mod workspace;

pub use instance_state::{State, StateFormat1};
pub use workspace::Workspace;

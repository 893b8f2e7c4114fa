//! Per-instance state and per-thread workspace.

mod instance_state;
mod workspace;

pub use instance_state::{Sensitivity, State, StateFormat1, StateFormat2};
pub use workspace::Workspace;

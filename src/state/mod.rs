//! Per-instance state, its checkpoint bytes ([`persist`]) and the per-thread workspace.

mod instance_state;
pub mod persist;
mod workspace;

pub use instance_state::{PathCurvature, Quantized, Sensitivity, State, SENSITIVITY_BLOCK};
pub use persist::{StateSizes, STATE_FORMAT_VERSION};
pub use workspace::Workspace;

//! Per-instance state and per-thread workspace.

mod instance_state;
mod workspace;

pub use instance_state::{
    PathCurvature, Quantized, Sensitivity, State, StateFormat1, StateFormat2, StateFormat3,
    StateFormat4, SENSITIVITY_BLOCK,
};
pub use workspace::Workspace;

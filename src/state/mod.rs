//! The small state an RVE instance owns and its checkpoint bytes ([`persist`]); the
//! per-thread workspace is the solver's.

mod instance_state;
pub mod persist;

pub use instance_state::{PathCurvature, Quantized, Sensitivity, State, SENSITIVITY_BLOCK};
pub use persist::{StateSizes, STATE_FORMAT_VERSION};

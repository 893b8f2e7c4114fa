//! The small state an RVE instance owns (the per-thread workspace is the solver's).

mod instance_state;

pub use instance_state::{
    PathCurvature, Quantized, Sensitivity, State, StateFormat1, StateFormat2, StateFormat3,
    StateFormat4, SENSITIVITY_BLOCK,
};

//! The small state an RVE instance owns and its checkpoint bytes ([`persist`]); the
//! per-thread workspace is the solver's.

mod instance_state;
mod linear_branch;
pub mod persist;
pub mod statev;

pub use instance_state::{held_contact_words, PathCurvature, Quantized, State};
pub use instance_state::{ImplexHistory, Sensitivity, SENSITIVITY_BLOCK};
pub use linear_branch::{LinearBranch, JUMP_OPERATOR_LEN};
pub use persist::{StateSizes, STATE_FORMAT_VERSION};
pub use statev::{Core, CoreView};

//! Bulk materials (placeholder until the kernels branch lands).
use serde::{Deserialize, Serialize};
/// Plane state of the 2D analysis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Analysis {
    PlaneStrain,
    PlaneStress,
}

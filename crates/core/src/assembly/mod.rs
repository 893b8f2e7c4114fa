//! Assembly of the RVE equilibrium system into one fixed sparsity pattern per model.

mod discretization;
mod laws;
mod pattern;

pub use discretization::{Discretization, DiscretizationSpec, SystemEvaluation};
pub use laws::InterfaceLaws;

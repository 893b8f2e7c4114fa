//! Assembly of the RVE equilibrium system into one fixed sparsity pattern per model.

mod discretization;
mod pattern;

pub use discretization::{Discretization, DiscretizationSpec, SystemEvaluation};

//! Solution of the RVE equilibrium problem: sparse LU, Newton-Raphson with line search,
//! sub-stepping of the macro strain increment, and the consistent homogenized tangent.

mod arclength;
mod linear;
mod newton;

pub use linear::{FactorKind, LinearSolver, NumericFactor};
pub use newton::{solve_increment, IncrementReport, Problem, TangentRequest};

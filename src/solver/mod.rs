//! Solution of the RVE equilibrium problem at a macro strain: the problem's residual and
//! tangent (`problem`), sparse factorizations (`linear`), the predictor, the Newton kernel,
//! path following (`arclength`), the condensed tangent, and the sub-stepping driver with
//! its remedy ladder (`increment`) above them. The per-thread `workspace` holds every
//! buffer, so a solve allocates nothing.
//!
//! Dependencies inside: `increment -> {predictor, newton, arclength, tangent}`,
//! `arclength -> newton`, all of them `-> contact -> problem -> {linear, workspace,
//! settings}`.

mod arclength;
mod contact;
mod increment;
mod linear;
mod newton;
mod predictor;
mod problem;
mod settings;
mod tangent;
mod workspace;

pub use increment::{solve_increment, Solved};
pub use linear::{FactorKind, LinearSolver, NumericFactor};
pub use problem::{Problem, Strain};
pub use settings::{ContactStatus, IncrementReport, Settings, TangentRequest};
pub use workspace::{Factorization, Workspace};

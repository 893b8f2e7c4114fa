//! Solution of the RVE equilibrium problem at a macro strain: the problem's residual and
//! tangent (`problem`), sparse direct factorizations (`sparse_direct`), the predictor, the
//! Newton kernel, path following (`arclength`), the condensed tangent, and the
//! sub-stepping driver with its remedy ladder (`increment`) above them. The per-thread `workspace` holds every
//! buffer, so a solve allocates nothing.
//!
//! The fast path (`fast_path`) answers updates that keep every interface point on its
//! linear branch without any of them.
//!
//! Dependencies inside: `increment -> {fast_path, predictor, newton, arclength, tangent}`,
//! `arclength -> newton`, all of them `-> contact -> problem -> {sparse_direct, workspace,
//! settings}`.

mod arclength;
mod contact;
pub mod fast_path;
pub mod implex;
mod increment;
mod lu;
mod newton;
mod predictor;
mod problem;
mod settings;
mod sparse_direct;
pub mod step_check;
mod supernodal_solve;
mod tangent;
mod workspace;

pub use increment::solve_increment;
pub use increment::Solved;
pub use newton::equilibrium_unknowns;
pub use problem::Problem;
pub use problem::Strain;
pub use settings::{Answer, ContactStatus, IncrementReport, Integration, Settings, TangentRequest};
pub use sparse_direct::{FactorKind, LinearSolver};
pub use sparse_direct::{FactorMethod, NumericFactor};
pub use workspace::Workspace;
pub use workspace::{FactorUse, Factorization};

//! mesorve: a mesoscale Representative Volume Element (RVE) of concrete -- matrix,
//! aggregates and cohesive-contact interfaces (ITZ) -- behind a UMAT-style material-point
//! interface. The physics follows Pituba & Souza Neto (2015), "Modeling of unilateral
//! effect in brittle materials by a mesoscopic scale approach"; equation numbers in the
//! doc comments refer to that paper.
//!
//! Dependencies flow one way:
//! `ffi -> host -> model -> {homogenization, solver, assembly, constraint} -> {element, material, interface, mesh}`,
//! with `scene` describing everything and `geometry` producing microstructures.

pub mod assembly;
pub mod cli;
pub mod constraint;
pub mod element;
pub mod error;
pub mod ffi;
pub mod geometry;
pub mod homogenization;
pub mod host;
pub mod interface;
pub mod io;
pub mod material;
pub mod mesh;
pub mod model;
pub mod scene;
pub mod solver;
pub mod state;

pub use error::{Error, Result};
pub use model::{Instance, Model, Response};
pub use scene::Scene;
pub use solver::TangentRequest;
pub use state::{State, Workspace};

/// The crate version, `major.minor.patch`, as in Cargo.toml.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

//! mesorve: a mesoscale Representative Volume Element (RVE) of concrete -- matrix,
//! aggregates and cohesive-contact interfaces (ITZ) -- behind a UMAT-style material-point
//! interface. The physics follows Pituba & Souza Neto (2015), "Modeling of unilateral
//! effect in brittle materials by a mesoscopic scale approach"; equation numbers in the
//! doc comments refer to that paper.
//!
//! The safe API is [`Model`] (one per scene, shared) and [`Instance`] (one per material
//! point: the trial/commit lifecycle and checkpoint bytes, see [`state::persist`]); the C
//! interface in [`ffi`] is a thin translation over it. The command-line tool (`src/cli/`)
//! is a module of the `rve` binary, not of this library, so `librve.so` does not link
//! clap.
//!
//! Dependencies flow one way (`tests/layers.rs` fails on an import against this order):
//!
//! ```text
//! ffi -> host -> model -> {scene, io, solver, homogenization} -> assembly -> constraint
//!     -> {mesh, element, state} -> {geometry, material, interface} -> error
//! ```
//!
//! `model` is the edge where the scene schema becomes the numerical modules' own types
//! (`model::from_scene`); no numerical module reads `scene`.
//!
//! `unsafe` code is denied everywhere but in [`ffi`], the C boundary.

#![deny(unsafe_code)]

pub(crate) mod assembly;
pub mod constraint;
pub mod element;
pub mod error;
#[allow(unsafe_code)]
pub mod ffi;
pub mod geometry;
pub(crate) mod homogenization;
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
pub use scene::{Scene, MAX_STRAIN};
pub use solver::TangentRequest;
pub use solver::Workspace;
pub use state::{State, STATE_FORMAT_VERSION};

/// The crate version, `major.minor.patch`, as in Cargo.toml.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

//! mesorve: a mesoscale Representative Volume Element (RVE) of concrete -- matrix,
//! aggregates and cohesive-contact interfaces (ITZ) -- behind a UMAT-style material-point
//! interface. The physics follows Pituba & Souza Neto (2015), "Modeling of unilateral
//! effect in brittle materials by a mesoscopic scale approach"; equation numbers in the
//! doc comments refer to that paper.
//!
//! # The Rust API
//!
//! - [`Scene`]: what to build (a TOML file, [`Scene::embedded_default`], or a text).
//! - [`Model`]: one per scene, immutable, shared by all the points of that material
//!   (`Arc<Model>`): mesh, sparsity pattern, symbolic factorizations, elastic tangent.
//! - [`Instance`]: one per material point, small: the committed state, the trial/commit
//!   lifecycle ([`Instance::update`], [`Instance::update_timed`], [`Instance::commit`],
//!   [`Instance::revert`]) and checkpoint bytes ([`persist`]).
//! - [`Workspace`]: one per thread, reused by every update on that thread, so the update
//!   allocates nothing.
//! - [`Response`]: the homogenized stress `[s_xx, s_yy, s_xy]`, the consistent tangent
//!   (row-major, engineering shear strain) and an [`IncrementReport`].
//! - Errors are [`Error`], typed, each carrying its context.
//!
//! The modules [`ffi`] (the C interface, a thin translation over this API), [`host`] (the
//! UMAT's translation of host tensor layouts and `STATEV`), [`io`] (VTK and SVG output),
//! [`scene`] (the schema) and [`model`] are public too. The numerical core (mesh,
//! elements, interface laws, constraints, assembly, solver, homogenization, state) is the
//! crate `mesorve-core`; this crate re-exports the part of it users program against.
//!
//! ```
//! use std::sync::Arc;
//! use rve::{Instance, Model, Scene, TangentRequest};
//!
//! let scene = Scene::embedded_default()?; // the paper's RVE (section 5.2)
//! let model = Arc::new(Model::from_scene(&scene)?); // meshed once, shared by points
//! let mut workspace = model.workspace(); // one per thread
//! let mut point = Instance::new(model.clone()); // one per integration point
//! let mut last = 0.0;
//! for k in 1..=5 {
//!     let strain = [2e-5 * k as f64, 0.0, 0.0]; // [eps_xx, eps_yy, gamma_xy]
//!     let response = point.update(strain, &mut workspace, TangentRequest::Consistent)?;
//!     point.commit()?; // the host's increment converged
//!     assert!(response.stress[0] > last); // elastic range: the stress grows
//!     last = response.stress[0];
//! }
//! // The ITZ softens from the first opening (eq. 23): below the virgin RVE's response.
//! let d11 = model.elastic_tangent()[0];
//! assert!(last < d11 * 1e-4 && last > 0.5 * d11 * 1e-4);
//! # Ok::<(), rve::Error>(())
//! ```
//!
//! # Structure
//!
//! The workspace's crates are its layers (docs/architecture.md): `mesorve-core` (the
//! numerics) below this crate (scene, model, host, ffi: `librve.so`), and the `rve` tool
//! (`crates/cli`) above it, the only crate that links clap. Inside this crate dependencies
//! flow one way (`tests/layers.rs` fails on an import against this order):
//!
//! ```text
//! ffi -> host -> model -> scene -> io
//! ```
//!
//! `model` is the edge where the scene schema becomes the core's own types
//! (`model::from_scene`); the core never reads a scene.
//!
//! `unsafe` code is denied everywhere but in [`ffi`], the C boundary.

#![deny(unsafe_code)]

pub use mesorve_core::error;
#[allow(unsafe_code)]
pub mod ffi;
pub mod host;
pub mod io;
pub mod model;
pub mod scene;

pub use error::{Error, Result};
pub use mesorve_core::material::Analysis;
pub use mesorve_core::mesh::MeshStats;
pub use mesorve_core::solver::{
    Answer, FactorKind, IncrementReport, Integration, TangentRequest, Workspace,
};
pub use mesorve_core::state::{persist, Quantized, State, StateSizes, STATE_FORMAT_VERSION};
pub use model::{Instance, Model, Response};
pub use scene::{Scene, MAX_STRAIN};

/// The crate version, `major.minor.patch`, as in Cargo.toml.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

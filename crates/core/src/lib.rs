//! mesorve's numerical core: everything below the scene. The mesh of a cell and its ITZ,
//! the element kernels, the interface laws, the boundary conditions as constraints, the
//! assembled problem, the solvers (Newton, path following, IMPL-EX, the fast path), the
//! homogenization (eqs. 6 and 18 of Pituba & Souza Neto 2015) and the state a material
//! point owns. The `mesorve` crate builds models and instances from scenes on top of it
//! and puts the C interface in front; this crate knows no scene, host or C.
//!
//! Its public items are the verification surface as well: the tests and benches of the
//! workspace check the kernels, laws and factorizations through them (finite-difference
//! tangents, patch tests, closed forms). They carry no compatibility promise beyond the
//! workspace: library users program against `mesorve` (`rve`), which re-exports what it
//! supports.
//!
//! Dependencies flow one way inside the crate (`tests/layers.rs` checks it):
//!
//! ```text
//! {solver, homogenization} -> assembly -> constraint -> {mesh, element, state}
//!     -> {geometry, material, interface} -> error
//! ```

#![deny(unsafe_code)]

pub mod assembly;
pub mod constraint;
pub mod element;
pub mod error;
pub mod geometry;
pub mod homogenization;
pub mod interface;
pub mod material;
pub mod mesh;
pub mod solver;
pub mod state;

pub use error::{Error, Result};

//! Meshes: the data model, triangulation of a microstructure, Gmsh import, ITZ insertion.

pub mod gmsh;
mod model;

pub use model::{BoundaryNodes, InterfaceElement, Mesh, Phase, PhaseMesh, Triangle};

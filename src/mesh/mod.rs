//! Meshes: the data model, triangulation of a microstructure, Gmsh import, ITZ insertion.

mod boundary;
pub mod gmsh;
mod itz;
mod model;
mod stats;
mod triangulate;

pub use boundary::{find_boundary_nodes, find_boundary_nodes_split};
pub use itz::{insert_itz, without_itz};
pub use model::{
    BoundaryNodes, InterfaceElement, Mesh, Microstructure, Phase, PhaseMesh, Triangle,
};
pub use stats::{triangle_angles_deg, MeshStats};
pub use triangulate::{triangulate, triangulate_straight_interface};

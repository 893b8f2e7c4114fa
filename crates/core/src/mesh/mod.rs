//! Meshes: the data model, triangulation of a microstructure, Gmsh import, the insertion
//! of interface elements on the ITZ (and along the paste's edges: cracks).

mod boundary;
mod cracks;
pub mod gmsh;
mod itz;
mod model;
mod stats;
mod triangulate;

pub use boundary::{find_boundary_nodes, find_boundary_nodes_split};
pub use cracks::insert_cracks;
pub use itz::{insert_itz, without_itz};
pub use model::BoundaryNodes;
pub use model::{
    InterfaceElement, InterfaceKind, Mesh, Microstructure, Phase, PhaseMesh, Triangle,
};
pub use stats::triangle_angles_deg;
pub use stats::MeshStats;
pub use triangulate::{triangulate, triangulate_straight_interface};

/// Most triangles an RVE mesh may have, generated (scene validation refuses a `mesh.size`
/// that would give more) or imported from Gmsh.
pub const MAX_TRIANGLES: usize = 2_000_000;

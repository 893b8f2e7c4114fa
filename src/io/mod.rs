//! Writers: VTK unstructured grids for ParaView and SVG pictures of meshes, and the micro
//! fields of a state they show.

mod fields;
mod svg;
mod vtk;

pub use fields::{ItzFields, RveFields, BRANCH_CONTACT, BRANCH_LOADING, BRANCH_UNLOADING};
pub use svg::write_svg;
pub use vtk::{write_pvd, write_vtu, write_vtu_fields};

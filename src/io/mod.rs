//! Writers: VTK unstructured grids for ParaView and SVG pictures of meshes, and the micro
//! fields of a state they show.

mod fields;
mod svg;
mod vtk;

pub use fields::{ItzFields, RveFields, BRANCH_CONTACT, BRANCH_LOADING, BRANCH_UNLOADING};
pub use svg::{amplification, write_deformed_svg, write_response_svg, write_svg, ResponsePoint};
pub use vtk::{write_pvd, write_vtu, write_vtu_fields};

//! Writers: VTK unstructured grids for ParaView and SVG pictures of meshes.

mod svg;
mod vtk;

pub use svg::write_svg;
pub use vtk::write_vtu;

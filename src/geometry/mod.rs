//! Microstructures: inclusion shapes and their placement in the cell.

mod placement;
pub mod polygon;
mod shape;

pub use placement::{build_inclusions, place_random, Placement};
pub use shape::Inclusion;

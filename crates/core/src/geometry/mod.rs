//! Microstructures: inclusion shapes and their placement in the cell.

mod placement;
pub mod polygon;
mod shape;
mod spec;

pub use placement::Placement;
pub use placement::{build_inclusions, place_random};
pub use shape::Inclusion;
pub use spec::RandomWord;
pub use spec::{Explicit, ExplicitInclusion, Orientation, RandomSpec, ShapeKind};

//! Microstructures: inclusion shapes and their placement in the cell.

mod placement;
pub mod polygon;
mod shape;
mod spec;

pub use placement::{build_inclusions, place_random};
#[cfg(any(test, feature = "internals"))]
pub use placement::Placement;
pub use shape::Inclusion;
pub use spec::{Explicit, ExplicitInclusion, Orientation, RandomSpec, ShapeKind};
#[cfg(any(test, feature = "internals"))]
pub use spec::RandomWord;

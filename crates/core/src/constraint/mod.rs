//! Boundary conditions on the displacement fluctuation, as a map from mesh dofs to the
//! unknowns of one fixed linear system per model.

mod dof_map;

pub use dof_map::{BoundaryCondition, DofMap, FIXED};

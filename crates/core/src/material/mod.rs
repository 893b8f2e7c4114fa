//! Bulk constitutive laws of the matrix and aggregate triangles.

mod elastic;

pub use elastic::{Analysis, IsotropicElastic};

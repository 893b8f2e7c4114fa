//! Homogenized stress (eq. 6) and consistent tangent (eq. 18).

mod operators;

pub use operators::Homogenizer;

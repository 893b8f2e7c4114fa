//! Element kernels: the constant-strain bulk triangle and the 4-node zero-thickness
//! cohesive-contact interface element. Pure, fixed-size, allocation free.

pub mod interface4;
pub mod triangle;

pub use interface4::{InterfaceGeometry, InterfaceQuadrature};
pub use interface4::{InterfaceResponse, MAX_POINTS};

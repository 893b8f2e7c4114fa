//! Element kernels: the constant-strain bulk triangle and the 4-node zero-thickness
//! cohesive-contact interface element. Pure, fixed-size, allocation free.

pub mod triangle;

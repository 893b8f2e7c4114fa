//! Constitutive laws of the zero-thickness interfaces (ITZ): the cohesive-contact law.

mod cohesive;

pub use cohesive::{Branch, CohesiveHistory, CohesiveLaw, CohesivePoint, ContactShear, Penalty};

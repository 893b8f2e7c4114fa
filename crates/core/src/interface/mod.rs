//! Constitutive laws of the zero-thickness interfaces (ITZ), behind the [`InterfaceLaw`]
//! trait: the paper's cohesive-contact law and a linear elastic interface.

mod cohesive;
mod implex;
mod law;
mod linear;

pub use cohesive::{CohesiveHistory, CohesivePoint};
pub use cohesive::{CohesiveLaw, ContactShear, Penalty};
pub use cohesive::{ItzSpec, PenaltySpec};
pub use implex::Implex;
pub use law::{Branch, InterfaceLaw, InterfaceLawSpec, LawPoint, PointMeasures, TangentKind};
pub use linear::LinearInterface;
pub use linear::LinearItzSpec;

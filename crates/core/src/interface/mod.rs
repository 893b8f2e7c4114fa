//! Constitutive laws of the zero-thickness interfaces, behind the [`InterfaceLaw`] trait:
//! the paper's cohesive-contact law of the ITZ, a linear elastic interface, and the law of
//! a crack through the paste (stiff to its strength, then Hordijk's softening), and Coulomb
//! friction on the closed cracks of either.

mod cohesive;
mod crack;
mod friction;
mod implex;
mod law;
mod linear;

pub use cohesive::{CohesiveHistory, CohesivePoint};
pub use cohesive::{CohesiveLaw, ContactShear, Penalty};
pub use cohesive::{ItzSpec, PenaltySpec};
pub use crack::{CrackLaw, CrackSpec, RESIDUAL, STIFFNESS_FACTOR};
pub use friction::{Coulomb, FrictionPoint, Frictional};
pub use implex::Implex;
pub use law::{Branch, InterfaceLaw, InterfaceLawSpec, LawPoint, PointMeasures, TangentKind};
pub use linear::LinearInterface;
pub use linear::LinearItzSpec;

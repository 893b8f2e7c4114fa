//! Scenes: the TOML description of an RVE (cell, geometry, mesh, materials, effects,
//! boundary condition, solver settings, strain path), its loading, its validation and the
//! strain points of its path (with the strain bound [`MAX_STRAIN`] that validation and
//! the model's updates share).

mod load;
mod path;
mod schema;
mod validate;

pub use load::{Scene, DEFAULT_SCENE_NAME, DEFAULT_SCENE_TOML};
pub use mesorve_core::geometry::{Explicit, ExplicitInclusion, Orientation, RandomSpec, ShapeKind};
pub use path::{path_points, path_zero_stress, MAX_STRAIN};
pub use schema::{
    BoundaryKind, BoundarySpec, CellSpec, ContactStatusSpec, CrackSpec, EffectsSpec, ElasticSpec,
    GeometrySpec, GmshSpec, IntegrationSpec, InterfaceQuadratureSpec, ItzSpec, LinearItzSpec,
    MaterialsSpec, MeshSpec, PathSegment, PenaltySpec, SceneSpec, SolverSpec, StatevSpec,
    StraightInterfaceSpec, ZeroAtStrain, ZeroStress,
};
pub use validate::{MAX_PATH_INCREMENTS, MAX_TRIANGLES};

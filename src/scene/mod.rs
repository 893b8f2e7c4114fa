//! Scenes: the TOML description of an RVE (cell, geometry, mesh, materials, effects,
//! boundary condition, solver settings, strain path), its loading and its validation.

mod load;
mod schema;
mod validate;

pub use load::{Scene, DEFAULT_SCENE_NAME, DEFAULT_SCENE_TOML};
pub use schema::{
    BoundaryKind, BoundarySpec, CellSpec, EffectsSpec, ElasticSpec, Explicit, ExplicitInclusion,
    GeometrySpec, GmshSpec, InterfaceQuadratureSpec, ItzSpec, LinearItzSpec, MaterialsSpec,
    MeshSpec, Orientation, PathSegment, PenaltySpec, RandomSpec, SceneSpec, ShapeKind, SolverSpec,
    StraightInterfaceSpec,
};

//! The edge between the scene schema and the numerics: the solver settings and the
//! interface law that a scene describes, in the numerical modules' own types. The law
//! comes from its own scene table (`interface::InterfaceLawSpec`, registered in
//! `scene::MaterialsSpec::interface_laws`); the boundary condition is its scene value.

use std::sync::Arc;

use crate::interface::InterfaceLaw;
use crate::scene::{ContactStatusSpec, IntegrationSpec, SceneSpec, SolverSpec};
use crate::solver::{ContactStatus, Integration, Settings};

/// The solver settings of `[solver]`.
pub fn solver_settings(spec: &SolverSpec) -> Settings {
    Settings {
        tolerance: spec.tolerance,
        max_iterations: spec.max_iterations,
        line_search: spec.line_search,
        max_substep_depth: spec.max_substep_depth,
        path_following: spec.path_following,
        max_secant_iterations: spec.max_secant_iterations,
        reuse_factorization: spec.reuse_factorization,
        second_order_predictor: spec.second_order_predictor,
        contact_status: match spec.contact_status {
            ContactStatusSpec::ActiveSet => ContactStatus::ActiveSet,
            ContactStatusSpec::PerIteration => ContactStatus::PerIteration,
        },
        fast_path: spec.fast_path,
        integration: match spec.integration {
            IntegrationSpec::Implicit => Integration::Implicit,
            IntegrationSpec::Implex => Integration::Implex,
        },
        step_check: spec.step_check,
    }
}

/// The interface law of `[materials]`, or `None` without ITZ (`effects.cohesive` off, or
/// no law given for a cell without inclusions).
pub fn interface_law(spec: &SceneSpec) -> Option<Arc<dyn InterfaceLaw>> {
    if !spec.effects.cohesive {
        return None;
    }
    let mut laws = spec.materials.interface_laws().into_iter();
    let law = laws.find_map(|(_, law)| law)?;
    Some(law.build(spec.effects.contact))
}

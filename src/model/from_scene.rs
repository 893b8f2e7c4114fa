//! The edge between the scene schema and the numerics: the solver settings, the boundary
//! condition and the interface law that a scene describes, in the numerical modules' own
//! types. This is where a new interface law is registered.

use std::sync::Arc;

use crate::constraint::BoundaryCondition;
use crate::interface::{CohesiveLaw, InterfaceLaw, LinearInterface, Penalty};
use crate::scene::{
    BoundaryKind, ContactStatusSpec, IntegrationSpec, ItzSpec, SceneSpec, SolverSpec,
};
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

/// The constraint of `boundary.kind`.
pub fn boundary_condition(kind: BoundaryKind) -> BoundaryCondition {
    match kind {
        BoundaryKind::Taylor => BoundaryCondition::Taylor,
        BoundaryKind::Linear => BoundaryCondition::Linear,
        BoundaryKind::Periodic => BoundaryCondition::Periodic,
        BoundaryKind::Minimal => BoundaryCondition::Minimal,
    }
}

/// The interface law of `[materials]`, or `None` without ITZ (`effects.cohesive` off, or
/// no law given for a cell without inclusions).
pub fn interface_law(spec: &SceneSpec) -> Option<Arc<dyn InterfaceLaw>> {
    if !spec.effects.cohesive {
        return None;
    }
    let materials = &spec.materials;
    if let Some(linear) = materials.linear_itz {
        return Some(Arc::new(LinearInterface {
            shear: linear.shear_stiffness,
            normal: linear.normal_stiffness,
        }));
    }
    let itz: &ItzSpec = materials.itz.as_ref()?;
    Some(Arc::new(CohesiveLaw {
        sigma_c: itz.sigma_c,
        delta_c: itz.delta_c,
        beta: itz.beta,
        penalty: match (itz.penalty.lambda_p, itz.penalty.stiffness) {
            (Some(lambda_p), _) => Penalty::PerLength { lambda_p },
            (None, Some(stiffness)) => Penalty::PerArea { stiffness },
            (None, None) => Penalty::PerArea { stiffness: 0.0 },
        },
        contact: spec.effects.contact,
        contact_shear: itz.contact_shear,
    }))
}

//! The edge between the scene schema and the numerics: the interface law that a scene
//! describes, from its own scene table (`interface::InterfaceLawSpec`, registered in
//! `scene::MaterialsSpec::interface_laws`). The boundary condition and the solver
//! settings are their scene values.

use std::sync::Arc;

use crate::error::Result;
use crate::scene::SceneSpec;
use mesorve_core::interface::{Frictional, InterfaceLaw, STIFFNESS_FACTOR};

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

/// `law` with the scene's Coulomb friction (`effects.friction`), or `law` itself.
pub fn with_friction(
    spec: &SceneSpec,
    law: Arc<dyn InterfaceLaw>,
) -> Result<Arc<dyn InterfaceLaw>> {
    match (&spec.materials.friction, spec.effects.friction) {
        (Some(friction), true) => Ok(Arc::new(Frictional::new(
            law,
            friction.coefficient,
            "materials.friction",
        )?)),
        _ => Ok(law),
    }
}

/// The law of cracks through the paste (`effects.paste_cracking`), its default stiffness
/// `STIFFNESS_FACTOR E_paste / h` (`h` the mesh size), or `None`.
pub fn paste_law(spec: &SceneSpec) -> Option<Arc<dyn InterfaceLaw>> {
    let crack = spec.materials.paste_crack.as_ref()?;
    if !(spec.effects.cohesive && spec.effects.paste_cracking) {
        return None;
    }
    let stiffness = STIFFNESS_FACTOR * spec.materials.matrix.young / spec.mesh.size;
    Some(crack.build(spec.effects.contact, stiffness))
}

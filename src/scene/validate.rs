//! Validation: every check names the offending key and says why.

use super::path::MAX_STRAIN;
use super::schema::*;
use crate::error::{require_positive, Error, Result};
use mesorve_core::geometry::{Explicit, Orientation, RandomSpec, ShapeKind};
use mesorve_core::interface::ContactShear;
use mesorve_core::solver::Integration;

/// Densest random packing we attempt; above it random sequential placement jams.
pub const MAX_AREA_FRACTION: f64 = 0.7;
// The bound on the estimated triangle count, to refuse runaway mesh sizes.
pub use mesorve_core::mesh::MAX_TRIANGLES;
/// Upper bound on the increments of the whole strain path (all `[[path]]` segments): the
/// path is materialized as one strain per increment.
pub const MAX_PATH_INCREMENTS: u64 = 1_000_000;

fn positive(key: &str, v: f64) -> Result<()> {
    require_positive(key, v)
}

fn non_negative(key: &str, v: f64) -> Result<()> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(Error::scene(
            key,
            format!("must be a finite number >= 0, got {v}"),
        ))
    }
}

fn check_elastic(key: &str, m: &ElasticSpec) -> Result<()> {
    positive(&format!("{key}.young"), m.young)?;
    if !(m.poisson.is_finite() && m.poisson > -1.0 && m.poisson < 0.5) {
        return Err(Error::scene(
            format!("{key}.poisson"),
            format!("must lie in (-1, 0.5), got {}", m.poisson),
        ));
    }
    Ok(())
}

impl SceneSpec {
    /// Checks magnitudes and consistency of the whole scene.
    pub fn validate(&self) -> Result<()> {
        let [w, h] = self.cell.size;
        positive("cell.size[0]", w)?;
        positive("cell.size[1]", h)?;
        let has_inclusions = validate_geometry(&self.geometry, w, h)?;
        validate_mesh(&self.mesh, w, h)?;
        self.validate_materials(has_inclusions)?;
        validate_solver(&self.solver)?;
        validate_path(&self.path)
    }

    /// The materials and the effects that need them; `has_inclusions`: the geometry has
    /// inclusions.
    fn validate_materials(&self, has_inclusions: bool) -> Result<()> {
        check_elastic("materials.matrix", &self.materials.matrix)?;
        match (&self.materials.aggregate, has_inclusions) {
            (Some(a), _) => check_elastic("materials.aggregate", a)?,
            (None, true) => {
                return Err(Error::scene(
                    "materials.aggregate",
                    "missing: the geometry has inclusions",
                ))
            }
            (None, false) => {}
        }
        if self.effects.contact && !self.effects.cohesive {
            return Err(Error::scene(
                "effects.contact",
                "contact acts on ITZ elements, which need effects.cohesive = true",
            ));
        }
        validate_interface_laws(&self.materials, self.effects.cohesive && has_inclusions)?;
        validate_paste_cracking(&self.effects, &self.materials)?;
        validate_friction(&self.effects, &self.materials, &self.solver)?;
        if self.effects.regularization && !self.effects.paste_cracking {
            // Only the paste's cracks are stretched (`InterfaceLaws::regularized`): a cell
            // whose ITZ alone cracks never fails, and has nothing to regularize.
            return Err(Error::scene(
                "effects.regularization",
                "needs effects.paste_cracking: the regularization stretches the softening of \
                 the paste's cracks, and a cell without them never softens to zero",
            ));
        }
        if self.effects.paste_cracking && self.solver.step_tolerance.is_some() {
            // The estimate does not yet fall with the step at the paste's brittle drops
            // (docs/fracture.md): a tolerance it cannot hold is refused.
            return Err(Error::scene(
                "solver.step_tolerance",
                "not with effects.paste_cracking yet: its error estimate does not cover the \
                 paste's cracks, so it would not hold (docs/fracture.md); leave it out and \
                 choose the increments",
            ));
        }
        Ok(())
    }
}

/// Cracks through the paste need the ITZ's cohesive law beside them (the two laws share
/// one history layout) and the paste's crack law; a crack law without the effect is
/// refused, so that a scene says what it simulates.
fn validate_paste_cracking(effects: &EffectsSpec, materials: &MaterialsSpec) -> Result<()> {
    match (&materials.paste_crack, effects.paste_cracking) {
        (Some(_), false) => Err(Error::scene(
            "materials.paste_crack",
            "given, but effects.paste_cracking is off: turn it on, or remove the table",
        )),
        (None, true) => Err(Error::scene(
            "materials.paste_crack",
            "missing: effects.paste_cracking is on (give { strength, fracture_energy })",
        )),
        (Some(crack), true) => {
            if !effects.cohesive || materials.itz.is_none() {
                return Err(Error::scene(
                    "effects.paste_cracking",
                    "cracks through the paste need effects.cohesive = true and the cohesive \
                     ITZ law materials.itz beside them",
                ));
            }
            crack.validate("paste_crack")
        }
        (None, false) => Ok(()),
    }
}

/// Friction needs its coefficient, contact, the cohesive ITZ law (and the paste's crack
/// law, if on) with the shear of a closed crack on the law (`contact_shear =
/// "cohesive"`: the penalty's would stick it for good), and implicit integration: an
/// IMPL-EX step is linear through the origin, which a sticking point with slip is not.
fn validate_friction(
    effects: &EffectsSpec,
    materials: &MaterialsSpec,
    solver: &SolverSpec,
) -> Result<()> {
    let spec = match (&materials.friction, effects.friction) {
        (Some(_), false) => {
            return Err(Error::scene(
                "materials.friction",
                "given, but effects.friction is off: turn it on, or remove the table",
            ))
        }
        (None, true) => {
            return Err(Error::scene(
                "materials.friction",
                "missing: effects.friction is on (give { coefficient })",
            ))
        }
        (None, false) => return Ok(()),
        (Some(spec), true) => spec,
    };
    if !(spec.coefficient.is_finite() && spec.coefficient >= 0.0) {
        return Err(Error::scene(
            "materials.friction.coefficient",
            format!("must be a finite number >= 0, got {}", spec.coefficient),
        ));
    }
    let itz_shear = materials.itz.as_ref().map(|itz| itz.contact_shear);
    let paste_shear = materials.paste_crack.as_ref().map(|c| c.contact_shear);
    if !(effects.cohesive && effects.contact) || itz_shear.is_none() {
        return Err(Error::scene(
            "effects.friction",
            "friction acts on closed cracks: it needs effects.cohesive, effects.contact and \
             the cohesive ITZ law materials.itz",
        ));
    }
    for (key, shear) in [
        ("materials.itz.contact_shear", itz_shear),
        ("materials.paste_crack.contact_shear", paste_shear),
    ] {
        if shear == Some(ContactShear::Penalty) {
            return Err(Error::scene(
                key,
                "\"penalty\" sticks a closed crack for good; with effects.friction set \
                 \"cohesive\", so that friction carries the shear of the damaged part",
            ));
        }
    }
    if solver.integration == Integration::Implex {
        return Err(Error::scene(
            "solver.integration",
            "\"implex\" cannot carry effects.friction: its step is linear through the origin, \
             and a sticking point with slip is not (docs/fracture.md); use \"implicit\"",
        ));
    }
    Ok(())
}

/// At most one interface law, one when `required`, each valid (its own checks).
fn validate_interface_laws(materials: &MaterialsSpec, required: bool) -> Result<()> {
    let laws = materials.interface_laws();
    let keys: Vec<String> = laws
        .iter()
        .map(|(key, _)| format!("materials.{key}"))
        .collect();
    let given: Vec<_> = laws
        .iter()
        .filter_map(|&(key, law)| Some((key, law?)))
        .collect();
    match given.as_slice() {
        [] if required => Err(Error::scene(
            &keys[0],
            format!(
                "missing: effects.cohesive is on and the geometry has inclusions (give one of {})",
                keys.join(", ")
            ),
        )),
        [_, (second, _), ..] => Err(Error::scene(
            format!("materials.{second}"),
            format!("give one interface law of {}, not several", keys.join(", ")),
        )),
        _ => given.iter().try_for_each(|(key, law)| law.validate(key)),
    }
}

/// The geometry of a `w` x `h` cell; returns whether it has inclusions.
fn validate_geometry(geometry: &GeometrySpec, w: f64, h: f64) -> Result<bool> {
    match geometry {
        GeometrySpec::Homogeneous => Ok(false),
        GeometrySpec::Random(r) => {
            validate_random(r, w.min(h))?;
            Ok(true)
        }
        GeometrySpec::Explicit(e) => {
            validate_explicit(e, w, h)?;
            Ok(!e.inclusions.is_empty())
        }
        GeometrySpec::Gmsh(g) => {
            validate_gmsh(g)?;
            Ok(true)
        }
        GeometrySpec::StraightInterface(s) => {
            if !(s.x.is_finite() && s.x > 0.0 && s.x < w) {
                return Err(Error::scene(
                    "geometry.x",
                    format!(
                        "the interface must cut the cell: 0 < x < {w} (cell.size[0]), got {}",
                        s.x
                    ),
                ));
            }
            Ok(true)
        }
    }
}

fn validate_gmsh(g: &GmshSpec) -> Result<()> {
    if g.file.trim().is_empty() {
        return Err(Error::scene("geometry.file", "must name an .msh file"));
    }
    if g.matrix.trim().is_empty() {
        return Err(Error::scene(
            "geometry.matrix",
            "must name a physical group",
        ));
    }
    if g.inclusions.iter().any(|n| n == &g.matrix) {
        return Err(Error::scene(
            "geometry.inclusions",
            format!("group `{}` is also the matrix group", g.matrix),
        ));
    }
    Ok(())
}

/// The mesh sizes and angle of a `w` x `h` cell, and the triangle count they give.
fn validate_mesh(m: &MeshSpec, w: f64, h: f64) -> Result<()> {
    let min_side = w.min(h);
    positive("mesh.size", m.size)?;
    if m.size > min_side {
        return Err(Error::scene(
            "mesh.size",
            format!("{} is larger than the cell side {min_side}", m.size),
        ));
    }
    let h_itz = m.interface_size.unwrap_or(m.size);
    positive("mesh.interface_size", h_itz)?;
    let estimate = 2.0 * w * h / (0.5 * 3f64.sqrt() * m.size.min(h_itz).powi(2));
    if estimate > MAX_TRIANGLES as f64 {
        return Err(Error::scene(
            "mesh.size",
            format!(
                "would give about {estimate:.0} triangles, more than the limit {MAX_TRIANGLES}"
            ),
        ));
    }
    if !(20.0..=30.0).contains(&m.min_angle) {
        return Err(Error::scene(
            "mesh.min_angle",
            format!("must lie in [20, 30] degrees, got {}", m.min_angle),
        ));
    }
    Ok(())
}

/// The largest `solver.share_tolerance`: beyond a tenth, two points' strains may differ
/// in direction as well as size, and a first-order correction is no answer.
const MAX_SHARE_TOLERANCE: f64 = 0.1;

/// Why `solver.step_tolerance` needs `solver.smallest_step`, and how to choose it.
const MISSING_FLOOR: &str = "missing: solver.step_tolerance needs the step control's floor, \
     in the host's time units (the DTIME or dt it passes). Past the first crack the error \
     estimate stays above the tolerance at any step, and a host without a floor halves its \
     increment down to its own minimum and stops there (CalculiX: \"increment size smaller \
     than minimum\"). Set smallest_step to 1/16 of the host's time increment: 0.003125 for \
     CalculiX's *STATIC 0.05, 1. (and a minimum increment below it on that line); for rve \
     run, 1/16 of the strain norm of a path increment (see docs/step_control.md)";

fn validate_solver(s: &SolverSpec) -> Result<()> {
    positive("solver.tolerance", s.tolerance)?;
    if s.tolerance >= 1.0 {
        return Err(Error::scene(
            "solver.tolerance",
            "must be below 1 (relative residual)",
        ));
    }
    if s.max_iterations == 0 || s.max_iterations > 1000 {
        return Err(Error::scene(
            "solver.max_iterations",
            "must lie in 1..=1000",
        ));
    }
    if s.max_secant_iterations > 10_000 {
        return Err(Error::scene(
            "solver.max_secant_iterations",
            "must be at most 10000",
        ));
    }
    if let Some(t) = s.step_tolerance {
        positive("solver.step_tolerance", t)?;
        if t >= 1.0 {
            return Err(Error::scene(
                "solver.step_tolerance",
                format!("must be below 1 (a relative error), got {t}"),
            ));
        }
        if s.integration != mesorve_core::solver::Integration::Implex {
            return Err(Error::scene(
                "solver.step_tolerance",
                "applies to integration = \"implex\" only: the implicit scheme's step is \
                 controlled by solver.step_check (see docs/step_control.md)",
            ));
        }
        if s.smallest_step.is_none() {
            return Err(Error::scene("solver.smallest_step", MISSING_FLOOR));
        }
    }
    if let Some(t) = s.smallest_step {
        positive("solver.smallest_step", t)?;
        if s.step_tolerance.is_none() {
            return Err(Error::scene(
                "solver.smallest_step",
                "is the step control's floor: it needs solver.step_tolerance",
            ));
        }
    }
    if let Some(t) = s.share_tolerance {
        positive("solver.share_tolerance", t)?;
        if t > MAX_SHARE_TOLERANCE {
            return Err(Error::scene(
                "solver.share_tolerance",
                format!(
                    "must be at most {MAX_SHARE_TOLERANCE} (a relative distance between two \
                     points' strains and histories), got {t}"
                ),
            ));
        }
    }
    if s.max_substep_depth > 20 {
        return Err(Error::scene(
            "solver.max_substep_depth",
            "must be at most 20",
        ));
    }
    Ok(())
}

/// The increments of each segment and of the whole path, and the strains it reaches.
fn validate_path(path: &[PathSegment]) -> Result<()> {
    let mut total: u64 = 0;
    for (k, seg) in path.iter().enumerate() {
        if seg.increments == 0 || u64::from(seg.increments) > MAX_PATH_INCREMENTS {
            return Err(Error::scene(
                format!("path[{k}].increments"),
                format!("must lie in 1..={MAX_PATH_INCREMENTS}"),
            ));
        }
        total += u64::from(seg.increments);
        if total > MAX_PATH_INCREMENTS {
            return Err(Error::scene(
                format!("path[{k}].increments"),
                format!(
                    "the path's segments up to this one add up to {total} increments, more \
                     than the limit {MAX_PATH_INCREMENTS} for a whole path"
                ),
            ));
        }
        if seg
            .to
            .iter()
            .any(|v| !v.is_finite() || v.abs() > MAX_STRAIN)
        {
            return Err(Error::scene(
                format!("path[{k}].to"),
                format!(
                    "strain components must be finite and at most {} in magnitude",
                    MAX_STRAIN
                ),
            ));
        }
        if let Some(i) = (0..3).find(|&i| seg.zero_stress.0[i] && seg.to[i] != 0.0) {
            return Err(Error::scene(
                format!("path[{k}].to"),
                format!(
                    "component {i} is held at zero stress (path[{k}].zero_stress): its strain \
                     is found, so its value in `to` must be 0, got {}",
                    seg.to[i]
                ),
            ));
        }
    }
    Ok(())
}

fn validate_random(r: &RandomSpec, min_side: f64) -> Result<()> {
    let [dmin, dmax] = r.diameter;
    positive("geometry.diameter[0]", dmin)?;
    positive("geometry.diameter[1]", dmax)?;
    if dmin > dmax {
        return Err(Error::scene(
            "geometry.diameter",
            format!("[min, max] with min {dmin} > max {dmax}"),
        ));
    }
    non_negative("geometry.gap", r.gap)?;
    non_negative("geometry.margin", r.margin)?;
    if dmax + 2.0 * r.margin > min_side {
        return Err(Error::scene(
            "geometry.diameter",
            format!(
                "largest diameter {dmax} plus twice the margin {} does not fit in the cell side {min_side}",
                r.margin
            ),
        ));
    }
    if !(r.area_fraction.is_finite()
        && r.area_fraction > 0.0
        && r.area_fraction <= MAX_AREA_FRACTION)
    {
        return Err(Error::scene(
            "geometry.area_fraction",
            format!(
                "must lie in (0, {MAX_AREA_FRACTION}]; got {} (random placement jams above ~0.7)",
                r.area_fraction
            ),
        ));
    }
    if !(r.aspect_ratio.is_finite() && (1.0..=10.0).contains(&r.aspect_ratio)) {
        return Err(Error::scene(
            "geometry.aspect_ratio",
            format!(
                "must lie in [1, 10] (major over minor), got {}",
                r.aspect_ratio
            ),
        ));
    }
    if r.shape == ShapeKind::Circle && r.aspect_ratio != 1.0 {
        return Err(Error::scene(
            "geometry.aspect_ratio",
            "only meaningful for shape = \"ellipse\"",
        ));
    }
    if let Orientation::Fixed(a) = r.orientation {
        if !a.is_finite() {
            return Err(Error::scene(
                "geometry.orientation",
                "must be finite or \"random\"",
            ));
        }
    }
    if r.max_attempts == 0 || r.max_rounds == 0 {
        return Err(Error::scene(
            "geometry.max_attempts",
            "attempts and rounds must be >= 1",
        ));
    }
    Ok(())
}

fn validate_explicit(e: &Explicit, w: f64, h: f64) -> Result<()> {
    for (k, inc) in e.inclusions.iter().enumerate() {
        let key = format!("geometry.inclusions[{k}]");
        let [cx, cy] = inc.center;
        if !(cx.is_finite() && cy.is_finite() && cx > 0.0 && cx < w && cy > 0.0 && cy < h) {
            return Err(Error::scene(
                format!("{key}.center"),
                "must lie inside the cell",
            ));
        }
        match (inc.radius, inc.semi_axes) {
            (Some(r), None) => positive(&format!("{key}.radius"), r)?,
            (None, Some([a, b])) => {
                positive(&format!("{key}.semi_axes[0]"), a)?;
                positive(&format!("{key}.semi_axes[1]"), b)?;
            }
            _ => {
                return Err(Error::scene(
                    key,
                    "give exactly one of `radius` (circle) or `semi_axes` (ellipse)",
                ))
            }
        }
        if !inc.angle.is_finite() {
            return Err(Error::scene(format!("{key}.angle"), "must be finite"));
        }
    }
    Ok(())
}

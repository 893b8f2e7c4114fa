//! From a scene to a mesh: geometry, triangulation (or Gmsh import), the insertion of
//! interface elements (the ITZ, and cracks through the paste).

use std::path::Path;

use crate::error::{Error, Result};
use crate::scene::{GeometrySpec, Scene, SceneSpec};
use mesorve_core::geometry::{build_inclusions, place_random, Inclusion};
use mesorve_core::mesh::gmsh::read_msh;
use mesorve_core::mesh::{
    insert_cracks, insert_itz, triangulate, triangulate_straight_interface, without_itz, Mesh,
    Microstructure, PhaseMesh,
};

/// Builds the mesh that `scene` describes.
pub fn build_microstructure(scene: &Scene) -> Result<Microstructure> {
    let spec = &scene.spec;
    let [width, height] = spec.cell.size;
    let mut placement_rounds = None;
    let inclusions = match &spec.geometry {
        GeometrySpec::Homogeneous => Vec::new(),
        GeometrySpec::Random(r) => {
            let placed = place_random(r, width, height)?;
            placement_rounds = Some(placed.rounds);
            placed.inclusions
        }
        GeometrySpec::Explicit(e) => build_inclusions(e, width, height)?,
        GeometrySpec::Gmsh(g) => {
            let path = scene.base_dir.join(&g.file);
            let phase_mesh = read_msh(&path, &g.matrix, &g.inclusions)?;
            let phase_mesh = fit_to_cell(phase_mesh, width, height, &path)?;
            let mesh = finish(phase_mesh, width, height, spec)?;
            return Ok(Microstructure {
                mesh,
                inclusions: Vec::new(),
                geometric_area_fraction: None,
                placement_rounds: None,
            });
        }
        GeometrySpec::StraightInterface(s) => {
            let phase_mesh = triangulate_straight_interface(
                width,
                height,
                s.x,
                spec.mesh.size,
                spec.mesh.interface_size.unwrap_or(spec.mesh.size),
                spec.mesh.min_angle,
            )?;
            let mesh = finish(phase_mesh, width, height, spec)?;
            return Ok(Microstructure {
                mesh,
                inclusions: Vec::new(),
                geometric_area_fraction: Some(s.x / width),
                placement_rounds: None,
            });
        }
    };
    let h_itz = spec.mesh.interface_size.unwrap_or(spec.mesh.size);
    let polygons: Vec<Vec<[f64; 2]>> = inclusions.iter().map(|i| i.polygon(h_itz)).collect();
    let phase_mesh = triangulate(
        width,
        height,
        &polygons,
        spec.mesh.size,
        spec.mesh.min_angle,
    )?;
    let mesh = finish(phase_mesh, width, height, spec)?;
    let area: f64 = inclusions.iter().map(Inclusion::area).sum();
    Ok(Microstructure {
        mesh,
        geometric_area_fraction: Some(area / (width * height)),
        inclusions,
        placement_rounds,
    })
}

/// The interface elements the scene's effects call for: none, the ITZ, or the ITZ and
/// cracks through the paste.
fn finish(phase_mesh: PhaseMesh, width: f64, height: f64, spec: &SceneSpec) -> Result<Mesh> {
    match (&spec.materials.paste_crack, spec.effects) {
        (_, e) if !e.cohesive => without_itz(phase_mesh, width, height),
        (Some(crack), e) if e.paste_cracking => {
            insert_cracks(phase_mesh, width, height, |p| crack.cracks_at(p))
        }
        _ => insert_itz(phase_mesh, width, height),
    }
}

/// Moves a Gmsh mesh so its bounding box starts at the origin, and checks that the box is
/// the scene's cell.
fn fit_to_cell(mut pm: PhaseMesh, width: f64, height: f64, path: &Path) -> Result<PhaseMesh> {
    let bb = mesorve_core::geometry::polygon::bounding_box(&pm.nodes);
    let (w, h) = (bb[2] - bb[0], bb[3] - bb[1]);
    let tol = 1e-6 * width.max(height);
    if (w - width).abs() > tol || (h - height).abs() > tol {
        return Err(Error::scene(
            "cell.size",
            format!(
                "[{width}, {height}] does not match the bounding box [{w}, {h}] of {}",
                path.display()
            ),
        ));
    }
    for p in pm.nodes.iter_mut() {
        *p = [p[0] - bb[0], p[1] - bb[1]];
    }
    Ok(pm)
}

//! Conforming triangulation of a cell with polygonal inclusions (spade's constrained
//! Delaunay refinement).
//!
//! The cell boundary gets the same number of equally spaced points on opposite sides and
//! its constraint edges are never split (`keep_constraint_edges`), so opposite sides carry
//! matching nodes, as periodic boundary conditions need. Inclusion polygons are constraint
//! edges too: each polygon edge becomes exactly one ITZ element.

use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};

use super::model::{Phase, PhaseMesh, Triangle};
use crate::error::{Error, Result};
use crate::geometry::polygon::{bounding_box, point_in_polygon, polygon_distance};

/// Points along the cell boundary, counter-clockwise from `(0, 0)`, `n` per side.
fn cell_boundary(width: f64, height: f64, nx: usize, ny: usize) -> Vec<[f64; 2]> {
    let mut pts = Vec::with_capacity(2 * (nx + ny));
    pts.extend((0..nx).map(|i| [width * i as f64 / nx as f64, 0.0]));
    pts.extend((0..ny).map(|j| [width, height * j as f64 / ny as f64]));
    pts.extend((0..nx).map(|i| [width * (nx - i) as f64 / nx as f64, height]));
    pts.extend((0..ny).map(|j| [0.0, height * (ny - j) as f64 / ny as f64]));
    pts
}

/// Checks that the inclusion polygons lie strictly inside the cell and do not touch each
/// other, so the constrained triangulation is well defined.
fn check_polygons(width: f64, height: f64, polygons: &[Vec<[f64; 2]>]) -> Result<()> {
    for (k, p) in polygons.iter().enumerate() {
        if p.iter()
            .any(|q| q[0] <= 0.0 || q[0] >= width || q[1] <= 0.0 || q[1] >= height)
        {
            return Err(Error::Mesh(format!(
                "inclusion {k}: its boundary polygon leaves the cell; increase geometry.margin"
            )));
        }
    }
    let bbox: Vec<[f64; 4]> = polygons.iter().map(|p| bounding_box(p)).collect();
    for i in 0..polygons.len() {
        for j in i + 1..polygons.len() {
            let (a, b) = (bbox[i], bbox[j]);
            let apart = a[2] < b[0] || b[2] < a[0] || a[3] < b[1] || b[3] < a[1];
            if !apart && polygon_distance(&polygons[i], &polygons[j]) <= 0.0 {
                return Err(Error::Mesh(format!(
                    "inclusions {i} and {j} touch once discretised; increase geometry.gap \
                     or decrease mesh.interface_size"
                )));
            }
        }
    }
    Ok(())
}

/// Triangulates the cell `[0, w] x [0, h]` with inclusion polygons (counter-clockwise) as
/// constraints: target edge length `h_bulk`, minimum angle `min_angle_deg`.
pub fn triangulate(
    width: f64,
    height: f64,
    polygons: &[Vec<[f64; 2]>],
    h_bulk: f64,
    min_angle_deg: f64,
) -> Result<PhaseMesh> {
    check_polygons(width, height, polygons)?;
    let nx = (width / h_bulk).ceil().max(1.0) as usize;
    let ny = (height / h_bulk).ceil().max(1.0) as usize;
    let to_point = |p: &[f64; 2]| Point2::new(p[0], p[1]);

    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    let boundary = cell_boundary(width, height, nx, ny);
    cdt.add_constraint_edges(boundary.iter().map(to_point), true)
        .map_err(|e| Error::Mesh(format!("cell boundary: {e:?}")))?;
    for (k, p) in polygons.iter().enumerate() {
        cdt.add_constraint_edges(p.iter().map(to_point), true)
            .map_err(|e| Error::Mesh(format!("inclusion {k}: {e:?}")))?;
    }

    let max_area = 3f64.sqrt() / 4.0 * h_bulk * h_bulk;
    // Bound the refinement so it always terminates; 20x the nominal count is never needed
    // by a sane request, and hitting it is reported as an error.
    let budget = (20.0 * 2.0 * width * height / max_area) as usize + 10_000;
    let result = cdt.refine(
        RefinementParameters::new()
            .with_max_allowed_area(max_area)
            .with_angle_limit(AngleLimit::from_deg(min_angle_deg))
            .keep_constraint_edges()
            .exclude_outer_faces(false)
            .with_max_additional_vertices(budget),
    );
    if !result.refinement_complete {
        return Err(Error::Mesh(format!(
            "refinement did not finish within {budget} added vertices; coarsen mesh.size or \
             lower mesh.min_angle"
        )));
    }

    let nodes: Vec<[f64; 2]> = cdt
        .vertices()
        .map(|v| [v.position().x, v.position().y])
        .collect();
    let bboxes: Vec<[f64; 4]> = polygons.iter().map(|p| bounding_box(p)).collect();
    let mut triangles = Vec::with_capacity(cdt.num_inner_faces());
    for face in cdt.inner_faces() {
        let ids = face.vertices().map(|v| v.fix().index());
        let c = ids.iter().fold([0.0, 0.0], |c, &i| {
            [c[0] + nodes[i][0] / 3.0, c[1] + nodes[i][1] / 3.0]
        });
        let inside = polygons.iter().zip(&bboxes).any(|(p, b)| {
            c[0] >= b[0] && c[0] <= b[2] && c[1] >= b[1] && c[1] <= b[3] && point_in_polygon(c, p)
        });
        triangles.push(Triangle {
            nodes: ids,
            phase: if inside {
                Phase::Inclusion
            } else {
                Phase::Matrix
            },
        });
    }
    Ok(PhaseMesh { nodes, triangles })
}

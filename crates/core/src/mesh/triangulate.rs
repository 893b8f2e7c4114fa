//! Conforming triangulation of a cell with polygonal inclusions (spade's constrained
//! Delaunay refinement).
//!
//! The cell boundary gets the same number of equally spaced points on opposite sides and
//! its constraint edges are never split (`keep_constraint_edges`), so opposite sides carry
//! matching nodes, as periodic boundary conditions need. Inclusion polygons are constraint
//! edges too: each polygon edge becomes exactly one ITZ element. So are open polylines
//! (the straight interface of `kind = "straight_interface"`); where one ends on the cell
//! boundary its end point becomes a node of that side and of the opposite side.

use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};

use super::model::{Phase, PhaseMesh, Triangle};
use crate::error::{Error, Result};
use crate::geometry::polygon::{bounding_box, point_in_polygon, polygon_distance};

/// Points along the cell boundary, counter-clockwise from `(0, 0)`. Bottom and top carry
/// the same abscissae, left and right the same ordinates: each side is cut at the interior
/// break points (`x_breaks`, `y_breaks`, where constraint lines meet the boundary) and
/// every piece is split into equal segments of length at most `h`.
fn cell_boundary(
    width: f64,
    height: f64,
    x_breaks: &[f64],
    y_breaks: &[f64],
    h: f64,
) -> Vec<[f64; 2]> {
    // Abscissae (or ordinates) from 0 (inclusive) to `length` (exclusive).
    let stations = |length: f64, breaks: &[f64]| {
        let mut ends: Vec<f64> = breaks.to_vec();
        ends.push(length);
        let mut out = Vec::new();
        let mut a = 0.0;
        for &b in &ends {
            let n = ((b - a) / h).ceil().max(1.0) as usize;
            out.extend((0..n).map(|i| a + (b - a) * i as f64 / n as f64));
            a = b;
        }
        out
    };
    let xs = stations(width, x_breaks);
    let ys = stations(height, y_breaks);
    let mut pts = Vec::with_capacity(2 * (xs.len() + ys.len()));
    pts.extend(xs.iter().map(|&x| [x, 0.0]));
    pts.extend(ys.iter().map(|&y| [width, y]));
    // Top and left run backwards: `length - station` would round differently from the
    // station itself, so take the stations of the opposite side in reverse.
    pts.push([width, height]);
    pts.extend(xs[1..].iter().rev().map(|&x| [x, height]));
    pts.push([0.0, height]);
    pts.extend(ys[1..].iter().rev().map(|&y| [0.0, y]));
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
    let (nodes, faces) = constrained_mesh(width, height, polygons, &[], h_bulk, min_angle_deg)?;
    let bboxes: Vec<[f64; 4]> = polygons.iter().map(|p| bounding_box(p)).collect();
    let triangles = faces
        .into_iter()
        .map(|ids| {
            let c = centroid(&nodes, ids);
            let inside = polygons.iter().zip(&bboxes).any(|(p, b)| {
                c[0] >= b[0]
                    && c[0] <= b[2]
                    && c[1] >= b[1]
                    && c[1] <= b[3]
                    && point_in_polygon(c, p)
            });
            Triangle {
                nodes: ids,
                phase: if inside {
                    Phase::Inclusion
                } else {
                    Phase::Matrix
                },
            }
        })
        .collect();
    Ok(PhaseMesh { nodes, triangles })
}

/// Triangulates the cell cut by the vertical line `x = x_cut` from `(x_cut, 0)` to
/// `(x_cut, h)`: the line is a constraint of `ceil(h / h_itz)` equal segments (never
/// split by the refinement, so every ITZ element has the same length), the bottom and top
/// sides carry a node at `x_cut`, triangles left of the line are [`Phase::Inclusion`] and
/// right of it [`Phase::Matrix`].
pub fn triangulate_straight_interface(
    width: f64,
    height: f64,
    x_cut: f64,
    h_bulk: f64,
    h_itz: f64,
    min_angle_deg: f64,
) -> Result<PhaseMesh> {
    if !(x_cut > 0.0 && x_cut < width) {
        return Err(Error::Mesh(format!(
            "the interface x = {x_cut} does not cut the cell [0, {width}]"
        )));
    }
    let n = (height / h_itz).ceil().max(1.0) as usize;
    let mut line: Vec<[f64; 2]> = (0..n)
        .map(|j| [x_cut, height * j as f64 / n as f64])
        .collect();
    line.push([x_cut, height]);
    let (nodes, faces) = constrained_mesh(width, height, &[], &[line], h_bulk, min_angle_deg)?;
    let triangles = faces
        .into_iter()
        .map(|ids| Triangle {
            nodes: ids,
            phase: if centroid(&nodes, ids)[0] < x_cut {
                Phase::Inclusion
            } else {
                Phase::Matrix
            },
        })
        .collect();
    Ok(PhaseMesh { nodes, triangles })
}

/// Node coordinates and counter-clockwise triangles of a triangulation.
type NodesAndFaces = (Vec<[f64; 2]>, Vec<[usize; 3]>);

fn centroid(nodes: &[[f64; 2]], ids: [usize; 3]) -> [f64; 2] {
    ids.iter().fold([0.0, 0.0], |c, &i| {
        [c[0] + nodes[i][0] / 3.0, c[1] + nodes[i][1] / 3.0]
    })
}

/// The refined constrained Delaunay triangulation of the cell with closed `polygons` and
/// open `polylines` as constraint edges: nodes and counter-clockwise triangles. Polyline
/// end points on the bottom/top (left/right) sides become break points of both opposite
/// sides, so the sides still carry matching nodes.
fn constrained_mesh(
    width: f64,
    height: f64,
    polygons: &[Vec<[f64; 2]>],
    polylines: &[Vec<[f64; 2]>],
    h_bulk: f64,
    min_angle_deg: f64,
) -> Result<NodesAndFaces> {
    let to_point = |p: &[f64; 2]| Point2::new(p[0], p[1]);
    let (mut x_breaks, mut y_breaks) = (Vec::new(), Vec::new());
    for p in polylines
        .iter()
        .flat_map(|l| [l.first(), l.last()])
        .flatten()
    {
        let [x, y] = *p;
        let interior_x = x > 0.0 && x < width;
        let interior_y = y > 0.0 && y < height;
        if interior_x && (y == 0.0 || y == height) {
            x_breaks.push(x);
        } else if interior_y && (x == 0.0 || x == width) {
            y_breaks.push(y);
        }
    }
    for breaks in [&mut x_breaks, &mut y_breaks] {
        breaks.sort_by(f64::total_cmp);
        breaks.dedup();
    }

    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    let boundary = cell_boundary(width, height, &x_breaks, &y_breaks, h_bulk);
    cdt.add_constraint_edges(boundary.iter().map(to_point), true)
        .map_err(|e| Error::Mesh(format!("cell boundary: {e:?}")))?;
    for (k, p) in polygons.iter().enumerate() {
        cdt.add_constraint_edges(p.iter().map(to_point), true)
            .map_err(|e| Error::Mesh(format!("inclusion {k}: {e:?}")))?;
    }
    for (k, l) in polylines.iter().enumerate() {
        cdt.add_constraint_edges(l.iter().map(to_point), false)
            .map_err(|e| Error::Mesh(format!("interface line {k}: {e:?}")))?;
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
    let faces = cdt
        .inner_faces()
        .map(|face| face.vertices().map(|v| v.fix().index()))
        .collect();
    Ok((nodes, faces))
}

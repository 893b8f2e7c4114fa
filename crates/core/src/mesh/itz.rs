//! ITZ insertion: duplicate the nodes along every inclusion/matrix boundary and insert a
//! zero-thickness 4-node interface element on each boundary edge (paper section 4:
//! intrinsic cohesive elements inserted a priori).
//!
//! Works on any conforming phase-labelled triangulation (our mesher or a Gmsh file):
//! an edge shared by one inclusion triangle and one matrix triangle is an ITZ edge. Its
//! nodes keep their ids on the inclusion side; every matrix triangle that touches such a
//! node is renumbered to a duplicate created for it. Where two inclusions share a vertex
//! (possible in Gmsh meshes only; generated microstructures keep a gap), the two
//! inclusions stay bonded at that vertex and the matrix around it shares one duplicate.
//!
//! ITZ nodes may lie on the cell boundary (an interface that crosses the cell, as
//! `kind = "straight_interface"` makes): the node and its duplicate then both sit on the
//! side, and [`find_boundary_nodes_split`] orders and pairs them by the side of the
//! interface they belong to. Whether the sides still match for periodic conditions is
//! reported in [`crate::mesh::BoundaryNodes::sides_match`] (an inclusion that touches one
//! side only leaves an unpaired duplicate there, and periodic conditions are refused).

use std::collections::HashMap;

use super::boundary::{find_boundary_nodes, find_boundary_nodes_split};
use super::model::{InterfaceElement, InterfaceKind, Mesh, Phase, PhaseMesh, Triangle};
use crate::error::{Error, Result};

/// Builds the mesh without interface elements (perfect bonding).
pub fn without_itz(phase_mesh: PhaseMesh, width: f64, height: f64) -> Result<Mesh> {
    let boundary = find_boundary_nodes(&phase_mesh.nodes, width, height)?;
    Ok(Mesh {
        width,
        height,
        nodes: phase_mesh.nodes,
        triangles: phase_mesh.triangles,
        interfaces: Vec::new(),
        boundary,
    })
}

/// Duplicates ITZ nodes and inserts one interface element per inclusion/matrix edge.
pub fn insert_itz(phase_mesh: PhaseMesh, width: f64, height: f64) -> Result<Mesh> {
    let PhaseMesh {
        mut nodes,
        mut triangles,
    } = phase_mesh;
    let itz_edges = itz_edges(&triangles)?;
    let duplicate = duplicate_nodes(&mut nodes, &mut triangles, &itz_edges);
    let interfaces = itz_edges
        .iter()
        .map(|&(a0, a1)| {
            let (p, q) = (nodes[a0], nodes[a1]);
            let length = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
            let tangent = [(q[0] - p[0]) / length, (q[1] - p[1]) / length];
            InterfaceElement {
                nodes: [a0, a1, duplicate[&a0], duplicate[&a1]],
                length,
                tangent,
                normal: [tangent[1], -tangent[0]],
                kind: InterfaceKind::Itz,
            }
        })
        .collect();

    let boundary = find_boundary_nodes_split(&nodes, &triangles, width, height)?;
    Ok(Mesh {
        width,
        height,
        nodes,
        triangles,
        interfaces,
        boundary,
    })
}

/// The ITZ edges (between an inclusion and a matrix triangle), oriented
/// counter-clockwise around the inclusion triangle, sorted so the element numbering is
/// deterministic. An edge of more than two triangles is an error.
fn itz_edges(triangles: &[Triangle]) -> Result<Vec<(usize, usize)>> {
    // Edge -> (triangle, local edge index) of its (at most two) triangles.
    let mut edges: HashMap<(usize, usize), Vec<(usize, usize)>> = HashMap::new();
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri.nodes[k], tri.nodes[(k + 1) % 3]);
            edges.entry((a.min(b), a.max(b))).or_default().push((t, k));
        }
    }

    let mut itz_edges: Vec<(usize, usize)> = Vec::new();
    for (key, tris) in &edges {
        if tris.len() > 2 {
            return Err(Error::Mesh(format!(
                "edge {key:?} is shared by {} triangles: the mesh is not conforming",
                tris.len()
            )));
        }
        if let [(t0, k0), (t1, k1)] = tris[..] {
            let (p0, p1) = (triangles[t0].phase, triangles[t1].phase);
            let inclusion_side = match (p0, p1) {
                (Phase::Inclusion, Phase::Matrix) => Some((t0, k0)),
                (Phase::Matrix, Phase::Inclusion) => Some((t1, k1)),
                _ => None,
            };
            if let Some((t, k)) = inclusion_side {
                let tri = &triangles[t];
                itz_edges.push((tri.nodes[k], tri.nodes[(k + 1) % 3]));
            }
        }
    }
    itz_edges.sort_unstable();
    Ok(itz_edges)
}

/// One duplicate per ITZ node, for the matrix side: appended to `nodes`, and the matrix
/// triangles moved onto them. Returns the duplicate of each ITZ node.
fn duplicate_nodes(
    nodes: &mut Vec<[f64; 2]>,
    triangles: &mut [Triangle],
    itz_edges: &[(usize, usize)],
) -> HashMap<usize, usize> {
    let mut duplicate: HashMap<usize, usize> = HashMap::new();
    for &(a, b) in itz_edges {
        for n in [a, b] {
            if let std::collections::hash_map::Entry::Vacant(slot) = duplicate.entry(n) {
                slot.insert(nodes.len());
                nodes.push(nodes[n]);
            }
        }
    }
    for tri in triangles.iter_mut().filter(|t| t.phase == Phase::Matrix) {
        for n in tri.nodes.iter_mut() {
            if let Some(&d) = duplicate.get(n) {
                *n = d;
            }
        }
    }
    duplicate
}

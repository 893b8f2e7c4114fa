//! Nodes on the cell boundary, sorted per side, and the periodic matching check.

use super::model::{BoundaryNodes, Triangle};
use crate::error::{Error, Result};

/// Finds corners and side nodes of the cell `[0, w] x [0, h]` (tolerance `1e-9 max(w, h)`)
/// of a mesh without coincident boundary nodes (ties in the sort go by node index).
pub fn find_boundary_nodes(nodes: &[[f64; 2]], width: f64, height: f64) -> Result<BoundaryNodes> {
    boundary_nodes(nodes, None, width, height)
}

/// Like [`find_boundary_nodes`], for a mesh that may carry coincident nodes on its
/// boundary: an ITZ that ends on a side has its node and the node's duplicate there.
///
/// Coincident nodes along a side are ordered by where their triangles lie: along the
/// bottom and top sides the copy whose triangles lie further left (smaller mean centroid
/// `x`) comes first, along the left and right sides the lower one. So
///
/// * the chain of boundary edges along a side is geometrically right: the edge between
///   the two copies has zero length, and every other edge joins nodes of the same
///   triangle side (what the minimal BC integrates);
/// * bottom and top (left and right) pair the copies on the same side of the interface
///   (for a periodic microstructure the interface crosses both sides the same way): the
///   original nodes with each other, the duplicates with each other.
///
/// An ITZ node at a cell corner is refused (a corner must be a single node).
pub fn find_boundary_nodes_split(
    nodes: &[[f64; 2]],
    triangles: &[Triangle],
    width: f64,
    height: f64,
) -> Result<BoundaryNodes> {
    // Mean triangle centroid minus node position, per node: where the node's material is.
    let mut offset = vec![[0.0f64; 2]; nodes.len()];
    let mut count = vec![0u32; nodes.len()];
    for t in triangles {
        let p = t.nodes.map(|i| nodes[i]);
        let c = [
            (p[0][0] + p[1][0] + p[2][0]) / 3.0,
            (p[0][1] + p[1][1] + p[2][1]) / 3.0,
        ];
        for &i in &t.nodes {
            offset[i][0] += c[0];
            offset[i][1] += c[1];
            count[i] += 1;
        }
    }
    for ((o, &c), p) in offset.iter_mut().zip(&count).zip(nodes) {
        if c > 0 {
            *o = [o[0] / c as f64 - p[0], o[1] / c as f64 - p[1]];
        }
    }
    boundary_nodes(nodes, Some(&offset), width, height)
}

fn boundary_nodes(
    nodes: &[[f64; 2]],
    offset: Option<&[[f64; 2]]>,
    width: f64,
    height: f64,
) -> Result<BoundaryNodes> {
    let tol = 1e-9 * width.max(height);
    let near = |a: f64, b: f64| (a - b).abs() <= tol;
    let corner_xy = [[0.0, 0.0], [width, 0.0], [width, height], [0.0, height]];
    let mut corners = [usize::MAX; 4];
    let (mut left, mut right, mut bottom, mut top) = (vec![], vec![], vec![], vec![]);
    for (i, &[x, y]) in nodes.iter().enumerate() {
        if let Some(c) = corner_xy
            .iter()
            .position(|c| near(x, c[0]) && near(y, c[1]))
        {
            if offset.is_some() && corners[c] != usize::MAX {
                return Err(Error::Mesh(format!(
                    "two nodes at the cell corner {:?}: an interface may not end in a corner",
                    corner_xy[c]
                )));
            }
            corners[c] = i;
            continue;
        }
        if near(x, 0.0) {
            left.push(i);
        } else if near(x, width) {
            right.push(i);
        }
        if near(y, 0.0) {
            bottom.push(i);
        } else if near(y, height) {
            top.push(i);
        }
    }
    if let Some(c) = corners.iter().position(|&c| c == usize::MAX) {
        return Err(Error::Mesh(format!(
            "no mesh node at cell corner {:?}: the mesh does not fill the rectangle",
            corner_xy[c]
        )));
    }
    // Sort along the side; coincident nodes by the side their material lies on (then by
    // index, which keeps the sort deterministic).
    let by = |k: usize| {
        move |a: &usize, b: &usize| {
            nodes[*a][k]
                .total_cmp(&nodes[*b][k])
                .then_with(|| match offset {
                    Some(o) => o[*a][k].total_cmp(&o[*b][k]),
                    None => std::cmp::Ordering::Equal,
                })
                .then(a.cmp(b))
        }
    };
    left.sort_by(by(1));
    right.sort_by(by(1));
    bottom.sort_by(by(0));
    top.sort_by(by(0));
    let pairs_match = |a: &[usize], b: &[usize], k: usize| {
        a.len() == b.len()
            && a.iter()
                .zip(b)
                .all(|(&i, &j)| near(nodes[i][k], nodes[j][k]))
    };
    let sides_match = pairs_match(&left, &right, 1) && pairs_match(&bottom, &top, 0);
    Ok(BoundaryNodes {
        corners,
        left,
        right,
        bottom,
        top,
        sides_match,
        periodic_ties: Vec::new(),
    })
}

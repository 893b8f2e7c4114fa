//! Nodes on the cell boundary, sorted per side, and the periodic matching check.

use super::model::BoundaryNodes;
use crate::error::{Error, Result};

/// Finds corners and side nodes of the cell `[0, w] x [0, h]` (tolerance `1e-9 max(w, h)`).
pub fn find_boundary_nodes(nodes: &[[f64; 2]], width: f64, height: f64) -> Result<BoundaryNodes> {
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
    let by = |k: usize| move |a: &usize, b: &usize| nodes[*a][k].total_cmp(&nodes[*b][k]);
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
    })
}

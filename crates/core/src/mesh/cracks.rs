//! Interface elements on the ITZ and along the paste's element edges (cracks through the
//! paste, `docs/fracture.md`): the general insertion of zero-thickness elements on any set
//! of interior edges, of which [`super::insert_itz`] is the ITZ-only case (kept as it is:
//! meshes without paste cracks keep their node numbering).
//!
//! **Node copies.** Around every node the triangles that touch it fall into groups joined
//! by edges that are not crack edges; each group gets its own copy of the node (the group
//! of the node's lowest triangle keeps the node's index, the others get new indices in the
//! order of their lowest triangle). A crack edge then separates the copies of its two
//! triangles, and its interface element ties them: nodes `[a0, a1, b0, b1]` with `a` the
//! copies of the side-A triangle (the inclusion on the ITZ, the triangle of lower index in
//! the paste), `b` those of the other, the edge counter-clockwise around side A, so that
//! the normal points out of it (`super::model`'s conventions).
//!
//! **Which edges crack.** Every interior edge between an inclusion and a matrix triangle
//! (the ITZ), and the interior matrix-matrix edges the caller selects, but no edge that
//! touches a cell corner (a corner stays one node, which the boundary conditions fix).
//!
//! **The boundary.** A node on a side may have copies whose triangles only touch the side
//! at that node; only the copies of triangles with a boundary edge there carry the side's
//! trace, and only they are listed on the side (ordered along it, the lower copy first).
//! Periodic conditions tie the trace edge by edge: the copy that ends a side's boundary
//! edge at a node is tied to the copy that ends the opposite side's matching edge, below
//! with below and above with above (`BoundaryNodes::periodic_ties`). Where one side has
//! one copy and the other two, the two are tied together: a crack ends at the cell's side
//! unless it continues through the opposite one.

use std::collections::HashMap;

use super::model::{
    BoundaryNodes, InterfaceElement, InterfaceKind, Mesh, Phase, PhaseMesh, Triangle,
};
use crate::error::{Error, Result};

/// Inserts interface elements on every ITZ edge and on the matrix-matrix edges whose
/// midpoint `paste` selects (none touching a cell corner).
pub fn insert_cracks(
    phase_mesh: PhaseMesh,
    width: f64,
    height: f64,
    paste: impl Fn([f64; 2]) -> bool,
) -> Result<Mesh> {
    let PhaseMesh {
        mut nodes,
        mut triangles,
    } = phase_mesh;
    let edges = edge_map(&triangles)?;
    let mut cracks = crack_edges(&nodes, &triangles, &edges, width, height, paste);
    // The ITZ first, then the paste, each by its nodes: a deterministic numbering.
    cracks.sort_unstable_by_key(|c| (c.kind, c.ends));
    let crack_keys: std::collections::HashSet<(usize, usize)> = cracks
        .iter()
        .map(|c| (c.ends[0].min(c.ends[1]), c.ends[0].max(c.ends[1])))
        .collect();
    let copies = node_copies(&mut nodes, &triangles, &edges, &crack_keys);
    let copy_of = |n: usize, t: usize| copies[&(n, t)];
    let interfaces = cracks
        .iter()
        .map(|c| {
            let [n0, n1] = c.ends;
            let (p, q) = (nodes[n0], nodes[n1]);
            let length = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
            let tangent = [(q[0] - p[0]) / length, (q[1] - p[1]) / length];
            InterfaceElement {
                nodes: [
                    copy_of(n0, c.a),
                    copy_of(n1, c.a),
                    copy_of(n0, c.b),
                    copy_of(n1, c.b),
                ],
                length,
                tangent,
                normal: [tangent[1], -tangent[0]],
                kind: c.kind,
            }
        })
        .collect::<Vec<_>>();
    for (t, tri) in triangles.iter_mut().enumerate() {
        for n in tri.nodes.iter_mut() {
            *n = copy_of(*n, t);
        }
    }
    let boundary = boundary_of(&nodes, &triangles, width, height)?;
    Ok(Mesh {
        width,
        height,
        nodes,
        triangles,
        interfaces,
        boundary,
    })
}

/// The crack edges: every ITZ edge and the selected paste edges, side A as in the module
/// documentation.
fn crack_edges(
    nodes: &[[f64; 2]],
    triangles: &[Triangle],
    edges: &Edges,
    width: f64,
    height: f64,
    paste: impl Fn([f64; 2]) -> bool,
) -> Vec<Crack> {
    let tol = 1e-9 * width.max(height);
    let at_corner = |p: [f64; 2]| {
        let near = |a: f64, b: f64| (a - b).abs() <= tol;
        (near(p[0], 0.0) || near(p[0], width)) && (near(p[1], 0.0) || near(p[1], height))
    };
    let mut cracks: Vec<Crack> = Vec::new();
    for (&(n0, n1), tris) in edges {
        let [(t0, k0), (t1, k1)] = tris[..] else {
            continue;
        };
        let (p0, p1) = (triangles[t0].phase, triangles[t1].phase);
        let (side_a, kind) = match (p0, p1) {
            (Phase::Inclusion, Phase::Matrix) => ((t0, k0, t1), InterfaceKind::Itz),
            (Phase::Matrix, Phase::Inclusion) => ((t1, k1, t0), InterfaceKind::Itz),
            (Phase::Matrix, Phase::Matrix) => {
                let (a, b) = (nodes[n0], nodes[n1]);
                let mid = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
                if at_corner(a) || at_corner(b) || !paste(mid) {
                    continue;
                }
                (
                    (t0.min(t1), if t0 < t1 { k0 } else { k1 }, t0.max(t1)),
                    InterfaceKind::Paste,
                )
            }
            (Phase::Inclusion, Phase::Inclusion) => continue,
        };
        let (ta, ka, tb) = side_a;
        let tri = &triangles[ta];
        cracks.push(Crack {
            ends: [tri.nodes[ka], tri.nodes[(ka + 1) % 3]],
            a: ta,
            b: tb,
            kind,
        });
    }
    cracks
}

/// A crack edge: its nodes counter-clockwise around triangle `a`, the triangle `b` across.
struct Crack {
    ends: [usize; 2],
    a: usize,
    b: usize,
    kind: InterfaceKind,
}

/// Edge `(min, max)` -> its (one or two) triangles with the edge's local index.
type Edges = HashMap<(usize, usize), Vec<(usize, usize)>>;

fn edge_map(triangles: &[Triangle]) -> Result<Edges> {
    let mut edges: Edges = HashMap::new();
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri.nodes[k], tri.nodes[(k + 1) % 3]);
            edges.entry((a.min(b), a.max(b))).or_default().push((t, k));
        }
    }
    if let Some((key, tris)) = edges.iter().find(|(_, t)| t.len() > 2) {
        return Err(Error::Mesh(format!(
            "edge {key:?} is shared by {} triangles: the mesh is not conforming",
            tris.len()
        )));
    }
    Ok(edges)
}

/// The copy of every `(node, triangle)` (see the module documentation); new copies are
/// appended to `nodes`.
fn node_copies(
    nodes: &mut Vec<[f64; 2]>,
    triangles: &[Triangle],
    edges: &Edges,
    cracks: &std::collections::HashSet<(usize, usize)>,
) -> HashMap<(usize, usize), usize> {
    let mut around: Vec<Vec<usize>> = vec![Vec::new(); nodes.len()];
    for (t, tri) in triangles.iter().enumerate() {
        for &n in &tri.nodes {
            around[n].push(t);
        }
    }
    let mut copy = HashMap::new();
    for n in 0..around.len() {
        let tris = &around[n];
        // Union-find over the triangles around `n`, joined through non-crack edges at `n`.
        let mut parent: Vec<usize> = (0..tris.len()).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        for (i, &t) in tris.iter().enumerate() {
            for &m in &triangles[t].nodes {
                if m == n {
                    continue;
                }
                let key = (n.min(m), n.max(m));
                if cracks.contains(&key) {
                    continue;
                }
                for &(u, _) in edges.get(&key).into_iter().flatten() {
                    if let Some(j) = tris.iter().position(|&x| x == u) {
                        let (ri, rj) = (root(&mut parent, i), root(&mut parent, j));
                        parent[ri.max(rj)] = ri.min(rj);
                    }
                }
            }
        }
        // Groups by their lowest triangle (`tris` is in increasing order).
        let mut group_node: HashMap<usize, usize> = HashMap::new();
        for (i, &t) in tris.iter().enumerate() {
            let r = root(&mut parent, i);
            let id = *group_node.entry(r).or_insert_with(|| {
                if r == 0 {
                    n
                } else {
                    nodes.push(nodes[n]);
                    nodes.len() - 1
                }
            });
            copy.insert((n, t), id);
        }
    }
    copy
}

/// The boundary of a cracked mesh: corners, each side's trace copies in order, and the
/// periodic ties (see the module documentation).
fn boundary_of(
    nodes: &[[f64; 2]],
    triangles: &[Triangle],
    width: f64,
    height: f64,
) -> Result<BoundaryNodes> {
    let sides = Sides::new(nodes, width, height);
    let ends = sides.edge_ends(triangles);
    let corners = sides.corners()?;
    // Each side's copies (not the corners), along the side, the lower copy first.
    let list = |side: usize| -> Vec<usize> {
        let axis = Sides::axis(side);
        let mut v: Vec<usize> = ends[side]
            .keys()
            .copied()
            .filter(|n| !corners.contains(n))
            .collect();
        v.sort_by(|&i, &j| {
            let below = |n: usize| ends[side][&n][0] && !ends[side][&n][1];
            nodes[i][axis]
                .total_cmp(&nodes[j][axis])
                .then_with(|| below(j).cmp(&below(i)))
                .then(i.cmp(&j))
        });
        v
    };
    let lists = [list(0), list(1), list(2), list(3)];
    let (periodic_ties, sides_match) = sides.periodic_ties(&lists, &ends);
    let [bottom, right, top, left] = lists;
    Ok(BoundaryNodes {
        corners,
        left,
        right,
        bottom,
        top,
        sides_match,
        periodic_ties,
    })
}

/// Per node copy on a side: whether it ends a boundary edge below it and one above it
/// (smaller, larger coordinate along the side).
type EdgeEnds = [HashMap<usize, [bool; 2]>; 4];

/// The cell's four sides (0 bottom, 1 right, 2 top, 3 left) over a node list.
struct Sides<'a> {
    nodes: &'a [[f64; 2]],
    width: f64,
    height: f64,
    tol: f64,
}

impl<'a> Sides<'a> {
    fn new(nodes: &'a [[f64; 2]], width: f64, height: f64) -> Self {
        let tol = 1e-9 * width.max(height);
        Self {
            nodes,
            width,
            height,
            tol,
        }
    }

    fn near(&self, a: f64, b: f64) -> bool {
        (a - b).abs() <= self.tol
    }

    /// The coordinate that runs along a side.
    fn axis(side: usize) -> usize {
        if side % 2 == 0 {
            0
        } else {
            1
        }
    }

    /// The side an edge lies on, if any.
    fn side_of(&self, p: [f64; 2], q: [f64; 2]) -> Option<usize> {
        let (w, h) = (self.width, self.height);
        if self.near(p[1], 0.0) && self.near(q[1], 0.0) {
            Some(0)
        } else if self.near(p[0], w) && self.near(q[0], w) {
            Some(1)
        } else if self.near(p[1], h) && self.near(q[1], h) {
            Some(2)
        } else if self.near(p[0], 0.0) && self.near(q[0], 0.0) {
            Some(3)
        } else {
            None
        }
    }

    /// The boundary edges (those of one triangle) each node copy ends, per side.
    fn edge_ends(&self, triangles: &[Triangle]) -> EdgeEnds {
        let mut count: HashMap<(usize, usize), u32> = HashMap::new();
        for tri in triangles {
            for k in 0..3 {
                let (a, b) = (tri.nodes[k], tri.nodes[(k + 1) % 3]);
                *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        let mut ends: EdgeEnds = Default::default();
        for ((a, b), c) in &count {
            if *c != 1 {
                continue;
            }
            let (p, q) = (self.nodes[*a], self.nodes[*b]);
            let Some(side) = self.side_of(p, q) else {
                continue;
            };
            let axis = Self::axis(side);
            for (n, other) in [(*a, q), (*b, p)] {
                let above = other[axis] > self.nodes[n][axis];
                ends[side].entry(n).or_insert([false; 2])[usize::from(above)] = true;
            }
        }
        ends
    }

    /// The four corner nodes, each of which must be one node.
    fn corners(&self) -> Result<[usize; 4]> {
        let (w, h) = (self.width, self.height);
        let corner_xy = [[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]];
        let mut corners = [usize::MAX; 4];
        for (c, xy) in corner_xy.iter().enumerate() {
            let found: Vec<usize> = (0..self.nodes.len())
                .filter(|&i| {
                    self.near(self.nodes[i][0], xy[0]) && self.near(self.nodes[i][1], xy[1])
                })
                .collect();
            match found[..] {
                [i] => corners[c] = i,
                _ => {
                    return Err(Error::Mesh(format!(
                        "{} nodes at the cell corner {xy:?}: a corner must be one node",
                        found.len()
                    )))
                }
            }
        }
        Ok(corners)
    }

    /// Periodic ties: at each position of a side, the copies ending the edge below and the
    /// edge above, tied to the opposite side's; and whether the opposite sides' positions
    /// match at all.
    fn periodic_ties(
        &self,
        lists: &[Vec<usize>; 4],
        ends: &EdgeEnds,
    ) -> (Vec<(usize, usize)>, bool) {
        let mut ties = Vec::new();
        let mut sides_match = true;
        for (lo, hi) in [(3usize, 1usize), (0, 2)] {
            let (a, b) = (
                self.positions(lo, lists, ends),
                self.positions(hi, lists, ends),
            );
            if a.len() != b.len() || a.iter().zip(&b).any(|(x, y)| !self.near(x.0, y.0)) {
                sides_match = false;
                continue;
            }
            for ((_, ea), (_, eb)) in a.iter().zip(&b) {
                for k in 0..2 {
                    if ea[k] != usize::MAX && eb[k] != usize::MAX {
                        ties.push((eb[k], ea[k]));
                    }
                }
            }
        }
        (ties, sides_match)
    }

    /// A side's positions, each with the copy ending the edge below and the one above
    /// (`usize::MAX` where none).
    fn positions(
        &self,
        side: usize,
        lists: &[Vec<usize>; 4],
        ends: &EdgeEnds,
    ) -> Vec<(f64, [usize; 2])> {
        let axis = Self::axis(side);
        let mut by_pos: Vec<(f64, [usize; 2])> = Vec::new();
        for &n in &lists[side] {
            let pos = self.nodes[n][axis];
            if !matches!(by_pos.last(), Some(last) if self.near(last.0, pos)) {
                by_pos.push((pos, [usize::MAX; 2]));
            }
            let slot = by_pos.last_mut().expect("pushed above");
            for (k, has) in ends[side][&n].iter().enumerate() {
                if *has {
                    slot.1[k] = n;
                }
            }
        }
        by_pos
    }
}

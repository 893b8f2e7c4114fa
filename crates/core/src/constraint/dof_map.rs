//! Master-slave elimination of the four kinematic constraints (paper section 2, eqs. 10-12;
//! Peric et al. 2011), plus Lagrange multipliers for the minimal one.
//!
//! Unknowns are the reduced fluctuation dofs `u~_r` followed by the multipliers `lambda`.
//! Every mesh dof `2 * node + component` maps to one reduced dof or is fixed at zero:
//!
//! | kind      | fluctuation space                              | how                                   |
//! |-----------|------------------------------------------------|---------------------------------------|
//! | Taylor    | `u~ = 0` everywhere                            | every dof fixed (no unknowns)         |
//! | linear    | `u~ = 0` on the boundary (eq. 12)              | boundary dofs fixed                   |
//! | periodic  | `u~(y+) = u~(y-)` (eq. 10)                     | right -> left, top -> bottom slaves; corners fixed (removes the translation) |
//! | minimal   | `int_dOmega u~ (x) n dA = 0`                   | corner (0,0) fixed, 4 multiplier rows |
//!
//! The minimal constraint is the full tensor `int u~ (x) n = 0` (equivalently a zero mean
//! fluctuation gradient), not only its symmetric part: it also removes the rigid rotation,
//! and with the fixed corner the system is regular. The spaces are nested,
//! Taylor ⊂ linear ⊂ periodic ⊂ minimal, hence the stiffness ordering
//! Taylor >= linear >= periodic >= minimal.

use crate::mesh::Mesh;

/// The kinematic constraint on the fluctuation, stiffest first (the spaces are nested).
/// The scene's `boundary.kind` is this value, by its snake_case name.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BoundaryCondition {
    /// `u~ = 0` everywhere.
    Taylor,
    /// `u~ = 0` on the boundary (eq. 12).
    Linear,
    /// `u~(y+) = u~(y-)` (eq. 10).
    #[default]
    Periodic,
    /// `int u~ (x) n dA = 0` on the boundary (eq. 11).
    Minimal,
}

/// Marker of a dof fixed at zero.
pub const FIXED: u32 = u32::MAX;

/// The map from mesh dofs to unknowns.
#[derive(Clone, Debug)]
pub struct DofMap {
    /// Reduced index of mesh dof `2 * node + component`, or [`FIXED`].
    pub reduced: Vec<u32>,
    /// Number of reduced fluctuation dofs.
    pub n_reduced: usize,
    /// Minimal BC only: rows `(i, j)` in the order xx, xy, yx, yy of
    /// `int u~_i n_j dA = sum_edges L/2 (u~_i(p) + u~_i(q)) n_j`, as (reduced dof, coefficient).
    pub constraint_rows: Vec<Vec<(u32, f64)>>,
}

impl DofMap {
    /// Builds the map for `kind` on `mesh` (whose opposite sides must match for periodic).
    pub fn build(mesh: &Mesh, kind: BoundaryCondition) -> Self {
        let n_dofs = 2 * mesh.nodes.len();
        let b = &mesh.boundary;
        // master[node] = the node whose unknowns it shares (itself if independent),
        // or usize::MAX when fixed.
        let mut master: Vec<usize> = (0..mesh.nodes.len()).collect();
        let fix = |master: &mut Vec<usize>, n: usize| master[n] = usize::MAX;
        match kind {
            BoundaryCondition::Taylor => master.iter_mut().for_each(|m| *m = usize::MAX),
            BoundaryCondition::Linear => {
                for &n in b
                    .corners
                    .iter()
                    .chain(&b.left)
                    .chain(&b.right)
                    .chain(&b.bottom)
                    .chain(&b.top)
                {
                    fix(&mut master, n);
                }
            }
            BoundaryCondition::Periodic => {
                for &n in &b.corners {
                    fix(&mut master, n);
                }
                if b.periodic_ties.is_empty() {
                    for (&l, &r) in b.left.iter().zip(&b.right) {
                        master[r] = l;
                    }
                    for (&bo, &t) in b.bottom.iter().zip(&b.top) {
                        master[t] = bo;
                    }
                } else {
                    tie(&mut master, &b.periodic_ties);
                }
            }
            BoundaryCondition::Minimal => fix(&mut master, b.corners[0]),
        }
        let mut reduced = vec![FIXED; n_dofs];
        let mut n_reduced = 0u32;
        for node in 0..mesh.nodes.len() {
            if master[node] == node {
                for c in 0..2 {
                    reduced[2 * node + c] = n_reduced;
                    n_reduced += 1;
                }
            }
        }
        for node in 0..mesh.nodes.len() {
            let m = master[node];
            if m != node && m != usize::MAX {
                for c in 0..2 {
                    reduced[2 * node + c] = reduced[2 * m + c];
                }
            }
        }
        let constraint_rows = if kind == BoundaryCondition::Minimal {
            minimal_rows(mesh, &reduced)
        } else {
            Vec::new()
        };
        DofMap {
            reduced,
            n_reduced: n_reduced as usize,
            constraint_rows,
        }
    }

    /// Number of multipliers (4 for minimal, else 0).
    pub fn n_multipliers(&self) -> usize {
        self.constraint_rows.len()
    }

    /// Size of the linear system: reduced dofs plus multipliers.
    pub fn n_unknowns(&self) -> usize {
        self.n_reduced + self.n_multipliers()
    }

    /// Reduced indices of the dofs of `nodes`, in node-major order (x, y per node).
    pub fn element_dofs<const N: usize, const D: usize>(&self, nodes: [usize; N]) -> [u32; D] {
        debug_assert_eq!(D, 2 * N);
        let mut out = [FIXED; D];
        for (k, &n) in nodes.iter().enumerate() {
            out[2 * k] = self.reduced[2 * n];
            out[2 * k + 1] = self.reduced[2 * n + 1];
        }
        out
    }
}

/// Ties the nodes of every `(slave, master)` pair and of their chains to one master, the
/// lowest node of its class (a copy may be tied to two copies of the opposite side, which
/// are then tied to each other).
fn tie(master: &mut [usize], ties: &[(usize, usize)]) {
    fn root(m: &[usize], mut i: usize) -> usize {
        while m[i] != i {
            i = m[i];
        }
        i
    }
    for &(a, b) in ties {
        if master[a] == usize::MAX || master[b] == usize::MAX {
            continue;
        }
        let (ra, rb) = (root(master, a), root(master, b));
        if ra != rb {
            master[ra.max(rb)] = ra.min(rb);
        }
    }
    for i in 0..master.len() {
        if master[i] != usize::MAX {
            master[i] = root(master, i);
        }
    }
}

/// The four rows of `int u~ (x) n dA = 0` over the cell boundary, trapezoidal per edge
/// (exact for the piecewise linear fluctuation).
fn minimal_rows(mesh: &Mesh, reduced: &[u32]) -> Vec<Vec<(u32, f64)>> {
    let b = &mesh.boundary;
    let [c0, c1, c2, c3] = b.corners;
    let chain = |first: usize, mid: &[usize], last: usize| {
        let mut v = Vec::with_capacity(mid.len() + 2);
        v.push(first);
        v.extend_from_slice(mid);
        v.push(last);
        v
    };
    let sides = [
        (chain(c0, &b.bottom, c1), [0.0, -1.0]),
        (chain(c1, &b.right, c2), [1.0, 0.0]),
        (chain(c3, &b.top, c2), [0.0, 1.0]),
        (chain(c0, &b.left, c3), [-1.0, 0.0]),
    ];
    // Accumulate weights per (row, reduced dof).
    let mut rows: Vec<std::collections::BTreeMap<u32, f64>> = vec![Default::default(); 4];
    for (nodes, normal) in &sides {
        for pair in nodes.windows(2) {
            let (p, q) = (mesh.nodes[pair[0]], mesh.nodes[pair[1]]);
            let half = 0.5 * ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
            for &node in pair {
                for i in 0..2 {
                    let r = reduced[2 * node + i];
                    if r == FIXED {
                        continue;
                    }
                    for j in 0..2 {
                        *rows[2 * i + j].entry(r).or_insert(0.0) += half * normal[j];
                    }
                }
            }
        }
    }
    rows.into_iter()
        .map(|m| m.into_iter().filter(|&(_, w)| w != 0.0).collect())
        .collect()
}

//! The RVE mesh: nodes, bulk triangles with their phase, and zero-thickness
//! interface (ITZ) elements.
//!
//! Conventions, fixed for every later stage (element, assembly, constraints):
//!
//! * The cell is the rectangle `[0, width] x [0, height]`.
//! * Triangles are counter-clockwise (positive signed area).
//! * An interface element has four nodes `[a0, a1, b0, b1]`:
//!
//! ```text
//!        matrix side B (paper's minus side)      b0 ------------- b1
//!                                                 ^ n (out of the inclusion)
//!        inclusion side A (paper's plus side)    a0 ------------- a1   --> s
//! ```
//!
//!   `a0, a1` belong to the inclusion triangle, `b0, b1` are their duplicates that belong
//!   to the matrix triangle; `a_k` and `b_k` coincide in the reference configuration.
//!   The tangent is `s = (x(a1) - x(a0)) / length`, the normal `n = (s_y, -s_x)` points out
//!   of the inclusion (the edge runs counter-clockwise around the inclusion). The
//!   displacement jump (paper eq. 27) is `delta = u_B - u_A`, so `delta . n > 0` is opening.

use serde::Serialize;

/// Which constituent a bulk triangle belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub enum Phase {
    /// Cement paste.
    Matrix,
    /// Aggregate; all inclusions share the aggregate material.
    Inclusion,
}

impl Phase {
    /// Integer id written to VTK files and statistics: 0 matrix, 1 inclusion.
    pub fn id(self) -> u8 {
        match self {
            Phase::Matrix => 0,
            Phase::Inclusion => 1,
        }
    }
}

/// A 3-node bulk triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// Node indices, counter-clockwise.
    pub nodes: [usize; 3],
    pub phase: Phase,
}

/// A zero-thickness 4-node interface element on an inclusion/matrix boundary edge.
/// See the module documentation for node order and orientation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InterfaceElement {
    /// `[a0, a1, b0, b1]`: inclusion side, then the matrix-side duplicates.
    pub nodes: [usize; 4],
    /// Reference length `l_e` of the edge.
    pub length: f64,
    /// Unit tangent `s`, from `a0` to `a1`.
    pub tangent: [f64; 2],
    /// Unit normal `n = (s_y, -s_x)`, out of the inclusion.
    pub normal: [f64; 2],
    /// What the element is: the ITZ, or a crack through the paste.
    pub kind: InterfaceKind,
}

/// Where an interface element sits, which selects its law.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum InterfaceKind {
    /// Between an aggregate and the paste (side A the aggregate).
    #[default]
    Itz,
    /// Between two paste triangles (side A the one of lower index).
    Paste,
}

/// Nodes on the cell boundary, sorted along each side, for boundary conditions.
///
/// `left[k]` and `right[k]` have the same `y`; `bottom[k]` and `top[k]` the same `x`
/// when [`BoundaryNodes::sides_match`] holds. Corners are not in the side lists.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BoundaryNodes {
    /// Corner nodes: `[(0,0), (w,0), (w,h), (0,h)]`.
    pub corners: [usize; 4],
    pub left: Vec<usize>,
    pub right: Vec<usize>,
    pub bottom: Vec<usize>,
    pub top: Vec<usize>,
    /// True when opposite sides carry the same number of nodes at matching positions.
    pub sides_match: bool,
    /// Periodic ties `(slave, master)` of a mesh whose side nodes have several copies
    /// (cracks through the paste, `super::cracks`); empty: `right[k]` is tied to
    /// `left[k]` and `top[k]` to `bottom[k]`.
    pub periodic_ties: Vec<(usize, usize)>,
}

/// A conforming RVE mesh with ITZ interface elements inserted.
#[derive(Clone, Debug)]
pub struct Mesh {
    pub width: f64,
    pub height: f64,
    pub nodes: Vec<[f64; 2]>,
    pub triangles: Vec<Triangle>,
    pub interfaces: Vec<InterfaceElement>,
    pub boundary: BoundaryNodes,
}

impl Mesh {
    /// Cell area `V_mu` (per unit thickness).
    pub fn cell_area(&self) -> f64 {
        self.width * self.height
    }

    /// Signed area of triangle `t` (positive for counter-clockwise).
    pub fn triangle_area(&self, t: &Triangle) -> f64 {
        let [p, q, r] = t.nodes.map(|i| self.nodes[i]);
        0.5 * ((q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1]))
    }
}

/// A conforming phase-labelled triangulation before ITZ insertion: what a mesher or a
/// Gmsh file delivers. [`crate::mesh::insert_itz`] turns it into a [`Mesh`].
#[derive(Clone, Debug, Default)]
pub struct PhaseMesh {
    pub nodes: Vec<[f64; 2]>,
    /// Counter-clockwise triangles with their phase.
    pub triangles: Vec<Triangle>,
}

/// The mesh of a scene and the geometry it came from.
#[derive(Clone, Debug)]
pub struct Microstructure {
    pub mesh: Mesh,
    /// Exact inclusion shapes (empty for Gmsh meshes, homogeneous cells and the straight
    /// interface).
    pub inclusions: Vec<crate::geometry::Inclusion>,
    /// Exact inclusion area over cell area, before discretisation (None for Gmsh; for the
    /// straight interface the part left of it).
    pub geometric_area_fraction: Option<f64>,
    /// Random placement rounds used (None unless random).
    pub placement_rounds: Option<u32>,
}

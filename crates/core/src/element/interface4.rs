//! The 4-node zero-thickness cohesive-contact interface element (paper section 4,
//! eqs. 26-47).
//!
//! Node order and orientation follow [`crate::mesh`] exactly:
//! ```text
//!     matrix side B (paper's minus side)      b0 ------------- b1
//!                                              ^ n = (s_y, -s_x), out of the inclusion
//!     inclusion side A (paper's plus side)    a0 ------------- a1   --> s = (x_a1 - x_a0)/l_e
//!
//!     xi:                                     -1               +1
//! ```
//! Dofs `u = [a0x, a0y, a1x, a1y, b0x, b0y, b1x, b1y]` (global axes). `a_k` and `b_k`
//! coincide in the reference configuration.
//!
//! # Kinematics
//! Linear shape functions on `xi in [-1, 1]`: `N0 = (1 - xi)/2`, `N1 = (1 + xi)/2`.
//! The global jump at a point (eq. 27, `delta = u^- - u^+ = u_B - u_A`) is `B(xi) u` with
//! the 2x8 jump operator (eqs. 28, 44)
//! ```text
//! B = [ -N0 I2 | -N1 I2 | N0 I2 | N1 I2 ]
//! ```
//! and the local jump `[delta_s, delta_n] = R B u`, with the rotation to the local axes
//! ```text
//! R = | s_x  s_y |
//!     | n_x  n_y |
//! ```
//!
//! # Internal force and tangent
//! With the local traction `t_i` and tangent `C_i = dt/d delta` of the
//! [cohesive-contact law](crate::interface) at point `i` (eqs. 32-37, 45-47):
//! ```text
//! F = (l_e/2) sum_i w_i B_i^T R^T t_i                         (eqs. 30, 38-39)
//! K = dF/du = (l_e/2) sum_i w_i B_i^T (R^T C_i R) B_i          (eqs. 41-44)
//! ```
//! `F` is the internal force in the sense of the bulk elements (`F = dW/du`, `W` the
//! stored interface energy), so that the assembled residual is `F_int - F_ext`. The
//! paper writes the plus-side force with the traction acting on that face and fixes the
//! sign of the minus side afterwards (eqs. 39, 41); here both signs come out of `B`:
//! `F_A = -F_B` node by node (equilibrium of the element, zero net force and moment) and
//! `K = [[A, -A], [-A, A]]` with `A = (l_e/2) sum_i w_i (N N^T) (x) R^T C_i R`. `K` is
//! symmetric when every `C_i` is: not at a point that slides under friction
//! (`interface::Frictional`).
//!
//! Because of the block structure only the 4x4 block `A` and the 4-vector
//! `F_B = (l_e/2) sum_i w_i [N0 t_g; N1 t_g]` (with `t_g = R^T t`) are accumulated.
//!
//! # Quadrature
//! [`InterfaceQuadrature::Gauss3`] is the paper's 3-point Gauss rule;
//! [`InterfaceQuadrature::Lobatto2`] puts the points at the nodes (2-point Newton-Cotes,
//! i.e. nodal lumping), the usual cure for the spurious traction oscillations of Gauss
//! integrated interface elements with a stiff (penalty or initial cohesive) response.
//! The branch (loading, unloading, contact) is decided per quadrature point on the
//! interpolated jump there (the paper's "gap between the Gauss points"), so one element
//! may be partly closed and partly open, and its faces need not stay parallel.
//! The `PerLength` penalty uses the element's reference length `l_e`.
//! Points are numbered in increasing `xi` (from the `a0`/`b0` end to the `a1`/`b1` end);
//! history slices use that numbering.

use nalgebra::{Matrix2, SMatrix, SVector, Vector2};

use crate::interface::{Branch, InterfaceLaw, LawPoint, TangentKind};

/// The largest number of quadrature points of any [`InterfaceQuadrature`].
///
/// (Not part of the C API: kept out of the cbindgen header.)
/// cbindgen:ignore
pub const MAX_POINTS: usize = 3;

/// Quadrature rule along the interface element.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum InterfaceQuadrature {
    /// 3-point Gauss-Legendre, `xi = -sqrt(3/5), 0, sqrt(3/5)`, `w = 5/9, 8/9, 5/9`
    /// (the paper's choice; the default).
    #[default]
    Gauss3,
    /// 2-point Newton-Cotes / Gauss-Lobatto (trapezoidal), `xi = -1, 1`, `w = 1, 1`:
    /// the points are the nodes.
    Lobatto2,
}

const GAUSS3_XI: f64 = 0.774_596_669_241_483_4; // sqrt(3/5)
const GAUSS3: [(f64, f64); 3] = [
    (-GAUSS3_XI, 5.0 / 9.0),
    (0.0, 8.0 / 9.0),
    (GAUSS3_XI, 5.0 / 9.0),
];
const LOBATTO2: [(f64, f64); 2] = [(-1.0, 1.0), (1.0, 1.0)];

impl InterfaceQuadrature {
    /// Number of quadrature points (at most [`MAX_POINTS`]).
    #[inline]
    pub const fn num_points(self) -> usize {
        match self {
            InterfaceQuadrature::Gauss3 => 3,
            InterfaceQuadrature::Lobatto2 => 2,
        }
    }

    /// The rule as `(xi, weight)` pairs on `[-1, 1]`, in increasing `xi`; weights sum to 2.
    #[inline]
    pub fn rule(self) -> &'static [(f64, f64)] {
        match self {
            InterfaceQuadrature::Gauss3 => &GAUSS3,
            InterfaceQuadrature::Lobatto2 => &LOBATTO2,
        }
    }
}

/// Reference geometry of an interface element: what the kernel needs from the mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InterfaceGeometry {
    /// Reference length `l_e`.
    pub length: f64,
    /// Unit tangent `s`, from `a0` to `a1`.
    pub tangent: [f64; 2],
    /// Unit normal `n = (s_y, -s_x)`, out of the inclusion.
    pub normal: [f64; 2],
}

impl InterfaceGeometry {
    /// Geometry of the edge from `a0` to `a1` (the inclusion-side nodes), with the mesh
    /// conventions `s = (a1 - a0)/l_e`, `n = (s_y, -s_x)`.
    pub fn from_nodes(a0: [f64; 2], a1: [f64; 2]) -> Self {
        let (dx, dy) = (a1[0] - a0[0], a1[1] - a0[1]);
        let length = dx.hypot(dy);
        let s = [dx / length, dy / length];
        InterfaceGeometry {
            length,
            tangent: s,
            normal: [s[1], -s[0]],
        }
    }

    /// Rotation to the local axes, rows `s` and `n`.
    #[inline]
    fn rotation(&self) -> Matrix2<f64> {
        let (s, n) = (self.tangent, self.normal);
        Matrix2::new(s[0], s[1], n[0], n[1])
    }
}

/// Internal force, tangent and branch statistics of one interface element.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InterfaceResponse {
    /// Internal force `F` (8-vector, dof order of the module doc), eqs. 38-39.
    pub force: SVector<f64, 8>,
    /// Consistent tangent `dF/du` (8x8, eqs. 41-47): symmetric unless a point slides.
    pub stiffness: SMatrix<f64, 8, 8>,
    /// Number of points on the loading branch (damage growing).
    pub loading: usize,
    /// Number of points on the unloading/reloading branch.
    pub unloading: usize,
    /// Number of points in contact, sliding ones included.
    pub contact: usize,
    /// Number of closed points sliding under friction ([`Branch::Sliding`]), whose
    /// tangent is not symmetric.
    pub sliding: usize,
    /// The branch of every point, two bits each from the lowest (point `i` at bits
    /// `2i..2i+2`): 1 loading, 2 unloading, 3 contact, 0 sliding.
    pub branches: u8,
}

impl InterfaceResponse {
    /// True when some point is on the loading branch.
    #[inline]
    pub fn any_loading(&self) -> bool {
        self.loading > 0
    }

    /// True when some point is in contact.
    #[inline]
    pub fn any_contact(&self) -> bool {
        self.contact > 0
    }
}

/// Global nodal jumps `u_b0 - u_a0`, `u_b1 - u_a1`.
#[inline]
fn nodal_jumps(u: &SVector<f64, 8>) -> [Vector2<f64>; 2] {
    [
        Vector2::new(u[4] - u[0], u[5] - u[1]),
        Vector2::new(u[6] - u[2], u[7] - u[3]),
    ]
}

/// Local jumps `[delta_s, delta_n]` at the quadrature points (first
/// `quadrature.num_points()` entries; the rest are zero). For post-processing and
/// linear-range predictions.
pub fn local_jumps(
    geometry: &InterfaceGeometry,
    quadrature: InterfaceQuadrature,
    u: &SVector<f64, 8>,
) -> [[f64; 2]; MAX_POINTS] {
    let r = geometry.rotation();
    let [j0, j1] = nodal_jumps(u);
    let mut out = [[0.0; 2]; MAX_POINTS];
    for (o, &(xi, _)) in out.iter_mut().zip(quadrature.rule()) {
        let jl = r * (j0 * (0.5 * (1.0 - xi)) + j1 * (0.5 * (1.0 + xi)));
        *o = [jl[0], jl[1]];
    }
    out
}

/// Evaluates the element: internal force, consistent tangent, and the trial histories.
///
/// `committed` holds the converged history of the element's quadrature points, `trial`
/// receives their trial history; both hold `law.history_len()` values per point, points
/// in increasing `xi`, and at least `quadrature.num_points()` points (extra entries are
/// neither read nor written). `u` is the element's total
/// displacement in the dof order of the module doc. Allocation free.
///
/// # Panics
/// If `committed` or `trial` is shorter than `quadrature.num_points()`.
pub fn evaluate(
    geometry: &InterfaceGeometry,
    quadrature: InterfaceQuadrature,
    law: &dyn InterfaceLaw,
    committed: &[f64],
    u: &SVector<f64, 8>,
    trial: &mut [f64],
) -> InterfaceResponse {
    evaluate_with(
        geometry,
        quadrature,
        law,
        committed,
        u,
        trial,
        TangentKind::Consistent,
        None,
    )
}

/// The contact status of every quadrature point for the element displacement `u`, as the
/// law reads it from the gap there ([`InterfaceLaw::is_closed`]); first
/// `quadrature.num_points()` entries, the rest `false`. The solver takes the status a
/// Newton loop starts from with this (see [`evaluate_with`]).
pub fn contact_status(
    geometry: &InterfaceGeometry,
    quadrature: InterfaceQuadrature,
    law: &dyn InterfaceLaw,
    u: &SVector<f64, 8>,
) -> [bool; MAX_POINTS] {
    let jumps = local_jumps(geometry, quadrature, u);
    let mut out = [false; MAX_POINTS];
    for (o, j) in out.iter_mut().zip(&jumps).take(quadrature.num_points()) {
        *o = law.is_closed(*j);
    }
    out
}

/// [`evaluate`] with a choice of matrix and of contact status. `status`: `None` reads the
/// status of each point from its gap at `u` ([`InterfaceLaw::respond`]); `Some(closed)`
/// holds it per point ([`InterfaceLaw::respond_as`], at least `quadrature.num_points()`
/// entries), so that the force is continuous in `u`.
#[allow(clippy::too_many_arguments)]
pub fn evaluate_with(
    geometry: &InterfaceGeometry,
    quadrature: InterfaceQuadrature,
    law: &dyn InterfaceLaw,
    committed: &[f64],
    u: &SVector<f64, 8>,
    trial: &mut [f64],
    kind: TangentKind,
    status: Option<&[bool]>,
) -> InterfaceResponse {
    let rule = quadrature.rule();
    let hl = law.history_len();
    debug_assert!(
        (geometry.normal[0] - geometry.tangent[1]).abs() < 1e-12
            && (geometry.normal[1] + geometry.tangent[0]).abs() < 1e-12,
        "interface normal must be (s_y, -s_x)"
    );
    let r = geometry.rotation();
    let [j0, j1] = nodal_jumps(u);
    let half_l = 0.5 * geometry.length;

    let mut sums = ElementSums::new();
    for (point, &(xi, w)) in rule.iter().enumerate() {
        let shape = [0.5 * (1.0 - xi), 0.5 * (1.0 + xi)];
        let jl = r * (j0 * shape[0] + j1 * shape[1]);
        let span = point * hl..(point + 1) * hl;
        let jump = [jl[0], jl[1]];
        let (committed, trial) = (&committed[span.clone()], &mut trial[span]);
        let p = match status {
            None => law.respond(committed, trial, jump, geometry.length, kind),
            Some(st) => law.respond_as(committed, trial, jump, geometry.length, kind, st[point]),
        };
        sums.count(p.branch, point);
        sums.add(shape, w * half_l, &r, &p);
    }
    sums.response()
}

/// What [`evaluate_with`] accumulates over the quadrature points: the matrix-side half
/// of the force `F_B` and the 4x4 block `A` (see the module doc), and the branches.
struct ElementSums {
    fb: SVector<f64, 4>,
    a: SMatrix<f64, 4, 4>,
    loading: usize,
    unloading: usize,
    contact: usize,
    sliding: usize,
    branches: u8,
}

impl ElementSums {
    #[inline]
    fn new() -> Self {
        ElementSums {
            fb: SVector::<f64, 4>::zeros(),
            a: SMatrix::<f64, 4, 4>::zeros(),
            loading: 0,
            unloading: 0,
            contact: 0,
            sliding: 0,
            branches: 0,
        }
    }

    /// Counts the branch of point `point` and puts its code in `branches`.
    #[inline]
    fn count(&mut self, branch: Branch, point: usize) {
        let code = match branch {
            Branch::Loading => {
                self.loading += 1;
                1
            }
            Branch::Unloading => {
                self.unloading += 1;
                2
            }
            Branch::Contact => {
                self.contact += 1;
                3
            }
            // Code 0: every point has a code, so the element's byte still tells the
            // branches apart.
            Branch::Sliding => {
                self.contact += 1;
                self.sliding += 1;
                0
            }
        };
        self.branches |= code << (2 * point);
    }

    /// Adds the point with shape values `shape`, weight `wl = w_i l_e/2`, rotation `r`
    /// and law response `p` (eqs. 32-37, 45-47): `wl N t_g` to `F_B` (eqs. 30, 38-39),
    /// `wl (N N^T) (x) R^T C_i R` to `A` (eqs. 41-44).
    #[inline]
    fn add(&mut self, shape: [f64; 2], wl: f64, r: &Matrix2<f64>, p: &LawPoint) {
        let tg = r.transpose() * p.traction;
        let cg = r.transpose() * p.matrix * r;
        for (i, &ni) in shape.iter().enumerate() {
            let f = tg * (wl * ni);
            self.fb[2 * i] += f[0];
            self.fb[2 * i + 1] += f[1];
            for (j, &nj) in shape.iter().enumerate() {
                let mut blk = self.a.fixed_view_mut::<2, 2>(2 * i, 2 * j);
                blk += cg * (wl * ni * nj);
            }
        }
    }

    /// The element's force `F = [-F_B, F_B]` (eq. 39) and tangent
    /// `K = [[A, -A], [-A, A]]` (eq. 41), both sides from `B` (see the module doc).
    #[inline]
    fn response(self) -> InterfaceResponse {
        let (fb, a) = (self.fb, self.a);
        let mut force = SVector::<f64, 8>::zeros();
        force.fixed_rows_mut::<4>(0).copy_from(&(-fb));
        force.fixed_rows_mut::<4>(4).copy_from(&fb);
        let mut stiffness = SMatrix::<f64, 8, 8>::zeros();
        stiffness.fixed_view_mut::<4, 4>(0, 0).copy_from(&a);
        stiffness.fixed_view_mut::<4, 4>(0, 4).copy_from(&(-a));
        stiffness.fixed_view_mut::<4, 4>(4, 0).copy_from(&(-a));
        stiffness.fixed_view_mut::<4, 4>(4, 4).copy_from(&a);
        InterfaceResponse {
            force,
            stiffness,
            loading: self.loading,
            unloading: self.unloading,
            contact: self.contact,
            sliding: self.sliding,
            branches: self.branches,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interface::{CohesiveHistory, CohesiveLaw, ContactShear, Penalty};

    const DC: f64 = 2e-4;
    const QUADS: [InterfaceQuadrature; 2] =
        [InterfaceQuadrature::Gauss3, InterfaceQuadrature::Lobatto2];

    fn law() -> CohesiveLaw {
        CohesiveLaw {
            sigma_c: 4.0,
            delta_c: DC,
            beta: 0.707,
            penalty: Penalty::PerLength { lambda_p: 1e7 },
            contact: true,
            contact_shear: ContactShear::Penalty,
        }
    }

    /// Edge from (1.0, 0.5) to (1.3, 0.9): l = 0.5, s = (0.6, 0.8), n = (0.8, -0.6).
    fn geom() -> InterfaceGeometry {
        InterfaceGeometry::from_nodes([1.0, 0.5], [1.3, 0.9])
    }

    fn history_at(delta: f64) -> [f64; MAX_POINTS] {
        [delta; MAX_POINTS]
    }

    /// Element displacement: an arbitrary motion of side A (translation, small rotation,
    /// stretch) plus prescribed local nodal jumps `[ds, dn]` at nodes 0 and 1.
    fn displacement(g: &InterfaceGeometry, jumps: [[f64; 2]; 2]) -> SVector<f64, 8> {
        let ua = [[3e-4, -1e-4], [2.5e-4, 0.4e-4]];
        let mut u = SVector::<f64, 8>::zeros();
        for k in 0..2 {
            let jg = [
                jumps[k][0] * g.tangent[0] + jumps[k][1] * g.normal[0],
                jumps[k][0] * g.tangent[1] + jumps[k][1] * g.normal[1],
            ];
            u[2 * k] = ua[k][0];
            u[2 * k + 1] = ua[k][1];
            u[4 + 2 * k] = ua[k][0] + jg[0];
            u[4 + 2 * k + 1] = ua[k][1] + jg[1];
        }
        u
    }

    fn eval(
        g: &InterfaceGeometry,
        q: InterfaceQuadrature,
        committed: &[f64],
        u: &SVector<f64, 8>,
    ) -> (InterfaceResponse, [f64; MAX_POINTS]) {
        let mut trial = [0.0; MAX_POINTS];
        let r = evaluate(g, q, &law(), committed, u, &mut trial);
        (r, trial)
    }

    /// Stiffness against a central FD of the internal force; returns the relative error.
    /// Asserts that no perturbation changes the branch of any point.
    fn fd_error(
        g: &InterfaceGeometry,
        q: InterfaceQuadrature,
        committed: &[f64],
        u: &SVector<f64, 8>,
    ) -> f64 {
        let (r0, _) = eval(g, q, committed, u);
        let h = 1e-6 * DC;
        let mut kfd = SMatrix::<f64, 8, 8>::zeros();
        for j in 0..8 {
            let mut e = SVector::<f64, 8>::zeros();
            e[j] = h;
            let (rp, _) = eval(g, q, committed, &(u + e));
            let (rm, _) = eval(g, q, committed, &(u - e));
            for r in [&rp, &rm] {
                assert_eq!(
                    (r.loading, r.unloading, r.contact),
                    (r0.loading, r0.unloading, r0.contact),
                    "FD crosses a branch"
                );
            }
            kfd.set_column(j, &((rp.force - rm.force) / (2.0 * h)));
        }
        let k = r0.stiffness;
        assert!((k - k.transpose()).norm() <= 1e-13 * k.norm());
        (k - kfd).norm() / k.norm()
    }

    #[test]
    fn quadrature_rules() {
        for q in QUADS {
            let rule = q.rule();
            assert_eq!(rule.len(), q.num_points());
            assert!(rule.len() <= MAX_POINTS);
            assert!((rule.iter().map(|p| p.1).sum::<f64>() - 2.0).abs() < 1e-15);
            // Exact for linear functions; Gauss3 also for quintics.
            assert!(rule.iter().map(|p| p.0 * p.1).sum::<f64>().abs() < 1e-15);
        }
        let x4: f64 = GAUSS3.iter().map(|p| p.0.powi(4) * p.1).sum();
        assert!((x4 - 0.4).abs() < 1e-15);
        assert!((GAUSS3_XI - 0.6f64.sqrt()).abs() < 1e-16);
        assert_eq!(InterfaceQuadrature::default(), InterfaceQuadrature::Gauss3);
        let q: InterfaceQuadrature = serde_json::from_str("\"lobatto2\"").unwrap();
        assert_eq!(q, InterfaceQuadrature::Lobatto2);
    }

    #[test]
    fn geometry_follows_mesh_conventions() {
        let g = geom();
        assert!((g.length - 0.5).abs() < 1e-15);
        assert!((g.tangent[0] - 0.6).abs() < 1e-15 && (g.tangent[1] - 0.8).abs() < 1e-15);
        assert_eq!(g.normal, [g.tangent[1], -g.tangent[0]]);
    }

    #[test]
    fn local_jumps_interpolate_nodal_jumps() {
        let g = geom();
        let u = displacement(&g, [[0.1 * DC, 0.5 * DC], [0.3 * DC, -0.2 * DC]]);
        let j = local_jumps(&g, InterfaceQuadrature::Lobatto2, &u);
        assert!((j[0][0] - 0.1 * DC).abs() < 1e-18 && (j[0][1] - 0.5 * DC).abs() < 1e-18);
        assert!((j[1][0] - 0.3 * DC).abs() < 1e-18 && (j[1][1] + 0.2 * DC).abs() < 1e-18);
        assert_eq!(j[2], [0.0, 0.0]);
        let j = local_jumps(&g, InterfaceQuadrature::Gauss3, &u);
        assert!((j[1][0] - 0.2 * DC).abs() < 1e-18 && (j[1][1] - 0.15 * DC).abs() < 1e-18);
    }

    #[test]
    fn stiffness_matches_fd_loading() {
        let g = geom();
        let u = displacement(&g, [[0.5 * DC, 0.8 * DC], [-0.3 * DC, 1.6 * DC]]);
        let virgin = [0.0; MAX_POINTS];
        for q in QUADS {
            let (r, _) = eval(&g, q, &virgin, &u);
            assert_eq!(r.loading, q.num_points());
            let err = fd_error(&g, q, &virgin, &u);
            assert!(err < 1e-6, "{q:?}: rel err {err:e}");
        }
    }

    #[test]
    fn stiffness_matches_fd_unloading() {
        let g = geom();
        let u = displacement(&g, [[0.2 * DC, 0.5 * DC], [0.4 * DC, 1.0 * DC]]);
        let committed = history_at(3.0 * DC);
        for q in QUADS {
            let (r, trial) = eval(&g, q, &committed, &u);
            assert_eq!(r.unloading, q.num_points());
            assert_eq!(&trial[..q.num_points()], &committed[..q.num_points()]);
            let err = fd_error(&g, q, &committed, &u);
            assert!(err < 1e-6, "{q:?}: rel err {err:e}");
        }
    }

    #[test]
    fn stiffness_matches_fd_contact() {
        let g = geom();
        let u = displacement(&g, [[0.2 * DC, -0.5 * DC], [-0.4 * DC, -0.1 * DC]]);
        for committed in [[0.0; MAX_POINTS], history_at(2.0 * DC)] {
            for q in QUADS {
                let (r, trial) = eval(&g, q, &committed, &u);
                assert_eq!(r.contact, q.num_points());
                assert!(r.any_contact() && !r.any_loading());
                assert_eq!(&trial[..q.num_points()], &committed[..q.num_points()]);
                let err = fd_error(&g, q, &committed, &u);
                assert!(err < 1e-6, "{q:?}: rel err {err:e}");
            }
        }
    }

    #[test]
    fn stiffness_matches_fd_mixed() {
        // dn goes from +1.0 dc at node 0 to -0.8 dc at node 1: the points near node 0
        // are open, the one near node 1 is closed. With delta_max = 0.5 dc the first
        // Gauss point loads and the middle one unloads.
        let g = geom();
        let u = displacement(&g, [[0.3 * DC, 1.0 * DC], [0.2 * DC, -0.8 * DC]]);
        let committed = history_at(0.5 * DC);
        let (r, _) = eval(&g, InterfaceQuadrature::Gauss3, &committed, &u);
        assert_eq!((r.loading, r.unloading, r.contact), (1, 1, 1));
        let (r, _) = eval(&g, InterfaceQuadrature::Lobatto2, &committed, &u);
        assert_eq!((r.loading, r.unloading, r.contact), (1, 0, 1));
        for q in QUADS {
            let err = fd_error(&g, q, &committed, &u);
            assert!(err < 1e-6, "{q:?}: rel err {err:e}");
            let virgin = [0.0; MAX_POINTS];
            let err = fd_error(&g, q, &virgin, &u);
            assert!(err < 1e-6, "{q:?} virgin: rel err {err:e}");
        }
    }

    #[test]
    fn trial_histories_are_the_laws() {
        let g = geom();
        let u = displacement(&g, [[0.3 * DC, 1.0 * DC], [0.2 * DC, -0.8 * DC]]);
        let committed = history_at(0.5 * DC);
        for q in QUADS {
            let sentinel = -1.0;
            let mut trial = [sentinel; MAX_POINTS];
            evaluate(&g, q, &law(), &committed, &u, &mut trial);
            let jumps = local_jumps(&g, q, &u);
            for i in 0..q.num_points() {
                let history = crate::interface::CohesiveHistory {
                    delta_max: committed[i],
                };
                let p = law().evaluate(&history, jumps[i], g.length);
                assert_eq!(trial[i], p.history.delta_max);
            }
            for t in &trial[q.num_points()..] {
                assert_eq!(*t, sentinel, "entries past num_points are not written");
            }
        }
        // Lobatto2 accepts exactly two entries.
        let mut two = [0.0; 2];
        evaluate(
            &g,
            InterfaceQuadrature::Lobatto2,
            &law(),
            &committed[..2],
            &u,
            &mut two,
        );
        assert!(two[0] > 0.5 * DC);
    }

    /// A held status per point is passed to the law point by point; the status read from
    /// the gap is what `contact_status` returns. With the status held the force is
    /// continuous across closure (Lipschitz, with a kink of the normal stiffness there);
    /// with the status read from the gap it jumps.
    #[test]
    fn held_status_per_point() {
        let g = geom();
        // delta_n from +1e-9 dc at node 0 to -1e-9 dc at node 1: the first Gauss point is
        // open, the last closed, the middle one at delta_n = 0 (open).
        let u = displacement(&g, [[0.3 * DC, 1e-9 * DC], [0.2 * DC, -1e-9 * DC]]);
        let committed = history_at(0.5 * DC);
        let st = contact_status(&g, InterfaceQuadrature::Gauss3, &law(), &u);
        assert_eq!(st, [false, false, true]);
        let (r, _) = eval(&g, InterfaceQuadrature::Gauss3, &committed, &u);
        let at = |u: &SVector<f64, 8>, held: Option<&[bool]>, trial: &mut [f64]| {
            evaluate_with(
                &g,
                InterfaceQuadrature::Gauss3,
                &law(),
                &committed,
                u,
                trial,
                TangentKind::Consistent,
                held,
            )
        };
        let mut trial = [0.0; MAX_POINTS];
        assert_eq!(at(&u, Some(&st), &mut trial), r);
        // Largest |F(u + h e_j) - F(u - h e_j)| / 2h over the dofs, with steps of 1e-6 dc
        // that cross the gaps of 1e-9 dc.
        let h = 1e-6 * DC;
        let slope = |held: Option<&[bool]>| {
            (0..8)
                .map(|j| {
                    let mut e = SVector::<f64, 8>::zeros();
                    e[j] = h;
                    let mut t = [0.0; MAX_POINTS];
                    let fp = at(&(u + e), held, &mut t).force;
                    let fm = at(&(u - e), held, &mut t).force;
                    (fp - fm).norm() / (2.0 * h)
                })
                .fold(0.0, f64::max)
        };
        for held in [
            [false, true, false],
            [true, true, true],
            [false, false, false],
        ] {
            let mut trial = [0.0; MAX_POINTS];
            let r = at(&u, Some(&held), &mut trial);
            let jumps = local_jumps(&g, InterfaceQuadrature::Gauss3, &u);
            for i in 0..3 {
                let h = CohesiveHistory {
                    delta_max: committed[i],
                };
                let p = law().evaluate_as(&h, jumps[i], g.length, held[i]);
                assert_eq!(trial[i], p.history.delta_max);
            }
            let s = slope(Some(&held));
            assert!(s < 2.0 * r.stiffness.norm(), "held {held:?}: slope {s:e}");
        }
        let s = slope(None);
        assert!(
            s > 1e3 * r.stiffness.norm(),
            "read from the gap: slope {s:e}"
        );
    }

    #[test]
    fn rigid_motion_gives_zero_jump_and_force() {
        let g = geom();
        // Both sides move together: translation plus an infinitesimal rotation about
        // the origin (a_k and b_k coincide, so they get the same displacement).
        let x = [[1.0, 0.5], [1.3, 0.9]];
        let mut u = SVector::<f64, 8>::zeros();
        for (k, p) in x.iter().enumerate() {
            let d = [1e-3 - 2e-4 * p[1], -5e-4 + 2e-4 * p[0]];
            for side in 0..2 {
                u[4 * side + 2 * k] = d[0];
                u[4 * side + 2 * k + 1] = d[1];
            }
        }
        for q in QUADS {
            for committed in [[0.0; MAX_POINTS], history_at(DC)] {
                let (r, trial) = eval(&g, q, &committed, &u);
                assert_eq!(r.force, SVector::<f64, 8>::zeros());
                assert!(local_jumps(&g, q, &u).iter().all(|j| *j == [0.0, 0.0]));
                assert_eq!(&trial[..q.num_points()], &committed[..q.num_points()]);
            }
        }
    }

    #[test]
    fn forces_balance_and_opening_pulls_sides_together() {
        let g = geom();
        let u = displacement(&g, [[0.5 * DC, 0.8 * DC], [-0.3 * DC, 1.6 * DC]]);
        for q in QUADS {
            let (r, _) = eval(&g, q, &[0.0; MAX_POINTS], &u);
            let f = r.force;
            for c in 0..2 {
                let sum: f64 = (0..4).map(|k| f[2 * k + c]).sum();
                assert!(sum.abs() <= 1e-14 * f.norm(), "sum {sum:e}");
                // Node pairs carry equal and opposite forces.
                for k in 0..2 {
                    assert_eq!(f[2 * k + c], -f[4 + 2 * k + c]);
                }
            }
            // Opening: the internal force on the matrix side points along +n.
            for k in 0..2 {
                let fn_b = f[4 + 2 * k] * g.normal[0] + f[4 + 2 * k + 1] * g.normal[1];
                assert!(fn_b > 0.0);
            }
        }
    }

    #[test]
    fn linear_branch_gives_consistent_and_lumped_matrices() {
        // Unloading: C is constant, so Gauss3 integrates exactly the consistent matrix
        // (l/6)[[2,1],[1,2]] (x) C_g and Lobatto2 gives the lumped (l/2) I (x) C_g.
        let g = geom();
        let u = displacement(&g, [[0.2 * DC, 0.5 * DC], [0.4 * DC, 1.0 * DC]]);
        let committed = history_at(3.0 * DC);
        let k = law().envelope(committed[0]) / committed[0]; // eq. 24
        let r = g.rotation();
        let cg = r.transpose() * Matrix2::new(k * 0.707 * 0.707, 0.0, 0.0, k) * r;
        let l = g.length;
        for (q, m) in [
            (
                InterfaceQuadrature::Gauss3,
                [[l / 3.0, l / 6.0], [l / 6.0, l / 3.0]],
            ),
            (
                InterfaceQuadrature::Lobatto2,
                [[l / 2.0, 0.0], [0.0, l / 2.0]],
            ),
        ] {
            let (res, _) = eval(&g, q, &committed, &u);
            for (i, row) in m.iter().enumerate() {
                for (j, &mij) in row.iter().enumerate() {
                    let blk = res.stiffness.fixed_view::<2, 2>(4 + 2 * i, 4 + 2 * j);
                    let exp = cg * mij;
                    assert!((blk - exp).norm() <= 1e-14 * cg.norm(), "{q:?} {i}{j}");
                    let off = res.stiffness.fixed_view::<2, 2>(2 * i, 4 + 2 * j);
                    assert!((off + exp).norm() <= 1e-14 * cg.norm());
                }
            }
        }
    }

    #[test]
    fn rotating_geometry_and_displacement_rotates_force() {
        let g0 = geom();
        let jumps = [[0.3 * DC, 1.0 * DC], [0.2 * DC, -0.8 * DC]];
        let u0 = displacement(&g0, jumps);
        let committed = history_at(0.5 * DC);
        for theta in [0.3_f64, 1.9, -2.6, std::f64::consts::PI] {
            let (c, s) = (theta.cos(), theta.sin());
            let q2 = Matrix2::new(c, -s, s, c);
            let mut q8 = SMatrix::<f64, 8, 8>::zeros();
            for k in 0..4 {
                q8.fixed_view_mut::<2, 2>(2 * k, 2 * k).copy_from(&q2);
            }
            let rot = |v: [f64; 2]| {
                let w = q2 * Vector2::new(v[0], v[1]);
                [w[0], w[1]]
            };
            let a0 = rot([1.0, 0.5]);
            let a1 = rot([1.3, 0.9]);
            let g = InterfaceGeometry::from_nodes(a0, a1);
            assert!((Vector2::from(g.tangent) - q2 * Vector2::from(g0.tangent)).norm() < 1e-15);
            assert!((Vector2::from(g.normal) - q2 * Vector2::from(g0.normal)).norm() < 1e-15);
            let u = q8 * u0;
            for q in QUADS {
                let (r0, t0) = eval(&g0, q, &committed, &u0);
                let (r, t) = eval(&g, q, &committed, &u);
                let scale = r0.force.norm();
                assert!((r.force - q8 * r0.force).norm() <= 1e-12 * scale);
                let ks = r0.stiffness.norm();
                assert!((r.stiffness - q8 * r0.stiffness * q8.transpose()).norm() <= 1e-12 * ks);
                for i in 0..q.num_points() {
                    assert!((t[i] - t0[i]).abs() <= 1e-12 * DC);
                }
                assert!(fd_error(&g, q, &committed, &u) < 1e-6);
            }
        }
    }

    #[test]
    fn per_area_penalty_is_length_independent() {
        let g = geom();
        let u = displacement(&g, [[0.0, -0.5 * DC], [0.0, -0.5 * DC]]);
        let committed = [0.0; MAX_POINTS];
        let per_area = CohesiveLaw {
            penalty: Penalty::PerArea { stiffness: 1e6 },
            ..law()
        };
        let mut trial = [0.0; MAX_POINTS];
        for q in QUADS {
            let r = evaluate(&g, q, &per_area, &committed, &u, &mut trial);
            // Uniform closure: total normal force on side B = k * dn * l_e.
            let fn_b: f64 = (0..2)
                .map(|k| r.force[4 + 2 * k] * g.normal[0] + r.force[5 + 2 * k] * g.normal[1])
                .sum();
            assert!((fn_b - 1e6 * (-0.5 * DC) * g.length).abs() < 1e-12);
            // The paper's penalty: lambda_p l_e per unit area.
            let (rp, _) = eval(&g, q, &committed, &u);
            let fn_p: f64 = (0..2)
                .map(|k| rp.force[4 + 2 * k] * g.normal[0] + rp.force[5 + 2 * k] * g.normal[1])
                .sum();
            assert!((fn_p - 1e7 * g.length * (-0.5 * DC) * g.length).abs() < 1e-10);
        }
    }
}

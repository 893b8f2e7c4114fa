//! The discrete RVE equilibrium problem (paper eq. 14) on the fluctuation:
//!
//! ```text
//! R(x; eps) = K_const x + G eps + F_itz(x) = 0,     x = [u~_r; lambda]
//! K(x)      = dR/dx = K_const + K_itz(x)
//! ```
//!
//! The bulk is linear elastic, so its contribution `sum_e A_e B_e^T D_e (eps + B_e u~_e)`
//! splits into the constant stiffness `K_bulk` (in `K_const`) and the constant coupling
//! `G = dR/d eps = sum_e A_e B_e^T D_e`. `K_const` also holds the multiplier rows of the
//! minimal BC, scaled by the matrix Young's modulus for balance. The macro strain does not
//! enter the interface jumps: both faces of an ITZ element sit at the same reference point,
//! so `eps y` has no jump there.

use std::sync::Arc;

use nalgebra::{Matrix3, SMatrix, SVector};

use super::laws::InterfaceLaws;
use super::pattern::{Pattern, NO_SLOT};
use crate::constraint::{BoundaryCondition, DofMap, FIXED};
use crate::element::{interface4, triangle, InterfaceGeometry, InterfaceQuadrature};
use crate::error::Result;
use crate::interface::{Implex, InterfaceLaw, TangentKind};
use crate::material::{Analysis, IsotropicElastic};
use crate::mesh::{InterfaceElement, Mesh, Phase};

/// A bulk triangle, precomputed: strain operator, area, elastic matrix, dofs.
#[derive(Clone, Debug)]
pub struct BulkElement {
    pub b: SMatrix<f64, 3, 6>,
    pub area: f64,
    pub d: Matrix3<f64>,
    pub poisson: f64,
    pub dofs: [u32; 6],
}

/// Branch counts of the interface quadrature points after an evaluation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SystemEvaluation {
    pub loading: usize,
    pub unloading: usize,
    pub contact: usize,
    /// Closed points sliding under friction: while any does, the tangent is not
    /// symmetric.
    pub sliding: usize,
    /// A hash (FNV-1a) of the branch of every interface point, in order: two evaluations
    /// with the same signature have (but for a hash collision) every point on the same
    /// branch, so the system is smooth between them and Newton's rate is quadratic there.
    pub branch_signature: u64,
}

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0100_0000_01b3;

/// Everything needed to assemble the RVE system; immutable and shared. The mesh's parts
/// sit behind `Arc`s, so that [`Discretization::with_laws`] gives the same cell with other
/// laws (a regularized one) for the price of the laws.
#[derive(Clone, Debug)]
pub struct Discretization {
    pub analysis: Analysis,
    pub dofs: Arc<DofMap>,
    pub bulk: Arc<[BulkElement]>,
    pub interfaces: Arc<[InterfaceGeometry]>,
    pub interface_dofs: Arc<[[u32; 8]]>,
    /// The interface laws; `None` when the scene has no ITZ (then there are no interface
    /// elements).
    pub law: Option<InterfaceLaws>,
    pub quadrature: InterfaceQuadrature,
    pub pattern: Arc<Pattern>,
    /// Values of `K_const` on the pattern.
    pub k_const: Arc<[f64]>,
    /// `G = dR/d eps`, `n x 3`, column-major.
    pub g: Arc<[f64]>,
    /// Cell area `V_mu`.
    pub volume: f64,
}

/// Inputs of [`Discretization::new`] besides the mesh.
pub struct DiscretizationSpec {
    pub analysis: Analysis,
    pub matrix: IsotropicElastic,
    pub aggregate: IsotropicElastic,
    /// The ITZ's law (`None`: no interface elements).
    pub law: Option<Arc<dyn InterfaceLaw>>,
    /// The law of cracks through the paste, for the mesh's paste interface elements.
    pub paste_law: Option<Arc<dyn InterfaceLaw>>,
    pub quadrature: InterfaceQuadrature,
    pub boundary: BoundaryCondition,
}

impl Discretization {
    pub fn new(mesh: &Mesh, spec: &DiscretizationSpec) -> Result<Self> {
        let dofs = DofMap::build(mesh, spec.boundary);
        let bulk: Vec<BulkElement> = mesh
            .triangles
            .iter()
            .map(|t| {
                let coords = t.nodes.map(|i| mesh.nodes[i]);
                let (b, signed_area) = triangle::b_matrix(&coords);
                let material = match t.phase {
                    Phase::Matrix => spec.matrix,
                    Phase::Inclusion => spec.aggregate,
                };
                BulkElement {
                    b,
                    area: signed_area.abs(),
                    d: material.stiffness(spec.analysis),
                    poisson: material.poisson,
                    dofs: dofs.element_dofs(t.nodes),
                }
            })
            .collect();
        let (interfaces, interface_dofs): (Vec<_>, Vec<_>) = if spec.law.is_some() {
            mesh.interfaces
                .iter()
                .map(|e| (interface_geometry(e), dofs.element_dofs(e.nodes)))
                .unzip()
        } else {
            (Vec::new(), Vec::new())
        };
        let law = match &spec.law {
            Some(itz) => {
                let kinds = mesh.interfaces.iter().map(|e| e.kind).collect();
                Some(InterfaceLaws::new(
                    itz.clone(),
                    spec.paste_law.clone(),
                    kinds,
                )?)
            }
            None => None,
        };
        let triangle_dofs: Vec<[u32; 6]> = bulk.iter().map(|e| e.dofs).collect();
        let pattern = Pattern::build(&dofs, &triangle_dofs, &interface_dofs)?;

        let mut k_const = vec![0.0; pattern.nnz()];
        for (e, slots) in bulk.iter().zip(&pattern.triangle_slots) {
            let k = triangle::stiffness(&e.b, e.area, &e.d);
            scatter(&mut k_const, slots, k.transpose().as_slice());
        }
        let scale = spec.matrix.young;
        for &(s_rm, s_mr, w) in &pattern.constraint_slots {
            k_const[s_rm as usize] += scale * w;
            k_const[s_mr as usize] += scale * w;
        }

        let n = pattern.n;
        let mut g = vec![0.0; 3 * n];
        for e in &bulk {
            let btd = e.area * e.b.transpose() * e.d;
            for (i, &r) in e.dofs.iter().enumerate() {
                if r != FIXED {
                    for k in 0..3 {
                        g[k * n + r as usize] += btd[(i, k)];
                    }
                }
            }
        }
        Ok(Discretization {
            analysis: spec.analysis,
            dofs: Arc::new(dofs),
            bulk: bulk.into(),
            interfaces: interfaces.into(),
            interface_dofs: interface_dofs.into(),
            law,
            quadrature: spec.quadrature,
            pattern: Arc::new(pattern),
            k_const: k_const.into(),
            g: g.into(),
            volume: mesh.cell_area(),
        })
    }

    /// This cell with its interface laws replaced (the mesh, pattern and constant
    /// operators shared); a cell without interfaces stays without laws.
    pub fn with_laws(&self, laws: InterfaceLaws) -> Discretization {
        Discretization {
            law: self.law.as_ref().map(|_| laws),
            ..self.clone()
        }
    }

    /// Number of unknowns.
    pub fn n(&self) -> usize {
        self.pattern.n
    }

    /// Quadrature points per interface element.
    pub fn points_per_interface(&self) -> usize {
        self.quadrature.num_points()
    }

    /// History values per interface element (points x the laws' values per point).
    fn history_per_interface(&self) -> usize {
        self.law
            .as_ref()
            .map_or(0, |laws| self.points_per_interface() * laws.history_len())
    }

    /// Length of the flat interface history (elements x points x values per point).
    pub fn history_len(&self) -> usize {
        self.interfaces.len() * self.history_per_interface()
    }

    /// Whether some interface point passes the peak of its law between the histories
    /// `start` and `trial` (see [`InterfaceLaw::passes_peak`]).
    pub fn passes_peak(&self, start: &[f64], trial: &[f64]) -> bool {
        let Some(laws) = &self.law else {
            return false;
        };
        let (hl, np) = (laws.history_len(), self.points_per_interface());
        hl > 0
            && start
                .chunks_exact(hl)
                .zip(trial.chunks_exact(hl))
                .enumerate()
                .any(|(q, (s, t))| laws.of(q / np).passes_peak(s, t))
    }

    /// Gathers the element vector of `dofs` from the unknowns `x` (fixed dofs are zero).
    fn gather<const D: usize>(x: &[f64], dofs: &[u32; D]) -> SVector<f64, D> {
        SVector::<f64, D>::from_fn(|i, _| {
            if dofs[i] == FIXED {
                0.0
            } else {
                x[dofs[i] as usize]
            }
        })
    }

    /// Evaluates the residual `r = R(x; eps)` and, if asked, the tangent values `k` on the
    /// pattern, with interface histories `committed` (start of the step); the trial
    /// histories go to `trial`. Allocates nothing.
    pub fn evaluate(
        &self,
        x: &[f64],
        eps: &[f64; 3],
        committed: &[f64],
        trial: &mut [f64],
        r: &mut [f64],
        k: Option<&mut [f64]>,
    ) -> SystemEvaluation {
        self.evaluate_with(
            x,
            eps,
            committed,
            trial,
            r,
            k,
            TangentKind::Consistent,
            None,
        )
    }

    /// The contact status of every interface point at the unknowns `x`, read from its gap
    /// ([`interface4::contact_status`]), into `closed` (one entry per point, element-major);
    /// returns how many are closed. All open without a law that has a contact status.
    pub fn contact_status(&self, x: &[f64], closed: &mut [bool]) -> usize {
        closed.fill(false);
        let Some(laws) = self.law.as_ref().filter(|l| l.has_contact_status()) else {
            return 0;
        };
        let np = self.points_per_interface();
        let mut count = 0;
        for (e, ((geometry, dofs), out)) in self
            .interfaces
            .iter()
            .zip(self.interface_dofs.iter())
            .zip(closed.chunks_exact_mut(np))
            .enumerate()
        {
            let u = Self::gather(x, dofs);
            let st = interface4::contact_status(geometry, self.quadrature, laws.of(e), &u);
            out.copy_from_slice(&st[..np]);
            count += st[..np].iter().filter(|&&c| c).count();
        }
        count
    }

    /// Calls `f(point, [delta_s, delta_n])` with the local jump of every interface point at
    /// the unknowns `x` (points element-major, as in a contact status). Allocates nothing.
    pub fn for_each_jump(&self, x: &[f64], mut f: impl FnMut(usize, [f64; 2])) {
        let np = self.points_per_interface();
        for (e, (geometry, dofs)) in self
            .interfaces
            .iter()
            .zip(self.interface_dofs.iter())
            .enumerate()
        {
            let u = Self::gather(x, dofs);
            let jumps = interface4::local_jumps(geometry, self.quadrature, &u);
            for (p, &jump) in jumps[..np].iter().enumerate() {
                f(e * np + p, jump);
            }
        }
    }

    /// Number of interface quadrature points (entries of a contact status).
    pub fn interface_points(&self) -> usize {
        self.interfaces.len() * self.points_per_interface()
    }

    /// [`Discretization::evaluate`] with the interface matrix of choice (consistent or
    /// secant, see [`TangentKind`]) and the contact status of every interface point held
    /// (`Some`, one entry per point, element-major) or read from the gaps at `x` (`None`),
    /// see [`interface4::evaluate_with`].
    #[allow(clippy::too_many_arguments)]
    pub fn evaluate_with(
        &self,
        x: &[f64],
        eps: &[f64; 3],
        committed: &[f64],
        trial: &mut [f64],
        r: &mut [f64],
        k: Option<&mut [f64]>,
        kind: TangentKind,
        status: Option<&[bool]>,
    ) -> SystemEvaluation {
        // Linear part: K_const x + G eps.
        self.pattern.mul_symmetric(&self.k_const, x, r);
        let n = self.n();
        for (c, &e) in eps.iter().enumerate() {
            if e != 0.0 {
                for (ri, gi) in r.iter_mut().zip(&self.g[c * n..(c + 1) * n]) {
                    *ri += gi * e;
                }
            }
        }
        let mut k = k;
        if let Some(k) = k.as_deref_mut() {
            k.copy_from_slice(&self.k_const);
        }
        let mut counts = SystemEvaluation {
            branch_signature: FNV_OFFSET,
            ..Default::default()
        };
        let Some(laws) = self.law.as_ref() else {
            return counts;
        };
        let per_element = self.history_per_interface();
        let np = self.points_per_interface();
        for (e, (geometry, dofs)) in self
            .interfaces
            .iter()
            .zip(self.interface_dofs.iter())
            .enumerate()
        {
            let u = Self::gather(x, dofs);
            let range = e * per_element..(e + 1) * per_element;
            let resp = interface4::evaluate_with(
                geometry,
                self.quadrature,
                laws.of(e),
                &committed[range.clone()],
                &u,
                &mut trial[range],
                kind,
                status.map(|st| &st[e * np..(e + 1) * np]),
            );
            counts.loading += resp.loading;
            counts.unloading += resp.unloading;
            counts.contact += resp.contact;
            counts.sliding += resp.sliding;
            counts.branch_signature =
                (counts.branch_signature ^ u64::from(resp.branches)).wrapping_mul(FNV_PRIME);
            for (i, &d) in dofs.iter().enumerate() {
                if d != FIXED {
                    r[d as usize] += resp.force[i];
                }
            }
            if let Some(k) = k.as_deref_mut() {
                // Row-major slots; nalgebra is column-major, so read the transpose.
                scatter(
                    k,
                    &self.pattern.interface_slots[e],
                    resp.stiffness.transpose().as_slice(),
                );
            }
        }
        counts
    }
}

impl Discretization {
    /// The stiffness values `K = K_const + K_itz` on the pattern with every interface
    /// point on a fixed linear branch: each element's law answers on its frozen branch
    /// (`t = S delta`, [`crate::interface::Implex`]) with the per-point history `frozen`
    /// and contact status `closed` (one entry per point, element-major). No interface:
    /// `K_const`. Allocates nothing.
    pub fn frozen_stiffness(&self, frozen: &[f64], closed: &[bool], k: &mut [f64]) {
        k.copy_from_slice(&self.k_const);
        let Some(laws) = self.law.as_ref() else {
            return;
        };
        let per_element = self.history_per_interface();
        let np = self.points_per_interface();
        let mut scratch = [0.0; 64];
        let trial = &mut scratch[..per_element];
        let zero = SVector::<f64, 8>::zeros();
        for (e, geometry) in self.interfaces.iter().enumerate() {
            let resp = interface4::evaluate_with(
                geometry,
                self.quadrature,
                &Implex { law: laws.of(e) },
                &frozen[e * per_element..(e + 1) * per_element],
                &zero,
                trial,
                TangentKind::Consistent,
                Some(&closed[e * np..(e + 1) * np]),
            );
            scatter(
                k,
                &self.pattern.interface_slots[e],
                resp.stiffness.transpose().as_slice(),
            );
        }
    }
}

/// Adds a row-major element matrix into the pattern values.
fn scatter(values: &mut [f64], slots: &[u32], entries: &[f64]) {
    for (&s, &v) in slots.iter().zip(entries) {
        if s != NO_SLOT {
            values[s as usize] += v;
        }
    }
}

/// What the interface kernel needs of a mesh's interface element.
fn interface_geometry(e: &InterfaceElement) -> InterfaceGeometry {
    InterfaceGeometry {
        length: e.length,
        tangent: e.tangent,
        normal: e.normal,
    }
}

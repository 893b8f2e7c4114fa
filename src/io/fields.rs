//! The micro fields of one RVE state, per node and per cell, for pictures and VTK output.
//!
//! - Displacement at the nodes: `u = eps y + u~`, the macro part (paper eq. 2) measured
//!   from the cell's first corner `y_0` (`u_x = eps_xx dy_x + gamma_xy/2 dy_y`,
//!   `u_y = gamma_xy/2 dy_x + eps_yy dy_y`, `dy = y - y_0`) plus the fluctuation.
//! - Per triangle: the strain `eps + B_e u~_e` (engineering shear) and the stress
//!   `D_e (eps + B_e u~_e)`. Their area average is the homogenized stress (eq. 6), the
//!   sum `Homogenizer::stress` computes in another order.
//! - Per interface element: the local jump `[delta_s, delta_n]` averaged over the element
//!   with the quadrature weights (the jump at mid-length: it is linear), and the law's
//!   [`PointMeasures`] and the frictional slip averaged the same way; the branch is the
//!   majority of the points.

use nalgebra::{SVector, Vector3};

use mesorve_core::assembly::Discretization;
use mesorve_core::constraint::FIXED;
use mesorve_core::element::interface4;
use mesorve_core::interface::{Branch, InterfaceLaw, PointMeasures, TangentKind};
use mesorve_core::mesh::Mesh;
use mesorve_core::state::State;

/// Branch codes of [`ItzFields::branch`].
pub const BRANCH_LOADING: u8 = 0;
pub const BRANCH_UNLOADING: u8 = 1;
pub const BRANCH_CONTACT: u8 = 2;

/// Per-element values of an interface element.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ItzFields {
    /// Mean sliding jump `delta_s` (along the edge).
    pub shear_opening: f64,
    /// Mean normal jump `delta_n` (> 0 open, < 0 interpenetration).
    pub normal_opening: f64,
    /// Mean frictional slip (NaN for a law without friction).
    pub slip: f64,
    /// Mean `delta/delta_c`, `delta_max/delta_c`, `delta_max` and damage of the points (NaN when the
    /// law has no characteristic opening or the scene has no interface law).
    pub measures: PointMeasures,
    /// The majority branch of the points: [`BRANCH_LOADING`], [`BRANCH_UNLOADING`] or
    /// [`BRANCH_CONTACT`]; a tie goes to contact, then loading.
    pub branch: u8,
    /// Number of points in contact.
    pub closed_points: usize,
}

/// The fields of one state on the mesh of its model.
#[derive(Clone, Debug, PartialEq)]
pub struct RveFields {
    /// The macro strain `[eps_xx, eps_yy, gamma_xy]`.
    pub macro_strain: [f64; 3],
    /// Total displacement per node.
    pub displacement: Vec<[f64; 2]>,
    /// Strain `[eps_xx, eps_yy, gamma_xy]` per triangle.
    pub strain: Vec<[f64; 3]>,
    /// Stress `[s_xx, s_yy, s_xy]` per triangle.
    pub stress: Vec<[f64; 3]>,
    /// Area per triangle.
    pub area: Vec<f64>,
    /// Per interface element of the mesh (empty when the discretization has none).
    pub itz: Vec<ItzFields>,
}

impl RveFields {
    /// The fields of `state` (macro strain, unknowns and interface history, e.g. the
    /// committed state of an instance) on `mesh`, discretized as `disc`.
    pub fn compute(mesh: &Mesh, disc: &Discretization, state: &State) -> Self {
        let eps = state.strain;
        let x = &state.unknowns;
        let fluct = |dof: u32| if dof == FIXED { 0.0 } else { x[dof as usize] };
        let y0 = mesh.nodes[mesh.boundary.corners[0]];
        let displacement = mesh
            .nodes
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let (dx, dy) = (p[0] - y0[0], p[1] - y0[1]);
                [
                    eps[0] * dx + 0.5 * eps[2] * dy + fluct(disc.dofs.reduced[2 * i]),
                    0.5 * eps[2] * dx + eps[1] * dy + fluct(disc.dofs.reduced[2 * i + 1]),
                ]
            })
            .collect();
        let macro_eps = Vector3::from(eps);
        let (mut strain, mut stress) = (Vec::new(), Vec::new());
        for e in disc.bulk.iter() {
            let u = SVector::<f64, 6>::from_fn(|i, _| fluct(e.dofs[i]));
            let s = macro_eps + e.b * u;
            let t = e.d * s;
            strain.push([s[0], s[1], s[2]]);
            stress.push([t[0], t[1], t[2]]);
        }
        let area = disc.bulk.iter().map(|e| e.area).collect();
        let itz = Self::interfaces(disc, state, fluct);
        RveFields {
            macro_strain: eps,
            displacement,
            strain,
            stress,
            area,
            itz,
        }
    }

    fn interfaces(
        disc: &Discretization,
        state: &State,
        fluct: impl Fn(u32) -> f64,
    ) -> Vec<ItzFields> {
        let Some(laws) = disc.law.as_ref() else {
            return Vec::new();
        };
        let per_element = disc.quadrature.rule().len() * laws.history_len();
        disc.interfaces
            .iter()
            .zip(disc.interface_dofs.iter())
            .enumerate()
            .map(|(e, (geometry, dofs))| {
                let u = SVector::<f64, 8>::from_fn(|i, _| fluct(dofs[i]));
                let jumps = interface4::local_jumps(geometry, disc.quadrature, &u);
                let history = &state.history[e * per_element..(e + 1) * per_element];
                element_fields(disc, laws.of(e), geometry.length, &jumps, history)
            })
            .collect()
    }

    /// The area average of the per-triangle stresses over the cell area `volume`.
    pub fn average_stress(&self, volume: f64) -> [f64; 3] {
        let mut s = [0.0; 3];
        for (t, a) in self.stress.iter().zip(&self.area) {
            for k in 0..3 {
                s[k] += a * t[k];
            }
        }
        s.map(|v| v / volume)
    }
}

/// The fields of one interface element with law `law` and reference length `length`,
/// from its points' local jumps and histories.
fn element_fields(
    disc: &Discretization,
    law: &dyn InterfaceLaw,
    length: f64,
    jumps: &[[f64; 2]],
    history: &[f64],
) -> ItzFields {
    let hl = law.history_len();
    let mut scratch = [0.0; 16];
    let (mut ds, mut dn, mut slip) = (0.0, 0.0, 0.0);
    let mut m = PointMeasures {
        opening_ratio: 0.0,
        max_opening_ratio: 0.0,
        max_opening: 0.0,
        damage: 0.0,
    };
    let mut has_measures = true;
    let mut counts = [0usize; 3];
    for (p, &(_, w)) in disc.quadrature.rule().iter().enumerate() {
        let h = &history[p * hl..(p + 1) * hl];
        let w = 0.5 * w;
        ds += w * jumps[p][0];
        dn += w * jumps[p][1];
        slip += w * law.slip(h).unwrap_or(f64::NAN);
        match law.measures(h, jumps[p], length) {
            Some(pm) => {
                m.opening_ratio += w * pm.opening_ratio;
                m.max_opening_ratio += w * pm.max_opening_ratio;
                m.max_opening += w * pm.max_opening;
                m.damage += w * pm.damage;
            }
            None => has_measures = false,
        }
        let point = law.respond(
            h,
            &mut scratch[..hl],
            jumps[p],
            length,
            TangentKind::Consistent,
        );
        counts[match point.branch {
            Branch::Loading => 0,
            Branch::Unloading => 1,
            Branch::Contact | Branch::Sliding => 2,
        }] += 1;
    }
    let branch = if counts[2] >= counts[0] && counts[2] >= counts[1] {
        BRANCH_CONTACT
    } else if counts[0] >= counts[1] {
        BRANCH_LOADING
    } else {
        BRANCH_UNLOADING
    };
    let nan = f64::NAN;
    ItzFields {
        shear_opening: ds,
        normal_opening: dn,
        slip,
        measures: if has_measures {
            m
        } else {
            PointMeasures {
                opening_ratio: nan,
                max_opening_ratio: nan,
                max_opening: nan,
                damage: nan,
            }
        },
        branch,
        closed_points: counts[2],
    }
}

//! Volume averages over the RVE, written with the precomputed bulk operators.
//!
//! With the bulk linear elastic, the homogenized stress (eq. 6) is
//!
//! ```text
//! sigma = 1/V sum_e A_e D_e (eps + B_e u~_e) = D_Taylor eps + (1/V) G^T u~
//! ```
//!
//! where `D_Taylor = 1/V sum_e A_e D_e` is the volume average of the micro tangent and
//! `G = sum_e A_e B_e^T D_e = dR/d eps` (so `G^T u~ = sum_e A_e D_e B_e u~_e`). Interface
//! elements have zero volume; their tractions enter through equilibrium. The consistent
//! tangent follows by differentiating at equilibrium, `K du~/d eps = -G`:
//!
//! ```text
//! D_hom = D_Taylor + D~,      D~ = -(1/V) G^T K^-1 G                   (eq. 18)
//! ```
//!
//! In plane strain the out-of-plane stress is averaged the same way:
//! `s_zz = 1/V sum_e A_e nu_e (s_xx + s_yy)_e = c_Taylor . eps + (1/V) h^T u~`,
//! `h = sum_e A_e nu_e B_e^T D_e [1, 1, 0]^T`.

use nalgebra::{Matrix3, Vector3};

use crate::assembly::Discretization;
use crate::constraint::FIXED;
use crate::material::Analysis;

/// Precomputed averaging operators of a model.
#[derive(Clone, Debug)]
pub struct Homogenizer {
    /// `D_Taylor`, the volume-averaged elastic tangent.
    pub d_taylor: Matrix3<f64>,
    /// Plane strain: `s_zz = c_taylor . eps + h . u~ / V`; zero in plane stress.
    pub szz_taylor: Vector3<f64>,
    pub h_szz: Vec<f64>,
    pub volume: f64,
}

impl Homogenizer {
    pub fn new(disc: &Discretization) -> Self {
        let n = disc.n();
        let v = disc.volume;
        let mut d_taylor = Matrix3::zeros();
        let mut szz_taylor = Vector3::zeros();
        let mut h_szz = vec![0.0; n];
        let plane_strain = disc.analysis == Analysis::PlaneStrain;
        for e in disc.bulk.iter() {
            d_taylor += e.area * e.d;
            if plane_strain {
                let row = e.poisson * (e.d.row(0) + e.d.row(1));
                szz_taylor += e.area * row.transpose();
                let contrib = e.area * e.b.transpose() * row.transpose();
                for (i, &r) in e.dofs.iter().enumerate() {
                    if r != FIXED {
                        h_szz[r as usize] += contrib[i];
                    }
                }
            }
        }
        Homogenizer {
            d_taylor: d_taylor / v,
            szz_taylor: szz_taylor / v,
            h_szz,
            volume: v,
        }
    }

    /// Homogenized stress (eq. 6) and out-of-plane stress at macro strain `eps` and
    /// unknowns `x`.
    pub fn stress(&self, disc: &Discretization, eps: &[f64; 3], x: &[f64]) -> ([f64; 3], f64) {
        let e = Vector3::from(*eps);
        let mut s = self.d_taylor * e;
        let n = disc.n();
        for k in 0..3 {
            let g = &disc.g[k * n..(k + 1) * n];
            s[k] += g.iter().zip(x).map(|(a, b)| a * b).sum::<f64>() / self.volume;
        }
        let szz = self.szz_taylor.dot(&e)
            + self.h_szz.iter().zip(x).map(|(a, b)| a * b).sum::<f64>() / self.volume;
        ([s[0], s[1], s[2]], szz)
    }

    /// The out-of-plane row of the consistent tangent, `d s_zz / d eps`, from
    /// `X = K^-1 G` (n x 3, column-major) at the converged state. Differentiating
    /// `s_zz = c_Taylor . eps + h . u~ / V` at equilibrium, where `du~/d eps = -X`:
    ///
    /// ```text
    /// d s_zz / d eps_j = c_Taylor_j - (1/V) h^T X_j
    /// ```
    ///
    /// the counterpart of eq. 18 for `s_zz`. Zero in plane stress (`c_Taylor = h = 0`).
    pub fn szz_tangent(&self, kg: &[f64]) -> [f64; 3] {
        let n = self.h_szz.len();
        std::array::from_fn(|j| {
            let x = &kg[j * n..(j + 1) * n];
            self.szz_taylor[j]
                - self.h_szz.iter().zip(x).map(|(a, b)| a * b).sum::<f64>() / self.volume
        })
    }

    /// `D_hom = D_Taylor - (1/V) G^T X` with `X = K^-1 G` (n x 3, column-major), row-major.
    pub fn tangent(&self, disc: &Discretization, kg: &[f64]) -> [f64; 9] {
        let n = disc.n();
        let mut condensed = [0.0; 9];
        for i in 0..3 {
            let g = &disc.g[i * n..(i + 1) * n];
            for j in 0..3 {
                let x = &kg[j * n..(j + 1) * n];
                condensed[3 * i + j] = g.iter().zip(x).map(|(a, b)| a * b).sum();
            }
        }
        self.tangent_from_condensed(&condensed)
    }

    /// `D_hom = D_Taylor - (1/V) C` (eq. 18) from the condensed term `C = G^T K^-1 G`
    /// (3 x 3, row-major).
    pub fn tangent_from_condensed(&self, condensed: &[f64; 9]) -> [f64; 9] {
        let mut out = [0.0; 9];
        for i in 0..3 {
            for j in 0..3 {
                out[3 * i + j] = self.d_taylor[(i, j)] - condensed[3 * i + j] / self.volume;
            }
        }
        out
    }
}

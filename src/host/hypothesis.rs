//! The host's convention for stress and strain vectors, and its map to the RVE's plane
//! state (in the spirit of MGIS's `Hypothesis`).
//!
//! The RVE is two-dimensional: it takes `[eps_xx, eps_yy, gamma_xy]` and answers
//! `[s_xx, s_yy, s_xy]`, the consistent tangent `D` (eq. 18) and, in plane strain, the
//! out-of-plane stress `s_zz` with its row `d s_zz / d eps` (see
//! `Homogenizer::szz_tangent`). A host passes Voigt vectors in the Abaqus order with
//! ENGINEERING shear (`gamma_ij = 2 eps_ij`), of one of three lengths `NTENS`:
//!
//! | `NTENS` | layout | hypothesis | RVE `cell.analysis` |
//! |---|---|---|---|
//! | 3 | `[11, 22, 12]` | plane stress (`s_33 = 0`) | `plane_stress` |
//! | 4 | `[11, 22, 33, 12]` | plane strain (`eps_33 = 0`) | `plane_strain` |
//! | 6 | `[11, 22, 33, 12, 13, 23]` | a 3D element held in plane strain (CalculiX expands its 2D elements so) | `plane_strain` |
//!
//! Axes 1, 2 are the RVE's x, y. Out-of-plane components:
//! - **strain**: `eps_33`, `gamma_13`, `gamma_23` must be zero: the 2D RVE has no response
//!   to them. Values up to [`OUT_OF_PLANE_TOLERANCE`] in magnitude (round-off of a host
//!   that computes them from displacements) are taken as zero; larger ones are refused
//!   with [`Error::HostConvention`]. So axisymmetric elements (NTENS 4 with a hoop strain
//!   `eps_33`) and 3D elements under general loading are refused, not answered wrongly.
//! - **stress**: `s_33 = s_zz` of the RVE in plane strain; `s_13 = s_23 = 0`.
//! - **tangent** `DDSDDE(i, j) = d s_i / d eps_j` (column-major, as Fortran declares it):
//!   - the in-plane block (host indices 1, 2 and 4 of NTENS 4 and 6) is the RVE's
//!     consistent tangent `D`, as it is: not symmetric where a crack slides under
//!     friction;
//!   - row 3 is the exact `d s_zz / d eps` of the RVE;
//!   - column 3 (`d s_i / d eps_33`) is row 3 transposed. The 2D RVE cannot compute the
//!     response to an out-of-plane strain; the transpose is exact for the elastic RVE
//!     (whose 3D homogenized stiffness is symmetric) and never multiplies a non-zero
//!     strain, since `eps_33 = 0` is checked;
//!   - `DDSDDE(3, 3)` is `(D_el11 + D_el22) / 2` and the out-of-plane shear diagonal
//!     `DDSDDE(5, 5) = DDSDDE(6, 6)` is `D_el33`, from the elastic tangent `D_el` of the
//!     virgin RVE: `lambda + 2 mu` and `mu` of an isotropic RVE. They keep the host's
//!     stiffness positive in directions its constraints hold fixed; every other entry of
//!     rows and columns 5 and 6 is zero.

use crate::error::{Error, Result};
use crate::model::{Model, Response};
use mesorve_core::material::Analysis;

/// Largest out-of-plane strain component (`eps_33`, `gamma_13`, `gamma_23`) taken as
/// round-off and ignored. Concrete strains are 1e-5..1e-3; a host's round-off in a
/// strain computed from displacements is about 1e-16 of them.
pub const OUT_OF_PLANE_TOLERANCE: f64 = 1e-10;

/// How a host lays out its Voigt vectors; see the module documentation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hypothesis {
    /// `NTENS = 3`: `[11, 22, 12]`, plane stress.
    PlaneStress,
    /// `NTENS = 4`: `[11, 22, 33, 12]`, plane strain (the axisymmetric layout, with
    /// `eps_33 = 0`).
    PlaneStrain,
    /// `NTENS = 6`: `[11, 22, 33, 12, 13, 23]`, a 3D element held in plane strain.
    Tridimensional,
}

/// The RVE's answer in its plane state, the input of the maps to a host.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneResponse {
    /// `[s_xx, s_yy, s_xy]`.
    pub stress: [f64; 3],
    /// Row-major `d stress_i / d strain_j`.
    pub tangent: [f64; 9],
    /// Out-of-plane stress (0 in plane stress).
    pub s_zz: f64,
    /// `d s_zz / d strain_j` (0 in plane stress).
    pub s_zz_tangent: [f64; 3],
}

impl From<&Response> for PlaneResponse {
    fn from(r: &Response) -> Self {
        PlaneResponse {
            stress: r.stress,
            tangent: r.tangent,
            s_zz: r.s_zz,
            s_zz_tangent: r.s_zz_tangent,
        }
    }
}

/// Host positions (0-based) of the RVE's `xx, yy, xy` components, and of `zz`.
const IN_PLANE_3: [usize; 3] = [0, 1, 2];
const IN_PLANE_4: [usize; 3] = [0, 1, 3];
const ZZ: usize = 2;

impl Hypothesis {
    /// The hypothesis of an Abaqus call: `NTENS = NDI + NSHR` with `(NDI, NSHR)` =
    /// `(2, 1)`, `(3, 1)` or `(3, 3)`.
    pub fn from_abaqus(ndi: i32, nshr: i32, ntens: i32) -> Result<Self> {
        let h = match (ndi, nshr, ntens) {
            (2, 1, 3) => Hypothesis::PlaneStress,
            (3, 1, 4) => Hypothesis::PlaneStrain,
            (3, 3, 6) => Hypothesis::Tridimensional,
            _ => {
                return Err(Error::HostConvention(format!(
                    "NDI = {ndi}, NSHR = {nshr}, NTENS = {ntens}: the RVE answers NTENS 3 \
                     (plane stress, NDI 2, NSHR 1), 4 (plane strain, NDI 3, NSHR 1) or 6 \
                     (3D in plane strain, NDI 3, NSHR 3)"
                )))
            }
        };
        Ok(h)
    }

    /// Length of the host's stress and strain vectors.
    pub fn ntens(self) -> usize {
        match self {
            Hypothesis::PlaneStress => 3,
            Hypothesis::PlaneStrain => 4,
            Hypothesis::Tridimensional => 6,
        }
    }

    /// The plane state the RVE must be solved in.
    pub fn analysis(self) -> Analysis {
        match self {
            Hypothesis::PlaneStress => Analysis::PlaneStress,
            Hypothesis::PlaneStrain | Hypothesis::Tridimensional => Analysis::PlaneStrain,
        }
    }

    /// Refuses a model whose `cell.analysis` is not this hypothesis's plane state (a
    /// plane-stress RVE under a plane-strain host would return `s_zz = 0` with a stiffness
    /// that ignores the constraint, and the reverse).
    pub fn check_model(self, model: &Model) -> Result<()> {
        let scene = model.scene.spec.cell.analysis;
        if scene == self.analysis() {
            return Ok(());
        }
        let name = |a: Analysis| match a {
            Analysis::PlaneStress => "plane_stress",
            Analysis::PlaneStrain => "plane_strain",
        };
        Err(Error::HostConvention(format!(
            "the host passes NTENS = {} ({}), which needs an RVE scene with \
             cell.analysis = \"{}\"; this scene has \"{}\"",
            self.ntens(),
            self.describe(),
            name(self.analysis()),
            name(scene)
        )))
    }

    fn describe(self) -> &'static str {
        match self {
            Hypothesis::PlaneStress => "plane stress",
            Hypothesis::PlaneStrain => "plane strain",
            Hypothesis::Tridimensional => "a 3D element in plane strain",
        }
    }

    /// Host positions of the RVE's `[xx, yy, xy]`.
    fn in_plane(self) -> [usize; 3] {
        match self {
            Hypothesis::PlaneStress => IN_PLANE_3,
            Hypothesis::PlaneStrain | Hypothesis::Tridimensional => IN_PLANE_4,
        }
    }

    /// Host positions of the components the RVE must see as zero.
    fn out_of_plane(self) -> &'static [(usize, &'static str)] {
        match self {
            Hypothesis::PlaneStress => &[],
            Hypothesis::PlaneStrain => &[(ZZ, "eps_33")],
            Hypothesis::Tridimensional => &[(ZZ, "eps_33"), (4, "gamma_13"), (5, "gamma_23")],
        }
    }

    /// The RVE's strain `[eps_xx, eps_yy, gamma_xy]` from a host strain of length
    /// `NTENS` (engineering shear in both). Refuses a wrong length and out-of-plane
    /// components beyond [`OUT_OF_PLANE_TOLERANCE`].
    pub fn rve_strain(self, host: &[f64]) -> Result<[f64; 3]> {
        self.check_len("strain", host.len())?;
        for &(k, name) in self.out_of_plane() {
            let e = host[k];
            if e.is_nan() || e.abs() > OUT_OF_PLANE_TOLERANCE {
                return Err(Error::HostConvention(format!(
                    "{name} = {e:e} (strain component {} of NTENS = {}): the 2D RVE holds \
                     the out-of-plane strains at zero (plane strain), and accepts at most \
                     {OUT_OF_PLANE_TOLERANCE:e} of round-off; axisymmetric and general 3D \
                     states are not supported. In CalculiX use plane-strain elements (CPE4, \
                     CPE8) with a plane_strain scene: a plane-stress element (CPS4) reaches \
                     the UMAT as a 3D state with a free eps_33, which the RVE cannot take",
                    k + 1,
                    self.ntens()
                )));
            }
        }
        Ok(self.in_plane().map(|k| host[k]))
    }

    /// Writes the host stress (length `NTENS`): the RVE's in-plane stress, `s_33 = s_zz`
    /// (NTENS 4 and 6) and `s_13 = s_23 = 0` (NTENS 6).
    pub fn host_stress(self, r: &PlaneResponse, stress: &mut [f64]) -> Result<()> {
        self.check_len("stress", stress.len())?;
        stress.fill(0.0);
        for (i, &k) in self.in_plane().iter().enumerate() {
            stress[k] = r.stress[i];
        }
        if self != Hypothesis::PlaneStress {
            stress[ZZ] = r.s_zz;
        }
        Ok(())
    }

    /// Writes `ddsdde` (length `NTENS^2`, column-major: `ddsdde[i + NTENS j] = d s_i /
    /// d eps_j`, Fortran's `DDSDDE(i+1, j+1)`) from the RVE's response and the elastic
    /// tangent `elastic` of the virgin RVE (row-major), as the module documentation says.
    pub fn host_tangent(
        self,
        r: &PlaneResponse,
        elastic: &[f64; 9],
        ddsdde: &mut [f64],
    ) -> Result<()> {
        let n = self.ntens();
        if ddsdde.len() != n * n {
            return Err(Error::HostConvention(format!(
                "DDSDDE has {} entries, NTENS = {n} needs {}",
                ddsdde.len(),
                n * n
            )));
        }
        ddsdde.fill(0.0);
        let at = |i: usize, j: usize| i + n * j;
        let plane = self.in_plane();
        for (i, &hi) in plane.iter().enumerate() {
            for (j, &hj) in plane.iter().enumerate() {
                ddsdde[at(hi, hj)] = r.tangent[3 * i + j];
            }
        }
        if self == Hypothesis::PlaneStress {
            return Ok(());
        }
        for (j, &hj) in plane.iter().enumerate() {
            ddsdde[at(ZZ, hj)] = r.s_zz_tangent[j];
            ddsdde[at(hj, ZZ)] = r.s_zz_tangent[j];
        }
        ddsdde[at(ZZ, ZZ)] = 0.5 * (elastic[0] + elastic[4]);
        if self == Hypothesis::Tridimensional {
            ddsdde[at(4, 4)] = elastic[8];
            ddsdde[at(5, 5)] = elastic[8];
        }
        Ok(())
    }

    fn check_len(self, what: &str, len: usize) -> Result<()> {
        if len == self.ntens() {
            Ok(())
        } else {
            Err(Error::HostConvention(format!(
                "the {what} vector has {len} components, NTENS = {} needs {}",
                self.ntens(),
                self.ntens()
            )))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn response() -> PlaneResponse {
        PlaneResponse {
            stress: [1.0, 2.0, 3.0],
            tangent: [11.0, 12.0, 13.0, 21.0, 22.0, 23.0, 31.0, 32.0, 33.0],
            s_zz: 4.0,
            s_zz_tangent: [41.0, 42.0, 43.0],
        }
    }

    const ELASTIC: [f64; 9] = [100.0, 30.0, 0.0, 30.0, 120.0, 0.0, 0.0, 0.0, 40.0];

    #[test]
    fn layouts_follow_abaqus() {
        assert_eq!(
            Hypothesis::from_abaqus(2, 1, 3).unwrap(),
            Hypothesis::PlaneStress
        );
        assert_eq!(
            Hypothesis::from_abaqus(3, 1, 4).unwrap(),
            Hypothesis::PlaneStrain
        );
        assert_eq!(
            Hypothesis::from_abaqus(3, 3, 6).unwrap(),
            Hypothesis::Tridimensional
        );
        for (ndi, nshr, ntens) in [(3, 0, 3), (1, 0, 1), (3, 3, 4), (2, 1, 4), (3, 2, 5)] {
            let e = Hypothesis::from_abaqus(ndi, nshr, ntens).unwrap_err();
            assert!(e.to_string().contains(&format!("NTENS = {ntens}")), "{e}");
        }
    }

    #[test]
    fn strain_maps_in_plane_components_and_checks_the_others() {
        let h = Hypothesis::PlaneStrain;
        assert_eq!(
            h.rve_strain(&[1.0, 2.0, 0.0, 3.0]).unwrap(),
            [1.0, 2.0, 3.0]
        );
        assert_eq!(
            h.rve_strain(&[1.0, 2.0, 1e-12, 3.0]).unwrap(),
            [1.0, 2.0, 3.0]
        );
        let e = h.rve_strain(&[1.0, 2.0, 1e-6, 3.0]).unwrap_err();
        assert!(e.to_string().contains("eps_33 = 1e-6"), "{e}");
        assert!(e.to_string().contains("plane-strain elements (CPE4"), "{e}");
        let t = Hypothesis::Tridimensional;
        assert_eq!(
            t.rve_strain(&[1.0, 2.0, 0.0, 3.0, 0.0, 0.0]).unwrap(),
            [1.0, 2.0, 3.0]
        );
        let e = t.rve_strain(&[1.0, 2.0, 0.0, 3.0, 0.0, 2e-5]).unwrap_err();
        assert!(e.to_string().contains("gamma_23"), "{e}");
        let e = t
            .rve_strain(&[1.0, 2.0, 0.0, 3.0, f64::NAN, 0.0])
            .unwrap_err();
        assert!(e.to_string().contains("gamma_13 = NaN"), "{e}");
        assert_eq!(
            Hypothesis::PlaneStress
                .rve_strain(&[1.0, 2.0, 3.0])
                .unwrap(),
            [1.0, 2.0, 3.0]
        );
        assert!(Hypothesis::PlaneStress
            .rve_strain(&[1.0, 2.0, 3.0, 4.0])
            .is_err());
    }

    #[test]
    fn stress_and_tangent_land_where_the_module_docs_say() {
        let r = response();
        let mut s3 = [9.0; 3];
        Hypothesis::PlaneStress.host_stress(&r, &mut s3).unwrap();
        assert_eq!(s3, [1.0, 2.0, 3.0]);
        let mut d3 = [9.0; 9];
        Hypothesis::PlaneStress
            .host_tangent(&r, &ELASTIC, &mut d3)
            .unwrap();
        // Column-major: d3[i + 3 j] = D[3 i + j].
        assert_eq!(d3, [11.0, 21.0, 31.0, 12.0, 22.0, 32.0, 13.0, 23.0, 33.0]);

        let mut s4 = [9.0; 4];
        Hypothesis::PlaneStrain.host_stress(&r, &mut s4).unwrap();
        assert_eq!(s4, [1.0, 2.0, 4.0, 3.0]);
        let mut d4 = [9.0; 16];
        Hypothesis::PlaneStrain
            .host_tangent(&r, &ELASTIC, &mut d4)
            .unwrap();
        let d = |i: usize, j: usize| d4[(i - 1) + 4 * (j - 1)];
        assert_eq!([d(1, 1), d(1, 2), d(1, 4)], [11.0, 12.0, 13.0]);
        assert_eq!([d(4, 1), d(4, 2), d(4, 4)], [31.0, 32.0, 33.0]);
        assert_eq!([d(3, 1), d(3, 2), d(3, 4)], [41.0, 42.0, 43.0]);
        assert_eq!([d(1, 3), d(2, 3), d(4, 3)], [41.0, 42.0, 43.0]);
        assert_eq!(d(3, 3), 110.0);

        let mut s6 = [9.0; 6];
        Hypothesis::Tridimensional.host_stress(&r, &mut s6).unwrap();
        assert_eq!(s6, [1.0, 2.0, 4.0, 3.0, 0.0, 0.0]);
        let mut d6 = [9.0; 36];
        Hypothesis::Tridimensional
            .host_tangent(&r, &ELASTIC, &mut d6)
            .unwrap();
        let d = |i: usize, j: usize| d6[(i - 1) + 6 * (j - 1)];
        assert_eq!([d(2, 1), d(2, 2), d(2, 4)], [21.0, 22.0, 23.0]);
        assert_eq!(
            [d(3, 1), d(3, 2), d(3, 3), d(3, 4)],
            [41.0, 42.0, 110.0, 43.0]
        );
        assert_eq!([d(5, 5), d(6, 6)], [40.0, 40.0]);
        for i in 1..=6 {
            for j in [5, 6] {
                if i != j {
                    assert_eq!((d(i, j), d(j, i)), (0.0, 0.0), "({i}, {j})");
                }
            }
        }
        assert!(Hypothesis::Tridimensional
            .host_tangent(&r, &ELASTIC, &mut d4)
            .is_err());
        assert!(Hypothesis::Tridimensional.host_stress(&r, &mut s4).is_err());
    }
}

//! Host adaptors: how finite element codes call the RVE. Pure safe Rust over
//! [`crate::model`] and [`crate::scene`]; `crate::ffi` exports it.
//!
//! - [`diagnostics`]: the library's messages on stderr, each said once per process (a
//!   note once, a failure once per reason);
//! - [`hypothesis`]: the one place that maps a host's stress and strain vectors (Abaqus
//!   `NTENS` 3, 4 or 6, engineering shear) to the RVE's plane state and back, `s_zz` and
//!   `DDSDDE` included;
//! - [`material`]: the scene a material name selects on a search path, with `PROPS`
//!   overrides;
//! - [`mirrors`]: the values the UMAT writes after the RVE state for a host to plot
//!   (point id, iterations, sub-steps, the RVE's damage, its largest ITZ opening);
//! - [`umat`]: the Abaqus UMAT: instances per (element, integration point), committed and
//!   reverted by the host's increments;
//! - `values_hash`: a quick hash of values' bits, a filter before comparing them;
//! - [`vtk_dump`]: `MESORVE_UMAT_VTK`, the RVE fields of chosen points as VTK files.

pub(crate) mod diagnostics;
pub mod hypothesis;
pub mod material;
pub mod mirrors;
mod share_table;
pub mod umat;
mod values_hash;
pub mod vtk_dump;

pub use hypothesis::{Hypothesis, PlaneResponse, OUT_OF_PLANE_TOLERANCE};
pub use material::{Material, SearchPath, UmatScene, SCENE_PATH_VAR, UMAT_SCENE_VAR};
pub use mirrors::{RveMeasures, MIRRORS};
pub use umat::{
    global, strain_mismatch, umat_scene, HostSignal, Outcome, Umat, UmatCall, UmatFailure,
    UmatOutputs, UmatStats, STRAIN_MATCH_FLOOR, STRAIN_MATCH_RELATIVE, TABLE_MODE_MAX_NSTATV,
};
pub use vtk_dump::{VtkDump, VtkSpec, VtkSpecError, UMAT_VTK_VAR};

//! The table of a host's integration points ([`Umat`]): the process's table, the
//! materials (resolved once per name and `PROPS`), the points keyed by `(NOEL, NPT)`, the
//! counters, the answer to a failed call, and the outputs that both modes write.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, LazyLock, Mutex, PoisonError, RwLock};

use super::call::{request_step_ratio, trim, UmatCall, UmatFailure, UmatOutputs, UmatStats};
use super::point::{MaterialKey, Point, PointRef};
use crate::error::Error;
use crate::host::diagnostics::{note_once, Note};
use crate::host::hypothesis::PlaneResponse;
use crate::host::material::{Material, SearchPath, UmatScene};
use crate::host::mirrors::{mirrors, mirrors_of};
use crate::host::share_table::ShareTable;
use crate::host::vtk_dump::VtkDump;
use crate::model::Response;

/// The largest `PNEWDT` asked for an increment whose error exceeds `solver.step_tolerance`.
const TOLERANCE_CUT: f64 = 0.5;

/// `PNEWDT` after a failure other than the solver's (which suggests its own ratio).
pub const FAILURE_STEP_RATIO: f64 = 0.25;

type MaterialEntry = Result<Arc<Material>, Arc<Error>>;

/// A failed call before it is reported: the error, whether it is reported for the first
/// time, and the material when known (for the elastic DDSDDE).
pub(super) struct Failed {
    pub(super) error: Arc<Error>,
    pub(super) first: bool,
    pub(super) material: Option<Arc<Material>>,
}

impl Failed {
    /// A failure to resolve a call's material or point, as [`Umat::material`] and
    /// [`Umat::point`] give it (the error, and whether it is reported for the first time):
    /// no material.
    pub(super) fn unresolved((error, first): (Arc<Error>, bool)) -> Self {
        Failed {
            error,
            first,
            material: None,
        }
    }

    /// The failures of a call whose material is known, each reported as new.
    pub(super) fn of(material: &Arc<Material>) -> impl Fn(Error) -> Failed + Copy + '_ {
        |e| Failed {
            error: Arc::new(e),
            first: true,
            material: Some(material.clone()),
        }
    }
}

/// A failure without a material.
pub(super) fn plain(e: Error) -> Failed {
    Failed {
        error: Arc::new(e),
        first: true,
        material: None,
    }
}

/// The table of a host's integration points.
pub struct Umat {
    /// This table's number in the process: the key of its points in each thread's
    /// `SLOTS` (`statev_mode.rs`).
    pub(super) id: u64,
    pub(super) search: SearchPath,
    pub(super) materials: Mutex<HashMap<MaterialKey, MaterialEntry>>,
    pub(super) points: RwLock<HashMap<(i32, i32), PointRef>>,
    pub(super) next_id: AtomicU64,
    pub(super) calls: AtomicU64,
    pub(super) solves: AtomicU64,
    pub(super) repeats: AtomicU64,
    pub(super) commits: AtomicU64,
    pub(super) reverts: AtomicU64,
    pub(super) loads: AtomicU64,
    pub(super) failures: AtomicU64,
    pub(super) shared: AtomicU64,
    /// Answer sharing's per-increment tables (`share_table`).
    pub(super) share: ShareTable,
    /// `MESORVE_UMAT_VTK`: the RVE fields of chosen points as VTK
    /// ([`crate::host::vtk_dump`]).
    pub(super) vtk: Option<VtkDump>,
}

/// The process's table, searching scenes on `MESORVE_SCENE_PATH` (read at the first
/// call), after the directory of `MESORVE_UMAT_SCENE` when it is a path; the one the
/// exported `umat_` uses.
pub fn global() -> &'static Umat {
    static GLOBAL: LazyLock<Umat> = LazyLock::new(|| {
        let search = SearchPath::from_env();
        Umat::new(match umat_scene().and_then(|s| s.dir.clone()) {
            Some(dir) => search.with_first(dir),
            None => search,
        })
        .with_vtk(VtkDump::from_env())
    });
    &GLOBAL
}

/// `MESORVE_UMAT_SCENE` as the process read it at its first call: when set, the scene of
/// every call of the exported `umat_`, whose `CMNAME` is then not read.
pub fn umat_scene() -> Option<&'static UmatScene> {
    static SCENE: LazyLock<Option<UmatScene>> = LazyLock::new(UmatScene::from_env);
    SCENE.as_ref()
}

impl Umat {
    pub fn new(search: SearchPath) -> Self {
        static TABLES: AtomicU64 = AtomicU64::new(1);
        Umat {
            id: TABLES.fetch_add(1, Ordering::Relaxed),
            search,
            materials: Mutex::new(HashMap::new()),
            points: RwLock::new(HashMap::new()),
            next_id: AtomicU64::new(1),
            calls: AtomicU64::new(0),
            solves: AtomicU64::new(0),
            repeats: AtomicU64::new(0),
            commits: AtomicU64::new(0),
            reverts: AtomicU64::new(0),
            loads: AtomicU64::new(0),
            failures: AtomicU64::new(0),
            shared: AtomicU64::new(0),
            share: ShareTable::default(),
            vtk: None,
        }
    }

    /// This table writing the RVE fields of the points `vtk` chooses ([`crate::host::vtk_dump`];
    /// `None`: none, the default).
    pub fn with_vtk(mut self, vtk: Option<VtkDump>) -> Self {
        self.vtk = vtk;
        self
    }

    /// The VTK switch of this table, if on.
    pub fn vtk(&self) -> Option<&VtkDump> {
        self.vtk.as_ref()
    }

    pub fn search_path(&self) -> &SearchPath {
        &self.search
    }

    pub fn stats(&self) -> UmatStats {
        let get = |c: &AtomicU64| c.load(Ordering::Relaxed);
        UmatStats {
            calls: get(&self.calls),
            solves: get(&self.solves),
            repeats: get(&self.repeats),
            commits: get(&self.commits),
            reverts: get(&self.reverts),
            loads: get(&self.loads),
            failures: get(&self.failures),
            shared: get(&self.shared),
            points: self
                .points
                .read()
                .unwrap_or_else(PoisonError::into_inner)
                .len() as u64,
        }
    }

    /// The point `(NOEL, NPT)`, created with its material on the first call.
    pub(super) fn point(&self, c: &UmatCall) -> Result<PointRef, (Arc<Error>, bool)> {
        let key = (c.noel, c.npt);
        if let Some(p) = self
            .points
            .read()
            .unwrap_or_else(PoisonError::into_inner)
            .get(&key)
        {
            return Ok(p.clone());
        }
        let material = self.material(c)?;
        let id = self.next_id.fetch_add(1, Ordering::Relaxed);
        let point = Point::new(id, MaterialKey::of(c), material);
        let mut points = self.points.write().unwrap_or_else(PoisonError::into_inner);
        Ok(points
            .entry(key)
            .or_insert_with(|| Arc::new(Mutex::new(point)))
            .clone())
    }

    /// The material of a call, resolved once per name and `PROPS` (failures too, so a
    /// bad material is reported once and not rebuilt at every point; a scene file not
    /// found is looked for again at the next call, so one written later is used).
    pub(super) fn material(&self, c: &UmatCall) -> Result<Arc<Material>, (Arc<Error>, bool)> {
        let key = MaterialKey::of(c);
        let mut materials = self
            .materials
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        let reported = match materials.get(&key) {
            // A scene not found yet may be written later: searched again at every call
            // (a few file tests), reported once.
            Some(Err(e)) if matches!(**e, Error::SceneNotFound { .. }) => true,
            Some(entry) => return entry.clone().map_err(|e| (e, false)),
            None => false,
        };
        let entry = Material::resolve(&key.cmname, c.props, &self.search)
            .map(Arc::new)
            .map_err(Arc::new);
        materials.insert(key, entry.clone());
        entry.map_err(|e| (e, !reported))
    }

    /// The embedded paper RVE, whose elastic tangent a failed call without a material
    /// (a scene not found, a bad name or `PROPS`) returns: a host that assembles it gets
    /// a regular matrix, not the zeros on which CalculiX reports a singular system.
    fn embedded(&self) -> crate::Result<Material> {
        Material::resolve("", &[], &self.search)
    }

    pub(super) fn fail(
        &self,
        c: &UmatCall,
        out: &mut UmatOutputs,
        error: Arc<Error>,
        first_report: bool,
        material: Option<&Material>,
    ) -> UmatFailure {
        let pnewdt = match *error {
            Error::Solve {
                suggested_step_ratio,
                ..
            } => suggested_step_ratio,
            _ => FAILURE_STEP_RATIO,
        };
        request_step_ratio(out.pnewdt, pnewdt);
        let n = c.hypothesis.ntens();
        if out.ddsdde.len() == n * n {
            let elastic = material
                .map(|m| m.elastic)
                .or_else(|| self.embedded().ok().map(|m| m.elastic));
            match elastic {
                Some(e) => {
                    // Lengths checked: cannot fail.
                    let _ = c.hypothesis.host_tangent(&e, &e.tangent, out.ddsdde);
                }
                None => out.ddsdde.fill(0.0),
            }
        }
        UmatFailure {
            noel: c.noel,
            npt: c.npt,
            cmname: trim(c.cmname).to_string(),
            error,
            pnewdt,
            first_report,
        }
    }
}

/// Writes `STRESS`, `DDSDDE` and `STATEV`: `written` in `STATEV(1:len)` (in `STATEV`
/// mode the values of the trial's core, or of a core shared from another point, which the
/// mode writes first; empty in table mode) and the inspection mirrors
/// ([`crate::host::mirrors`]) after it, of the instance's trial or of `shared_history`
/// (the shared core's history); `PNEWDT` < 1 when the answer depends on the increment's
/// size.
pub(super) fn write_outputs(
    p: &Point,
    c: &UmatCall,
    r: &Response,
    out: &mut UmatOutputs,
    written: &[f64],
    shared_history: Option<&[f64]>,
) -> crate::Result<()> {
    let material = &p.material;
    let plane = PlaneResponse::from(r);
    let h = c.hypothesis;
    h.host_stress(&plane, out.stress)?;
    h.host_tangent(&plane, &material.elastic.tangent, out.ddsdde)?;
    out.statev[..written.len()].copy_from_slice(written);
    let mirrors_at = written.len();
    let room = out.statev.len() - mirrors_at;
    let mirrors = match shared_history {
        Some(history) => mirrors_of(
            p.id,
            r.report.iterations,
            r.report.substeps,
            (&material.model, history),
            room,
        ),
        None => mirrors(
            p.id,
            r.report.iterations,
            r.report.substeps,
            &p.instance,
            room,
        ),
    };
    for (s, m) in out.statev[mirrors_at..].iter_mut().zip(mirrors) {
        *s = m;
    }
    ask_for_smaller_step(c, r, out);
    Ok(())
}

/// `PNEWDT` < 1 when the answer depends on the increment's size (`solver.step_check`) or
/// its integration error exceeds `solver.step_tolerance`, said once per process on
/// stderr. A ratio of 1 or more is never written: ccx takes any positive `PNEWDT` as a
/// request to redo the increment (`docs/calculix.md`); growth is the host's own rule.
fn ask_for_smaller_step(c: &UmatCall, r: &Response, out: &mut UmatOutputs) {
    let ratio = r.report.suggested_step_ratio();
    if r.report.exceeds_tolerance() && ratio < 1.0 {
        // At most half the increment: ccx allows few cut-backs of one increment (`*CONTROLS`,
        // 5 by default), which ratios of 0.8 or 0.9 spend without reaching the tolerance;
        // but not below `solver.smallest_step`, where ccx would grow back into a cut.
        let ratio = ratio.min(TOLERANCE_CUT).max(r.report.smallest_ratio);
        request_step_ratio(out.pnewdt, ratio);
        note_once(Note::Tolerance, || {
            format!(
                "mesorve: element {}, point {}: the increment's integration error is {:.3} \
                 times solver.step_tolerance: PNEWDT = {ratio:.3} asks for a smaller step \
                 (printed once)",
                c.noel,
                c.npt,
                r.report.error_estimate.unwrap_or(0.0)
            )
        });
    }
    if !r.report.step_too_large {
        return;
    }
    request_step_ratio(out.pnewdt, ratio);
    note_once(Note::StepSize, || {
        format!(
            "mesorve: element {}, point {}: the RVE's answer depends on the size of this \
             increment (one step landed beyond a snap-back that half steps take; \
             solver.step_check): PNEWDT = {ratio} asks for a smaller step (printed once)",
            c.noel, c.npt
        )
    });
}

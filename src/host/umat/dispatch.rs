//! The table of a host's integration points ([`Umat`]): its materials (resolved once per
//! name and `PROPS`), its two modes, its books. A call ([`Umat::call_as`]) checks the
//! lengths, finds the material and picks the mode by `NSTATV` ([`statev_mode_for`]); a
//! failed call gets the material's elastic `DDSDDE` ([`Umat::fail`]), and what the host
//! hears of a failure or a request for a smaller step is decided once, [`tell_host`].

use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};

use super::call::{
    plain, request_step_ratio, trim, Books, Failed, HostSignal, Outcome, UmatCall, UmatFailure,
    UmatOutputs, UmatStats,
};
use super::point::MaterialKey;
use super::slots::slot_material;
use super::statev_mode::StatevMode;
use super::table_mode::{table_refused, TableMode};
use crate::error::Error;
use crate::host::material::{Material, SearchPath};
use crate::host::mirrors::MIRRORS;
use crate::host::vtk_dump::VtkDump;
use mesorve_core::solver::Integration;

/// `NSTATV` up to this keeps the state in the library's table (room for the mirrors).
pub const TABLE_MODE_MAX_NSTATV: usize = MIRRORS;

/// `PNEWDT` after a failure other than the solver's (which suggests its own ratio).
pub const FAILURE_STEP_RATIO: f64 = 0.25;

type MaterialEntry = Result<Arc<Material>, Arc<Error>>;

/// The table of a host's integration points.
pub struct Umat {
    search: SearchPath,
    /// The materials by name, `PROPS` and `CELENT`, failures included (see
    /// [`Umat::material`]).
    materials: Mutex<HashMap<MaterialKey, MaterialEntry>>,
    /// The materials by name and `PROPS` before their element's length: the scene of a
    /// graded mesh's every length is resolved once.
    scenes: Mutex<HashMap<MaterialKey, Arc<Material>>>,
    statev: StatevMode,
    table: TableMode,
    books: Books,
}

impl Umat {
    pub fn new(search: SearchPath) -> Self {
        Umat {
            search,
            materials: Mutex::new(HashMap::new()),
            scenes: Mutex::new(HashMap::new()),
            statev: StatevMode::new(),
            table: TableMode::new(),
            books: Books::new(),
        }
    }

    /// This table writing the RVE fields of the points `vtk` chooses ([`crate::host::vtk_dump`];
    /// `None`: none, the default).
    pub fn with_vtk(mut self, vtk: Option<VtkDump>) -> Self {
        self.books.vtk = vtk;
        self
    }

    /// The VTK switch of this table, if on.
    pub fn vtk(&self) -> Option<&VtkDump> {
        self.books.vtk.as_ref()
    }

    pub fn search_path(&self) -> &SearchPath {
        &self.search
    }

    pub fn stats(&self) -> UmatStats {
        let points = self.statev.points() + self.table.points();
        self.books.stats(points as u64)
    }

    /// One UMAT call of a host that passes `PNEWDT`: see the module documentation of
    /// [`crate::host::umat`].
    pub fn call(&self, c: &UmatCall, out: &mut UmatOutputs) -> Result<Outcome, UmatFailure> {
        self.call_as(c, out, HostSignal::Pnewdt)
    }

    /// One UMAT call of a host that hears of failures and step requests by `signal`. With
    /// [`HostSignal::NanStress`], `out.pnewdt` is the caller's own (start it at 0: no
    /// request), and `STRESS` is NaN when the call fails or asks for a smaller step.
    pub fn call_as(
        &self,
        c: &UmatCall,
        out: &mut UmatOutputs,
        signal: HostSignal,
    ) -> Result<Outcome, UmatFailure> {
        Books::count(&self.books.calls);
        let result = self.answer(c, out, signal).map_err(|f| {
            Books::count(&self.books.failures);
            self.fail(c, out, f)
        });
        let failed = result.as_ref().err().map(|f| f.pnewdt);
        tell_host(signal, out.stress, out.pnewdt, failed);
        result
    }

    /// The call in the mode its `NSTATV` picks, its failure not yet reported. A numbering
    /// host's point that knows the call's material answers without resolving it
    /// ([`StatevMode::answer_held`], [`TableMode::answer_held`]); otherwise the material is
    /// this thread's slot's (a host without `PNEWDT`) or resolved by [`Umat::material`].
    fn answer(
        &self,
        c: &UmatCall,
        out: &mut UmatOutputs,
        signal: HostSignal,
    ) -> Result<Outcome, Failed> {
        check_lengths(c, out).map_err(plain)?;
        check_dtime(c, None).map_err(plain)?;
        if signal == HostSignal::Pnewdt {
            let in_mode = |m: &Arc<Material>, nstatv: usize| statev_mode_for(c, nstatv, m);
            let books = &self.books;
            let held = (self.statev.answer_held(books, c, out, in_mode))
                .or_else(|| self.table.answer_held(books, c, out, in_mode));
            if let Some(answered) = held {
                return answered;
            }
        }
        let material = match slot_material(self.books.table, c) {
            Some(m) => m,
            None => self.material(c).map_err(Failed::unresolved)?,
        };
        if statev_mode_for(c, out.statev.len(), &material)? {
            return self.statev.call(&self.books, c, out, material, signal);
        }
        if signal == HostSignal::NanStress {
            let needed = material.model.statev_len();
            return Err(Failed::of(&material)(table_refused(
                out.statev.len(),
                needed,
            )));
        }
        self.table.call(&self.books, c, out, material)
    }

    /// The material of a call, resolved once per name and `PROPS` (failures too, so a
    /// bad material is reported once and not rebuilt at every point; a scene file not
    /// found is looked for again at the next call, so one written later is used). Returns
    /// a failure's error with whether it is reported for the first time.
    fn material(&self, c: &UmatCall) -> Result<Arc<Material>, (Arc<Error>, bool)> {
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
        let mut scenes = self.scenes.lock().unwrap_or_else(PoisonError::into_inner);
        let base = match scenes.get(&key.without_length()) {
            Some(base) => Ok(base.clone()),
            None => Material::resolve(&key.cmname, c.props, &self.search).map(Arc::new),
        };
        if let Ok(base) = &base {
            scenes.insert(key.without_length(), base.clone());
        }
        drop(scenes);
        let entry = base
            .and_then(|b| b.for_element(c.props, c.celent))
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

    /// A failed call: `DDSDDE` the elastic tangent of its material's virgin RVE (of the
    /// embedded paper RVE when the material is unknown), and the failure with the
    /// `PNEWDT` it asks for (the solver's suggestion after a solver failure,
    /// [`FAILURE_STEP_RATIO`] otherwise), which [`tell_host`] writes.
    fn fail(&self, c: &UmatCall, out: &mut UmatOutputs, f: Failed) -> UmatFailure {
        let pnewdt = match *f.error {
            Error::Solve {
                suggested_step_ratio,
                ..
            } => suggested_step_ratio,
            _ => FAILURE_STEP_RATIO,
        };
        let n = c.hypothesis.ntens();
        if out.ddsdde.len() == n * n {
            let elastic = (f.material.as_deref())
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
            error: f.error,
            pnewdt,
            first_report: f.first,
        }
    }
}

/// What a host hears besides the answer: after a failure (`failed`: the ratio it asks
/// for) `PNEWDT` at most that ratio; and a host without `PNEWDT`
/// ([`HostSignal::NanStress`]) NaN in `STRESS` when the call failed or asks for a
/// smaller step (its own `pnewdt` below 1), the signal such a host cuts its step on.
pub(super) fn tell_host(
    signal: HostSignal,
    stress: &mut [f64],
    pnewdt: &mut f64,
    failed: Option<f64>,
) {
    if let Some(ratio) = failed {
        request_step_ratio(pnewdt, ratio);
    }
    let asks_smaller = *pnewdt > 0.0 && *pnewdt < 1.0;
    if signal == HostSignal::NanStress && (failed.is_some() || asks_smaller) {
        stress.fill(f64::NAN);
    }
}

/// Refuses arrays whose lengths are not those `NTENS` needs.
fn check_lengths(c: &UmatCall, out: &UmatOutputs) -> crate::Result<()> {
    let n = c.hypothesis.ntens();
    let lengths = [
        ("STRAN", c.stran.len(), n),
        ("DSTRAN", c.dstran.len(), n),
        ("STRESS", out.stress.len(), n),
        ("DDSDDE", out.ddsdde.len(), n * n),
    ];
    for (name, got, want) in lengths {
        if got != want {
            return Err(Error::HostConvention(format!(
                "{name} has {got} entries, NTENS = {n} needs {want}"
            )));
        }
    }
    Ok(())
}

/// Refuses a `DTIME` that is not finite (before the material is known: `integration`
/// `None`), and a negative one where the material's integration reads it (IMPL-EX scales
/// its extrapolation by `DTIME`; implicit integration ignores it). A refused call leaves
/// `STRESS` and `STATEV` as they came (a host without `PNEWDT` gets NaN stress).
fn check_dtime(c: &UmatCall, integration: Option<Integration>) -> crate::Result<()> {
    let refused = match integration {
        None => !c.dtime.is_finite(),
        Some(Integration::Implex) => c.dtime < 0.0,
        Some(_) => false,
    };
    if refused {
        let reads = if integration.is_some() {
            " (the material's IMPL-EX integration scales its step by DTIME)"
        } else {
            ""
        };
        return Err(Error::HostConvention(format!(
            "DTIME = {} is not a time increment{reads}: the host must pass a finite \
             DTIME >= 0",
            c.dtime
        )));
    }
    Ok(())
}

/// `STATEV` mode (true) or table mode (false) for a call of `material` with `nstatv`
/// entries, after its `DTIME` is checked for the material's integration: `STATEV` mode
/// from the state's length on, table mode up to [`TABLE_MODE_MAX_NSTATV`] (room for the
/// mirrors only, the 0.1-0.3 decks' rule for the table), an error naming the count in
/// between (a `*DEPVAR` short of the state, which would otherwise run in the table
/// without a restart or a re-added element carrying it).
fn statev_mode_for(c: &UmatCall, nstatv: usize, material: &Arc<Material>) -> Result<bool, Failed> {
    let with_material = Failed::of(material);
    check_dtime(c, Some(material.model.solver.integration)).map_err(with_material)?;
    let needed = material.model.statev_len();
    if nstatv >= needed {
        return Ok(true);
    }
    if nstatv <= TABLE_MODE_MAX_NSTATV {
        return Ok(false);
    }
    Err(with_material(Error::HostConvention(format!(
        "NSTATV = {nstatv}: material `{}` keeps its RVE state in STATEV(1:{needed}) (set \
         *DEPVAR to at least {needed}, `rve info`'s umat_nstatv; {} with the {MIRRORS} \
         mirrors); an NSTATV of at most {TABLE_MODE_MAX_NSTATV} keeps the state in the \
         library's table instead",
        trim(c.cmname),
        needed + MIRRORS
    ))))
}

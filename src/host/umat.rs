//! The standard Abaqus UMAT, safe side: a table of RVE instances keyed by (element,
//! integration point) that follows the host's increments. `crate::ffi` exports it with
//! the Abaqus argument list (`rve_umat`, `umat_`, `UMAT`) and only translates pointers.
//!
//! **Two modes, chosen per call by `NSTATV`.**
//! - **`STATEV` mode** (`NSTATV` >= the model's [`Model::statev_len`](crate::Model::statev_len), which `rve info`
//!   prints as `umat_nstatv`; the recommended mode). The point's committed RVE state is
//!   `STATEV(1:umat_nstatv)`: its core (strain, interface history, contact status,
//!   IMPL-EX's data) as integer-valued doubles with a checksum (`statev`); all zeros is
//!   a virgin RVE. Each call solves from the state `STATEV` holds, at the total strain
//!   `STRAN + DSTRAN` and the time increment `DTIME`, and writes the trial's core back.
//!   The host keeps the values of the converged increment, hands the start-of-increment
//!   values at every call (as Abaqus/Standard and CalculiX do), writes them to its
//!   restart files and zeroes them for new elements and new analyses: there is no commit
//!   or revert rule to guess. The answer is a function of `STATEV`, the strain and
//!   `DTIME` alone; the library only caches the state the values stand for (rebuilt by
//!   [`Model::expand_core`](crate::Model::expand_core), one factorization, when the cache
//!   does not hold them), and a call that repeats one (the same values, strain and
//!   `DTIME`: a host's stress call, then its tangent call) is answered without solving
//!   again. A host that passes `PNEWDT` (CalculiX, Abaqus) numbers its points, and the
//!   cache is its table's point `(NOEL, NPT)`: one rebuild per point and increment. A
//!   host that does not (Kratos, every point 0) is keyed on nothing but the values: each
//!   thread keeps a few instances per material ([`SLOTS_PER_THREAD`]) and takes the one
//!   that holds them, so no point shares or waits for another. `STATEV(umat_nstatv+1..+5)` receive the inspection mirrors below. A
//!   `STATEV` that is not exactly what the library wrote (flipped bits, a changed,
//!   zeroed or truncated entry, another model's state) fails the call with a message, and
//!   so does a valid state that is not this point's at this increment: written under
//!   another fingerprint (scene after `PROPS`, Gmsh file, integration:
//!   [`Error::StateOwner`]), committed at another strain than `STRAN` (another point's,
//!   a stale one, an element re-added with its old state: [`Error::StateStrain`]), or all
//!   zeros at a strained point (a lost state: [`Error::StateLost`]); the scene's
//!   `[statev]` table relaxes the last two for hosts that need it.
//! - **Table mode** (`NSTATV` up to [`TABLE_MODE_MAX_NSTATV`]; printed once on stderr;
//!   an `NSTATV` between that and `umat_nstatv` is refused). The RVE state lives in
//!   the process's table keyed by `(NOEL, NPT)`, and the increments are inferred from
//!   `(KSTEP, KINC, TIME(2))` as described next. A restart, a second analysis or a
//!   re-added element then does not carry the state; a point whose `KSTEP` or `TIME(2)`
//!   goes back (a new analysis in the process) restarts from a virgin RVE, said once.
//!
//! **Instances (table mode).** The first call for `(NOEL, NPT)` resolves the material (`CMNAME` and
//! `PROPS`, see [`super::material`]) and creates a virgin instance of its model; the
//! instance lives in the table until the process ends. When `NSTATV` allows, the
//! mirrors (`STATEV(1:5)` in table mode, after the state in `STATEV` mode) receive the
//! point's id in the table (1, 2, ... in creation order; for a host without `PNEWDT` the
//! id of the thread's instance that answered, which identifies no point), the RVE's
//! Newton iterations,
//! its sub-steps, its damage and its largest ITZ opening ([`super::mirrors`]), for
//! inspection; the library never reads them.
//!
//! **Increments (table mode).** A call belongs to the increment `(KSTEP, KINC, TIME(2))`,
//! `TIME(2)` being the total time at its start. Every call is a trial from the point's
//! committed state at the total strain `STRAN + DSTRAN`. Then:
//! - a call of a new increment (`KSTEP` or `KINC` changed, or `TIME(2)` advanced beyond
//!   round-off) first commits the point's last trial, which is the converged state of the
//!   previous increment when the host's last call there was at its converged strain (as
//!   in Abaqus/Standard and CalculiX);
//! - a call of the same increment after this point failed (the host cut back on our
//!   `PNEWDT`), or with a smaller `DTIME` (the host cut back for another reason), reverts:
//!   the trial is dropped and the committed state stays;
//! - a call at the same strain, bit for bit, as the point's current trial returns that
//!   trial's answer without solving again (CalculiX calls twice per iteration, for the
//!   stress and for the stiffness; in `STATEV` mode too, with the same `STATEV`).
//!
//! Limits of the table rule: a host that calls a point after convergence at another
//! strain (a perturbation for a numerical tangent, a line-search probe) before the next
//! increment makes that trial the one committed; a host that moves on to a new increment
//! after the point's last call failed (ignoring `PNEWDT`) commits nothing for it, and the
//! point stays at its last converged state; a host that keeps `KINC` and advances
//! `TIME(2)` by less than `1e-9` of it commits nothing. In both modes `DROT`, `DFGRD*`,
//! temperatures and field variables are ignored (small strains, the RVE's axes are the
//! host's material axes); `SSE`, `SPD`, `SCD`, `RPL` and the thermal derivatives are not
//! written.
//!
//! **Failures** (a missing scene, a host convention the RVE cannot answer, a solver
//! failure) never panic across the boundary: `PNEWDT` receives a ratio below 1 (the
//! solver's suggestion after a solver failure, [`FAILURE_STEP_RATIO`] otherwise),
//! `DDSDDE` the elastic tangent of the material's virgin RVE (of the embedded paper RVE
//! when the material is unknown: a scene not found, a bad name or `PROPS`), `STRESS` is
//! left as it came, and [`UmatFailure`] says what went wrong; the C shim keeps it for
//! `rve_last_error` and says it on stderr once per reason ([`super::diagnostics`]).
//!
//! **Threads.** Distinct points may be called from several threads at once (each thread
//! keeps one workspace per model, and its own `STATEV`-mode instances: no lock is shared
//! between points). In table mode one point from two threads at once is refused with
//! `Error::HostConvention` (a host never does that within an increment).
//!
//! **Hosts without `PNEWDT`** ([`HostSignal::NanStress`], Kratos): a failure or a request
//! for a smaller step comes back as NaN in `STRESS`; `TIME` is one value (`TIME(2)` is not
//! read: the state records no time and the `[statev]` time check is off); table mode is
//! refused.

use std::cell::RefCell;
use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, LazyLock, Mutex, MutexGuard, PoisonError, RwLock, TryLockError};

use super::diagnostics::{note_once, Note};
use super::hypothesis::{Hypothesis, PlaneResponse};
use super::material::{Material, SearchPath, UmatScene};
use super::mirrors::{mirrors, mirrors_of, MIRRORS};
use super::share_table::{Anchor, IncrementKey, ShareTable, Step};
use super::vtk_dump::{self, DumpAt, VtkDump};
use crate::error::Error;
use crate::model::share;
use crate::model::workspaces::with_workspace;
use crate::model::{Instance, Response};
use crate::scene::ZeroAtStrain;
use crate::solver::TangentRequest;
use crate::solver::{Answer, Integration};
use crate::state::statev;

/// The largest `PNEWDT` asked for an increment whose error exceeds `solver.step_tolerance`.
const TOLERANCE_CUT: f64 = 0.5;

/// `PNEWDT` after a failure other than the solver's (which suggests its own ratio).
pub const FAILURE_STEP_RATIO: f64 = 0.25;

/// How the host hears of a failure or a request for a smaller step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HostSignal {
    /// Through `PNEWDT` (Abaqus, CalculiX): `STRESS` is left as it came on failure, and
    /// `TIME(1:2)` are both given.
    #[default]
    Pnewdt,
    /// The host passes no `PNEWDT` (a NULL pointer: Kratos): a failure or a request for
    /// a smaller step fills `STRESS` with NaN, the signal such a host cuts its step on.
    /// `TIME` is one value, so `TIME(2)` (`UmatCall::time[1]`) is never read: the
    /// `STATEV` state records no time and its time check is off, and table mode, which
    /// follows increments by `TIME(2)`, is refused.
    NanStress,
}

/// Relative round-off of `TIME(2)` tolerated within one increment: CalculiX computes it
/// as `(t + dt) - dt`, which moves by an ulp when a cut-back changes `dt`.
const TIME_ROUNDOFF: f64 = 1e-9;

/// The arguments of one UMAT call that the RVE uses (Abaqus names).
#[derive(Clone, Copy, Debug)]
pub struct UmatCall<'a> {
    /// `CMNAME`, padding included or not.
    pub cmname: &'a str,
    /// `PROPS(1:NPROPS)`.
    pub props: &'a [f64],
    /// From `NDI`, `NSHR`, `NTENS`.
    pub hypothesis: Hypothesis,
    /// `STRAN(1:NTENS)`: total strain at the start of the increment, engineering shear.
    pub stran: &'a [f64],
    /// `DSTRAN(1:NTENS)`: strain increment.
    pub dstran: &'a [f64],
    /// `TIME(1:2)`: step time and total time at the start of the increment.
    pub time: [f64; 2],
    pub dtime: f64,
    pub noel: i32,
    pub npt: i32,
    pub kstep: i32,
    pub kinc: i32,
}

impl UmatCall<'_> {
    /// The call's point and increment, as the VTK dump names its files.
    fn dump_at(&self) -> DumpAt {
        DumpAt {
            noel: self.noel,
            npt: self.npt,
            kstep: self.kstep,
            kinc: self.kinc,
            time_end: self.time[1] + self.dtime,
        }
    }
}

/// The outputs of one UMAT call.
#[derive(Debug)]
pub struct UmatOutputs<'a> {
    /// `STRESS(1:NTENS)`.
    pub stress: &'a mut [f64],
    /// `DDSDDE(1:NTENS, 1:NTENS)`, column-major.
    pub ddsdde: &'a mut [f64],
    /// `STATEV(1:NSTATV)`: in `STATEV` mode the point's state then the mirrors, in table
    /// mode the mirrors.
    pub statev: &'a mut [f64],
    /// `PNEWDT`: lowered (never raised, see [`request_step_ratio`]) on failure and when
    /// the increment is to be redone smaller; otherwise left as the host passed it.
    pub pnewdt: &'a mut f64,
}

/// What a successful call did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Outcome {
    /// True when it solved the RVE; false when it repeated the point's trial.
    pub solved: bool,
    /// It committed the previous increment's trial first.
    pub committed: bool,
    /// It dropped the trial of a cut-back increment first.
    pub reverted: bool,
    /// RVE Newton iterations of the answer (of the repeated trial when not solved).
    pub iterations: u32,
}

/// Why a call failed, with what the host receives in `PNEWDT`.
#[derive(Clone, Debug)]
pub struct UmatFailure {
    pub noel: i32,
    pub npt: i32,
    pub cmname: String,
    pub error: Arc<Error>,
    pub pnewdt: f64,
    /// False when this material's error was reported before: print it once.
    pub first_report: bool,
}

impl std::fmt::Display for UmatFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "element {}, point {}, material `{}`: {} (PNEWDT = {})",
            self.noel, self.npt, self.cmname, self.error, self.pnewdt
        )
    }
}

/// Counters of a table since its creation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UmatStats {
    pub calls: u64,
    /// RVE updates solved.
    pub solves: u64,
    /// Calls answered from the point's trial (same strain).
    pub repeats: u64,
    /// Trials committed at the start of a new increment.
    pub commits: u64,
    /// Trials dropped on a cut-back.
    pub reverts: u64,
    /// `STATEV` mode: committed states rebuilt from `STATEV` (once per point and
    /// increment, and after any change the host made to the values).
    pub loads: u64,
    pub failures: u64,
    /// `STATEV` mode with `[solver] share_tolerance`: calls answered from another point
    /// of the increment (answer sharing, `docs/sharing.md`) instead of solving.
    pub shared: u64,
    /// Points in the table.
    pub points: u64,
}

/// A material as a host names it: `CMNAME` without padding and the bits of `PROPS`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
struct MaterialKey {
    cmname: String,
    props: Vec<u64>,
}

impl MaterialKey {
    fn of(c: &UmatCall) -> Self {
        MaterialKey {
            cmname: trim(c.cmname).to_string(),
            props: c.props.iter().map(|v| v.to_bits()).collect(),
        }
    }

    fn matches(&self, c: &UmatCall) -> bool {
        self.cmname == trim(c.cmname)
            && self
                .props
                .iter()
                .copied()
                .eq(c.props.iter().map(|v| v.to_bits()))
    }
}

fn trim(cmname: &str) -> &str {
    cmname.trim_end_matches([' ', '\0'])
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Increment {
    kstep: i32,
    kinc: i32,
    /// `TIME(2)`.
    start: f64,
}

impl Increment {
    /// Whether this increment comes before `prev`: an earlier step, an earlier total time
    /// (beyond round-off) in the same step, or an earlier `KINC` at the same time.
    fn goes_back_from(&self, prev: &Increment) -> bool {
        let roundoff = TIME_ROUNDOFF * prev.start.abs();
        self.kstep < prev.kstep
            || (self.kstep == prev.kstep
                && (self.start < prev.start - roundoff
                    || (self.start <= prev.start + roundoff && self.kinc < prev.kinc)))
    }
}

/// Refuses a state committed at the end of another time than this increment's start
/// (`TIME(2)`, to [`TIME_ROUNDOFF`] of the time plus the increment): a state of an earlier
/// increment, such as the one CalculiX 2.20 hands an element re-added by `*MODEL CHANGE`.
fn check_start_time(p: &Point, c: &UmatCall, check: bool) -> crate::Result<()> {
    let (Some(end), true) = (p.core_time, check) else {
        return Ok(());
    };
    let start = c.time[1];
    let tolerance = TIME_ROUNDOFF * (end.abs() + c.dtime.abs());
    if (start - end).abs() <= tolerance {
        return Ok(());
    }
    Err(Error::StateTime {
        stored: end,
        host: start,
        remedy: EARLIER_STATE_REMEDY.into(),
    })
}

/// `STRAN` and the state's committed strain agree when they differ by at most this
/// fraction of the larger of the two (infinity norms) plus [`STRAIN_MATCH_FLOOR`]. A host
/// that adds `DSTRAN` to `STRAN`, as Abaqus and CalculiX do, hands back the library's own
/// sum (docs/statev.md has the agreement measured over a CalculiX analysis); a total
/// strain recomputed from displacements differs by round-off; a state one increment old
/// differs by the increment.
pub const STRAIN_MATCH_RELATIVE: f64 = 1e-9;
/// The absolute floor of the strain match (at zero strain), strain units.
pub const STRAIN_MATCH_FLOOR: f64 = 1e-12;
/// `NSTATV` up to this keeps the state in the library's table (room for the mirrors).
pub const TABLE_MODE_MAX_NSTATV: usize = MIRRORS;

const STALE_STATE_REMEDY: &str = ". Check that the host hands every call of an increment \
    the STATEV kept at the end of this point's previous converged increment, with that \
    increment's total strain in STRAN (a state of another point, or of an earlier \
    increment, is not this one's). A host whose STRAN is not the total strain at the start \
    of the increment sets [statev] check_strain = false in the scene";
const EARLIER_STATE_REMEDY: &str = ". CalculiX 2.20 hands an element re-added by *MODEL \
    CHANGE, ADD the STATEV of its last call before the removal: such an element cannot \
    continue from its old state (see docs/statev.md: do not remove and re-add RVE \
    elements, or set [statev] check_time = false in the scene to continue the old state \
    as ccx does). Otherwise the host handed a state kept from an earlier increment; a \
    host whose TIME(2) is not the total time at the start of the increment sets [statev] \
    check_time = false";
const LOST_STATE_REMEDY: &str = ". CalculiX 2.20 writes STATEV to its restart file only \
    when the model has a contact pair: add a node-to-surface pair that never closes (see \
    docs/calculix.md) and run the analysis again from its start. A host that zeroes \
    STATEV on purpose to restart the point from a virgin RVE (an element re-added with \
    its state reset) sets [statev] zero_at_strain = \"virgin\" in the scene";
/// One integration point.
struct Point {
    id: u64,
    key: MaterialKey,
    material: Arc<Material>,
    instance: Instance,
    /// The increment of the last call.
    increment: Option<Increment>,
    dtime: f64,
    /// The strain and answer of the instance's trial (`Some` exactly when it has one).
    last: Option<([f64; 3], Response)>,
    /// The last call failed.
    failed: bool,
    /// `STATEV` mode: hashes ([`values_hash`]) of the values the committed state stands
    /// for (see [`Umat::statev_answer`]) and of the values written for the pending trial;
    /// `None` in table mode and before the first call. The values themselves are not
    /// kept: [`Point::holds_core`] and [`Point::holds_trial`] re-encode the state.
    core_hash: Option<u64>,
    trial_hash: Option<u64>,
    /// `STATEV` mode: the host's time the committed state and the pending trial were
    /// written at the end of (`statev::Core::time`).
    core_time: Option<f64>,
    trial_time: Option<f64>,
}

impl Point {
    /// A virgin point of `material`.
    fn new(id: u64, key: MaterialKey, material: Arc<Material>) -> Self {
        Point {
            id,
            key,
            instance: Instance::new(material.model.clone()),
            material,
            increment: None,
            dtime: 0.0,
            last: None,
            failed: false,
            core_hash: None,
            trial_hash: None,
            core_time: None,
            trial_time: None,
        }
    }

    /// Whether `statev` are the values the committed state stands for: they hash as the
    /// ones it was loaded from, and its core (at [`Point::core_time`]) encodes to them bit
    /// for bit (values of state format 1 never do: they are expanded again).
    /// All-zero values (a virgin RVE) are held by a committed state whose core is the
    /// virgin state's.
    fn holds_core(&self, statev: &[f64]) -> bool {
        if self.core_hash != Some(values_hash(statev)) {
            return false;
        }
        let committed = self.instance.committed_core();
        if statev.iter().all(|&v| v == 0.0) {
            let model = &self.material.model;
            let virgin = model.core_of(&model.new_state());
            let mut values = vec![0.0; statev.len()];
            let (sizes, fingerprint) = (model.state_sizes(), model.fingerprint());
            return statev::write(&virgin, sizes, fingerprint, &mut values).is_ok()
                && encodes_to(&committed, self, None, &values);
        }
        encodes_to(&committed, self, self.core_time, statev)
    }

    /// Whether `statev` are the values written for the pending trial.
    fn holds_trial(&self, statev: &[f64]) -> bool {
        self.trial_hash == Some(values_hash(statev))
            && (self.instance.trial_core())
                .is_ok_and(|core| encodes_to(&core, self, self.trial_time, statev))
    }

    /// The pending trial's values (at [`Point::trial_time`]) into `out`.
    fn write_trial(&self, out: &mut [f64]) -> crate::Result<()> {
        let model = &self.material.model;
        let mut core = self.instance.trial_core()?;
        core.time = self.trial_time;
        statev::write(&core, model.state_sizes(), model.fingerprint(), out)
    }

    /// Applies the increment protocol before a call of `inc`; returns (committed,
    /// reverted).
    fn advance(&mut self, inc: Increment, dtime: f64) -> crate::Result<(bool, bool)> {
        let (mut committed, mut reverted) = (false, false);
        if let Some(prev) = self.increment.filter(|prev| inc.goes_back_from(prev)) {
            // A new analysis (or a restart) in this process: the table cannot know the
            // host's state at this time, so the point starts again from virgin.
            note_once(Note::WentBack, || {
                format!(
                    "mesorve: KSTEP/TIME went back from ({}, {}) to ({}, {}): points of the \
                     library's table restart from virgin RVEs (keep the state in STATEV, \
                     *DEPVAR = `rve info`'s umat_nstatv, to carry it)",
                    prev.kstep, prev.start, inc.kstep, inc.start
                )
            });
            self.instance.reset();
            self.last = None;
            self.increment = None;
        }
        if let Some(prev) = self.increment {
            let advanced = inc.start - prev.start > TIME_ROUNDOFF * (prev.start.abs() + self.dtime);
            let same = prev.kstep == inc.kstep && prev.kinc == inc.kinc && !advanced;
            if !same {
                if self.last.take().is_some() {
                    let ignored = self.instance.ignored_redos().0;
                    self.instance.commit()?;
                    committed = true;
                    if self.instance.ignored_redos().0 > ignored {
                        note_ignored_redo(self.instance.ignored_redos().1);
                    }
                }
            } else if self.failed || dtime < self.dtime * (1.0 - TIME_ROUNDOFF) {
                self.instance.revert();
                self.last = None;
                reverted = true;
            }
        }
        self.increment = Some(inc);
        self.dtime = dtime;
        self.failed = false;
        Ok((committed, reverted))
    }
}

thread_local! {
    /// This thread's buffer for re-encoded `STATEV` values ([`encodes_to`]).
    static VALUES: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

/// A hash of `values`' bits (not cryptographic: a quick filter before [`encodes_to`]).
fn values_hash(values: &[f64]) -> u64 {
    values.iter().fold(0xcbf2_9ce4_8422_2325, |h: u64, v| {
        (h.rotate_left(5) ^ v.to_bits()).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Whether `core` at `time`, encoded for point `p`'s model, is `statev` bit for bit.
fn encodes_to(core: &statev::Core, p: &Point, time: Option<f64>, statev: &[f64]) -> bool {
    let model = &p.material.model;
    let mut core = core.clone();
    core.time = time;
    VALUES
        .try_with(|v| {
            let mut v = v.borrow_mut();
            v.clear();
            v.resize(statev.len(), 0.0);
            statev::write(&core, model.state_sizes(), model.fingerprint(), &mut v).is_ok()
                && v.iter()
                    .map(|x| x.to_bits())
                    .eq(statev.iter().map(|x| x.to_bits()))
        })
        .unwrap_or(false)
}

type MaterialEntry = Result<Arc<Material>, Arc<Error>>;
type PointRef = Arc<Mutex<Point>>;

/// Asks the host for `ratio` times the increment through `PNEWDT`, keeping a smaller
/// request of an earlier point of the increment. A value that is not positive is no
/// request: Abaqus hands `PNEWDT` in large, CalculiX as -1 (and any positive value it
/// gets back cuts the increment).
pub fn request_step_ratio(pnewdt: &mut f64, ratio: f64) {
    if !(*pnewdt > 0.0 && *pnewdt <= ratio) {
        *pnewdt = ratio;
    }
}

/// A failed call before it is reported: the error, whether it is reported for the first
/// time, and the material when known (for the elastic DDSDDE).
struct Failed {
    error: Arc<Error>,
    first: bool,
    material: Option<Arc<Material>>,
}

/// Said once per process when a host kept an increment whose integration error exceeded
/// `solver.step_tolerance` (`relative`: its estimate over the tolerance): the host ignored
/// the request to redo it smaller. Shared by the UMAT's table mode and `rve_commit`.
pub fn note_ignored_redo(relative: f64) {
    note_once(Note::IgnoredRedo, || {
        format!(
            "mesorve: the host kept an increment whose integration error is {relative:.3} \
             times solver.step_tolerance although it was asked to redo it smaller (PNEWDT / \
             RveInfo.suggested_step_ratio < 1): it ignores the ratio or is at its smallest \
             step; the analysis goes on outside the tolerance there (printed once)"
        )
    });
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

/// The table of a host's integration points.
pub struct Umat {
    /// This table's number in the process: the key of its points in each thread's
    /// [`SLOTS`].
    id: u64,
    search: SearchPath,
    materials: Mutex<HashMap<MaterialKey, MaterialEntry>>,
    points: RwLock<HashMap<(i32, i32), PointRef>>,
    next_id: AtomicU64,
    calls: AtomicU64,
    solves: AtomicU64,
    repeats: AtomicU64,
    commits: AtomicU64,
    reverts: AtomicU64,
    loads: AtomicU64,
    failures: AtomicU64,
    shared: AtomicU64,
    /// Answer sharing's per-increment tables (`share_table`).
    share: ShareTable,
    /// `MESORVE_UMAT_VTK`: the RVE fields of chosen points as VTK ([`super::vtk_dump`]).
    vtk: Option<VtkDump>,
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

    /// This table writing the RVE fields of the points `vtk` chooses ([`super::vtk_dump`];
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

    /// One UMAT call of a host that passes `PNEWDT`: see the module documentation.
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
        self.calls.fetch_add(1, Ordering::Relaxed);
        let result = self.call_inner(c, out, signal).map_err(|f| {
            self.failures.fetch_add(1, Ordering::Relaxed);
            self.fail(c, out, f.error, f.first, f.material.as_deref())
        });
        let asks_smaller = *out.pnewdt > 0.0 && *out.pnewdt < 1.0;
        if signal == HostSignal::NanStress && (result.is_err() || asks_smaller) {
            out.stress.fill(f64::NAN);
        }
        result
    }

    fn call_inner(
        &self,
        c: &UmatCall,
        out: &mut UmatOutputs,
        signal: HostSignal,
    ) -> Result<Outcome, Failed> {
        check_lengths(c, out).map_err(plain)?;
        let material = match slot_material(self.id, c) {
            Some(m) => m,
            None => self.material(c).map_err(|(error, first)| Failed {
                error,
                first,
                material: None,
            })?,
        };
        let with_material = |e: Error| Failed {
            error: Arc::new(e),
            first: true,
            material: Some(material.clone()),
        };
        let statev_len = material.model.statev_len();
        if statev_mode(c, out.statev.len(), statev_len).map_err(with_material)? {
            return self.statev_call(c, out, material, signal);
        }
        if signal == HostSignal::NanStress {
            return Err(with_material(table_refused(out.statev.len(), statev_len)));
        }
        self.table_call(c, out)
    }

    /// `STATEV` mode. A host that passes `PNEWDT` (CalculiX, Abaqus) numbers its points:
    /// the table's point `(NOEL, NPT)` is the cache of its state, rebuilt at most once per
    /// increment. A host that does not (Kratos: every point 0) gets this thread's
    /// point for the values (see [`SLOTS`]); with more points on a thread than slots that
    /// rebuilds the state at every call (one factorization), which is why a numbering
    /// host keeps its table.
    fn statev_call(
        &self,
        c: &UmatCall,
        out: &mut UmatOutputs,
        material: Arc<Material>,
        signal: HostSignal,
    ) -> Result<Outcome, Failed> {
        let failed = |e: Error| Failed {
            error: Arc::new(e),
            first: true,
            material: Some(material.clone()),
        };
        if signal == HostSignal::Pnewdt {
            let point = self.point(c).map_err(|(error, first)| Failed {
                error,
                first,
                material: None,
            })?;
            let mut p = lock(&point, c).map_err(failed)?;
            if !Arc::ptr_eq(&p.material, &material) {
                *p = Point::new(p.id, MaterialKey::of(c), material.clone());
            }
            return self.statev_outcome(&mut p, c, out, true).map_err(failed);
        }
        let n = material.model.statev_len();
        let mut p = take_slot(self.id, &material, &out.statev[..n]).unwrap_or_else(|| {
            let id = self.next_id.fetch_add(1, Ordering::Relaxed);
            Point::new(id, MaterialKey::of(c), material.clone())
        });
        let result = self.statev_outcome(&mut p, c, out, false);
        put_slot(self.id, p);
        result.map_err(failed)
    }

    /// The `STATEV`-mode answer of point `p` written to `out` (`timed`: the host's
    /// `TIME(2)` is meaningful).
    fn statev_outcome(
        &self,
        p: &mut Point,
        c: &UmatCall,
        out: &mut UmatOutputs,
        timed: bool,
    ) -> crate::Result<Outcome> {
        let n = p.material.model.statev_len();
        // The host keeps the committed state: implicit points keep no full trial, unless
        // `MESORVE_UMAT_VTK` writes the point's fields from it.
        let dumped = self.vtk.as_ref().is_some_and(|v| v.chooses(c.noel, c.npt));
        p.instance
            .set_lean(p.material.model.solver.integration != Integration::Implex && !dumped);
        // A point whose fields are written solves its own answer.
        let implex = p.material.model.solver.integration == Integration::Implex;
        if timed && !dumped && !implex {
            if let Some((r, core)) = self.shared_answer(p, c, &out.statev[..n])? {
                write_outputs(p, c, &r, out, Some(n), Some(&core))?;
                return Ok(Outcome {
                    solved: false,
                    committed: false,
                    reverted: false,
                    iterations: 0,
                });
            }
        }
        let may_share = timed && !dumped;
        let (r, solved) = self.statev_answer(p, c, &out.statev[..n], (timed, may_share))?;
        write_outputs(p, c, &r, out, Some(n), None)?;
        vtk_dump::at_answer(&self.vtk, &p.instance, &c.dump_at());
        Ok(Outcome {
            solved,
            committed: false,
            reverted: false,
            iterations: r.report.iterations,
        })
    }

    /// Table mode: the point `(NOEL, NPT)` of the process's table, following the
    /// host's increments.
    fn table_call(&self, c: &UmatCall, out: &mut UmatOutputs) -> Result<Outcome, Failed> {
        let point = self.point(c).map_err(|(error, first)| Failed {
            error,
            first,
            material: None,
        })?;
        let mut p = lock(&point, c).map_err(plain)?;
        if !p.key.matches(c) {
            self.rebind(&mut p, c, out.statev.len())?;
        }
        p.instance.set_lean(false);
        let material = p.material.clone();
        let with_material = |e: Error| Failed {
            error: Arc::new(e),
            first: true,
            material: Some(material.clone()),
        };
        table_note(c, out.statev.len(), material.model.statev_len());
        let inc = Increment {
            kstep: c.kstep,
            kinc: c.kinc,
            start: c.time[1],
        };
        let (committed, reverted) = p.advance(inc, c.dtime).map_err(with_material)?;
        self.commits.fetch_add(committed as u64, Ordering::Relaxed);
        self.reverts.fetch_add(reverted as u64, Ordering::Relaxed);
        let (r, solved) = self.answer(&mut p, c).map_err(|e| {
            p.failed = true;
            with_material(e)
        })?;
        write_outputs(&p, c, &r, out, None, None).map_err(with_material)?;
        vtk_dump::at_answer(&self.vtk, &p.instance, &c.dump_at());
        Ok(Outcome {
            solved,
            committed,
            reverted,
            iterations: r.report.iterations,
        })
    }

    /// The RVE's answer at the call's strain: the point's trial when the strain repeats
    /// it bit for bit, else a new trial (true: solved).
    fn answer(&self, p: &mut Point, c: &UmatCall) -> crate::Result<(Response, bool)> {
        let strain = call_strain(p, c)?;
        if let Some((s, r)) = p.last {
            if s.map(f64::to_bits) == strain.map(f64::to_bits) {
                self.repeats.fetch_add(1, Ordering::Relaxed);
                return Ok((r, false));
            }
        }
        self.solves.fetch_add(1, Ordering::Relaxed);
        let model = p.material.model.clone();
        let request = p.material.tangent;
        let r = with_workspace(&model, |ws| {
            p.instance.update_timed(strain, c.dtime, ws, request)
        });
        p.last = r.as_ref().ok().map(|r| (strain, *r));
        Ok((r?, true))
    }

    /// `STATEV` mode with answer sharing (`share_table`): the answer of an anchor of
    /// this increment that the point's committed core (decoded from `statev`) and strain
    /// match, corrected to first order, with the anchor's trial core at the point's own
    /// strain and time (the values to write, and the history for the mirrors); `None`: the
    /// point solves (no sharing, no anchor, or values the normal path refuses with its
    /// message). The point's instance is not rebuilt: its pending trial is dropped, so
    /// the next increment rebuilds it from the values if it solves.
    fn shared_answer(
        &self,
        p: &mut Point,
        c: &UmatCall,
        statev: &[f64],
    ) -> crate::Result<Option<(Response, statev::Core)>> {
        let Some(tol) = sharing(p) else {
            return Ok(None);
        };
        if p.instance.has_trial() && p.holds_core(statev) {
            return Ok(None);
        }
        let model = p.material.model.clone();
        let strain = call_strain(p, c)?;
        let sizes = model.state_sizes();
        let core = match statev::read(statev, sizes, model.interface_points(), model.fingerprint())
        {
            Ok(Some(s)) if s.verified => s.core,
            Ok(None) => model.core_of(&model.new_state()),
            _ => return Ok(None),
        };
        if !start_matches(&model, c, &core)? {
            return Ok(None);
        }
        let time = Some(c.time[1] + c.dtime);
        let found = self
            .share
            .follow(&model, increment_key(c), tol, (&core, strain, time));
        let Some((r, written_core)) = found else {
            return Ok(None);
        };
        p.instance.revert();
        p.trial_hash = None;
        p.trial_time = time;
        self.shared.fetch_add(1, Ordering::Relaxed);
        Ok(Some((r, written_core)))
    }

    /// `STATEV` mode: the answer from the committed state `statev` holds (the host's
    /// start-of-increment values). The point's instance is a cache of that state, rebuilt
    /// from the values whenever they differ from the ones it was rebuilt from, so the
    /// answer is a function of `statev`, the strain and `DTIME` alone: a cut-back, a
    /// restart, a new analysis or a re-added element gets what the host hands over. A
    /// call that repeats the pending trial (same values, same strain) is not solved again.
    fn statev_answer(
        &self,
        p: &mut Point,
        c: &UmatCall,
        statev: &[f64],
        (timed, may_share): (bool, bool),
    ) -> crate::Result<(Response, bool)> {
        let strain = call_strain(p, c)?;
        let model = p.material.model.clone();
        if !p.holds_core(statev) {
            p.core_hash = None;
            let implex = model.solver.integration == Integration::Implex;
            // IMPL-EX: the host kept the point's last trial, which is the state those values
            // expand to plus the step kept for carrying over (whose answers are the same
            // bit for bit): it is committed instead of rebuilt.
            if implex && p.holds_trial(statev) && p.instance.commit().is_ok() {
                p.core_time = p.trial_time;
            } else {
                let stored = statev::read(
                    statev,
                    model.state_sizes(),
                    model.interface_points(),
                    model.fingerprint(),
                )?;
                if stored.as_ref().is_some_and(|s| !s.verified) {
                    unverified_note(c);
                }
                let core = stored.map(|s| s.core);
                p.core_time = core.as_ref().and_then(|c| c.time);
                with_workspace(&model, |ws| p.instance.load_core(core.as_ref(), ws))?;
                self.loads.fetch_add(1, Ordering::Relaxed);
            }
            p.core_hash = Some(values_hash(statev));
        }
        let virgin = statev.iter().all(|&v| v == 0.0);
        check_start_strain(p, c, virgin, timed)?;
        p.trial_hash = None;
        let request = p.material.tangent;
        let step = may_share.then(|| self.shared_step(p, c)).flatten();
        let r = with_workspace(&model, |ws| {
            p.instance.update_timed(strain, c.dtime, ws, request)
        })?;
        let mut written = vec![0.0; statev.len()];
        p.trial_time = timed.then(|| c.time[1] + c.dtime);
        p.write_trial(&mut written)?;
        p.trial_hash = Some(values_hash(&written));
        let solved = r.report.answer != Answer::Repeated;
        if let Some(step) = step {
            return Ok((r, self.step_shared(p, c, step, &r)));
        }
        if solved && timed && sharing(p).is_some() && !implex_model(p) {
            let mut trial = p.instance.trial_core()?;
            trial.time = p.trial_time;
            let anchor = Anchor {
                committed: p.instance.committed_core(),
                strain,
                response: r,
                trial,
            };
            self.share.insert(&model, increment_key(c), anchor);
        }
        let counter = if solved { &self.solves } else { &self.repeats };
        counter.fetch_add(1, Ordering::Relaxed);
        Ok((r, solved))
    }

    /// IMPL-EX step sharing (`docs/sharing.md`): before the point's update, the step of
    /// this increment factorized from the point's committed core (an earlier call of the
    /// point), else from a core within the tolerance (another point), taken as the point's
    /// own ([`Instance::adopt_step`]), so the update answers without a factorization.
    /// `Some(committed core, shared)`: the point shares (`shared` true: a step was adopted);
    /// `None`: no sharing (not IMPL-EX, no tolerance, or the point already holds its step).
    fn shared_step(&self, p: &mut Point, c: &UmatCall) -> Option<(statev::Core, bool)> {
        let tol = sharing(p).filter(|_| implex_model(p))?;
        let ratio = crate::solver::implex::step_ratio(p.instance.committed().implex.step, c.dtime);
        let ratio = ratio.to_bits();
        if p.instance.implex_step().is_some_and(|(_, r)| r == ratio) {
            return None;
        }
        let core = p.instance.committed_core();
        let model = p.material.model.clone();
        let found = self
            .share
            .follow_step(&model, increment_key(c), tol, (&core, ratio));
        let adopted = found.is_some_and(|s| p.instance.adopt_step(&s.step, ratio, c.dtime));
        Some((core, adopted))
    }

    /// After an update of [`Umat::shared_step`]: counts the call, and records the step a
    /// call that factorized it solved; returns whether the call solved.
    fn step_shared(
        &self,
        p: &Point,
        c: &UmatCall,
        (core, adopted): (statev::Core, bool),
        r: &Response,
    ) -> bool {
        if adopted {
            self.shared.fetch_add(1, Ordering::Relaxed);
            return false;
        }
        let counter = match r.report.answer {
            Answer::Repeated => &self.repeats,
            _ => &self.solves,
        };
        counter.fetch_add(1, Ordering::Relaxed);
        let Some((step, ratio)) = p.instance.implex_step() else {
            return true;
        };
        if r.report.factorizations > 0 {
            let step = Step::new(core, step.clone(), ratio);
            self.share
                .insert_step(&p.material.model, increment_key(c), step);
        }
        r.report.answer != Answer::Repeated
    }

    /// A point called with another material than it was created for: a new analysis
    /// (`STATEV` mode, or table mode with `KSTEP`/`TIME(2)` gone back) makes it a virgin
    /// point of the call's material; otherwise the call is refused.
    fn rebind(&self, p: &mut Point, c: &UmatCall, nstatv: usize) -> Result<(), Failed> {
        let material = self.material(c).map_err(|(error, first)| Failed {
            error,
            first,
            material: None,
        })?;
        let inc = Increment {
            kstep: c.kstep,
            kinc: c.kinc,
            start: c.time[1],
        };
        let new_analysis = nstatv >= material.model.statev_len()
            || p.increment.is_some_and(|prev| inc.goes_back_from(&prev));
        if !new_analysis {
            return Err(Failed {
                error: Arc::new(Error::HostConvention(format!(
                    "element {}, point {} was created for material `{}` with other PROPS \
                     or another name; a point keeps its material within an analysis",
                    c.noel, c.npt, p.key.cmname
                ))),
                first: true,
                material: None,
            });
        }
        *p = Point::new(p.id, MaterialKey::of(c), material);
        Ok(())
    }

    /// The point `(NOEL, NPT)`, created with its material on the first call.
    fn point(&self, c: &UmatCall) -> Result<PointRef, (Arc<Error>, bool)> {
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

    fn fail(
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

/// A failure without a material.
fn plain(e: Error) -> Failed {
    Failed {
        error: Arc::new(e),
        first: true,
        material: None,
    }
}

/// Table mode asked for by a host without `PNEWDT` ([`HostSignal::NanStress`]): refused,
/// since such a host (Kratos) gives none of what the table follows: every point is
/// `NOEL` = `NPT` = 0, `KINC` counts Newton iterations, and `TIME` is one value.
fn table_refused(nstatv: usize, needed: usize) -> Error {
    Error::HostConvention(format!(
        "NSTATV = {nstatv} asks for the library's table of points, which a host without \
         PNEWDT (NULL, as Kratos passes it) cannot drive: it keys points on NOEL and NPT \
         and increments on KSTEP, KINC and TIME(2), and such a host numbers every point 0 \
         and counts Newton iterations in KINC. Give {needed} STATEV entries (plus up to \
         {MIRRORS} for the mirrors: `rve info`'s umat_nstatv), all zero, to keep the state \
         in STATEV"
    ))
}

/// `STATEV`-mode points kept per thread, at most this many (all tables together).
const SLOTS_PER_THREAD: usize = 4;

/// A `STATEV`-mode point of a thread: a cache of the state some `STATEV` values stand
/// for, keyed by nothing but those values (and the table and material), never by `NOEL`
/// or `NPT`. Two calls with the same values, strain and `DTIME` (a host's stress call
/// then its tangent call) are answered by one solve, bit for bit.
struct Slot {
    table: u64,
    /// Last use, for replacing the least recently used slot.
    stamp: u64,
    point: Point,
}

thread_local! {
    /// This thread's `STATEV`-mode points ([`Slot`]): no lock, no point shared with
    /// another thread.
    static SLOTS: RefCell<(u64, Vec<Slot>)> = const { RefCell::new((0, Vec::new())) };
}

/// The material of a call whose table and name this thread has a slot of.
fn slot_material(table: u64, c: &UmatCall) -> Option<Arc<Material>> {
    SLOTS
        .try_with(|slots| {
            let slots = slots.borrow();
            let found = slots
                .1
                .iter()
                .find(|s| s.table == table && s.point.key.matches(c));
            found.map(|s| s.point.material.clone())
        })
        .ok()
        .flatten()
}

/// Takes this thread's point of `material` whose committed values are `statev` (else
/// whose pending trial's values are, else the least recently used one), or `None`. The
/// caller puts it back with [`put_slot`]; a panic in between drops it.
fn take_slot(table: u64, material: &Arc<Material>, statev: &[f64]) -> Option<Point> {
    SLOTS
        .try_with(|slots| {
            let slots = &mut slots.borrow_mut().1;
            let ours = |s: &Slot| s.table == table && Arc::ptr_eq(&s.point.material, material);
            let find = |f: &dyn Fn(&Slot) -> bool| slots.iter().position(|s| ours(s) && f(s));
            let pick = find(&|s| s.point.holds_core(statev))
                .or_else(|| find(&|s| s.point.holds_trial(statev)))
                .or_else(|| {
                    let mine = slots.iter().enumerate().filter(|(_, s)| ours(s));
                    mine.min_by_key(|(_, s)| s.stamp).map(|(i, _)| i)
                })?;
            Some(slots.swap_remove(pick).point)
        })
        .ok()
        .flatten()
}

/// Gives `point` back to this thread's slots, dropping the least recently used one
/// beyond [`SLOTS_PER_THREAD`].
fn put_slot(table: u64, point: Point) {
    let _ = SLOTS.try_with(|slots| {
        let (clock, slots) = &mut *slots.borrow_mut();
        *clock += 1;
        slots.push(Slot {
            table,
            stamp: *clock,
            point,
        });
        if slots.len() > SLOTS_PER_THREAD {
            let oldest = slots.iter().enumerate().min_by_key(|(_, s)| s.stamp);
            if let Some((i, _)) = oldest {
                slots.swap_remove(i);
            }
        }
    });
}

/// The point's lock; a point poisoned by a panic in an earlier call keeps its committed
/// state (only ever replaced whole) and drops its trial.
fn lock<'p>(point: &'p PointRef, c: &UmatCall) -> crate::Result<MutexGuard<'p, Point>> {
    match point.try_lock() {
        Ok(p) => Ok(p),
        Err(TryLockError::WouldBlock) => Err(Error::HostConvention(format!(
            "element {}, point {} is being updated by another thread",
            c.noel, c.npt
        ))),
        Err(TryLockError::Poisoned(poisoned)) => {
            point.clear_poison();
            let mut p = poisoned.into_inner();
            p.instance.revert();
            p.last = None;
            p.failed = true;
            p.core_hash = None;
            p.trial_hash = None;
            p.core_time = None;
            p.trial_time = None;
            Ok(p)
        }
    }
}

/// The call's total strain `STRAN + DSTRAN` as the RVE's, for the point's model.
fn call_strain(p: &Point, c: &UmatCall) -> crate::Result<[f64; 3]> {
    let h = c.hypothesis;
    h.check_model(&p.material.model)?;
    let total: Vec<f64> = c.stran.iter().zip(c.dstran).map(|(a, b)| a + b).collect();
    h.rve_strain(&total)
}

/// Says once per process that a point's `STATEV` is of state format 1 (no fingerprint):
/// accepted, since an upgrade may find an analysis mid-way, but it cannot be verified to be
/// this material's; the point's next write is verified.
fn unverified_note(c: &UmatCall) {
    note_once(Note::Unverified, || {
        format!(
            "mesorve: element {}, point {}, material `{}`: STATEV written by an earlier \
             mesorve (state format 1, no fingerprint): accepted, but it cannot be verified \
             to be this material's state; the values written from now on can (printed \
             once)",
            c.noel,
            c.npt,
            trim(c.cmname)
        )
    });
}

/// `STATEV` mode (true) or table mode (false) for a call with `nstatv` entries when the
/// state needs `needed`: `STATEV` mode from `needed` on, table mode up to
/// [`TABLE_MODE_MAX_NSTATV`] (room for the mirrors only, the 0.1-0.3 decks' rule for the
/// table), an error naming the count in between (a `*DEPVAR` short of the state, which
/// would otherwise run in the table without a restart or a re-added element carrying it).
fn statev_mode(c: &UmatCall, nstatv: usize, needed: usize) -> crate::Result<bool> {
    if nstatv >= needed {
        return Ok(true);
    }
    if nstatv <= TABLE_MODE_MAX_NSTATV {
        return Ok(false);
    }
    Err(Error::HostConvention(format!(
        "NSTATV = {nstatv}: material `{}` keeps its RVE state in STATEV(1:{needed}) (set \
         *DEPVAR to {needed}, plus {MIRRORS} for the mirrors: `rve info`'s umat_nstatv); an \
         NSTATV of at most {TABLE_MODE_MAX_NSTATV} keeps the state in the library's table \
         instead",
        trim(c.cmname)
    )))
}

/// `Some((difference, tolerance))` when a state committed at `stored` does not belong to
/// the start of an increment at `host` (infinity norms; see [`STRAIN_MATCH_RELATIVE`]).
pub fn strain_mismatch(stored: [f64; 3], host: [f64; 3]) -> Option<(f64, f64)> {
    let norm = |e: &[f64; 3]| e.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let difference = norm(&std::array::from_fn(|i| stored[i] - host[i]));
    let tolerance = STRAIN_MATCH_RELATIVE * norm(&stored).max(norm(&host)) + STRAIN_MATCH_FLOOR;
    (difference > tolerance).then_some((difference, tolerance))
}

/// Refuses a state that is not this point's at this increment: its committed strain must
/// be the host's `STRAN` to [`STRAIN_MATCH_RELATIVE`] of the larger of the two, plus
/// [`STRAIN_MATCH_FLOOR`]; an all-zero `STATEV` (`virgin`) at a strained point is a lost
/// state unless the scene says the host zeroes it on purpose (`[statev]`).
fn check_start_strain(p: &Point, c: &UmatCall, virgin: bool, timed: bool) -> crate::Result<()> {
    let spec = p.material.model.scene().spec.statev;
    if !spec.check_strain {
        return Ok(());
    }
    let host = c.hypothesis.rve_strain(c.stran)?;
    let stored = p.instance.committed().strain;
    let Some((difference, tolerance)) = strain_mismatch(stored, host) else {
        return check_start_time(p, c, spec.check_time && timed);
    };
    if virgin {
        if spec.zero_at_strain == ZeroAtStrain::Virgin {
            return Ok(());
        }
        return Err(Error::StateLost {
            host,
            remedy: LOST_STATE_REMEDY.into(),
        });
    }
    Err(Error::StateStrain {
        stored,
        host,
        difference,
        tolerance,
        remedy: STALE_STATE_REMEDY.into(),
    })
}

/// The sharing tolerance of the point's material, when it shares: `[solver]
/// share_tolerance` and the consistent tangent returned (the first-order correction needs
/// it; `PROPS(6)` may ask for another).
fn sharing(p: &Point) -> Option<f64> {
    let tol = share::tolerance(&p.material.model)?;
    (p.material.tangent == TangentRequest::Consistent).then_some(tol)
}

/// Whether the point's material integrates by IMPL-EX (step sharing).
fn implex_model(p: &Point) -> bool {
    p.material.model.solver.integration == Integration::Implex
}

/// The share table's increment of a call.
fn increment_key(c: &UmatCall) -> IncrementKey {
    (c.time[1].to_bits(), c.dtime.to_bits(), c.kstep)
}

/// Whether a decoded core passes the checks of the start of the increment (strain and
/// time, as [`check_start_strain`]); a core that does not is left to the normal path,
/// which refuses it with its message.
fn start_matches(model: &crate::Model, c: &UmatCall, core: &statev::Core) -> crate::Result<bool> {
    let spec = model.scene().spec.statev;
    let host = c.hypothesis.rve_strain(c.stran)?;
    if spec.check_strain && strain_mismatch(core.strain, host).is_some() {
        return Ok(false);
    }
    let late = core
        .time
        .is_some_and(|end| (c.time[1] - end).abs() > TIME_ROUNDOFF * (end.abs() + c.dtime.abs()));
    Ok(!(spec.check_time && late))
}

/// Says once per process that `STATEV` is too short to hold the state.
fn table_note(c: &UmatCall, nstatv: usize, needed: usize) {
    note_once(Note::TableMode, || {
        format!(
            "mesorve: material `{}`: NSTATV = {nstatv}, the RVE state needs {needed} \
             (*DEPVAR, `rve info`'s umat_nstatv): the state stays in the library's table, \
             which a restart, a second analysis or a re-added element does not carry \
             (printed once)",
            trim(c.cmname)
        )
    });
}

/// Writes `STRESS`, `DDSDDE` and `STATEV`: in `STATEV` mode (`Some(len)`) the trial's
/// core (or `shared`, a core shared from another point) in `STATEV(1:len)` and the
/// inspection mirrors ([`super::mirrors`]) after it, in table mode the mirrors from
/// `STATEV(1)`; `PNEWDT` < 1 when the answer depends on the increment's size.
fn write_outputs(
    p: &Point,
    c: &UmatCall,
    r: &Response,
    out: &mut UmatOutputs,
    statev_len: Option<usize>,
    shared: Option<&statev::Core>,
) -> crate::Result<()> {
    let material = &p.material;
    let plane = PlaneResponse::from(r);
    let h = c.hypothesis;
    let mut written = vec![0.0; statev_len.unwrap_or(0)];
    match (statev_len, shared) {
        (None, _) => {}
        (Some(_), None) => p.write_trial(&mut written)?,
        (Some(_), Some(core)) => {
            let model = &material.model;
            statev::write(core, model.state_sizes(), model.fingerprint(), &mut written)?
        }
    }
    h.host_stress(&plane, out.stress)?;
    h.host_tangent(&plane, &material.elastic.tangent, out.ddsdde)?;
    out.statev[..written.len()].copy_from_slice(&written);
    let mirrors_at = written.len();
    let room = out.statev.len() - mirrors_at;
    let mirrors = match shared {
        Some(core) => mirrors_of(
            p.id,
            r.report.iterations,
            r.report.substeps,
            (&material.model, &core.history),
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

//! The arguments and results of one UMAT call: what the host passes ([`UmatCall`]), what
//! it gets back ([`UmatOutputs`], [`Outcome`], [`UmatFailure`]) and how it hears of a
//! failure or of a request for a smaller step ([`HostSignal`], [`request_step_ratio`]);
//! a failure before it is reported ([`Failed`]); the table's books that both modes write
//! ([`Books`]: counters, point ids, the VTK switch) and its counters ([`UmatStats`]).

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use crate::error::Error;
use crate::host::hypothesis::Hypothesis;
use crate::host::material::Material;
use crate::host::vtk_dump::{DumpAt, VtkDump};

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
    /// `CELENT`, the element's characteristic length, where the host passes one (`None`:
    /// a NULL pointer). Read only by a scene with `effects.regularization` and
    /// `PROPS(7)` = 0 (CalculiX 2.20 passes a value it never sets).
    pub celent: Option<f64>,
}

impl UmatCall<'_> {
    /// The call's point and increment, as the VTK dump names its files.
    pub(super) fn dump_at(&self) -> DumpAt {
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

impl Outcome {
    /// A `STATEV`-mode answer (no commit or revert: the host keeps the state).
    pub(super) fn answered(solved: bool, iterations: u32) -> Self {
        Outcome {
            solved,
            committed: false,
            reverted: false,
            iterations,
        }
    }
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

/// Asks the host for `ratio` times the increment through `PNEWDT`, keeping a smaller
/// request of an earlier point of the increment. A value that is not positive is no
/// request: Abaqus hands `PNEWDT` in large, CalculiX as -1 (and any positive value it
/// gets back cuts the increment).
pub fn request_step_ratio(pnewdt: &mut f64, ratio: f64) {
    if !(*pnewdt > 0.0 && *pnewdt <= ratio) {
        *pnewdt = ratio;
    }
}

/// `CMNAME` without its padding (blanks or NULs).
pub(super) fn trim(cmname: &str) -> &str {
    cmname.trim_end_matches([' ', '\0'])
}

/// A failed call before it is reported: the error, whether it is reported for the first
/// time, and the material when known (for the elastic `DDSDDE`).
pub(super) struct Failed {
    pub(super) error: Arc<Error>,
    pub(super) first: bool,
    pub(super) material: Option<Arc<Material>>,
}

impl Failed {
    /// A failure to resolve a call's material (the error, and whether it is reported for
    /// the first time): no material.
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

/// What both modes write besides their points: the counters, the next point id, the
/// table's number (the key of its points in each thread's `STATEV`-mode slots) and the
/// `MESORVE_UMAT_VTK` switch.
pub(super) struct Books {
    pub(super) table: u64,
    pub(super) next_id: AtomicU64,
    pub(super) calls: AtomicU64,
    pub(super) solves: AtomicU64,
    pub(super) repeats: AtomicU64,
    pub(super) commits: AtomicU64,
    pub(super) reverts: AtomicU64,
    pub(super) loads: AtomicU64,
    pub(super) failures: AtomicU64,
    pub(super) shared: AtomicU64,
    pub(super) vtk: Option<VtkDump>,
}

impl Books {
    /// The books of a new table, numbered in the process.
    pub(super) fn new() -> Self {
        static TABLES: AtomicU64 = AtomicU64::new(1);
        let zero = || AtomicU64::new(0);
        Books {
            table: TABLES.fetch_add(1, Ordering::Relaxed),
            next_id: AtomicU64::new(1),
            calls: zero(),
            solves: zero(),
            repeats: zero(),
            commits: zero(),
            reverts: zero(),
            loads: zero(),
            failures: zero(),
            shared: zero(),
            vtk: None,
        }
    }

    /// A new point's id (1, 2, ... in creation order).
    pub(super) fn new_id(&self) -> u64 {
        self.next_id.fetch_add(1, Ordering::Relaxed)
    }

    /// Adds one to `counter`.
    pub(super) fn count(counter: &AtomicU64) {
        counter.fetch_add(1, Ordering::Relaxed);
    }

    /// Adds one to `counter` when `happened`.
    pub(super) fn add(counter: &AtomicU64, happened: bool) {
        counter.fetch_add(u64::from(happened), Ordering::Relaxed);
    }

    /// Counts a solved (true) or repeated (false) answer.
    pub(super) fn count_answer(&self, solved: bool) {
        Self::count(if solved { &self.solves } else { &self.repeats });
    }

    /// The counters, with `points` points in the table.
    pub(super) fn stats(&self, points: u64) -> UmatStats {
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
            points,
        }
    }

    /// Writes the fields of `instance`'s trial when the switch chooses the call's point.
    pub(super) fn dump(&self, instance: &crate::model::Instance, c: &UmatCall) {
        crate::host::vtk_dump::at_answer(&self.vtk, instance, &c.dump_at());
    }

    /// Whether the switch writes the fields of the call's point.
    pub(super) fn dumps(&self, c: &UmatCall) -> bool {
        self.vtk.as_ref().is_some_and(|v| v.chooses(c.noel, c.npt))
    }
}

//! The arguments and results of one UMAT call: what the host passes ([`UmatCall`]), what
//! it gets back ([`UmatOutputs`], [`Outcome`], [`UmatFailure`]) and how it hears of a
//! failure or of a request for a smaller step ([`HostSignal`], [`request_step_ratio`]);
//! the table's counters ([`UmatStats`]).

use std::sync::Arc;

use crate::error::Error;
use crate::host::hypothesis::Hypothesis;
use crate::host::vtk_dump::DumpAt;

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

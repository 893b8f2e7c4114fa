//! The UMAT as a host calls it through C (`crate::ffi`'s `rve_umat`, `umat_`, `UMAT`):
//! [`answer_host`], the one entry behind the exported functions, which only translate
//! pointers ([`HostCall`]). Every rule of the seam is here:
//! - what is read: `CMNAME` only when it names the scene ([`SceneChoice`]: not when
//!   `MESORVE_UMAT_SCENE` is set, nor from a host without `PNEWDT`), at most 80 bytes,
//!   escaped; `TIME` as two values, or one from a host without `PNEWDT`; each array as
//!   long as `NTENS`, `NSTATV` and `NPROPS` say ([`HostLengths`]), after they are checked;
//! - which host it is: a NULL `PNEWDT` is a host that hears by NaN in `STRESS`
//!   ([`HostSignal::NanStress`], Kratos), else through `PNEWDT`;
//! - what the host hears of a failure: the table's answer ([`Umat::call_as`]), or, for a
//!   call that failed before the table saw it (a NULL argument, a layout the RVE cannot
//!   answer, a panic), `PNEWDT` = [`FAILURE_STEP_RATIO`] or NaN in `STRESS` by the same
//!   rule ([`tell_host`]); every failure said on stderr once per reason
//!   ([`crate::host::diagnostics`]) and returned for `rve_last_error`.

use std::borrow::Cow;
use std::fmt::Write;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::LazyLock;

use super::call::{HostSignal, UmatCall, UmatFailure, UmatOutputs};
use super::dispatch::{tell_host, Umat, FAILURE_STEP_RATIO};
use crate::error::Error;
use crate::host::diagnostics::{failure_once, note_once, Note};
use crate::host::hypothesis::Hypothesis;
use crate::host::material::{SearchPath, UmatScene};
use crate::host::vtk_dump::VtkDump;
use crate::model::batch::panic_message;

/// `CMNAME` is `CHARACTER*80` in Abaqus: no more is read.
const CMNAME_MAX: usize = 80;

/// The name a panic's message gives the entry (the exported aliases call it).
const ENTRY: &str = "rve_umat";

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

/// The scalar arguments of a C call, as the host passed them (`None`: a NULL pointer).
#[derive(Clone, Copy, Debug)]
pub struct HostScalars {
    pub ndi: Option<i32>,
    pub nshr: Option<i32>,
    pub ntens: Option<i32>,
    pub nstatv: Option<i32>,
    pub nprops: Option<i32>,
    pub noel: Option<i32>,
    pub npt: Option<i32>,
    pub kstep: Option<i32>,
    pub kinc: Option<i32>,
    pub dtime: Option<f64>,
    /// `CELENT` (`None`: NULL, Kratos).
    pub celent: Option<f64>,
    /// The hidden length of `CMNAME`.
    pub cmname_len: usize,
}

/// How many values of each array a call reads (`cmname`: `None` when `CMNAME` is not
/// read; a length 0 reads nothing).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HostLengths {
    pub cmname: Option<usize>,
    pub time: usize,
    pub props: usize,
    /// `STRAN` and `DSTRAN`.
    pub strain: usize,
    pub stress: usize,
    pub ddsdde: usize,
    pub statev: usize,
}

/// The arrays of a C call at the lengths asked (`None`: a NULL pointer).
#[derive(Debug, Default)]
pub struct HostArrays<'a> {
    pub cmname: Option<&'a [u8]>,
    pub time: Option<&'a [f64]>,
    pub props: Option<&'a [f64]>,
    pub stran: Option<&'a [f64]>,
    pub dstran: Option<&'a [f64]>,
    pub stress: Option<&'a mut [f64]>,
    pub ddsdde: Option<&'a mut [f64]>,
    pub statev: Option<&'a mut [f64]>,
}

/// A C call as the exported function reads it: the scalars, `PNEWDT` (`None`: NULL) and
/// the reader of the arrays, called once with the lengths [`answer_host`] decides.
pub struct HostCall<'a, R: FnOnce(HostLengths) -> HostArrays<'a>> {
    pub scalars: HostScalars,
    pub pnewdt: Option<&'a mut f64>,
    pub arrays: R,
}

/// Why a C call failed, as `rve_last_error` says it.
#[derive(Debug)]
pub enum HostError {
    /// A NULL pointer where the call reads the argument so named.
    Null(&'static str),
    /// Refused before the table saw it (a layout the RVE cannot answer).
    Refused(Error),
    /// Failed in the table (the message names the point and material).
    Failed(UmatFailure),
    /// A panic, caught: a bug.
    Panic(String),
}

impl std::fmt::Display for HostError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            HostError::Null(name) => write!(f, "argument `{name}` is NULL"),
            HostError::Refused(e) => e.fmt(f),
            HostError::Failed(failure) => failure.fmt(f),
            HostError::Panic(message) => f.write_str(message),
        }
    }
}

/// Where a call's scene comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum SceneChoice {
    /// `MESORVE_UMAT_SCENE`, for every call.
    Named(&'static str),
    /// A host without `PNEWDT` and no `MESORVE_UMAT_SCENE`: the embedded paper RVE, since
    /// its `CMNAME` has no length to trust (Kratos passes one uninitialised byte and no
    /// hidden length).
    Embedded,
    /// `CMNAME`.
    Cmname,
}

impl SceneChoice {
    fn of(signal: HostSignal) -> Self {
        match (umat_scene(), signal) {
            (Some(scene), _) => SceneChoice::Named(&scene.name),
            (None, HostSignal::NanStress) => SceneChoice::Embedded,
            (None, HostSignal::Pnewdt) => SceneChoice::Cmname,
        }
    }

    /// The material name the call gets (the embedded RVE said once).
    fn name(self, cmname: Option<&[u8]>) -> Result<Cow<'_, str>, HostError> {
        match self {
            SceneChoice::Named(name) => Ok(Cow::Borrowed(name)),
            SceneChoice::Embedded => {
                note_once(Note::NoScene, || {
                    "mesorve UMAT: a host without PNEWDT and no MESORVE_UMAT_SCENE: CMNAME is \
                     not read, every point is the embedded paper RVE (printed once)"
                        .to_string()
                });
                Ok(Cow::Borrowed(""))
            }
            SceneChoice::Cmname => Ok(printable(need(cmname, "CMNAME")?)),
        }
    }
}

/// `value`, or the failure of a NULL argument `name`.
fn need<T>(value: Option<T>, name: &'static str) -> Result<T, HostError> {
    value.ok_or(HostError::Null(name))
}

/// A count (`NSTATV`, `NPROPS`): a negative one is 0.
fn count(value: Option<i32>, name: &'static str) -> Result<usize, HostError> {
    Ok(usize::try_from(need(value, name)?).unwrap_or(0))
}

impl HostScalars {
    /// The layout of `NDI`, `NSHR`, `NTENS`.
    fn hypothesis(&self) -> Result<Hypothesis, HostError> {
        let (ndi, nshr) = (need(self.ndi, "NDI")?, need(self.nshr, "NSHR")?);
        Hypothesis::from_abaqus(ndi, nshr, need(self.ntens, "NTENS")?).map_err(HostError::Refused)
    }

    /// What a call reads: nothing of the strain and the tangent without a layout, the
    /// stress at `NTENS` from 1 to 6 (a failure fills it with NaN for a host without
    /// `PNEWDT`).
    fn lengths(
        &self,
        h: Option<Hypothesis>,
        scene: SceneChoice,
        signal: HostSignal,
    ) -> HostLengths {
        let n = h.map_or(0, Hypothesis::ntens);
        let stress = self.ntens.and_then(|n| usize::try_from(n).ok());
        let time = match signal {
            HostSignal::Pnewdt => 2,
            HostSignal::NanStress => 1,
        };
        HostLengths {
            cmname: (scene == SceneChoice::Cmname).then_some(self.cmname_len.min(CMNAME_MAX)),
            time,
            props: count(self.nprops, "NPROPS").unwrap_or(0),
            strain: n,
            stress: stress.filter(|n| (1..=6).contains(n)).unwrap_or(0),
            ddsdde: n * n,
            statev: count(self.nstatv, "NSTATV").unwrap_or(0),
        }
    }
}

/// Answers a C call: reads what the host passed as the call's rules say, answers it with
/// the process's table ([`global`]), and on failure says it on stderr once per reason and
/// tells the host (see the module documentation). A panic is caught and answered as a
/// failure.
pub fn answer_host<'a, R>(call: HostCall<'a, R>) -> Result<(), HostError>
where
    R: FnOnce(HostLengths) -> HostArrays<'a>,
{
    let s = call.scalars;
    let signal = match call.pnewdt {
        Some(_) => HostSignal::Pnewdt,
        None => HostSignal::NanStress,
    };
    let scene = SceneChoice::of(signal);
    let hypothesis = s.hypothesis();
    let mut arrays = (call.arrays)(s.lengths(hypothesis.as_ref().ok().copied(), scene, signal));
    // A host without PNEWDT: the request it would have got, for the NaN rule.
    let mut own = 0.0;
    let pnewdt = call.pnewdt.unwrap_or(&mut own);
    let mut stress = arrays.stress.take();
    let caught = catch_unwind(AssertUnwindSafe(|| {
        let read = Read {
            s: &s,
            signal,
            scene,
            arrays,
        };
        read.answer(hypothesis?, stress.as_deref_mut(), &mut *pnewdt)
    }));
    let result = caught.unwrap_or_else(|payload| {
        let what = panic_message(payload.as_ref());
        Err(HostError::Panic(format!(
            "{ENTRY}: internal error (panic: {what}); please report it"
        )))
    });
    if let Err(e) = &result {
        report(e, signal, stress.unwrap_or(&mut []), pnewdt);
    }
    result
}

/// The arguments of a call once read.
struct Read<'s, 'a> {
    s: &'s HostScalars,
    signal: HostSignal,
    scene: SceneChoice,
    arrays: HostArrays<'a>,
}

impl Read<'_, '_> {
    /// The call checked argument by argument (a NULL one fails it) and answered by the
    /// table.
    fn answer(
        self,
        hypothesis: Hypothesis,
        stress: Option<&mut [f64]>,
        pnewdt: &mut f64,
    ) -> Result<(), HostError> {
        let (s, a) = (self.s, self.arrays);
        let (nstatv, nprops) = (count(s.nstatv, "NSTATV")?, count(s.nprops, "NPROPS")?);
        let name = self.scene.name(a.cmname)?;
        let t = need(a.time, "TIME")?;
        let time = match self.signal {
            HostSignal::Pnewdt => [t[0], t[1]],
            // One value: TIME(2) is not read.
            HostSignal::NanStress => [t[0]; 2],
        };
        let call = UmatCall {
            cmname: &name,
            props: if nprops == 0 {
                &[]
            } else {
                need(a.props, "PROPS")?
            },
            hypothesis,
            stran: need(a.stran, "STRAN")?,
            dstran: need(a.dstran, "DSTRAN")?,
            time,
            dtime: need(s.dtime, "DTIME")?,
            noel: need(s.noel, "NOEL")?,
            npt: need(s.npt, "NPT")?,
            kstep: need(s.kstep, "KSTEP")?,
            kinc: need(s.kinc, "KINC")?,
            celent: s.celent,
        };
        let mut out = UmatOutputs {
            stress: need(stress, "STRESS")?,
            ddsdde: need(a.ddsdde, "DDSDDE")?,
            statev: match (nstatv, a.statev) {
                (0, _) => &mut [],
                (_, statev) => need(statev, "STATEV")?,
            },
            pnewdt,
        };
        let answered = global().call_as(&call, &mut out, self.signal);
        answered.map(drop).map_err(HostError::Failed)
    }
}

/// Says a failed call on stderr, once per reason; a call the table did not answer (it
/// told the host itself) gets `PNEWDT` = [`FAILURE_STEP_RATIO`], or NaN in `STRESS`.
fn report(e: &HostError, signal: HostSignal, stress: &mut [f64], pnewdt: &mut f64) {
    match e {
        HostError::Failed(f) => {
            if f.first_report {
                failure_once(&f.error.to_string(), &format!("mesorve UMAT: {f}"));
            }
        }
        _ => {
            let message = e.to_string();
            failure_once(&message, &format!("mesorve UMAT: {message}"));
            tell_host(signal, stress, pnewdt, Some(FAILURE_STEP_RATIO));
        }
    }
}

/// A host's bytes as text that is safe to print: up to the first NUL, printable ASCII
/// kept, any other byte as `\xNN`. Borrowed when every byte is printable (a host's usual
/// `CMNAME`): the UMAT reads it at every call, so it allocates only for a name to escape.
fn printable(bytes: &[u8]) -> Cow<'_, str> {
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    let bytes = &bytes[..end];
    let is_printable = |b: &u8| (b' '..=b'~').contains(b);
    if bytes.iter().all(is_printable) {
        if let Ok(text) = std::str::from_utf8(bytes) {
            return Cow::Borrowed(text);
        }
    }
    let mut text = String::with_capacity(4 * bytes.len());
    for &b in bytes {
        if is_printable(&b) {
            text.push(char::from(b));
        } else {
            // Writing into a String cannot fail.
            let _ = write!(text, "\\x{b:02x}");
        }
    }
    Cow::Owned(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A host's bytes print as printable ASCII, up to the first NUL.
    #[test]
    fn host_bytes_are_escaped() {
        assert_eq!(printable(b"CONCRETE  "), "CONCRETE  ");
        assert!(matches!(printable(b"CONCRETE  "), Cow::Borrowed(_)));
        assert_eq!(printable(b"A\x9c\n\x1b[2J"), "A\\x9c\\x0a\\x1b[2J");
        assert_eq!(printable(b"AB\0garbage\xff"), "AB");
        assert!(printable(&[0x80, 0xfe, 0x07])
            .chars()
            .all(|c| c.is_ascii_graphic()));
    }
}

//! The Abaqus UMAT entry point: `rve_umat`, and the same function under the names hosts
//! look up, `umat_` (gfortran's name for `CALL UMAT(...)`; MOOSE, OpenSees) and `UMAT`
//! (CalculiX, which upper-cases the function name of `@ABAQUS_<LIB>_<FUNC>`). Only
//! pointer translation here; the logic is `crate::host::umat`.

use std::borrow::Cow;
use std::ffi::{c_char, c_int};
use std::fmt::Write;

use super::guard::{guard, slice, slice_mut, Failure, FfiResult};
use super::status::RveStatus;
use crate::host::diagnostics::{failure_once, note_once, Note};
use crate::host::umat::{
    global, request_step_ratio, umat_scene, HostSignal, UmatCall, UmatOutputs, FAILURE_STEP_RATIO,
};
use crate::host::Hypothesis;

/// CMNAME is `CHARACTER*80` in Abaqus: no more is read.
const CMNAME_MAX: usize = 80;

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

/// Fills `STRESS(1:NTENS)` with NaN after a failure before the table saw the call, for a
/// host without `PNEWDT` ([`HostSignal::NanStress`]); nothing when `NTENS` or `STRESS`
/// cannot be read.
///
/// # Safety
/// As [`rve_umat`]'s.
unsafe fn nan_stress(stress: *mut f64, ntens: *const c_int) {
    let Some(&n) = ntens.as_ref() else { return };
    if let (Ok(n @ 1..=6), false) = (usize::try_from(n), stress.is_null()) {
        std::slice::from_raw_parts_mut(stress, n).fill(f64::NAN);
    }
}

/// The arguments of a UMAT call that the RVE reads or writes, as the host passed them.
struct Args {
    stress: *mut f64,
    statev: *mut f64,
    ddsdde: *mut f64,
    stran: *const f64,
    dstran: *const f64,
    time: *const f64,
    dtime: *const f64,
    cmname: *const c_char,
    cmname_len: usize,
    ndi: *const c_int,
    nshr: *const c_int,
    ntens: *const c_int,
    nstatv: *const c_int,
    props: *const f64,
    nprops: *const c_int,
    pnewdt: *mut f64,
    noel: *const c_int,
    npt: *const c_int,
    kstep: *const c_int,
    kinc: *const c_int,
}

impl Args {
    /// The material name: `MESORVE_UMAT_SCENE` when set; else none (the embedded paper
    /// RVE, said once) for a host without `PNEWDT`, whose `CMNAME` has no length to trust
    /// (Kratos passes one uninitialised byte and no hidden length); else `CMNAME`, up to
    /// [`CMNAME_MAX`] bytes, with bytes outside printable ASCII escaped.
    ///
    /// # Safety
    /// As [`rve_umat`]'s.
    unsafe fn material_name(&self, signal: HostSignal) -> FfiResult<Cow<'_, str>> {
        if let Some(scene) = umat_scene() {
            return Ok(Cow::Borrowed(&scene.name));
        }
        if signal == HostSignal::NanStress {
            note_once(Note::NoScene, || {
                "mesorve UMAT: a host without PNEWDT and no MESORVE_UMAT_SCENE: CMNAME is not \
                 read, every point is the embedded paper RVE (printed once)"
                    .to_string()
            });
            return Ok(Cow::Borrowed(""));
        }
        let name_len = (self.cmname_len as u32 as usize).min(CMNAME_MAX);
        let bytes = slice(self.cmname.cast::<u8>(), name_len, "CMNAME")?;
        Ok(printable(bytes))
    }

    /// Checks and translates the arguments and calls the table; a failure the table saw
    /// is printed (once per reason) and sets `reported`.
    ///
    /// # Safety
    /// As [`rve_umat`]'s.
    unsafe fn call(&self, reported: &mut bool) -> FfiResult {
        let int = |p: *const c_int, name: &str| -> FfiResult<i32> {
            p.as_ref().copied().ok_or_else(|| Failure::null(name))
        };
        let real = |p: *const f64, name: &str| -> FfiResult<f64> {
            p.as_ref().copied().ok_or_else(|| Failure::null(name))
        };
        let hypothesis = Hypothesis::from_abaqus(
            int(self.ndi, "NDI")?,
            int(self.nshr, "NSHR")?,
            int(self.ntens, "NTENS")?,
        )?;
        let n = hypothesis.ntens();
        let count = |p: *const c_int, name: &str| -> FfiResult<usize> {
            Ok(usize::try_from(int(p, name)?).unwrap_or(0))
        };
        let (nstatv, nprops) = (count(self.nstatv, "NSTATV")?, count(self.nprops, "NPROPS")?);
        let signal = if self.pnewdt.is_null() {
            HostSignal::NanStress
        } else {
            HostSignal::Pnewdt
        };
        let name = self.material_name(signal)?;
        let time = match signal {
            HostSignal::Pnewdt => {
                let t = slice(self.time, 2, "TIME")?;
                [t[0], t[1]]
            }
            // One value: TIME(2) is not read (HostSignal::NanStress).
            HostSignal::NanStress => [real(self.time, "TIME")?; 2],
        };
        let mut no_pnewdt = 0.0;
        let pnewdt = self.pnewdt.as_mut().unwrap_or(&mut no_pnewdt);
        let call = UmatCall {
            cmname: &name,
            props: if nprops == 0 {
                &[]
            } else {
                slice(self.props, nprops, "PROPS")?
            },
            hypothesis,
            stran: slice(self.stran, n, "STRAN")?,
            dstran: slice(self.dstran, n, "DSTRAN")?,
            time: [time[0], time[1]],
            dtime: real(self.dtime, "DTIME")?,
            noel: int(self.noel, "NOEL")?,
            npt: int(self.npt, "NPT")?,
            kstep: int(self.kstep, "KSTEP")?,
            kinc: int(self.kinc, "KINC")?,
        };
        let mut outputs = UmatOutputs {
            stress: slice_mut(self.stress, n, "STRESS")?,
            ddsdde: slice_mut(self.ddsdde, n * n, "DDSDDE")?,
            statev: if nstatv == 0 {
                &mut []
            } else {
                slice_mut(self.statev, nstatv, "STATEV")?
            },
            pnewdt,
        };
        global()
            .call_as(&call, &mut outputs, signal)
            .map(|_| ())
            .map_err(|f| {
                *reported = true;
                if f.first_report {
                    failure_once(&f.error.to_string(), &format!("mesorve UMAT: {f}"));
                }
                Failure {
                    status: RveStatus::from(&*f.error),
                    message: f.to_string(),
                    step_ratio: Some(f.pnewdt),
                }
            })
    }
}

/// The UMAT of the RVE, with the Abaqus argument list (every argument by reference, as
/// Fortran passes it, then the hidden length of `CMNAME`). See the README, "Use it from
/// an FE code", for the rules; in short:
/// - `NTENS` 3 (`NDI` 2, `NSHR` 1: plane stress `[11, 22, 12]`), 4 (`NDI` 3, `NSHR` 1:
///   plane strain `[11, 22, 33, 12]`) or 6 (`NDI` 3, `NSHR` 3: a 3D element held in
///   plane strain), engineering shear; out-of-plane strains must be zero;
/// - the environment variable `MESORVE_UMAT_SCENE`, when set (a scene file's path, or a
///   scene name searched as below), names the scene of every call, and `CMNAME` is not
///   read; without it, a host that passes a NULL `PNEWDT` gets the embedded paper RVE
///   (its `CMNAME` is not read either: Kratos passes one byte and no hidden length);
/// - otherwise `CMNAME` names the scene: `<SCENE>[@TAG]`, or `@ABAQUS_<LIB>_<FUNC>@<SCENE>[@TAG]`
///   for CalculiX; `<SCENE>.toml` (or its lower-case name) is searched in the directories
///   of `MESORVE_SCENE_PATH` (`:`-separated; default: the working directory); no scene
///   name is the embedded paper RVE;
/// - `PROPS(1..5)` override `materials.itz.sigma_c`, `materials.itz.delta_c`,
///   `geometry.seed`, `materials.matrix.young`, `materials.aggregate.young` when non-zero;
///   `PROPS(6)` = 1 returns the elastic tangent instead of the consistent one;
/// - the state: with `NSTATV` >= the scene's `umat_nstatv` (`rve info`), the point's
///   RVE state is `STATEV(1..umat_nstatv)`, read at every call and written with the
///   trial (integers below 2^48 with a checksum; all zeros: virgin), and the host owns
///   it; `STATEV(umat_nstatv+1..+5)` get the mirrors (point id, RVE iterations,
///   sub-steps, damage, largest ITZ opening). With a smaller `NSTATV` the state lives in
///   the library per (`NOEL`,
///   `NPT`): a new increment (`KSTEP`/`KINC` changed or `TIME(2)` advanced) commits the
///   last trial, a cut-back (same increment after a failure or with a smaller `DTIME`)
///   reverts, `KSTEP`/`TIME(2)` going back restarts the point from virgin, and
///   `STATEV(1..5)` get the mirrors;
/// - outputs: `STRESS`, `DDSDDE` (`NTENS` x `NTENS`, column-major), `STATEV`; on failure
///   (a corrupted `STATEV` among the reasons) `DDSDDE` the elastic tangent of the
///   material's virgin RVE (of the embedded paper RVE when the material is unknown),
///   `PNEWDT` < 1, a message in `rve_last_error`, `STRESS` untouched, and a line on
///   stderr the first time the process meets the reason (the material and the error's
///   text up to its numbers: a layout the RVE cannot answer prints one line, not one per
///   point);
/// - a NULL `PNEWDT` (Kratos) is a host that hears of failures and step requests by NaN
///   in `STRESS`: then `TIME` is one value (`TIME(2)` is not read), table mode is refused,
///   and a failure or a `PNEWDT` < 1 it would have got fills `STRESS(1:NTENS)` with NaN.
///
/// `SSE`, `SPD`, `SCD`, `RPL`, `DDSDDT`, `DRPLDE`, `DRPLDT` are not written; `TEMP`,
/// `DTEMP`, `PREDEF`, `DPRED`, `COORDS`, `DROT`, `CELENT`, `DFGRD0`, `DFGRD1`, `LAYER`,
/// `KSPT` are not read. Only the low 32 bits of `cmname_len` are used (gfortran passes
/// a `size_t`, CalculiX's C caller an `int`), and at most 80 characters. Distinct points
/// may be called from several threads at once.
///
/// # Safety
/// Each pointer the call reads or writes must be valid for the documented length:
/// `STRESS`, `STRAN`, `DSTRAN` (`NTENS`), `DDSDDE` (`NTENS^2`), `STATEV` (`NSTATV`),
/// `PROPS` (`NPROPS`), `TIME` (2; 1 when `PNEWDT` is NULL), `CMNAME` (`cmname_len`
/// bytes, at most 80 read; not read when `MESORVE_UMAT_SCENE` is set or `PNEWDT` is NULL),
/// the scalars; a NULL one fails the call. The arguments listed as not read may be NULL.
// Also exported as `umat_` and `UMAT`, the names hosts look up, kept out of the header (a
// C host declares the Abaqus prototype itself): the parameters are written once, here.
#[allow(clippy::too_many_arguments)]
#[mesorve_macros::aliases(umat_, UMAT)]
#[no_mangle]
pub unsafe extern "C" fn rve_umat(
    stress: *mut f64,
    statev: *mut f64,
    ddsdde: *mut f64,
    sse: *mut f64,
    spd: *mut f64,
    scd: *mut f64,
    rpl: *mut f64,
    ddsddt: *mut f64,
    drplde: *mut f64,
    drpldt: *mut f64,
    stran: *const f64,
    dstran: *const f64,
    time: *const f64,
    dtime: *const f64,
    temp: *const f64,
    dtemp: *const f64,
    predef: *const f64,
    dpred: *const f64,
    cmname: *const c_char,
    ndi: *const c_int,
    nshr: *const c_int,
    ntens: *const c_int,
    nstatv: *const c_int,
    props: *const f64,
    nprops: *const c_int,
    coords: *const f64,
    drot: *const f64,
    pnewdt: *mut f64,
    celent: *const f64,
    dfgrd0: *const f64,
    dfgrd1: *const f64,
    noel: *const c_int,
    npt: *const c_int,
    layer: *const c_int,
    kspt: *const c_int,
    kstep: *const c_int,
    kinc: *const c_int,
    cmname_len: usize,
) {
    let _unused = (
        sse, spd, scd, rpl, ddsddt, drplde, drpldt, temp, dtemp, predef, dpred,
    );
    let _unused = (coords, drot, celent, dfgrd0, dfgrd1, layer, kspt);
    let args = Args {
        stress,
        statev,
        ddsdde,
        stran,
        dstran,
        time,
        dtime,
        cmname,
        cmname_len,
        ndi,
        nshr,
        ntens,
        nstatv,
        props,
        nprops,
        pnewdt,
        noel,
        npt,
        kstep,
        kinc,
    };
    let mut reported = false;
    let status = guard("rve_umat", || args.call(&mut reported));
    if status != RveStatus::Ok && !reported {
        // Failed before the table saw the call (bad NTENS, a NULL argument, a panic).
        let message = super::last_error_message();
        failure_once(&message, &format!("mesorve UMAT: {message}"));
        match pnewdt.as_mut() {
            Some(p) => request_step_ratio(p, FAILURE_STEP_RATIO),
            None => nan_stress(stress, ntens),
        }
    }
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

//! The Abaqus UMAT entry point: `rve_umat`, and the same function under the names hosts
//! look up, `umat_` (gfortran's name for `CALL UMAT(...)`; MOOSE, OpenSees) and `UMAT`
//! (CalculiX, which upper-cases the function name of `@ABAQUS_<LIB>_<FUNC>`). Only
//! pointer translation here; the logic is `crate::host::umat`.

use std::collections::HashSet;
use std::ffi::{c_char, c_int};
use std::io::Write;
use std::sync::{LazyLock, Mutex, PoisonError};

use super::boundary::{guard, slice, slice_mut, Failure, FfiResult};
use super::status::RveStatus;
use crate::host::umat::{
    global, request_step_ratio, umat_scene, HostSignal, UmatCall, UmatOutputs, FAILURE_STEP_RATIO,
};
use crate::host::Hypothesis;

/// CMNAME is `CHARACTER*80` in Abaqus: no more is read.
const CMNAME_MAX: usize = 80;

/// The failure reasons printed on stderr by this process (see [`reason_key`]): a host
/// calls the UMAT at every point of every element, and an element type the RVE cannot
/// answer (a plane-stress element on a plane-strain scene, an axisymmetric one) fails at
/// each of them for one reason, which is printed once.
static PRINTED: LazyLock<Mutex<HashSet<String>>> = LazyLock::new(|| Mutex::new(HashSet::new()));

/// What stands after the first line of a reason.
const PRINTED_ONCE: &str =
    "(printed once per process for this reason; rve_last_error has each call's message)";

/// `text` with every number replaced by `#`: a run of digits that does not continue a
/// word (`gamma_13`, `E33` and `NTENS` stay), with its sign, decimals and exponent
/// (`-1.5e-5`, `0.25`, `4`). What the same reason at another point or strain shares.
fn mask_numbers(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let word = |i: usize| i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_');
    let digit = |i: usize| c.get(i).is_some_and(char::is_ascii_digit);
    let digits_from = |mut i: usize| {
        while digit(i) {
            i += 1;
        }
        i
    };
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < c.len() {
        let signed = matches!(c[i], '-' | '+') && digit(i + 1);
        if !(digit(i) || signed) || word(i) {
            out.push(c[i]);
            i += 1;
            continue;
        }
        i = digits_from(i + usize::from(signed));
        if c.get(i) == Some(&'.') && digit(i + 1) {
            i = digits_from(i + 1);
        }
        if matches!(c.get(i), Some('e' | 'E')) {
            let sign = usize::from(matches!(c.get(i + 1), Some('-' | '+')));
            if digit(i + 1 + sign) {
                i = digits_from(i + 1 + sign);
            }
        }
        out.push('#');
    }
    out
}

/// `text` with each span between backquotes (a material or scene name, a path: the
/// host's arguments as messages quote them) replaced by `#`.
fn mask_quoted(text: &str) -> String {
    text.split('`')
        .enumerate()
        .map(|(i, part)| if i % 2 == 1 { "#" } else { part })
        .collect::<Vec<_>>()
        .join("`")
}

/// The key a failure is printed once under: the error's text with its quoted names and
/// its numbers masked, so a reason is printed once whatever the arguments (the material,
/// the strain, PNEWDT, the element and point numbers); the line itself names them.
fn reason_key(reason: &str) -> String {
    mask_numbers(&mask_quoted(reason))
}

/// Writes `line` (and the note that it is printed once) to `out` when `seen` does not
/// hold the reason yet, and remembers it; returns whether it wrote. Write errors are
/// ignored (stderr closed: nothing to tell).
fn report_once(seen: &mut HashSet<String>, reason: &str, line: &str, out: &mut dyn Write) -> bool {
    if !seen.insert(reason_key(reason)) {
        return false;
    }
    let _ = writeln!(out, "{line} {PRINTED_ONCE}");
    true
}

/// [`report_once`] on stderr with the process's [`PRINTED`] reasons. Never unwinds (it
/// also runs outside the panic boundary).
fn print_once(reason: &str, line: &str) {
    let _ = std::panic::catch_unwind(|| {
        let mut seen = PRINTED.lock().unwrap_or_else(PoisonError::into_inner);
        report_once(&mut seen, reason, line, &mut std::io::stderr());
    });
}

/// Said once: a host without `PNEWDT` and without `MESORVE_UMAT_SCENE`.
static NO_SCENE_NOTE: std::sync::Once = std::sync::Once::new();

/// A host's bytes as text that is safe to print: up to the first NUL, printable ASCII
/// kept, any other byte as `\xNN`.
fn printable(bytes: &[u8]) -> String {
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    bytes[..end]
        .iter()
        .map(|&b| match b {
            b' '..=b'~' => char::from(b).to_string(),
            _ => format!("\\x{b:02x}"),
        })
        .collect()
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
    unsafe fn material_name(&self, signal: HostSignal) -> FfiResult<String> {
        if let Some(scene) = umat_scene() {
            return Ok(scene.name.clone());
        }
        if signal == HostSignal::NanStress {
            NO_SCENE_NOTE.call_once(|| {
                eprintln!(
                    "mesorve UMAT: a host without PNEWDT and no MESORVE_UMAT_SCENE: CMNAME is \
                     not read, every point is the embedded paper RVE (printed once)"
                )
            });
            return Ok(String::new());
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
                    print_once(&f.error.to_string(), &format!("mesorve UMAT: {f}"));
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
#[allow(clippy::too_many_arguments)]
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
        print_once(&message, &format!("mesorve UMAT: {message}"));
        match pnewdt.as_mut() {
            Some(p) => request_step_ratio(p, FAILURE_STEP_RATIO),
            None => nan_stress(stress, ntens),
        }
    }
}

/// `umat_` and `UMAT`: `rve_umat` under the names hosts look up (kept out of the header:
/// a C host declares the Abaqus prototype itself).
macro_rules! umat_alias {
    ($name:ident) => {
        #[allow(clippy::too_many_arguments, non_snake_case)]
        #[no_mangle]
        pub unsafe extern "C" fn $name(
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
            rve_umat(
                stress, statev, ddsdde, sse, spd, scd, rpl, ddsddt, drplde, drpldt, stran, dstran,
                time, dtime, temp, dtemp, predef, dpred, cmname, ndi, nshr, ntens, nstatv, props,
                nprops, coords, drot, pnewdt, celent, dfgrd0, dfgrd1, noel, npt, layer, kspt,
                kstep, kinc, cmname_len,
            )
        }
    };
}

umat_alias!(umat_);
umat_alias!(UMAT);

#[cfg(test)]
mod tests {
    use super::*;

    /// Numbers go, names with digits stay.
    #[test]
    fn numbers_are_masked_words_are_not() {
        assert_eq!(
            mask_numbers("E33 = -1.5e-5 (strain component 3 of NTENS = 4), gamma_13 0.25"),
            "E33 = # (strain component # of NTENS = #), gamma_13 #"
        );
        assert_eq!(mask_numbers("the 2D RVE, 1e+3, x-1"), "the #D RVE, #, x-#");
    }

    /// Two points failing for the same reason (at other strains, for other materials or
    /// names) print one line; another reason prints its own.
    #[test]
    fn a_reason_is_printed_once() {
        let why = |e: f64| {
            format!(
                "host convention: E33 = {e:e} (strain component 3 of NTENS = 4): the 2D RVE \
                 holds the out-of-plane strains at zero"
            )
        };
        let missing = |name: &str| format!("scene `{name}` not found (searched `./{name}.toml`)");
        let calls = [
            ("CONCRETE", why(1.2e-5), 1, 1),
            ("CONCRETE", why(-3.4e-6), 7, 4),
            ("CONCRETE", "host convention: NTENS = 5".to_string(), 7, 4),
            ("CONCRETE2", why(1.2e-5), 9, 1),
            ("CONCRETE", why(5e-7), 300, 2),
            ("\\x9c\\x01", missing("\\x9c\\x01"), 0, 0),
            ("\\x13", missing("\\x13"), 0, 0),
        ];
        let (mut seen, mut out) = (HashSet::new(), Vec::new());
        let printed: Vec<bool> = calls
            .iter()
            .map(|(material, reason, noel, npt)| {
                let line =
                    format!("mesorve UMAT: element {noel}, point {npt}, `{material}`: {reason}");
                report_once(&mut seen, reason, &line, &mut out)
            })
            .collect();
        assert_eq!(printed, [true, false, true, false, false, true, false]);
        let text = String::from_utf8(out).unwrap();
        assert_eq!(text.lines().count(), 3);
        assert!(text.starts_with(
            "mesorve UMAT: element 1, point 1, `CONCRETE`: host convention: E33 = 1.2e-5"
        ));
        assert!(text.lines().all(|l| l.ends_with(PRINTED_ONCE)));
    }

    /// A host's bytes print as printable ASCII, up to the first NUL.
    #[test]
    fn host_bytes_are_escaped() {
        assert_eq!(printable(b"CONCRETE  "), "CONCRETE  ");
        assert_eq!(printable(b"A\x9c\n\x1b[2J"), "A\\x9c\\x0a\\x1b[2J");
        assert_eq!(printable(b"AB\0garbage\xff"), "AB");
        assert!(printable(&[0x80, 0xfe, 0x07])
            .chars()
            .all(|c| c.is_ascii_graphic()));
    }
}

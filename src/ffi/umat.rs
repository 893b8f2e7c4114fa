//! The Abaqus UMAT entry point: `rve_umat`, and the same function under the names hosts
//! look up, `umat_` (gfortran's name for `CALL UMAT(...)`; MOOSE, OpenSees) and `UMAT`
//! (CalculiX, which upper-cases the function name of `@ABAQUS_<LIB>_<FUNC>`). Only
//! pointer translation here; the logic is `crate::host::umat`.

use std::ffi::{c_char, c_int};

use super::boundary::{guard, slice, slice_mut, Failure, FfiResult};
use super::status::RveStatus;
use crate::host::umat::{global, UmatCall, UmatOutputs, FAILURE_STEP_RATIO};
use crate::host::Hypothesis;

/// CMNAME is `CHARACTER*80` in Abaqus: no more is read.
const CMNAME_MAX: usize = 80;

/// The UMAT of the RVE, with the Abaqus argument list (every argument by reference, as
/// Fortran passes it, then the hidden length of `CMNAME`). See the README, "Use it from
/// an FE code", for the rules; in short:
/// - `NTENS` 3 (`NDI` 2, `NSHR` 1: plane stress `[11, 22, 12]`), 4 (`NDI` 3, `NSHR` 1:
///   plane strain `[11, 22, 33, 12]`) or 6 (`NDI` 3, `NSHR` 3: a 3D element held in
///   plane strain), engineering shear; out-of-plane strains must be zero;
/// - `CMNAME` names the scene: `<SCENE>[@TAG]`, or `@ABAQUS_<LIB>_<FUNC>@<SCENE>[@TAG]`
///   for CalculiX; `<SCENE>.toml` (or its lower-case name) is searched in the directories
///   of `MESORVE_SCENE_PATH` (`:`-separated; default: the working directory); no scene
///   name is the embedded paper RVE;
/// - `PROPS(1..5)` override `materials.itz.sigma_c`, `materials.itz.delta_c`,
///   `geometry.seed`, `materials.matrix.young`, `materials.aggregate.young` when non-zero;
///   `PROPS(6)` = 1 returns the elastic tangent instead of the consistent one;
/// - instances live in the library per (`NOEL`, `NPT`); a new increment (`KSTEP`/`KINC`
///   changed or `TIME(2)` advanced) commits the last trial, a cut-back (same increment
///   after a failure or with a smaller `DTIME`) reverts;
/// - outputs: `STRESS`, `DDSDDE` (`NTENS` x `NTENS`, column-major), `STATEV(1..3)` when
///   `NSTATV` allows (point id, RVE iterations, sub-steps; never read back); on failure
///   `PNEWDT` < 1, a message on stderr and in `rve_last_error`, `STRESS` untouched.
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
/// `PROPS` (`NPROPS`), `TIME` (2), `CMNAME` (`cmname_len` bytes, at most 80 read), the
/// scalars; a NULL one fails the call (`PNEWDT` set when it is not NULL itself).
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
    let mut reported = false;
    let status = guard("rve_umat", || {
        let int = |p: *const c_int, name: &str| -> FfiResult<i32> {
            p.as_ref().copied().ok_or_else(|| Failure::null(name))
        };
        let real = |p: *const f64, name: &str| -> FfiResult<f64> {
            p.as_ref().copied().ok_or_else(|| Failure::null(name))
        };
        let hypothesis =
            Hypothesis::from_abaqus(int(ndi, "NDI")?, int(nshr, "NSHR")?, int(ntens, "NTENS")?)?;
        let n = hypothesis.ntens();
        let count = |p: *const c_int, name: &str| -> FfiResult<usize> {
            Ok(usize::try_from(int(p, name)?).unwrap_or(0))
        };
        let (nstatv, nprops) = (count(nstatv, "NSTATV")?, count(nprops, "NPROPS")?);
        let name_len = (cmname_len as u32 as usize).min(CMNAME_MAX);
        let name = String::from_utf8_lossy(slice(cmname.cast::<u8>(), name_len, "CMNAME")?);
        let time = slice(time, 2, "TIME")?;
        let pnewdt = pnewdt.as_mut().ok_or_else(|| Failure::null("PNEWDT"))?;
        let call = UmatCall {
            cmname: &name,
            props: if nprops == 0 {
                &[]
            } else {
                slice(props, nprops, "PROPS")?
            },
            hypothesis,
            stran: slice(stran, n, "STRAN")?,
            dstran: slice(dstran, n, "DSTRAN")?,
            time: [time[0], time[1]],
            dtime: real(dtime, "DTIME")?,
            noel: int(noel, "NOEL")?,
            npt: int(npt, "NPT")?,
            kstep: int(kstep, "KSTEP")?,
            kinc: int(kinc, "KINC")?,
        };
        let mut outputs = UmatOutputs {
            stress: slice_mut(stress, n, "STRESS")?,
            ddsdde: slice_mut(ddsdde, n * n, "DDSDDE")?,
            statev: if nstatv == 0 {
                &mut []
            } else {
                slice_mut(statev, nstatv, "STATEV")?
            },
            pnewdt,
        };
        global().call(&call, &mut outputs).map(|_| ()).map_err(|f| {
            reported = true;
            if f.first_report {
                eprintln!("mesorve UMAT: {f}");
            }
            Failure {
                status: RveStatus::from(&*f.error),
                message: f.to_string(),
                step_ratio: Some(f.pnewdt),
            }
        })
    });
    if status != RveStatus::Ok && !reported {
        // Failed before the table saw the call (bad NTENS, a NULL argument, a panic).
        eprintln!("mesorve UMAT: {}", super::last_error_message());
        if let Some(p) = pnewdt.as_mut() {
            *p = FAILURE_STEP_RATIO;
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

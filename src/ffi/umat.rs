//! The Abaqus UMAT entry point: `rve_umat`, and the same function under the names hosts
//! look up, `umat_` (gfortran's name for `CALL UMAT(...)`; MOOSE, OpenSees) and `UMAT`
//! (CalculiX, which upper-cases the function name of `@ABAQUS_<LIB>_<FUNC>`). Only
//! pointer translation here: each argument read into a value or a slice (`None` for a
//! NULL pointer), the arrays at the lengths `crate::host::umat::answer_host` asks for;
//! which arguments are read, and every rule of the call, are there.

use std::ffi::{c_char, c_int};

use super::guard::{guard, Failure};
use super::status::RveStatus;
use crate::host::umat::{answer_host, HostArrays, HostCall, HostError, HostLengths, HostScalars};

/// `n` values at `p`; `None` when `p` is NULL. Nothing is read at `p` for `n` = 0 (an
/// array of no entries, which a host may pass unaligned).
///
/// # Safety
/// A non-NULL `p` must point to `n` values readable for `'a`.
unsafe fn read<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    match (p.is_null(), n) {
        (true, _) => None,
        (false, 0) => Some(&[]),
        _ => Some(std::slice::from_raw_parts(p, n)),
    }
}

/// `n` writable values at `p`; `None` when `p` is NULL (as [`read`]).
///
/// # Safety
/// A non-NULL `p` must point to `n` values writable for `'a` and not aliased.
unsafe fn write<'a>(p: *mut f64, n: usize) -> Option<&'a mut [f64]> {
    match (p.is_null(), n) {
        (true, _) => None,
        (false, 0) => Some(&mut []),
        _ => Some(std::slice::from_raw_parts_mut(p, n)),
    }
}

impl From<HostError> for Failure {
    fn from(e: HostError) -> Self {
        match e {
            HostError::Null(name) => Failure::null(name),
            HostError::Refused(error) => error.into(),
            HostError::Failed(f) => Failure::new(RveStatus::from(&*f.error), f.to_string()),
            HostError::Panic(message) => Failure::new(RveStatus::Panic, message),
        }
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
/// `DTEMP`, `PREDEF`, `DPRED`, `COORDS`, `DROT`, `DFGRD0`, `DFGRD1`, `LAYER`, `KSPT` are
/// not read; `CELENT` (NULL: none) only by a scene with `effects.regularization` whose
/// `PROPS(7)` is 0. Only the low 32 bits of `cmname_len` are used (gfortran passes
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
    let _unused = (coords, drot, dfgrd0, dfgrd1, layer, kspt);
    let int = |p: *const c_int| p.as_ref().copied();
    let scalars = HostScalars {
        ndi: int(ndi),
        nshr: int(nshr),
        ntens: int(ntens),
        nstatv: int(nstatv),
        nprops: int(nprops),
        noel: int(noel),
        npt: int(npt),
        kstep: int(kstep),
        kinc: int(kinc),
        dtime: dtime.as_ref().copied(),
        celent: celent.as_ref().copied(),
        // The low 32 bits: gfortran passes a `size_t`, CalculiX's C caller an `int`.
        cmname_len: cmname_len as u32 as usize,
    };
    let arrays = move |n: HostLengths| HostArrays {
        cmname: n.cmname.and_then(|len| read(cmname.cast::<u8>(), len)),
        time: read(time, n.time),
        props: read(props, n.props),
        stran: read(stran, n.strain),
        dstran: read(dstran, n.strain),
        stress: write(stress, n.stress),
        ddsdde: write(ddsdde, n.ddsdde),
        statev: write(statev, n.statev),
    };
    let call = HostCall {
        scalars,
        pnewdt: pnewdt.as_mut(),
        arrays,
    };
    guard("rve_umat", || answer_host(call).map_err(Failure::from));
}

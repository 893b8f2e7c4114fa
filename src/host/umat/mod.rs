//! The standard Abaqus UMAT, safe side: a table of RVE instances keyed by (element,
//! integration point) that follows the host's increments. `crate::ffi` exports it with
//! the Abaqus argument list (`rve_umat`, `umat_`, `UMAT`) and only translates pointers:
//! [`answer_host`] takes the call from there and holds every rule of the C seam.
//!
//! **Two modes, chosen per call by `NSTATV`.**
//! - **`STATEV` mode** (`NSTATV` >= the model's
//!   [`Model::statev_len`](crate::Model::statev_len), which `rve info` prints as
//!   `umat_nstatv`; the recommended mode). The point's committed RVE state is
//!   `STATEV(1:umat_nstatv)`: its core (strain, interface history, contact status,
//!   IMPL-EX's data) as integer-valued doubles with a checksum (`statev`); all zeros is a
//!   virgin RVE. Each call solves from the state `STATEV` holds, at the total strain
//!   `STRAN + DSTRAN` and the time increment `DTIME`, and writes the trial's core back.
//!   The host keeps the values of the converged increment, hands the start-of-increment values at
//!   every call (as Abaqus/Standard and CalculiX do), writes them to its restart files and
//!   zeroes them for new elements and new analyses: there is no commit or revert rule to
//!   guess. The answer is a function of `STATEV`, the strain and `DTIME` alone; the library
//!   only caches the state the values stand for (rebuilt by
//!   [`Model::expand_core`](crate::Model::expand_core), one factorization, when the cache
//!   does not hold them), and a call that repeats one (the same values, strain and `DTIME`:
//!   a host's stress call, then its tangent call) is answered without solving again. A host
//!   that passes `PNEWDT` (CalculiX, Abaqus) numbers its points, and the cache is its
//!   table's point `(NOEL, NPT)`: one rebuild per point and increment. A host that does not
//!   (Kratos, every point 0) is keyed on nothing but the values: each thread keeps a few
//!   instances per material (`slots.rs`) and takes the one
//!   that holds them, so no point shares or waits for another.
//!   `STATEV(umat_nstatv+1..+5)` receive the inspection mirrors below. A `STATEV` that is
//!   not exactly what the library wrote (flipped bits, a changed, zeroed or truncated
//!   entry, another model's state) fails the call with a message, and so does a valid state
//!   that is not this point's at this increment: written under another fingerprint (scene
//!   after `PROPS`, Gmsh file, integration:
//!   [`Error::StateOwner`](crate::Error::StateOwner)), committed at another strain than
//!   `STRAN` (another point's, a stale one, an element re-added with its old state:
//!   [`Error::StateStrain`](crate::Error::StateStrain)), or all zeros at a strained point
//!   (a lost state: [`Error::StateLost`](crate::Error::StateLost)); the scene's `[statev]`
//!   table relaxes the last two for hosts that need it.
//! - **Table mode** (`NSTATV` up to [`TABLE_MODE_MAX_NSTATV`]; printed once on stderr;
//!   an `NSTATV` between that and `umat_nstatv` is refused). The RVE state lives in
//!   the process's table keyed by `(NOEL, NPT)`, and the increments are inferred from
//!   `(KSTEP, KINC, TIME(2))` as described next. A restart, a second analysis or a
//!   re-added element then does not carry the state; a point whose `KSTEP` or `TIME(2)`
//!   goes back (a new analysis in the process) restarts from a virgin RVE, said once.
//!
//! **Instances (table mode).** The first call for `(NOEL, NPT)` resolves the material
//! (`CMNAME` and `PROPS`, see [`super::material`]) and creates a virgin instance of its
//! model; the instance lives in the table until the process ends. When `NSTATV` allows,
//! the mirrors (`STATEV(1:5)` in table mode, after the state in `STATEV` mode) receive the
//! point's id in the table (1, 2, ... in creation order; for a host without `PNEWDT` the
//! id of the thread's instance that answered, which identifies no point), the RVE's
//! Newton iterations, its sub-steps, its damage and its largest ITZ opening
//! ([`super::mirrors`]), for inspection; the library never reads them.
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
//! left as it came, and [`UmatFailure`] says what went wrong; [`answer_host`] returns it
//! for `rve_last_error` and says it on stderr once per reason ([`super::diagnostics`]).
//!
//! **Threads.** Distinct points may be called from several threads at once (each thread
//! keeps one workspace per model; a numbering host's points are found in a map split in
//! shards, and a point that knows its material answers without the table's lock on
//! materials; a host without `PNEWDT` gets its own thread's instances). One point from two
//! threads at once is refused with `Error::HostConvention` (a host never does that within
//! an increment).
//!
//! **Hosts without `PNEWDT`** ([`HostSignal::NanStress`], Kratos): a failure or a request
//! for a smaller step comes back as NaN in `STRESS`; `TIME` is one value (`TIME(2)` is not
//! read: the state records no time and the `[statev]` time check is off); table mode is
//! refused.
//!
//! **Files.** Each file imports only the ones listed before it:
//! - `call.rs`: the call and its answer ([`UmatCall`], [`UmatOutputs`], [`Outcome`],
//!   [`UmatFailure`], [`HostSignal`], [`UmatStats`]), a failure before it is reported,
//!   and the table's books (counters, point ids, the VTK switch);
//! - `point.rs`: one point as both modes keep it (its material as the host names it, its
//!   instance, the outputs it writes) and the points by `(NOEL, NPT)`, a map in shards;
//! - `statev_checks.rs`: `STATEV` mode's checks that the values are this point's at this
//!   increment;
//! - `statev_point.rs`: a `STATEV`-mode point, which values its instance stands for;
//! - `slots.rs`: the `STATEV`-mode points of a host without `PNEWDT`, per thread;
//! - `statev_mode.rs` and `table_mode.rs`: the two modes, one type each (`StatevMode`,
//!   `TableMode` with its `TablePoint`); neither uses the other;
//! - `dispatch.rs`: the table, [`Umat`]: its materials, [`Umat::call_as`], which picks
//!   the mode, and what a host hears of a failure;
//! - `host_call.rs`: [`answer_host`], the entry of the exported C functions: what is read
//!   of a C call, the scene choice, host quirks, messages; the process's table
//!   ([`global`]).

mod call;
mod dispatch;
mod host_call;
mod point;
mod slots;
mod statev_checks;
mod statev_mode;
mod statev_point;
mod table_mode;

pub use call::{
    request_step_ratio, HostSignal, Outcome, UmatCall, UmatFailure, UmatOutputs, UmatStats,
};
pub use dispatch::{Umat, FAILURE_STEP_RATIO, TABLE_MODE_MAX_NSTATV};
pub use host_call::{
    answer_host, global, umat_scene, HostArrays, HostCall, HostError, HostLengths, HostScalars,
};
pub use statev_checks::{strain_mismatch, STRAIN_MATCH_FLOOR, STRAIN_MATCH_RELATIVE};
pub use table_mode::note_ignored_redo;

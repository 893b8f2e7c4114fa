//! The entry of a UMAT call: checks the lengths, resolves the material and picks the
//! mode by `NSTATV` ([`in_statev_mode`]); the modes themselves are `statev_mode.rs` and
//! `table_mode.rs`.

use std::sync::atomic::Ordering;

use super::call::{trim, HostSignal, Outcome, UmatCall, UmatFailure, UmatOutputs};
use super::statev_mode::slot_material;
use super::table::{plain, Failed, Umat};
use super::table_mode::table_refused;
use crate::error::Error;
use crate::host::mirrors::MIRRORS;
use mesorve_core::solver::Integration;

/// `NSTATV` up to this keeps the state in the library's table (room for the mirrors).
pub const TABLE_MODE_MAX_NSTATV: usize = MIRRORS;

impl Umat {
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

    /// The call in the mode its `NSTATV` picks, its failure not yet reported.
    fn call_inner(
        &self,
        c: &UmatCall,
        out: &mut UmatOutputs,
        signal: HostSignal,
    ) -> Result<Outcome, Failed> {
        check_lengths(c, out).map_err(plain)?;
        check_dtime(c, None).map_err(plain)?;
        let material = match slot_material(self.id, c) {
            Some(m) => m,
            None => self.material(c).map_err(Failed::unresolved)?,
        };
        let with_material = Failed::of(&material);
        check_dtime(c, Some(material.model.solver.integration)).map_err(with_material)?;
        let statev_len = material.model.statev_len();
        if in_statev_mode(c, out.statev.len(), statev_len).map_err(with_material)? {
            return self.statev_call(c, out, material, signal);
        }
        if signal == HostSignal::NanStress {
            return Err(with_material(table_refused(out.statev.len(), statev_len)));
        }
        self.table_call(c, out)
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

/// `STATEV` mode (true) or table mode (false) for a call with `nstatv` entries when the
/// state needs `needed`: `STATEV` mode from `needed` on, table mode up to
/// [`TABLE_MODE_MAX_NSTATV`] (room for the mirrors only, the 0.1-0.3 decks' rule for the
/// table), an error naming the count in between (a `*DEPVAR` short of the state, which
/// would otherwise run in the table without a restart or a re-added element carrying it).
fn in_statev_mode(c: &UmatCall, nstatv: usize, needed: usize) -> crate::Result<bool> {
    if nstatv >= needed {
        return Ok(true);
    }
    if nstatv <= TABLE_MODE_MAX_NSTATV {
        return Ok(false);
    }
    Err(Error::HostConvention(format!(
        "NSTATV = {nstatv}: material `{}` keeps its RVE state in STATEV(1:{needed}) (set \
         *DEPVAR to at least {needed}, `rve info`'s umat_nstatv; {} with the {MIRRORS} \
         mirrors); an NSTATV of at most {TABLE_MODE_MAX_NSTATV} keeps the state in the \
         library's table instead",
        trim(c.cmname),
        needed + MIRRORS
    )))
}

//! Table mode: the library keeps the point's state in its table keyed by `(NOEL, NPT)`
//! and follows the host's increments (see the module documentation of
//! [`crate::host::umat`]).

use std::sync::atomic::Ordering;

use super::call::{trim, Outcome, UmatCall, UmatOutputs};
use super::point::{call_strain, lock, Increment, MaterialKey, Point, TIME_ROUNDOFF};
use super::table::{plain, write_outputs, Failed, Umat};
use crate::error::Error;
use crate::host::diagnostics::{note_once, Note};
use crate::host::mirrors::MIRRORS;
use crate::host::vtk_dump;
use crate::model::workspaces::with_workspace;
use crate::model::{share, Model, Response};

/// Table mode asked for by a host without `PNEWDT`
/// ([`HostSignal::NanStress`](super::HostSignal::NanStress)): refused, since such a host
/// (Kratos) gives none of what the table follows: every point is `NOEL` = `NPT` = 0,
/// `KINC` counts Newton iterations, and `TIME` is one value.
pub(super) fn table_refused(nstatv: usize, needed: usize) -> Error {
    Error::HostConvention(format!(
        "NSTATV = {nstatv} asks for the library's table of points, which a host without \
         PNEWDT (NULL, as Kratos passes it) cannot drive: it keys points on NOEL and NPT \
         and increments on KSTEP, KINC and TIME(2), and such a host numbers every point 0 \
         and counts Newton iterations in KINC. Give at least {needed} STATEV entries \
         (`rve info`'s umat_nstatv; {} with the {MIRRORS} mirrors), all zero, to keep the \
         state in STATEV",
        needed + MIRRORS
    ))
}

/// Says once per process that `STATEV` is too short to hold the state, and that a
/// scene's `share_tolerance` is not applied there (sharing is a `STATEV`-mode and batch
/// feature: table points are not looked up against each other).
fn table_note(c: &UmatCall, nstatv: usize, model: &Model) {
    note_once(Note::TableMode, || {
        let needed = model.statev_len();
        format!(
            "mesorve: material `{}`: NSTATV = {nstatv}, the RVE state needs {needed} \
             (*DEPVAR at least `rve info`'s umat_nstatv; {} with the {MIRRORS} mirrors): \
             the state stays in the library's table, which a restart, a second analysis or \
             a re-added element does not carry{} (printed once)",
            trim(c.cmname),
            needed + MIRRORS,
            if share::tolerance(model).is_some() {
                "; the scene's solver.share_tolerance is not applied in table mode (every \
                 point solves its own RVE: give the STATEV room to share)"
            } else {
                ""
            }
        )
    });
}

impl Umat {
    /// Table mode: the point `(NOEL, NPT)` of the process's table, following the
    /// host's increments.
    pub(super) fn table_call(
        &self,
        c: &UmatCall,
        out: &mut UmatOutputs,
    ) -> Result<Outcome, Failed> {
        let point = self.point(c).map_err(Failed::unresolved)?;
        let mut p = lock(&point, c).map_err(plain)?;
        if !p.key.matches(c) {
            self.rebind(&mut p, c)?;
        }
        p.instance.set_lean(false);
        let material = p.material.clone();
        let with_material = Failed::of(&material);
        table_note(c, out.statev.len(), &material.model);
        let inc = Increment {
            kstep: c.kstep,
            kinc: c.kinc,
            start: c.time[1],
        };
        let (committed, reverted) = p.advance(inc, c.dtime).map_err(with_material)?;
        self.commits.fetch_add(committed as u64, Ordering::Relaxed);
        self.reverts.fetch_add(reverted as u64, Ordering::Relaxed);
        let (r, solved) = self.answer(&mut p, c).map_err(|e| {
            p.table.failed = true;
            with_material(e)
        })?;
        write_outputs(&p, c, &r, out, &[], None).map_err(with_material)?;
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
        if let Some((s, r)) = p.table.last {
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
        p.table.last = r.as_ref().ok().map(|r| (strain, *r));
        Ok((r?, true))
    }

    /// A point called with another material than it was created for: a new analysis
    /// (`KSTEP` or `TIME(2)` gone back) makes it a virgin point of the call's material;
    /// otherwise the call is refused. (In `STATEV` mode a point takes the material of
    /// each call: `Umat::statev_call`.)
    fn rebind(&self, p: &mut Point, c: &UmatCall) -> Result<(), Failed> {
        let material = self.material(c).map_err(Failed::unresolved)?;
        let inc = Increment {
            kstep: c.kstep,
            kinc: c.kinc,
            start: c.time[1],
        };
        let new_analysis = p
            .table
            .increment
            .is_some_and(|prev| inc.goes_back_from(&prev));
        if !new_analysis {
            return Err(plain(Error::HostConvention(format!(
                "element {}, point {} was created for material `{}` with other PROPS or \
                 another name; a point keeps its material within an analysis",
                c.noel, c.npt, p.key.cmname
            ))));
        }
        *p = Point::new(p.id, MaterialKey::of(c), material);
        Ok(())
    }
}

impl Point {
    /// Applies the increment protocol before a call of `inc`; returns (committed,
    /// reverted).
    fn advance(&mut self, inc: Increment, dtime: f64) -> crate::Result<(bool, bool)> {
        let (mut committed, mut reverted) = (false, false);
        if let Some(prev) = self.table.increment.filter(|prev| inc.goes_back_from(prev)) {
            // A new analysis (or a restart) in this process: the table cannot know the
            // host's state at this time, so the point starts again from virgin.
            note_once(Note::WentBack, || {
                format!(
                    "mesorve: KSTEP/TIME went back from ({}, {}) to ({}, {}): points of the \
                     library's table restart from virgin RVEs (to carry it, keep the state \
                     in STATEV: *DEPVAR at least `rve info`'s umat_nstatv, + {MIRRORS} for \
                     the mirrors)",
                    prev.kstep, prev.start, inc.kstep, inc.start
                )
            });
            self.instance.reset();
            self.table.last = None;
            self.table.increment = None;
        }
        if let Some(prev) = self.table.increment {
            let advanced =
                inc.start - prev.start > TIME_ROUNDOFF * (prev.start.abs() + self.table.dtime);
            let same = prev.kstep == inc.kstep && prev.kinc == inc.kinc && !advanced;
            if !same {
                if self.table.last.take().is_some() {
                    let ignored = self.instance.ignored_redos().0;
                    self.instance.commit()?;
                    committed = true;
                    if self.instance.ignored_redos().0 > ignored {
                        note_ignored_redo(self.instance.ignored_redos().1);
                    }
                }
            } else if self.table.failed || dtime < self.table.dtime * (1.0 - TIME_ROUNDOFF) {
                self.instance.revert();
                self.table.last = None;
                reverted = true;
            }
        }
        self.table.increment = Some(inc);
        self.table.dtime = dtime;
        self.table.failed = false;
        Ok((committed, reverted))
    }
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

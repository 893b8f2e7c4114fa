//! Table mode ([`TableMode`]): the library keeps the point's state in its table keyed by
//! `(NOEL, NPT)` and follows the host's increments ([`TablePoint`]; see the module
//! documentation of [`crate::host::umat`]).

use std::sync::Arc;

use super::call::{plain, trim, Books, Failed, Outcome, UmatCall, UmatOutputs};
use super::point::{lock, Point, PointMap, TIME_ROUNDOFF};
use crate::error::Error;
use crate::host::diagnostics::{note_once, Note};
use crate::host::material::Material;
use crate::host::mirrors::MIRRORS;
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

/// Table mode of a table: its points by `(NOEL, NPT)`.
pub(super) struct TableMode {
    points: PointMap<TablePoint>,
}

impl TableMode {
    pub(super) fn new() -> Self {
        TableMode {
            points: PointMap::new(),
        }
    }

    /// Points in the table.
    pub(super) fn points(&self) -> usize {
        self.points.len()
    }

    /// A call whose point exists, is free and was last called with the call's material
    /// (name and `PROPS`, compared in place), when `in_mode` (the table's choice of mode
    /// for that material) says table mode: answered without resolving the material (as
    /// [`StatevMode::answer_held`](super::statev_mode::StatevMode::answer_held)). `None`:
    /// the call goes the general way.
    pub(super) fn answer_held(
        &self,
        books: &Books,
        c: &UmatCall,
        out: &mut UmatOutputs,
        in_mode: impl FnOnce(&Arc<Material>, usize) -> Result<bool, Failed>,
    ) -> Option<Result<Outcome, Failed>> {
        let point = self.points.get(c)?;
        let mut p = point.try_lock().ok()?;
        if !p.point.key.matches(c) {
            return None;
        }
        match in_mode(&p.point.material, out.statev.len()) {
            Ok(true) => None,
            Ok(false) => Some(p.answer_point(books, c, out)),
            Err(f) => Some(Err(f)),
        }
    }

    /// A call of `material`: the point `(NOEL, NPT)`, made for it on its first call.
    pub(super) fn call(
        &self,
        books: &Books,
        c: &UmatCall,
        out: &mut UmatOutputs,
        material: Arc<Material>,
    ) -> Result<Outcome, Failed> {
        let point =
            (self.points).get_or_insert(c, || TablePoint::new(books.new_id(), c, material.clone()));
        let mut p = lock(&point, c, TablePoint::recover).map_err(plain)?;
        if !p.point.key.matches(c) {
            p.rebind(c, material)?;
        }
        p.answer_point(books, c, out)
    }
}

/// The increment a call belongs to.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Increment {
    kstep: i32,
    kinc: i32,
    /// `TIME(2)`.
    start: f64,
}

impl Increment {
    fn of(c: &UmatCall) -> Self {
        Increment {
            kstep: c.kstep,
            kinc: c.kinc,
            start: c.time[1],
        }
    }

    /// Whether this increment comes before `prev`: an earlier step, an earlier total time
    /// (beyond round-off) in the same step, or an earlier `KINC` at the same time.
    fn goes_back_from(&self, prev: &Increment) -> bool {
        let roundoff = TIME_ROUNDOFF * prev.start.abs();
        self.kstep < prev.kstep
            || (self.kstep == prev.kstep
                && (self.start < prev.start - roundoff
                    || (self.start <= prev.start + roundoff && self.kinc < prev.kinc)))
    }
}

/// A table-mode point: a [`Point`] and the host's increments as it saw them, which commit
/// or revert its instance's trial.
struct TablePoint {
    point: Point,
    /// The increment of the last call.
    increment: Option<Increment>,
    /// `DTIME` of the last call.
    dtime: f64,
    /// The strain and answer of the instance's trial (`Some` exactly when it has one).
    last: Option<([f64; 3], Response)>,
    /// The last call failed.
    failed: bool,
}

impl TablePoint {
    /// A virgin point of `material`, which `c` names.
    fn new(id: u64, c: &UmatCall, material: Arc<Material>) -> Self {
        TablePoint {
            point: Point::new(id, c, material),
            increment: None,
            dtime: 0.0,
            last: None,
            failed: false,
        }
    }

    /// After a panic in a call of this point: the trial dropped, as after a failure.
    fn recover(&mut self) {
        self.point.instance.revert();
        self.last = None;
        self.failed = true;
    }

    /// The point's answer to a call of its material, following the host's increments.
    fn answer_point(
        &mut self,
        books: &Books,
        c: &UmatCall,
        out: &mut UmatOutputs,
    ) -> Result<Outcome, Failed> {
        self.point.instance.set_lean(false);
        let material = self.point.material.clone();
        let with_material = Failed::of(&material);
        table_note(c, out.statev.len(), &material.model);
        let inc = Increment::of(c);
        let (committed, reverted) = self.advance(inc, c.dtime).map_err(with_material)?;
        Books::add(&books.commits, committed);
        Books::add(&books.reverts, reverted);
        let (r, solved) = self.answer(books, c).map_err(|e| {
            self.failed = true;
            with_material(e)
        })?;
        (self.point)
            .write_outputs(c, &r, out, &[], None)
            .map_err(with_material)?;
        books.dump(&self.point.instance, c);
        Ok(Outcome {
            solved,
            committed,
            reverted,
            iterations: r.report.iterations,
        })
    }

    /// A point called with another material than it was created for: a new analysis
    /// (`KSTEP` or `TIME(2)` gone back) makes it a virgin point of the call's material;
    /// otherwise the call is refused. (In `STATEV` mode a point takes the material of
    /// each call.)
    fn rebind(&mut self, c: &UmatCall, material: Arc<Material>) -> Result<(), Failed> {
        let inc = Increment::of(c);
        let new_analysis = self.increment.is_some_and(|prev| inc.goes_back_from(&prev));
        if !new_analysis {
            return Err(plain(Error::HostConvention(format!(
                "element {}, point {} was created for material `{}` with other PROPS or \
                 another name; a point keeps its material within an analysis",
                c.noel, c.npt, self.point.key.cmname
            ))));
        }
        *self = TablePoint::new(self.point.id, c, material);
        Ok(())
    }

    /// Applies the increment protocol before a call of `inc`; returns (committed,
    /// reverted).
    fn advance(&mut self, inc: Increment, dtime: f64) -> crate::Result<(bool, bool)> {
        let (mut committed, mut reverted) = (false, false);
        let instance = &mut self.point.instance;
        if let Some(prev) = self.increment.filter(|prev| inc.goes_back_from(prev)) {
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
            instance.reset();
            self.last = None;
            self.increment = None;
        }
        if let Some(prev) = self.increment {
            let advanced = inc.start - prev.start > TIME_ROUNDOFF * (prev.start.abs() + self.dtime);
            let same = prev.kstep == inc.kstep && prev.kinc == inc.kinc && !advanced;
            if !same {
                if self.last.take().is_some() {
                    let ignored = instance.ignored_redos().0;
                    instance.commit()?;
                    committed = true;
                    if instance.ignored_redos().0 > ignored {
                        note_ignored_redo(instance.ignored_redos().1);
                    }
                }
            } else if self.failed || dtime < self.dtime * (1.0 - TIME_ROUNDOFF) {
                instance.revert();
                self.last = None;
                reverted = true;
            }
        }
        self.increment = Some(inc);
        self.dtime = dtime;
        self.failed = false;
        Ok((committed, reverted))
    }

    /// The RVE's answer at the call's strain: the instance's trial when the strain repeats
    /// it bit for bit, else a new trial (true: solved).
    fn answer(&mut self, books: &Books, c: &UmatCall) -> crate::Result<(Response, bool)> {
        let strain = self.point.strain(c)?;
        if let Some((s, r)) = self.last {
            if s.map(f64::to_bits) == strain.map(f64::to_bits) {
                Books::count(&books.repeats);
                return Ok((r, false));
            }
        }
        Books::count(&books.solves);
        let (model, request) = (
            self.point.material.model.clone(),
            self.point.material.tangent,
        );
        let r = with_workspace(&model, |ws| {
            (self.point.instance).update_timed(strain, c.dtime, ws, request)
        });
        self.last = r.as_ref().ok().map(|r| (strain, *r));
        Ok((r?, true))
    }
}

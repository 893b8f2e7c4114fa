//! `MESORVE_UMAT_VTK`: the UMAT writes the RVE fields of chosen host points as VTK, so that
//! an analyst can look inside the RVE at a macroscopic point (ParaView).
//!
//! **The switch.** `MESORVE_UMAT_VTK="DIR:NOEL.NPT[,NOEL.NPT...]"`, read at the process's
//! first UMAT call (as `MESORVE_UMAT_SCENE`), e.g. `rve_vtk:12.1,40.4`: element 12's point
//! 1 and element 40's point 4, written to `rve_vtk/` (created; relative to where the
//! host runs). `DIR` is what comes before the last `:`. Unset or empty: off.
//!
//! **The files.** At each answer of a chosen point (in both UMAT modes), the fields of the
//! state the call leaves for the host (the trial at `STRAN + DSTRAN`) go to
//! `DIR/e<NOEL>_p<NPT>_s<KSTEP>_i<KINC>.vtu`, the grid and arrays of `rve run --vtk`
//! ([`crate::io::write_vtu_fields`]: per triangle strain and stress, per ITZ element
//! openings, damage, branch; displacement per node). A later call of the same increment
//! (the host's next iteration) overwrites the file, so once the host moves on it holds the
//! increment's last answer: the converged one. A call that repeats the last written answer
//! (same increment, same strain, bit for bit: CalculiX's tangent call after its stress
//! call) writes nothing. `DIR/e<NOEL>_p<NPT>.pvd` indexes the point's files by the host's
//! total time at the end of the increment (`TIME(2) + DTIME`), so ParaView opens the
//! point's history as one time series. Each file is written under a temporary name and
//! renamed: a reader never sees half a file.
//!
//! **Why an environment variable**, not a scene key or a `PROPS` entry: which points to
//! look at is a choice of one run, not a property of the material. A scene key or a
//! `PROPS` value would change the material's fingerprint, which the `STATEV` state records
//! ([`mesorve_core::state::statev`]): a restart with the switch turned on or off would then
//! refuse its own state. The points are the host's numbering, which a scene shared by
//! several decks does not know. And the host's deck stays untouched: the same deck runs
//! with and without pictures.
//!
//! **Failures.** A bad value is said once on stderr and turns the switch off; a file that
//! cannot be written is said once and the analysis goes on (the answer to the host is the
//! same with and without the switch). `NOEL` and `NPT` must be at least 1: a host that
//! numbers every point 0 (Kratos) cannot choose points.
//!
//! **Cost.** Off: one test of an `Option` per call. On, at a point not chosen: a search in
//! the chosen list. At a chosen point: the fields (one factorization after a fast update)
//! and an ASCII file of about 70 kB for the paper's RVE (`calculix_examples/element.inp`:
//! 2 points, 30 of 40 increments each (IMPL-EX, below), 62 files, 8.5 MB).
//!
//! **Limit: IMPL-EX.** An IMPL-EX increment answered by reusing its step's factorization
//! (`solver.fast_path`: unloading, closed cracks) keeps no fluctuation that could be
//! formed again, so it gets no file (said once on stderr); the increments that factorize
//! (loading, the first of a step) are written.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError};

use super::diagnostics::{note_once, say, Note};
use crate::error::Error;
use crate::model::Instance;
use mesorve_core::solver::Integration;

/// The environment variable of the switch.
pub const UMAT_VTK_VAR: &str = "MESORVE_UMAT_VTK";

/// A bad value of [`UMAT_VTK_VAR`]: the value and what is wrong with it.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "{UMAT_VTK_VAR} = `{value}`: {reason}; expected DIR:NOEL.NPT[,NOEL.NPT...], e.g. \
     `rve_vtk:12.1,40.4`. No RVE fields are written; the analysis goes on"
)]
pub struct VtkSpecError {
    pub value: String,
    pub reason: String,
}

/// The parsed switch: where to write, and the chosen `(NOEL, NPT)`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VtkSpec {
    pub dir: PathBuf,
    pub points: Vec<(i32, i32)>,
}

impl VtkSpec {
    /// Parses `DIR:NOEL.NPT[,NOEL.NPT...]` (see the module documentation); repeated points
    /// are kept once.
    pub fn parse(value: &str) -> Result<VtkSpec, VtkSpecError> {
        let bad = |reason: String| VtkSpecError {
            value: value.to_string(),
            reason,
        };
        let Some((dir, list)) = value.trim().rsplit_once(':') else {
            return Err(bad("no `:` between the directory and the points".into()));
        };
        if dir.trim().is_empty() {
            return Err(bad("no directory before the `:`".into()));
        }
        let mut points = Vec::new();
        for item in list.split(',').map(str::trim) {
            let point = item
                .split_once('.')
                .and_then(|(e, p)| Some((e.trim().parse().ok()?, p.trim().parse().ok()?)))
                .filter(|&(e, p): &(i32, i32)| e >= 1 && p >= 1)
                .ok_or_else(|| {
                    bad(format!(
                        "`{item}` is not NOEL.NPT with an element and a point number of at \
                         least 1"
                    ))
                })?;
            if !points.contains(&point) {
                points.push(point);
            }
        }
        Ok(VtkSpec {
            dir: PathBuf::from(dir.trim()),
            points,
        })
    }
}

/// The files written for one chosen point.
#[derive(Default)]
struct Series {
    /// `(KSTEP, KINC)` -> (time, file name), the `.pvd` index.
    files: BTreeMap<(i32, i32), (f64, String)>,
    /// The increment and strain bits of the last file written.
    last: Option<((i32, i32), [u64; 3])>,
}

/// The switch at work: a [`VtkSpec`] and the files written so far.
pub struct VtkDump {
    spec: VtkSpec,
    series: Mutex<HashMap<(i32, i32), Series>>,
    written: AtomicU64,
    failures: AtomicU64,
    skipped: AtomicU64,
}

impl VtkDump {
    /// The switch of `spec`, its directory created.
    pub fn new(spec: VtkSpec) -> crate::Result<VtkDump> {
        std::fs::create_dir_all(&spec.dir).map_err(|source| Error::Io {
            path: spec.dir.clone(),
            source,
        })?;
        Ok(VtkDump {
            spec,
            series: Mutex::new(HashMap::new()),
            written: AtomicU64::new(0),
            failures: AtomicU64::new(0),
            skipped: AtomicU64::new(0),
        })
    }

    /// The switch of `value` (a [`UMAT_VTK_VAR`] value), or why not: a message for the user.
    pub fn from_value(value: &str) -> Result<VtkDump, String> {
        let spec = VtkSpec::parse(value).map_err(|e| format!("mesorve: {e}"))?;
        VtkDump::new(spec).map_err(|e| {
            format!(
                "mesorve: {UMAT_VTK_VAR} = `{value}`: cannot create the directory: {e}. No \
                 RVE fields are written; the analysis goes on"
            )
        })
    }

    /// The switch of [`UMAT_VTK_VAR`]: `None` when it is unset or empty, and when its
    /// value is bad, which is then said on stderr (the caller reads it once per process).
    pub fn from_env() -> Option<VtkDump> {
        let value = std::env::var_os(UMAT_VTK_VAR)?;
        let value = value.to_string_lossy();
        if value.trim().is_empty() {
            return None;
        }
        VtkDump::from_value(&value)
            .inspect_err(|message| say(message))
            .ok()
    }

    pub fn spec(&self) -> &VtkSpec {
        &self.spec
    }

    /// `.vtu` files written (overwrites included).
    pub fn written(&self) -> u64 {
        self.written.load(Ordering::Relaxed)
    }

    /// Writes that failed (the first one is said on stderr).
    pub fn failures(&self) -> u64 {
        self.failures.load(Ordering::Relaxed)
    }

    /// Answers not written because their fluctuation cannot be formed (IMPL-EX reusing
    /// its step's factorization; the first one is said on stderr).
    pub fn skipped(&self) -> u64 {
        self.skipped.load(Ordering::Relaxed)
    }

    /// The `.vtu` file of a point's increment, relative to the directory.
    pub fn file_name(noel: i32, npt: i32, kstep: i32, kinc: i32) -> String {
        format!("e{noel}_p{npt}_s{kstep}_i{kinc}.vtu")
    }

    /// The `.pvd` index of a point, relative to the directory.
    pub fn index_name(noel: i32, npt: i32) -> String {
        format!("e{noel}_p{npt}.pvd")
    }

    /// Whether the point `(noel, npt)` is one whose fields are written.
    pub fn chooses(&self, noel: i32, npt: i32) -> bool {
        self.spec.points.contains(&(noel, npt))
    }

    /// After an answer of the UMAT: the fields of `instance`'s trial when the call's point
    /// is chosen. Never fails: a failure is counted and said once.
    pub fn at_answer(&self, instance: &Instance, c: &DumpAt) {
        if !self.chooses(c.noel, c.npt) {
            return;
        }
        if let Err(e) = self.write(instance, c) {
            self.failures.fetch_add(1, Ordering::Relaxed);
            note_once(Note::VtkWrite, || {
                format!(
                    "mesorve: {UMAT_VTK_VAR}: element {}, point {}: cannot write the RVE \
                     fields: {e}; the analysis goes on (printed once)",
                    c.noel, c.npt
                )
            });
        }
    }

    /// An IMPL-EX answer that reused its step's factorization (the fast path: unloading,
    /// closed cracks) holds no fluctuation to write: counted, said once.
    fn skip(&self, c: &DumpAt) {
        self.skipped.fetch_add(1, Ordering::Relaxed);
        note_once(Note::VtkSkipped, || {
            format!(
                "mesorve: {UMAT_VTK_VAR}: element {}, point {}: with IMPL-EX an increment \
                 answered by reusing its step's factorization (unloading, closed cracks: \
                 solver.fast_path) has no RVE fluctuation to write; such increments get no \
                 file (printed once)",
                c.noel, c.npt
            )
        });
    }

    fn write(&self, instance: &Instance, c: &DumpAt) -> crate::Result<()> {
        let state = instance.trial_state().ok_or(Error::NoTrial)?;
        let increment = (c.kstep, c.kinc);
        let strain = state.strain.map(f64::to_bits);
        let mut all = self.series.lock().unwrap_or_else(PoisonError::into_inner);
        let series = all.entry((c.noel, c.npt)).or_default();
        if series.last == Some((increment, strain)) {
            return Ok(());
        }
        let name = Self::file_name(c.noel, c.npt, c.kstep, c.kinc);
        let path = self.spec.dir.join(&name);
        let index = self.spec.dir.join(Self::index_name(c.noel, c.npt));
        let implex = instance.model().solver.integration == Integration::Implex;
        if implex && !state.unknowns_are_current() {
            // An earlier iteration's file of this increment would not be its answer.
            self.skip(c);
            series.last = Some((increment, strain));
            if series.files.remove(&increment).is_some() {
                let _ = std::fs::remove_file(&path);
                let entries: Vec<(f64, String)> = series.files.values().cloned().collect();
                write_index(&index, &entries)?;
            }
            return Ok(());
        }
        let part = part_of(&path);
        instance.model().write_vtu(&state, &part)?;
        rename(&part, &path)?;
        self.written.fetch_add(1, Ordering::Relaxed);
        series.last = Some((increment, strain));
        let time = if c.time_end.is_finite() {
            c.time_end
        } else {
            f64::from(c.kinc)
        };
        series.files.insert(increment, (time, name));
        let entries: Vec<(f64, String)> = series.files.values().cloned().collect();
        write_index(&index, &entries)
    }
}

/// After an answer of the UMAT, when the switch is on (see [`VtkDump::at_answer`]).
pub fn at_answer(dump: &Option<VtkDump>, instance: &Instance, c: &DumpAt) {
    if let Some(dump) = dump {
        dump.at_answer(instance, c);
    }
}

/// Where and when an answer is written: the call's point and increment, told by the UMAT
/// (`host::umat` builds it from its call, so this module does not import the UMAT).
#[derive(Debug, Clone, Copy)]
pub struct DumpAt {
    pub noel: i32,
    pub npt: i32,
    pub kstep: i32,
    pub kinc: i32,
    /// Total time at the end of the increment, `TIME(2) + DTIME`: the `.pvd` time.
    pub time_end: f64,
}

/// The temporary name a file is written under before its rename.
fn part_of(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".part");
    path.with_file_name(name)
}

fn rename(from: &Path, to: &Path) -> crate::Result<()> {
    std::fs::rename(from, to).map_err(|source| Error::Io {
        path: to.to_path_buf(),
        source,
    })
}

/// Writes the `.pvd` index `path` of `entries` (under a temporary name, then renamed).
fn write_index(path: &Path, entries: &[(f64, String)]) -> crate::Result<()> {
    let part = part_of(path);
    let io_err = |source| Error::Io {
        path: part.clone(),
        source,
    };
    let mut w = BufWriter::new(File::create(&part).map_err(io_err)?);
    crate::io::write_pvd(entries, &mut w).map_err(io_err)?;
    w.flush().map_err(io_err)?;
    drop(w);
    rename(&part, path)
}

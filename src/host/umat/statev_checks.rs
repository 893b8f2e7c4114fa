//! `STATEV` mode's checks that the values a host hands over are this point's state at the
//! start of this increment: the committed strain against `STRAN`, the committed time
//! against `TIME(2)`, a lost state (all zeros at a strained point), and the note on values
//! of the first state format, which cannot be verified (docs/statev.md).

use super::call::{trim, UmatCall};
use super::point::{Point, TIME_ROUNDOFF};
use crate::error::Error;
use crate::host::diagnostics::{note_once, Note};
use crate::scene::ZeroAtStrain;
use mesorve_core::state::statev;

/// `STRAN` and the state's committed strain agree when they differ by at most this
/// fraction of the larger of the two (infinity norms) plus [`STRAIN_MATCH_FLOOR`]. A host
/// that adds `DSTRAN` to `STRAN`, as Abaqus and CalculiX do, hands back the library's own
/// sum (docs/statev.md has the agreement measured over a CalculiX analysis); a total
/// strain recomputed from displacements differs by round-off; a state one increment old
/// differs by the increment.
pub const STRAIN_MATCH_RELATIVE: f64 = 1e-9;
/// The absolute floor of the strain match (at zero strain), strain units.
pub const STRAIN_MATCH_FLOOR: f64 = 1e-12;

const STALE_STATE_REMEDY: &str = ". Check that the host hands every call of an increment \
    the STATEV kept at the end of this point's previous converged increment, with that \
    increment's total strain in STRAN (a state of another point, or of an earlier \
    increment, is not this one's). A host whose STRAN is not the total strain at the start \
    of the increment sets [statev] check_strain = false in the scene";
const EARLIER_STATE_REMEDY: &str = ". CalculiX 2.20 hands an element re-added by *MODEL \
    CHANGE, ADD the STATEV of its last call before the removal: such an element cannot \
    continue from its old state (see docs/statev.md: do not remove and re-add RVE \
    elements, or set [statev] check_time = false in the scene to continue the old state \
    as ccx does). Otherwise the host handed a state kept from an earlier increment; a \
    host whose TIME(2) is not the total time at the start of the increment sets [statev] \
    check_time = false";
const LOST_STATE_REMEDY: &str = ". CalculiX 2.20 writes STATEV to its restart file only \
    when the model has a contact pair: add a node-to-surface pair that never closes (see \
    docs/calculix.md) and run the analysis again from its start. A host that zeroes \
    STATEV on purpose to restart the point from a virgin RVE (an element re-added with \
    its state reset) sets [statev] zero_at_strain = \"virgin\" in the scene";

/// `Some((difference, tolerance))` when a state committed at `stored` does not belong to
/// the start of an increment at `host` (infinity norms; see [`STRAIN_MATCH_RELATIVE`]).
pub fn strain_mismatch(stored: [f64; 3], host: [f64; 3]) -> Option<(f64, f64)> {
    let norm = |e: &[f64; 3]| e.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let difference = norm(&std::array::from_fn(|i| stored[i] - host[i]));
    let tolerance = STRAIN_MATCH_RELATIVE * norm(&stored).max(norm(&host)) + STRAIN_MATCH_FLOOR;
    (difference > tolerance).then_some((difference, tolerance))
}

/// Refuses a state that is not this point's at this increment: its committed strain must
/// be the host's `STRAN` to [`STRAIN_MATCH_RELATIVE`] of the larger of the two, plus
/// [`STRAIN_MATCH_FLOOR`]; an all-zero `STATEV` (`virgin`) at a strained point is a lost
/// state unless the scene says the host zeroes it on purpose (`[statev]`); the time the
/// state was committed at the end of (`core_time`) must be this increment's start when
/// the host's time is meaningful (`timed`).
pub(super) fn check_start(
    p: &Point,
    core_time: Option<f64>,
    c: &UmatCall,
    (virgin, timed): (bool, bool),
) -> crate::Result<()> {
    let spec = p.material.model.scene().spec.statev;
    if !spec.check_strain {
        return Ok(());
    }
    let host = c.hypothesis.rve_strain(c.stran)?;
    let stored = p.instance.committed().strain;
    let Some((difference, tolerance)) = strain_mismatch(stored, host) else {
        return check_start_time(core_time, c, spec.check_time && timed);
    };
    if virgin {
        if spec.zero_at_strain == ZeroAtStrain::Virgin {
            return Ok(());
        }
        return Err(Error::StateLost {
            host,
            remedy: LOST_STATE_REMEDY.into(),
        });
    }
    Err(Error::StateStrain {
        stored,
        host,
        difference,
        tolerance,
        remedy: STALE_STATE_REMEDY.into(),
    })
}

/// Refuses a state committed at the end of another time than this increment's start
/// (`TIME(2)`, to [`TIME_ROUNDOFF`] of the time plus the increment): a state of an earlier
/// increment, such as the one CalculiX 2.20 hands an element re-added by `*MODEL CHANGE`.
fn check_start_time(core_time: Option<f64>, c: &UmatCall, check: bool) -> crate::Result<()> {
    let (Some(end), true) = (core_time, check) else {
        return Ok(());
    };
    let start = c.time[1];
    let tolerance = TIME_ROUNDOFF * (end.abs() + c.dtime.abs());
    if (start - end).abs() <= tolerance {
        return Ok(());
    }
    Err(Error::StateTime {
        stored: end,
        host: start,
        remedy: EARLIER_STATE_REMEDY.into(),
    })
}

/// Whether a decoded core passes the checks of the start of the increment (strain and
/// time, as [`check_start`]); a core that does not is left to the normal path, which
/// refuses it with its message.
pub(super) fn start_matches(
    model: &crate::Model,
    c: &UmatCall,
    core: &statev::Core,
) -> crate::Result<bool> {
    let spec = model.scene().spec.statev;
    let host = c.hypothesis.rve_strain(c.stran)?;
    if spec.check_strain && strain_mismatch(core.strain, host).is_some() {
        return Ok(false);
    }
    let late = core
        .time
        .is_some_and(|end| (c.time[1] - end).abs() > TIME_ROUNDOFF * (end.abs() + c.dtime.abs()));
    Ok(!(spec.check_time && late))
}

/// Says once per process that a point's `STATEV` is of state format 1 (no fingerprint):
/// accepted, since an upgrade may find an analysis mid-way, but it cannot be verified to be
/// this material's; the point's next write is verified.
pub(super) fn unverified_note(c: &UmatCall) {
    note_once(Note::Unverified, || {
        format!(
            "mesorve: element {}, point {}, material `{}`: STATEV written by an earlier \
             mesorve (state format 1, no fingerprint): accepted, but it cannot be verified \
             to be this material's state; the values written from now on can (printed \
             once)",
            c.noel,
            c.npt,
            trim(c.cmname)
        )
    });
}

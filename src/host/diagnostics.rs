//! The library's messages to the user: one sink, stderr ([`say`]), and two ways of saying
//! a thing once per process.
//!
//! A host calls the UMAT at every integration point of every increment, so a message
//! said at each call would bury the host's own output. Two rules keep it to a line:
//! - a [`Note`] (a fact about the run: a host without `PNEWDT` and no scene, a table
//!   point restarted from virgin, ...) is said the first time it holds, [`note_once`];
//! - a failure is said the first time its *reason* occurs, [`failure_once`]: the error's
//!   text with its numbers and quoted names masked ([`reason_key`]), so a layout the RVE
//!   cannot answer prints one line, not one per point, and another reason its own line.
//!
//! Each call's full message stays with the call (`rve_last_error`, [`super::UmatFailure`]).
//! A write to a closed stderr is ignored, and nothing here unwinds: it also runs outside
//! the C boundary's panic guard.

use std::collections::HashSet;
use std::io::Write;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{LazyLock, Mutex, PoisonError};

/// The facts said once per process.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Note {
    /// A host without `PNEWDT` and without `MESORVE_UMAT_SCENE`: every point is the
    /// embedded paper RVE.
    NoScene,
    /// An increment's answer depends on its size (`solver.step_check`).
    StepSize,
    /// An increment's integration error exceeds `solver.step_tolerance`.
    Tolerance,
    /// A host kept an increment it was asked to redo smaller.
    IgnoredRedo,
    /// `KSTEP`/`TIME` went back: table points restart from virgin.
    WentBack,
    /// A `STATEV` of state format 1, without fingerprint.
    Unverified,
    /// `NSTATV` too small for `STATEV` mode: the state stays in the library's table.
    TableMode,
    /// `MESORVE_UMAT_VTK`: a file could not be written.
    VtkWrite,
    /// `MESORVE_UMAT_VTK`: an IMPL-EX answer without a fluctuation got no file.
    VtkSkipped,
    /// A scene with `effects.regularization` called without an element length.
    NoElementLength,
    /// A scene with `effects.regularization` regularized by the host's `CELENT`.
    Celent,
}

/// The [`Note`]s said so far, one bit each.
static NOTES_SAID: AtomicU32 = AtomicU32::new(0);

/// The failure reasons said so far (their [`reason_key`]s).
static REASONS_SAID: LazyLock<Mutex<HashSet<String>>> =
    LazyLock::new(|| Mutex::new(HashSet::new()));

/// What stands after a failure's line.
pub const SAID_ONCE: &str =
    "(printed once per process for this reason; rve_last_error has each call's message)";

/// Writes `line` on stderr; a write error is ignored (stderr closed: nothing to tell).
/// The one writer of the library's messages (a message said once per process by its
/// nature, such as a bad `MESORVE_UMAT_VTK` read at the first call, uses it directly).
pub(crate) fn say(line: &str) {
    let _ = writeln!(std::io::stderr(), "{line}");
}

/// Says `message()` on stderr if `note` has not been said in this process (the message is
/// built only then); returns whether it did.
pub fn note_once(note: Note, message: impl FnOnce() -> String) -> bool {
    let bit = 1 << note as u32;
    if NOTES_SAID.fetch_or(bit, Ordering::Relaxed) & bit != 0 {
        return false;
    }
    let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| say(&message())));
    true
}

/// Says `line`, followed by [`SAID_ONCE`], on stderr if the process has not met `reason`
/// (the error's text, masked by [`reason_key`]) yet; returns whether it did.
pub fn failure_once(reason: &str, line: &str) -> bool {
    std::panic::catch_unwind(|| {
        let mut seen = REASONS_SAID.lock().unwrap_or_else(PoisonError::into_inner);
        report_once(&mut seen, reason, line, &mut std::io::stderr())
    })
    .unwrap_or(false)
}

/// Writes `line` and [`SAID_ONCE`] to `out` when `seen` does not hold the reason yet, and
/// remembers it; returns whether it wrote. Write errors are ignored.
fn report_once(seen: &mut HashSet<String>, reason: &str, line: &str, out: &mut dyn Write) -> bool {
    if !seen.insert(reason_key(reason)) {
        return false;
    }
    let _ = writeln!(out, "{line} {SAID_ONCE}");
    true
}

/// The key a failure is said once under: the error's text with its quoted names and its
/// numbers masked, so a reason is said once whatever the arguments (the material, the
/// strain, `PNEWDT`, the element and point numbers); the line itself names them.
fn reason_key(reason: &str) -> String {
    mask_numbers(&mask_quoted(reason))
}

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
        assert!(text.lines().all(|l| l.ends_with(SAID_ONCE)));
    }

    /// A note is said the first time only, and its message is not built after that.
    #[test]
    fn a_note_is_said_once() {
        // Another test of the process may say it first: the first call's answer is free.
        note_once(Note::IgnoredRedo, || "a note of the unit test".to_string());
        let built = std::cell::Cell::new(false);
        let again = note_once(Note::IgnoredRedo, || {
            built.set(true);
            String::new()
        });
        assert!(!again && !built.get());
    }
}

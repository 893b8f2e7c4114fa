//! Comments in the crates' sources and `tests/` say what the code does and why: no issue numbers, no
//! measured figures (speed-ups, timings, "measured ..." with a number; a test may give the
//! figure its threshold's margin rests on) and no history of what was tried. Measurements
//! belong in `docs/`, history in the CHANGELOG and commit messages.
//!
//! The rules are patterns over comment blocks (consecutive `//`, `///` or `//!` lines,
//! joined, so that a phrase wrapped over two lines is read whole), each with the reason
//! it exists; a match names the file and the block's first line.

use std::path::Path;

/// The rule of measured figures, which a test's comment may break (see below).
const MEASURED: &str = "a measured figure (docs/)";

/// A comment-line rule: the phrase it refuses, and a predicate on the lowercase text.
struct Rule {
    what: &'static str,
    matches: fn(&str) -> bool,
}

fn has_digit(s: &str) -> bool {
    s.chars().any(|c| c.is_ascii_digit())
}

/// `issue 12`, `issue #12`.
fn issue_number(s: &str) -> bool {
    s.match_indices("issue").any(|(i, _)| {
        let rest = s[i + 5..].trim_start().trim_start_matches('#');
        rest.starts_with(|c: char| c.is_ascii_digit())
    })
}

/// A timing with its unit: `0.5 ms`, `12us`, `3 µs`.
fn timing(s: &str) -> bool {
    let b = s.as_bytes();
    ["ms", "us", "µs"].iter().any(|unit| {
        s.match_indices(unit).any(|(i, _)| {
            let before = s[..i].trim_end();
            let after = &s[i + unit.len()..];
            let ends_word = !after.starts_with(|c: char| c.is_alphanumeric());
            let number_before = before.ends_with(|c: char| c.is_ascii_digit());
            let starts_word = i == 0 || !(b[i - 1] as char).is_alphabetic();
            ends_word && number_before && starts_word
        })
    })
}

const RULES: &[Rule] = &[
    Rule {
        what: "an issue number (history: commit messages and the CHANGELOG)",
        matches: issue_number,
    },
    Rule {
        what: "a speed comparison with a figure (docs/)",
        matches: |s| has_digit(s) && (s.contains("faster") || s.contains("slower")),
    },
    Rule {
        what: "a timing figure (docs/)",
        matches: timing,
    },
    Rule {
        what: MEASURED,
        matches: |s| {
            s.match_indices("measured")
                .any(|(i, _)| !s[i..].starts_with("measured from") && has_digit(&s[i..]))
        },
    },
    Rule {
        what: "a before/after figure (history: CHANGELOG)",
        matches: |s| {
            s.match_indices(" now").any(|(i, _)| {
                let after = &s[i + 4..];
                let ends_word = !after.starts_with(|c: char| c.is_alphanumeric());
                ends_word && s[..i].trim_end().ends_with(|c: char| c.is_ascii_digit())
            })
        },
    },
    Rule {
        what: "history of what was tried or reverted (CHANGELOG)",
        matches: |s| {
            (s.contains("tried") || s.contains("reverted") || s.contains("used to"))
                && (s.contains("dropped") || s.contains("removed") || s.contains("not kept"))
        },
    },
];

fn comment(line: &str) -> Option<&str> {
    let t = line.trim_start();
    t.starts_with("//")
        .then(|| t.trim_start_matches('/').trim_start_matches('!'))
}

/// The sentences of a file's comments: (the line it starts on, 1-based; its text with the
/// comment lines joined by spaces). A sentence ends at ". " or at the end of a line ending
/// with ".", at a blank comment line and where the comment ends.
fn blocks(text: &str) -> Vec<(usize, String)> {
    let mut out: Vec<(usize, String)> = Vec::new();
    let mut open = false;
    for (k, line) in text.lines().enumerate() {
        let Some(c) = comment(line).map(str::trim) else {
            open = false;
            continue;
        };
        if c.is_empty() {
            open = false;
            continue;
        }
        for (i, part) in c.split(". ").enumerate() {
            if open && i == 0 {
                let sentence = &mut out.last_mut().unwrap().1;
                sentence.push(' ');
                sentence.push_str(part);
            } else {
                out.push((k + 1, part.to_string()));
            }
            open = true;
        }
        open = !c.ends_with('.');
    }
    out
}

fn check(path: &Path, offences: &mut Vec<String>) {
    let text = std::fs::read_to_string(path).unwrap();
    for (line, block) in blocks(&text) {
        let lower = block.to_lowercase();
        for rule in RULES.iter().filter(|r| (r.matches)(&lower)) {
            offences.push(format!("{}:{line}: {}: {block}", path.display(), rule.what));
        }
    }
}

fn walk(dir: &Path, offences: &mut Vec<String>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            walk(&path, offences);
        } else if path.extension().is_some_and(|e| e == "rs") {
            check(&path, offences);
        }
    }
}

#[test]
fn comments_in_src_and_tests_hold_no_history_issue_numbers_or_measured_figures() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut offences = Vec::new();
    for crate_src in ["src", "crates/core/src", "crates/cli/src"] {
        walk(&root.join(crate_src), &mut offences);
    }
    // The tests too, but this file, whose comments quote what the rules refuse; a test's
    // measured figure stays (it is the reason for the margin of its threshold).
    let mut in_tests = Vec::new();
    walk(&root.join("tests"), &mut in_tests);
    in_tests.retain(|o| !o.contains("comment_hygiene.rs:") && !o.contains(MEASURED));
    offences.extend(in_tests);
    assert!(
        offences.is_empty(),
        "{} comment lines:\n{}",
        offences.len(),
        offences.join("\n")
    );
}

#[test]
fn the_rules_catch_what_they_name() {
    let caught = |s: &str| RULES.iter().any(|r| (r.matches)(&s.to_lowercase()));
    for bad in [
        "see Issue 13",
        "as in issue #7",
        "supernodal is 2x faster than simplicial",
        "the update takes 0.54 ms",
        "measured 1e2 times the reference",
        "tried X, reverted and dropped",
        "(118-375 factorizations; 66-90 now)",
    ] {
        assert!(caught(bad), "{bad}");
    }
    // A phrase wrapped over two comment lines is read as one.
    let wrapped = "/// We tried the LU first, but it was\n/// dropped again.\nfn f() {}\n";
    let joined = blocks(wrapped);
    assert_eq!(joined.len(), 1);
    assert!(caught(&joined[0].1), "{joined:?}");
    for fine in [
        "the remedies are tried in this order",
        "sums over 3 columns",
        "the jump is measured from the reference configuration",
        "eq. 36 of the paper",
        "the 3 points now closed",
    ] {
        assert!(!caught(fine), "{fine}");
    }
}

/// `tests/README.md` names every test file of `tests/` (its map of what each guards).
#[test]
fn the_test_map_names_every_test_file() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let map = std::fs::read_to_string(dir.join("README.md")).unwrap();
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        if name.ends_with(".rs") && !map.contains(&format!("`{name}`")) {
            missing.push(name);
        }
    }
    assert!(
        missing.is_empty(),
        "tests/README.md does not name {missing:?}"
    );
}

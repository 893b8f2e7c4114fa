//! No function in `src/` is longer than [`MAX_LINES`] lines, counted as
//! `scripts/function-lengths` counts them: from the line of the signature to the line of
//! the closing brace, by counting braces, in every `.rs` file of `src/`, the text from the
//! first `#[cfg(test)]` on (the test modules) left out.
//!
//! A signature is a line that starts (after spaces) with an optional `pub` or `pub(..)`,
//! then optionally `const`, `unsafe` and `extern "C"` in that order, then `fn` and the
//! name. A signature whose line ends with `;` before any `{` (a declaration) counts to
//! that line.

use std::path::{Path, PathBuf};

/// The project rule: no function over this many lines in `src/`.
const MAX_LINES: usize = 80;

/// `rest` after the literal `word`, or `None`.
fn after<'a>(rest: &'a str, word: &str) -> Option<&'a str> {
    rest.strip_prefix(word)
}

/// `rest` after at least one whitespace character and all that follow, or `None`.
fn after_spaces(rest: &str) -> Option<&str> {
    let trimmed = rest.trim_start();
    (trimmed.len() < rest.len()).then_some(trimmed)
}

/// `rest` after an optional `word` followed by whitespace; unchanged without them.
fn optional<'a>(rest: &'a str, word: &str) -> &'a str {
    after(rest, word).and_then(after_spaces).unwrap_or(rest)
}

/// `rest` after an optional `pub` or `pub(...)` (no `)` inside) followed by whitespace.
fn optional_pub(rest: &str) -> &str {
    let Some(tail) = after(rest, "pub") else {
        return rest;
    };
    let tail = match after(tail, "(") {
        Some(inner) => match inner.find(')') {
            Some(close) => &inner[close + 1..],
            None => return rest,
        },
        None => tail,
    };
    after_spaces(tail).unwrap_or(rest)
}

/// The name of the function whose signature starts `line`, if it does: the script's
/// `^\s*(pub(\([^)]*\))?\s+)?(const\s+)?(unsafe\s+)?(extern "C"\s+)?fn\s+(\w+)`.
fn signature(line: &str) -> Option<&str> {
    let rest = optional_pub(line.trim_start());
    let rest = optional(rest, "const");
    let rest = optional(rest, "unsafe");
    let rest = optional(rest, "extern \"C\"");
    let rest = after_spaces(after(rest, "fn")?)?;
    let end = rest
        .find(|c: char| !(c.is_alphanumeric() || c == '_'))
        .unwrap_or(rest.len());
    (end > 0).then(|| &rest[..end])
}

/// The lines of the function whose signature is `lines[start]`: to the line where its
/// braces balance, or to the first line ending with `;` before any brace.
fn length(lines: &[&str], start: usize) -> usize {
    let (mut depth, mut started) = (0i64, false);
    let mut j = start;
    while j < lines.len() {
        for c in lines[j].chars() {
            match c {
                '{' => {
                    depth += 1;
                    started = true;
                }
                '}' => depth -= 1,
                _ => {}
            }
        }
        if (started && depth == 0) || (!started && lines[j].trim_end().ends_with(';')) {
            break;
        }
        j += 1;
    }
    j - start + 1
}

/// `(lines, name)` of every function of a source text, test modules left out.
fn functions(text: &str) -> Vec<(usize, String)> {
    let code = text.split("#[cfg(test)]").next().unwrap_or("");
    let lines: Vec<&str> = code.split('\n').collect();
    (0..lines.len())
        .filter_map(|i| signature(lines[i]).map(|name| (length(&lines, i), name.to_string())))
        .collect()
}

fn visit(dir: &Path, files: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let hidden = path
            .file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with('.'));
        if hidden {
            continue;
        }
        if path.is_dir() {
            visit(&path, files);
        } else if path.extension().is_some_and(|e| e == "rs") {
            files.push(path);
        }
    }
}

/// `(lines, path, name)` of every function in `src/`, longest first (ties as the script
/// sorts them: by path, then name, both descending), paths as `src/a/b.rs`.
fn all_functions() -> Vec<(usize, String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    visit(&root.join("src"), &mut files);
    let mut rows = Vec::new();
    for file in &files {
        let relative = file.strip_prefix(root).unwrap();
        let parts: Vec<String> = relative
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        let path = parts.join("/");
        let text = std::fs::read_to_string(file).unwrap();
        for (n, name) in functions(&text) {
            rows.push((n, path.clone(), name));
        }
    }
    rows.sort_unstable_by(|a, b| b.cmp(a));
    rows
}

#[test]
fn no_function_over_80_lines_in_src() {
    let rows = all_functions();
    assert!(rows.len() > 500, "only {} functions found", rows.len());
    // The longest ten, as `scripts/function-lengths src` prints them (`--nocapture`).
    for (n, path, name) in rows.iter().take(10) {
        println!("{n:5}  {path}  {name}");
    }
    let long: Vec<String> = rows
        .iter()
        .filter(|(n, _, _)| *n > MAX_LINES)
        .map(|(n, path, name)| format!("{n:5}  {path}  {name}"))
        .collect();
    assert!(
        long.is_empty(),
        "functions over {MAX_LINES} lines (signature to closing brace):\n{}",
        long.join("\n")
    );
}

/// The counter itself: the signatures it takes and leaves, declarations, nested braces,
/// and the test module cut.
#[test]
fn the_counter_reads_signatures_braces_and_test_modules() {
    for (line, name) in [
        ("fn a() {", Some("a")),
        ("    pub fn b_1(x: u8) {", Some("b_1")),
        ("pub(crate) fn c() {", Some("c")),
        ("pub(super) const unsafe fn d() {", Some("d")),
        ("pub unsafe extern \"C\" fn e() -> u32 {", Some("e")),
        ("extern \"C\" fn f();", Some("f")),
        ("const fn g() {}", Some("g")),
        ("async fn h() {", None),
        ("pub(crate)fn i() {", None),
        ("let fnord = 1;", None),
        ("// fn j() {", None),
        ("fn(u8) -> u8", None),
    ] {
        assert_eq!(signature(line), name, "{line}");
    }
    let text = "fn a() {\n    if x {\n    }\n}\nfn b();\nfn c()\n    -> u8\n{ 1 }\n#[cfg(test)]\nfn d() {\n}\n";
    assert_eq!(
        functions(text),
        [
            (4, "a".to_string()),
            (1, "b".to_string()),
            (3, "c".to_string())
        ]
    );
}

//! No function in the crates' sources (`src/`, `crates/*/src/`) is longer than 80 lines (signature to closing brace, test modules
//! left out). The counting is `scripts/function-lengths`, the script a developer runs to
//! see the longest functions: this test runs it, so the rule and the tool cannot differ.

use std::path::Path;
use std::process::Command;

const LIMIT: usize = 80;

/// `(lines, file, name)` of every function below `dir`, as the script counts them.
fn lengths(dir: &Path) -> Vec<(usize, String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new("python3")
        .arg(root.join("scripts/function-lengths"))
        .arg(dir)
        .arg(usize::MAX.to_string())
        .output()
        .expect("python3 runs scripts/function-lengths");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|line| {
            let mut f = line.split_whitespace();
            let n = f.next().unwrap().parse().unwrap();
            let (file, name) = (f.next().unwrap(), f.next().unwrap());
            (n, file.to_string(), name.to_string())
        })
        .collect()
}

#[test]
fn no_function_over_80_lines_in_src() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let all: Vec<_> = ["src", "crates/core/src", "crates/cli/src"]
        .iter()
        .flat_map(|dir| lengths(&root.join(dir)))
        .collect();
    // The script found the crate's functions (not an empty or misread listing).
    assert!(all.len() > 500, "{} functions", all.len());
    let long: Vec<String> = all
        .iter()
        .filter(|(n, _, _)| *n > LIMIT)
        .map(|(n, file, name)| format!("{file}: {name}: {n} lines"))
        .collect();
    assert!(long.is_empty(), "over {LIMIT} lines:\n{}", long.join("\n"));
}

#[test]
fn the_counter_reads_signatures_braces_and_test_modules() {
    let dir = std::env::temp_dir().join(format!("function_lengths_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let body = "    let x = 1;\n".repeat(LIMIT - 1);
    let text = format!(
        "fn a() {{\n}}\npub(crate) fn long() {{\n{body}}}\n\
         pub(super) const unsafe fn d() {{ }}\n\
         pub unsafe extern \"C\" fn e() -> u32 {{\n    0\n}}\n\
         extern \"C\" fn f();\n\
         #[cfg(test)]\nmod tests {{\n    fn hidden() {{\n{body}{body}    }}\n}}\n"
    );
    std::fs::write(dir.join("sample.rs"), text).unwrap();
    let found = lengths(&dir);
    std::fs::remove_dir_all(&dir).unwrap();
    let of = |name: &str| found.iter().find(|(_, _, n)| n == name).map(|(n, _, _)| *n);
    assert_eq!(of("long"), Some(LIMIT + 1), "{found:?}");
    assert_eq!(of("a"), Some(2));
    assert_eq!(of("d"), Some(1));
    assert_eq!(of("e"), Some(3));
    assert_eq!(of("f"), Some(1));
    assert_eq!(of("hidden"), None, "a test module counted");
}

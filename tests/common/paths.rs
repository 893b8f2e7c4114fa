//! Where the repository's files are, for the tests of every crate of the workspace (the
//! CLI's tests include this file alone: it needs nothing but `rve`).
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use rve::scene::Scene;

/// Path of a file in the repository (the workspace root, which holds `Cargo.lock`, at or
/// above the testing crate's folder).
pub fn repo(rel: &str) -> PathBuf {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let root = crate_dir
        .ancestors()
        .find(|d| d.join("Cargo.lock").is_file())
        .unwrap_or(crate_dir);
    root.join(rel)
}

/// The `rve` binary of the workspace's `mesorve-cli` crate, beside this test's own
/// profile folder (`target/<profile>/rve`). A test of this crate cannot ask cargo for
/// another package's binary: the workspace build (`cargo build --release`, `cargo test`
/// of the workspace, which builds the binary for the CLI's own tests) puts it there.
pub fn rve_exe() -> PathBuf {
    let exe = std::env::current_exe().expect("the test's path");
    let profile = exe
        .parent()
        .and_then(Path::parent)
        .expect("target/<profile>/deps");
    let rve = profile.join("rve");
    assert!(
        rve.is_file(),
        "{} is missing: build the workspace first (cargo build --release builds the `rve` \
         tool of crates/cli)",
        rve.display()
    );
    rve
}

/// Loads a shipped scene.
pub fn scene(rel: &str) -> Scene {
    Scene::from_file(repo(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// The paper scene with text replacements applied (for variations and bad inputs).
pub fn paper_scene_with(replacements: &[(&str, &str)]) -> String {
    let mut text = std::fs::read_to_string(repo("scenes/paper_rve.toml")).unwrap();
    for (from, to) in replacements {
        assert!(text.contains(from), "scene text has no `{from}`");
        text = text.replacen(from, to, 1);
    }
    text
}

//! Inside each crate of the workspace dependencies flow one way; between crates the
//! compiler keeps the order (`mesorve-core` cannot name `mesorve`). This test keeps the
//! order inside a crate, which the compiler cannot see:
//!
//! ```text
//! mesorve (src/):            ffi -> host -> model -> scene -> io -> (the core, re-exported)
//! mesorve-core (crates/core): {solver, homogenization} -> assembly -> constraint
//!                             -> {mesh, element, state} -> {geometry, material, interface} -> error
//! ```
//!
//! Every `crate::<module>` path in a module's source (its `use` lines and inline paths)
//! must name a module of a lower layer of its crate, or its own; and no two files import
//! each other.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A crate of the workspace: its source folder (from the repository root), its layers
/// from the bottom (a module may use the modules of the layers below its own), and the
/// items its root re-exports, by the module that defines them (a re-export of the core
/// counts as the bottom layer).
struct Crate {
    src: &'static str,
    layers: &'static [&'static [&'static str]],
    root_items: &'static [(&'static str, &'static str)],
}

const CRATES: [Crate; 2] = [
    Crate {
        src: "crates/core/src",
        layers: &[
            &["error"],
            &["geometry", "material", "interface"],
            &["mesh", "element", "state"],
            &["constraint"],
            &["assembly"],
            &["solver", "homogenization"],
        ],
        root_items: &[("Error", "error"), ("Result", "error")],
    },
    Crate {
        src: "src",
        layers: &[
            &["error"],
            &["io"],
            &["scene"],
            &["model"],
            &["host"],
            &["ffi"],
        ],
        root_items: &[
            ("Error", "error"),
            ("Result", "error"),
            ("VERSION", "error"),
            ("Analysis", "error"),
            ("MeshStats", "error"),
            ("TangentRequest", "error"),
            ("Workspace", "error"),
            ("State", "error"),
            ("Instance", "model"),
            ("Model", "model"),
            ("Response", "model"),
            ("Scene", "scene"),
        ],
    },
];

fn layer_of(krate: &Crate, module: &str) -> Option<usize> {
    krate
        .layers
        .iter()
        .position(|layer| layer.contains(&module))
}

/// The modules a source text names through `crate::`, with the line of each (`root_items`
/// maps a re-exported item to its module).
fn crate_paths(text: &str, root_items: &[(&str, &str)]) -> Vec<(String, usize)> {
    let mut out = Vec::new();
    for (number, line) in text.lines().enumerate() {
        let code = line.split("//").next().unwrap_or("");
        let mut rest = code;
        while let Some(at) = rest.find("crate::") {
            let name: String = rest[at + 7..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            let module = root_items
                .iter()
                .find(|(item, _)| *item == name)
                .map_or(name.clone(), |(_, m)| m.to_string());
            if !module.is_empty() {
                out.push((module, number + 1));
            }
            rest = &rest[at + 7..];
        }
        // `use crate::{a::X, b::Y}` groups.
        if let Some(at) = code.find("crate::{") {
            let group = code[at + 8..].split('}').next().unwrap_or("");
            for part in group.split(',') {
                let name = part.trim().split("::").next().unwrap_or("").to_string();
                if !name.is_empty() {
                    out.push((name, number + 1));
                }
            }
        }
    }
    out
}

fn visit(dir: &Path, files: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            visit(&path, files);
        } else if path.extension().is_some_and(|e| e == "rs") {
            files.push(path);
        }
    }
}

fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

#[test]
fn imports_follow_the_layer_order() {
    let mut violations = Vec::new();
    for krate in &CRATES {
        let src = repository().join(krate.src);
        let mut files = Vec::new();
        visit(&src, &mut files);
        let mut modules = BTreeMap::new();
        for file in &files {
            let relative = file.strip_prefix(&src).unwrap();
            let first = relative
                .components()
                .next()
                .unwrap()
                .as_os_str()
                .to_str()
                .unwrap();
            let module = first.trim_end_matches(".rs");
            if module == "lib" {
                continue;
            }
            let own = layer_of(krate, module).unwrap_or_else(|| {
                panic!("{}/{module} is in no layer: add it to CRATES", krate.src)
            });
            *modules.entry(module.to_string()).or_insert(0) += 1;
            let text = std::fs::read_to_string(file).unwrap();
            for (target, line) in crate_paths(&text, krate.root_items) {
                if target == module {
                    continue;
                }
                match layer_of(krate, &target) {
                    Some(layer) if layer < own => {}
                    _ => violations.push(format!(
                        "{}/{}:{line}: {module} (layer {own}) uses crate::{target}",
                        krate.src,
                        relative.display()
                    )),
                }
            }
        }
        let declared: usize = krate.layers.iter().map(|l| l.len()).sum();
        // Every module of the crate but the re-exported `error` of the library has files.
        assert!(
            modules.len() + 1 >= declared,
            "{}: found only {modules:?}",
            krate.src
        );
    }
    assert!(
        violations.is_empty(),
        "imports against the layer order:\n{}",
        violations.join("\n")
    );
}

/// The checker itself sees the three forms of a path.
#[test]
fn the_checker_sees_use_lines_groups_and_inline_paths() {
    let text = "use crate::solver::Workspace;\nuse crate::{mesh::Mesh, scene};\nlet x = crate::model::MAX;\n// crate::ffi in a comment\n";
    let found: Vec<String> = crate_paths(text, &[]).into_iter().map(|(m, _)| m).collect();
    assert_eq!(found, ["solver", "mesh", "scene", "model"]);
}

/// The source file a `crate::a::b` or `super::b` path of `file` names, if any: the longest
/// prefix of the path that is a file of the tree (`a/b.rs`, or `a/mod.rs`).
fn target_file(src: &Path, file: &Path, path: &[&str]) -> Option<PathBuf> {
    let (mut base, rest) = match path.first() {
        Some(&"crate") => (src.to_path_buf(), &path[1..]),
        Some(&"super") => {
            let dir = file.parent()?.to_path_buf();
            // `super` of a `mod.rs` is the parent folder's module.
            let dir = if file.file_name()? == "mod.rs" {
                dir.parent()?.to_path_buf()
            } else {
                dir
            };
            (dir, &path[1..])
        }
        _ => return None,
    };
    let mut found = None;
    for part in rest {
        let as_file = base.join(format!("{part}.rs"));
        let as_dir = base.join(part);
        if as_file.is_file() {
            found = Some(as_file);
            break;
        } else if as_dir.join("mod.rs").is_file() {
            found = Some(as_dir.join("mod.rs"));
            base = as_dir;
        } else {
            break;
        }
    }
    found.filter(|f| f != file)
}

/// The files each `use crate::...`/`use super::...` line of `file` imports from.
fn file_imports(src: &Path, file: &Path) -> Vec<PathBuf> {
    let text = std::fs::read_to_string(file).unwrap();
    let code = text.split("#[cfg(test)]").next().unwrap_or("");
    let mut out = Vec::new();
    for line in code.lines() {
        let line = line.trim();
        let Some(rest) = line
            .strip_prefix("use ")
            .or_else(|| line.strip_prefix("pub use "))
        else {
            continue;
        };
        let head: Vec<&str> = rest
            .split(['{', ';'])
            .next()
            .unwrap_or("")
            .split("::")
            .filter(|p| !p.is_empty())
            .collect();
        if let Some(target) = target_file(src, file, &head) {
            out.push(target);
        }
    }
    out
}

/// No two source files import each other, directly or through others (the `mod.rs` files,
/// which only declare and re-export, are left out: they are the folders' doors).
#[test]
fn no_import_loop_between_files() {
    for krate in &CRATES {
        no_import_loop_in(&repository().join(krate.src));
    }
}

fn no_import_loop_in(src: &Path) {
    let mut files = Vec::new();
    visit(src, &mut files);
    let is_door = |f: &Path| {
        f.file_name()
            .is_some_and(|n| n == "mod.rs" || n == "lib.rs")
    };
    let graph: BTreeMap<_, Vec<_>> = files
        .iter()
        .filter(|f| !is_door(f))
        .map(|f| {
            let targets = file_imports(src, f)
                .into_iter()
                .filter(|t| !is_door(t))
                .collect();
            (f.clone(), targets)
        })
        .collect();
    // Depth-first search with colours: a grey node met again closes a loop.
    fn visit_node(
        node: &PathBuf,
        graph: &BTreeMap<PathBuf, Vec<PathBuf>>,
        colour: &mut BTreeMap<PathBuf, u8>,
        stack: &mut Vec<PathBuf>,
        loops: &mut Vec<String>,
    ) {
        colour.insert(node.clone(), 1);
        stack.push(node.clone());
        for next in graph.get(node).into_iter().flatten() {
            match colour.get(next).copied().unwrap_or(0) {
                0 => visit_node(next, graph, colour, stack, loops),
                1 => {
                    let at = stack.iter().position(|n| n == next).unwrap();
                    let names: Vec<String> = stack[at..]
                        .iter()
                        .map(|p| p.display().to_string())
                        .collect();
                    loops.push(names.join(" -> "));
                }
                _ => {}
            }
        }
        stack.pop();
        colour.insert(node.clone(), 2);
    }
    let (mut colour, mut loops) = (BTreeMap::new(), Vec::new());
    for node in graph.keys() {
        if colour.get(node).copied().unwrap_or(0) == 0 {
            visit_node(node, &graph, &mut colour, &mut Vec::new(), &mut loops);
        }
    }
    let edges: usize = graph.values().map(Vec::len).sum();
    assert!(
        edges > 20,
        "only {edges} file imports found: the parser is broken"
    );
    assert!(loops.is_empty(), "file import loops:\n{}", loops.join("\n"));
}

//! Gmsh MSH 2.2 and 4.1 files: the committed meshes of `tests/data/gmsh/` with one to
//! three mutations that know the format: truncation, deleted, duplicated and swapped
//! lines, counts and block sizes that lie (off by one, swapped, negative, 10^12,
//! 2^64 - 1), duplicate and missing node ids, NaN, infinite and 1e308 coordinates,
//! inverted and degenerate triangles, moved nodes, junk fields. A file that still parses
//! is built into the model of `scenes/gmsh_two_circles.toml` and updated once.
//!
//! Properties: no panic; a refused file gets an `Error::Gmsh` that names a line and a
//! reason (or, past the parser, a typed non-empty error); an accepted one builds and
//! returns a finite stress and tangent, or fails with a typed, non-empty error.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use arbitrary::{Arbitrary, Unstructured};
use mesorve_core::mesh::gmsh::parse_msh;
use rve::{Error, Model, Scene, TangentRequest};

use crate::driver::{self, Tally};

/// What a line of a valid file is, found by walking it with its own counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    /// A count line: `$Nodes`/`$Elements` headers, `$PhysicalNames` and `$Entities`
    /// counts.
    Count,
    /// A 4.1 node or element block header.
    BlockHeader,
    /// A 4.1 node tag line.
    NodeTag,
    /// Node coordinates (4.1), or `tag x y z` (2.2).
    NodeCoords,
    /// An element line; `first_node` is the field index of its first node tag.
    Element {
        first_node: usize,
        nodes: usize,
    },
    Other,
}

struct Msh {
    lines: Vec<String>,
    roles: Vec<Role>,
}

fn fields(line: &str) -> Vec<&str> {
    line.split_whitespace().collect()
}

/// Classifies the lines of a valid MSH 2.2 or 4.1 file.
fn classify(text: &str) -> Msh {
    let lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut roles = vec![Role::Other; lines.len()];
    let v41 = lines.get(1).is_some_and(|l| l.starts_with("4.1"));
    let mut i = 0;
    let num = |s: &str| s.parse::<usize>().unwrap();
    while i < lines.len() {
        match lines[i].as_str() {
            "$PhysicalNames" | "$Entities" => {
                roles[i + 1] = Role::Count;
                i += 2;
            }
            "$Nodes" if v41 => {
                roles[i + 1] = Role::Count;
                let blocks = num(fields(&lines[i + 1])[0]);
                i += 2;
                for _ in 0..blocks {
                    roles[i] = Role::BlockHeader;
                    let count = num(fields(&lines[i])[3]);
                    for k in 0..count {
                        roles[i + 1 + k] = Role::NodeTag;
                        roles[i + 1 + count + k] = Role::NodeCoords;
                    }
                    i += 1 + 2 * count;
                }
            }
            "$Nodes" => {
                roles[i + 1] = Role::Count;
                let count = num(&lines[i + 1]);
                for k in 0..count {
                    roles[i + 2 + k] = Role::NodeCoords;
                }
                i += 2 + count;
            }
            "$Elements" if v41 => {
                roles[i + 1] = Role::Count;
                let blocks = num(fields(&lines[i + 1])[0]);
                i += 2;
                for _ in 0..blocks {
                    roles[i] = Role::BlockHeader;
                    let f = fields(&lines[i]);
                    let (element_type, count) = (num(f[2]), num(f[3]));
                    let nodes = [0, 2, 3, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1][element_type];
                    for k in 0..count {
                        roles[i + 1 + k] = Role::Element {
                            first_node: 1,
                            nodes,
                        };
                    }
                    i += 1 + count;
                }
            }
            "$Elements" => {
                roles[i + 1] = Role::Count;
                let count = num(&lines[i + 1]);
                for k in 0..count {
                    let f = fields(&lines[i + 2 + k]);
                    let first_node = 3 + num(f[2]);
                    roles[i + 2 + k] = Role::Element {
                        first_node,
                        nodes: f.len() - first_node,
                    };
                }
                i += 2 + count;
            }
            _ => i += 1,
        }
    }
    Msh { lines, roles }
}

#[derive(Arbitrary, Debug, Clone, Copy)]
enum Num {
    Nan,
    Inf,
    NegInf,
    Huge,
    NegHuge,
    NegOne,
    Zero,
    PlusOne,
    MinusOne,
    U64Max,
    I64Min,
    Tera,
    Fraction,
    Garbage,
    Empty,
}

impl Num {
    fn text(self, original: &str) -> String {
        let int = original.parse::<i128>().ok();
        match self {
            Num::Nan => "nan".into(),
            Num::Inf => "inf".into(),
            Num::NegInf => "-inf".into(),
            Num::Huge => "1e308".into(),
            Num::NegHuge => "-1e308".into(),
            Num::NegOne => "-1".into(),
            Num::Zero => "0".into(),
            Num::PlusOne => int.map_or("1".into(), |v| (v + 1).to_string()),
            Num::MinusOne => int.map_or("-1".into(), |v| (v - 1).to_string()),
            Num::U64Max => u64::MAX.to_string(),
            Num::I64Min => i64::MIN.to_string(),
            Num::Tera => "1000000000000".into(),
            Num::Fraction => "1.5".into(),
            Num::Garbage => "x".into(),
            Num::Empty => String::new(),
        }
    }
}

#[derive(Arbitrary, Debug, Clone, Copy)]
enum Target {
    Count,
    BlockHeader,
    NodeTag,
    NodeCoords,
    Element,
    Any,
}

#[derive(Arbitrary, Debug)]
enum Mutation {
    Truncate(u16),
    DeleteLine(u16),
    DuplicateLine(u16),
    SwapLines(u16, u16),
    InsertJunk(u16, u8),
    /// Replaces field `field` of the `k`-th line of a role.
    Field {
        target: Target,
        k: u16,
        field: u8,
        value: Num,
    },
    /// Swaps two fields of a line (e.g. the block and item counts of a 4.1 header).
    SwapFields {
        target: Target,
        k: u16,
        a: u8,
        b: u8,
    },
    /// Gives node `a` the tag of node `b`.
    DuplicateNodeId(u16, u16),
    /// Points a node of element `k` at a tag that no node has.
    MissingNode(u16, u8),
    /// Swaps two nodes of element `k` (a clockwise triangle).
    InvertElement(u16),
    /// Repeats a node of element `k`.
    DegenerateElement(u16),
    /// Moves node `a` onto node `b`.
    CollapseNode(u16, u16),
    /// Moves a node by a fraction of the cell.
    MoveNode(u16, i8, i8),
}

impl Msh {
    fn lines_of(&self, target: Target) -> Vec<usize> {
        (0..self.lines.len())
            .filter(|&i| {
                matches!(
                    (target, self.roles[i]),
                    (Target::Any, _)
                        | (Target::Count, Role::Count)
                        | (Target::BlockHeader, Role::BlockHeader)
                        | (Target::NodeTag, Role::NodeTag)
                        | (Target::NodeCoords, Role::NodeCoords)
                        | (Target::Element, Role::Element { .. })
                )
            })
            .collect()
    }

    fn pick(&self, target: Target, k: u16) -> Option<usize> {
        let lines = self.lines_of(target);
        (!lines.is_empty()).then(|| lines[k as usize % lines.len()])
    }

    fn set_field(&mut self, line: usize, field: usize, value: String) {
        let mut f: Vec<String> = fields(&self.lines[line])
            .into_iter()
            .map(String::from)
            .collect();
        if f.is_empty() {
            return;
        }
        let field = field % f.len();
        f[field] = value;
        self.lines[line] = f.join(" ");
    }

    fn field(&self, line: usize, field: usize) -> String {
        let f = fields(&self.lines[line]);
        f.get(field % f.len().max(1)).unwrap_or(&"").to_string()
    }

    /// The node line holding the coordinates and, for 2.2, the tag (tag field index).
    fn node(&self, k: u16) -> Option<(usize, usize, Option<usize>)> {
        let coords = self.pick(Target::NodeCoords, k)?;
        if fields(&self.lines[coords]).len() == 4 {
            return Some((coords, 1, Some(coords)));
        }
        // 4.1: the tag line of the same node sits `count` lines before its coordinates.
        let tags = self.lines_of(Target::NodeTag);
        let all = self.lines_of(Target::NodeCoords);
        let index = all.iter().position(|&l| l == coords)?;
        Some((coords, 0, tags.get(index).copied()))
    }

    fn apply(&mut self, m: &Mutation) {
        let n = self.lines.len().max(1);
        match *m {
            Mutation::Truncate(_) | Mutation::DeleteLine(_) | Mutation::DuplicateLine(_) => {}
            Mutation::SwapLines(a, b) => self.lines.swap(a as usize % n, b as usize % n),
            Mutation::InsertJunk(k, kind) => {
                let junk = [
                    "$Nodes",
                    "$EndElements",
                    "1 2 3",
                    "",
                    "$Bogus\n$EndBogus",
                    "x",
                ];
                let at = k as usize % (n + 1);
                self.lines
                    .insert(at, junk[kind as usize % junk.len()].into());
                self.roles.insert(at, Role::Other);
            }
            Mutation::Field {
                target,
                k,
                field,
                value,
            } => {
                if let Some(line) = self.pick(target, k) {
                    let original = self.field(line, field as usize);
                    self.set_field(line, field as usize, value.text(&original));
                }
            }
            Mutation::SwapFields { target, k, a, b } => {
                if let Some(line) = self.pick(target, k) {
                    let (fa, fb) = (self.field(line, a as usize), self.field(line, b as usize));
                    self.set_field(line, a as usize, fb);
                    self.set_field(line, b as usize, fa);
                }
            }
            Mutation::DuplicateNodeId(a, b) => {
                if let (Some((_, _, Some(ta))), Some((_, _, Some(tb)))) =
                    (self.node(a), self.node(b))
                {
                    let tag = self.field(tb, 0);
                    self.set_field(ta, 0, tag);
                }
            }
            Mutation::MissingNode(k, which) => {
                if let Some(line) = self.pick(Target::Element, k) {
                    if let Role::Element { first_node, nodes } = self.roles[line] {
                        let at = first_node + which as usize % nodes.max(1);
                        self.set_field(line, at, "987654321".into());
                    }
                }
            }
            Mutation::InvertElement(k) | Mutation::DegenerateElement(k) => {
                if let Some(line) = self.pick(Target::Element, k) {
                    if let Role::Element { first_node, nodes } = self.roles[line] {
                        if nodes >= 2 {
                            let (a, b) = (
                                self.field(line, first_node),
                                self.field(line, first_node + 1),
                            );
                            let invert = matches!(m, Mutation::InvertElement(_));
                            self.set_field(line, first_node, if invert { b } else { a.clone() });
                            self.set_field(line, first_node + 1, a);
                        }
                    }
                }
            }
            Mutation::CollapseNode(a, b) => {
                if let (Some((la, fa, _)), Some((lb, fb, _))) = (self.node(a), self.node(b)) {
                    for c in 0..2 {
                        let v = self.field(lb, fb + c);
                        self.set_field(la, fa + c, v);
                    }
                }
            }
            Mutation::MoveNode(k, dx, dy) => {
                if let Some((line, first, _)) = self.node(k) {
                    for (c, d) in [(0, dx), (1, dy)] {
                        let v: f64 = self.field(line, first + c).parse().unwrap_or(0.0);
                        self.set_field(line, first + c, format!("{:?}", v + f64::from(d) / 16.0));
                    }
                }
            }
        }
    }

    fn text(&self, m: &Mutation) -> String {
        let mut lines = self.lines.clone();
        let n = lines.len().max(1);
        match *m {
            Mutation::DeleteLine(k) => {
                lines.remove(k as usize % n);
            }
            Mutation::DuplicateLine(k) => {
                let i = k as usize % n;
                lines.insert(i, lines[i].clone());
            }
            _ => {}
        }
        let text = lines.join("\n") + "\n";
        match *m {
            Mutation::Truncate(k) => text[..k as usize % text.len()].to_string(),
            _ => text,
        }
    }
}

fn data_files() -> Vec<(String, String)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gmsh");
    ["two_circles_v22.msh", "two_circles_v41.msh"]
        .iter()
        .map(|f| (f.to_string(), std::fs::read_to_string(dir.join(f)).unwrap()))
        .collect()
}

/// A per-thread scratch file for meshes that parse (the scene reads its mesh from a file).
fn scratch() -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(format!("mesh-{}.msh", std::process::id()))
}

#[test]
fn mutated_gmsh_files_are_refused_by_line_or_run() {
    let files = data_files();
    let scene_text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/gmsh_two_circles.toml"),
    )
    .unwrap();
    let groups = vec!["aggregate".to_string()];
    let scratch = scratch();
    driver::run(
        "gmsh_files",
        5000,
        Duration::from_secs(60),
        |u: &mut Unstructured, tally: &mut Tally| {
            let (name, original) = &files[u.choose_index(files.len()).unwrap_or(0)];
            let mut msh = classify(original);
            let count = u.int_in_range(1..=3).unwrap_or(1);
            let mut mutations = Vec::new();
            let mut text = original.clone();
            for _ in 0..count {
                let m = Mutation::arbitrary(u).unwrap_or(Mutation::Truncate(0));
                msh.apply(&m);
                text = msh.text(&m);
                if !matches!(
                    m,
                    Mutation::Truncate(_) | Mutation::DeleteLine(_) | Mutation::DuplicateLine(_)
                ) {
                    mutations.push(m);
                    continue;
                }
                // The line structure changed: re-read the roles from what is left when
                // it is still a valid file, else stop mutating.
                mutations.push(m);
                msh = Msh {
                    lines: text.lines().map(str::to_string).collect(),
                    roles: vec![Role::Other; text.lines().count()],
                };
                break;
            }
            let what = format!("{name} {mutations:?}");
            driver::show(&what, &text);
            match parse_msh(&text, Path::new(name), "matrix", &groups) {
                Err(Error::Gmsh { line, reason, .. }) => {
                    tally.count("refused by the reader");
                    return if line > 0 && reason.len() > 10 {
                        Ok(())
                    } else {
                        Err(format!(
                            "{what}: error without line or reason: {line} {reason}"
                        ))
                    };
                }
                Err(e) => return Err(format!("{what}: untyped reader error {e:?}")),
                Ok(_) => {}
            }
            std::fs::write(&scratch, &text).unwrap();
            let scene = scene_text.replace(
                "../tests/data/gmsh/two_circles_v41.msh",
                scratch.to_str().unwrap(),
            );
            let scene = Scene::from_toml_str(&scene, ".").map_err(|e| e.to_string())?;
            let model = match Model::from_scene(&scene) {
                Ok(m) => Arc::new(m),
                Err(e) => {
                    tally.count("read, refused when built");
                    return if e.to_string().len() > 10 {
                        Ok(())
                    } else {
                        Err(format!("{what}: empty error {e:?}"))
                    };
                }
            };
            let mut ws = model.workspace();
            let mut trial = model.new_state();
            match model.update(
                &model.new_state(),
                [1.1e-5, 0.0, 0.0],
                &mut ws,
                &mut trial,
                TangentRequest::Consistent,
            ) {
                Ok(r) if r.stress.iter().chain(&r.tangent).all(|v| v.is_finite()) => {
                    tally.count("read, built and updated");
                    Ok(())
                }
                Ok(r) => Err(format!(
                    "{what}: non-finite stress or tangent {:?} {:?}",
                    r.stress, r.tangent
                )),
                Err(e) => {
                    tally.count("read and built, update refused");
                    if e.to_string().len() > 10 {
                        Ok(())
                    } else {
                        Err(format!("{what}: empty update error {e:?}"))
                    }
                }
            }
        },
    );
}

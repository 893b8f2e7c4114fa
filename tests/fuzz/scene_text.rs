//! Scene text: the shipped scenes with one to three mutations (deleted, duplicated and
//! swapped lines, truncation, a number or a string replaced by NaN, infinities, 1e308,
//! denormals, wrong types, junk lines, flipped bytes). A scene that parses is meshed and
//! updated once at its first path point when its mesh is small enough for the budget.
//!
//! Properties: no panic; a refused scene gets a typed error that names a key (the
//! dotted key, or the TOML line of a syntax error); an accepted one either builds and
//! returns a finite stress and tangent, or fails with a typed, non-empty error.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use arbitrary::{Arbitrary, Unstructured};
use rve::{Error, Model, Scene, TangentRequest};

use crate::driver::{self, Tally};

/// Scenes whose estimated triangle count exceeds this are validated but not meshed here.
const BUILD_TRIANGLES: f64 = 30_000.0;

#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Value {
    Nan,
    Inf,
    NegInf,
    Huge,
    NegHuge,
    Tiny,
    Denormal,
    Zero,
    NegOne,
    BigInt,
    Text,
    Bool,
    EmptyArray,
    LongArray,
    Table,
    /// The original number times 10^k.
    Scaled(i8),
    Negated,
}

impl Value {
    pub fn text(self, original: &str) -> String {
        match self {
            Value::Nan => "nan".into(),
            Value::Inf => "inf".into(),
            Value::NegInf => "-inf".into(),
            Value::Huge => "1e308".into(),
            Value::NegHuge => "-1e308".into(),
            Value::Tiny => "1e-300".into(),
            Value::Denormal => "5e-324".into(),
            Value::Zero => "0".into(),
            Value::NegOne => "-1".into(),
            Value::BigInt => "99999999999999999999".into(),
            Value::Text => "\"x\"".into(),
            Value::Bool => "true".into(),
            Value::EmptyArray => "[]".into(),
            Value::LongArray => "[1.0, 2.0, 3.0, 4.0]".into(),
            Value::Table => "{ a = 1 }".into(),
            Value::Scaled(k) => match original.parse::<f64>() {
                Ok(x) => format!("{:e}", x * 10f64.powi(i32::from(k))),
                Err(_) => original.into(),
            },
            Value::Negated => match original.strip_prefix('-') {
                Some(rest) => rest.into(),
                None => format!("-{original}"),
            },
        }
    }
}

#[derive(Arbitrary, Debug)]
enum Junk {
    UnknownKey,
    UnknownTable,
    SecondCell,
    HugePath,
    ManyPaths,
    BadUtf8Lookalike,
}

impl Junk {
    fn text(&self) -> &'static str {
        match self {
            Junk::UnknownKey => "bogus_key = 1",
            Junk::UnknownTable => "[bogus]",
            Junk::SecondCell => "[cell]\nsize = [1.0, 1.0]",
            Junk::HugePath => "[[path]]\nto = [1e-4, 0.0, 0.0]\nincrements = 1000000000",
            Junk::ManyPaths => {
                "[[path]]\nto = [1e-4, 0.0, 0.0]\nincrements = 1000000\n\
                 [[path]]\nto = [0.0, 0.0, 0.0]\nincrements = 1000000"
            }
            Junk::BadUtf8Lookalike => "title = \"\u{fffd}\u{0}\"",
        }
    }
}

#[derive(Arbitrary, Debug)]
enum Mutation {
    DeleteLine(u16),
    DuplicateLine(u16),
    SwapLines(u16, u16),
    Truncate(u16),
    ReplaceNumber(u16, Value),
    ReplaceString(u16, Value),
    InsertLine(u16, Junk),
    FlipByte(u16, u8),
}

/// Byte ranges `(start, end)` in a text.
type Spans = Vec<(usize, usize)>;

/// Byte spans of the numbers and of the quoted strings outside comments.
pub fn spans(text: &str) -> (Spans, Spans) {
    let b = text.as_bytes();
    let (mut numbers, mut strings) = (Vec::new(), Vec::new());
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'#' => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'"' => {
                let start = i;
                i += 1;
                while i < b.len() && b[i] != b'"' && b[i] != b'\n' {
                    i += 1;
                }
                strings.push((start, (i + 1).min(b.len())));
                i += 1;
            }
            c if c.is_ascii_digit()
                || ((c == b'-' || c == b'+') && b.get(i + 1).is_some_and(u8::is_ascii_digit)) =>
            {
                let prev_is_word = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
                let start = i;
                i += 1;
                while i < b.len() && (b[i].is_ascii_digit() || b"._eE+-".contains(&b[i])) {
                    i += 1;
                }
                if !prev_is_word {
                    numbers.push((start, i));
                }
            }
            _ => i += 1,
        }
    }
    (numbers, strings)
}

fn pick<T: Copy>(items: &[T], k: u16) -> Option<T> {
    (!items.is_empty()).then(|| items[k as usize % items.len()])
}

/// The identifiers of a line (keys and table names), lowercase.
pub fn identifiers(line: &str) -> Vec<String> {
    let line = line.split('#').next().unwrap_or("");
    line.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|w| w.len() > 1 && w.starts_with(|c: char| c.is_ascii_alphabetic()))
        .map(str::to_lowercase)
        .collect()
}

/// Applies a mutation; returns the text and the lines it touched (for the key check).
fn apply(text: &str, m: &Mutation) -> (String, Vec<String>) {
    let lines: Vec<&str> = text.lines().collect();
    let n = lines.len().max(1);
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    let mut touched = Vec::new();
    match m {
        Mutation::DeleteLine(k) => {
            let i = *k as usize % n;
            if i < out.len() {
                touched.push(out.remove(i));
            }
        }
        Mutation::DuplicateLine(k) => {
            let i = *k as usize % n;
            if i < out.len() {
                touched.push(out[i].clone());
                out.insert(i, out[i].clone());
            }
        }
        Mutation::SwapLines(a, b) => {
            let (i, j) = (*a as usize % n, *b as usize % n);
            if i < out.len() && j < out.len() {
                touched.push(out[i].clone());
                touched.push(out[j].clone());
                out.swap(i, j);
            }
        }
        Mutation::Truncate(k) => {
            let mut at = *k as usize % text.len().max(1);
            while !text.is_char_boundary(at) {
                at -= 1;
            }
            let line_start = text[..at].rfind('\n').map_or(0, |p| p + 1);
            let line_end = text[at..].find('\n').map_or(text.len(), |p| at + p);
            touched.push(text[line_start..line_end].to_string());
            return (text[..at].to_string(), touched);
        }
        Mutation::ReplaceNumber(k, v) | Mutation::ReplaceString(k, v) => {
            let (numbers, strings) = spans(text);
            let list = if matches!(m, Mutation::ReplaceNumber(..)) {
                numbers
            } else {
                strings
            };
            let Some((s, e)) = pick(&list, *k) else {
                return (text.to_string(), touched);
            };
            let line_start = text[..s].rfind('\n').map_or(0, |p| p + 1);
            let line_end = text[e..].find('\n').map_or(text.len(), |p| e + p);
            touched.push(text[line_start..line_end].to_string());
            let new = format!("{}{}{}", &text[..s], v.text(&text[s..e]), &text[e..]);
            return (new, touched);
        }
        Mutation::InsertLine(k, junk) => {
            let i = *k as usize % (out.len() + 1);
            touched.push(junk.text().to_string());
            out.insert(i, junk.text().to_string());
        }
        Mutation::FlipByte(k, x) => {
            let mut bytes = text.as_bytes().to_vec();
            if bytes.is_empty() {
                return (String::new(), touched);
            }
            let i = *k as usize % bytes.len();
            bytes[i] ^= x | 1;
            let line_start = bytes[..i]
                .iter()
                .rposition(|&c| c == b'\n')
                .map_or(0, |p| p + 1);
            let line_end = bytes[i..]
                .iter()
                .position(|&c| c == b'\n')
                .map_or(bytes.len(), |p| i + p);
            touched.push(String::from_utf8_lossy(&bytes[line_start..line_end]).into_owned());
            return (String::from_utf8_lossy(&bytes).into_owned(), touched);
        }
    }
    (out.join("\n") + "\n", touched)
}

/// The shipped scenes, with the directory relative paths in them resolve against.
fn shipped() -> Vec<(PathBuf, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = Vec::new();
    for dir in ["scenes", "scenes/paper", "tests/data/scenes"] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(root.join(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        files.sort();
        for f in files {
            out.push((root.join(dir), std::fs::read_to_string(&f).unwrap()));
        }
    }
    out
}

/// Whether a refusal of the scene names a key: the dotted key of a validation error,
/// a key or table of a mutated line, or the TOML position of a syntax error.
fn names_a_key(e: &Error, touched: &[String], original: &str) -> bool {
    match e {
        Error::Scene { key, reason } => !key.is_empty() && !reason.is_empty(),
        Error::SceneParse(msg) => {
            let msg = msg.to_lowercase();
            let keys_in_scene: Vec<String> = original.lines().flat_map(identifiers).collect();
            msg.contains("line ")
                || msg.contains("key `")
                || touched
                    .iter()
                    .flat_map(|l| identifiers(l))
                    .chain(keys_in_scene)
                    .any(|id| msg.contains(&format!("`{id}`")))
        }
        _ => false,
    }
}

fn estimated_triangles(scene: &Scene) -> f64 {
    let [w, h] = scene.spec.cell.size;
    let m = &scene.spec.mesh;
    2.0 * w * h / (0.5 * 3f64.sqrt() * m.size.min(m.interface_size.unwrap_or(m.size)).powi(2))
}

#[test]
fn mutated_scenes_are_refused_by_key_or_run() {
    let scenes = shipped();
    assert!(scenes.len() >= 10, "found {} scenes", scenes.len());
    driver::run(
        "scene_text",
        1000,
        Duration::from_secs(120),
        |u: &mut Unstructured, tally: &mut Tally| {
            let (base, original) = &scenes[u.choose_index(scenes.len()).unwrap_or(0)];
            let count = u.int_in_range(1..=3).unwrap_or(1);
            let mut text = original.clone();
            let mut touched = Vec::new();
            let mut mutations = Vec::new();
            for _ in 0..count {
                let m = Mutation::arbitrary(u).unwrap_or(Mutation::DeleteLine(0));
                let (t, lines) = apply(&text, &m);
                text = t;
                touched.extend(lines);
                mutations.push(m);
            }
            driver::show(&format!("{mutations:?}"), &text);
            let scene = match Scene::from_toml_str(&text, base) {
                Ok(s) => s,
                Err(e) => {
                    tally.count("refused at parse/validation");
                    return if names_a_key(&e, &touched, original) {
                        Ok(())
                    } else {
                        Err(format!("{mutations:?}: refusal names no key: {e}"))
                    };
                }
            };
            if estimated_triangles(&scene) > BUILD_TRIANGLES {
                tally.count("valid, not meshed (large)");
                return Ok(());
            }
            let model = match Model::from_scene(&scene) {
                Ok(m) => Arc::new(m),
                Err(e) => {
                    tally.count("valid, refused at meshing");
                    return if e.to_string().len() > 10 {
                        Ok(())
                    } else {
                        Err(format!("{mutations:?}: empty meshing error {e:?}"))
                    };
                }
            };
            let mut ws = model.workspace();
            let mut trial = model.new_state();
            let strain = scene.spec.path.first().map_or([1e-5, 0.0, 0.0], |seg| {
                seg.to.map(|v| v / f64::from(seg.increments.max(1)))
            });
            match model.update(
                &model.new_state(),
                strain,
                &mut ws,
                &mut trial,
                TangentRequest::Consistent,
            ) {
                Ok(r) => {
                    tally.count("valid, built and updated");
                    if r.stress.iter().chain(&r.tangent).all(|v| v.is_finite()) {
                        Ok(())
                    } else {
                        Err(format!(
                            "{mutations:?}: update succeeded with a non-finite stress or \
                             tangent {:?} {:?}",
                            r.stress, r.tangent
                        ))
                    }
                }
                Err(e) => {
                    tally.count("valid, built, update refused");
                    if e.to_string().len() > 10 {
                        Ok(())
                    } else {
                        Err(format!("{mutations:?}: empty update error {e:?}"))
                    }
                }
            }
        },
    );
}

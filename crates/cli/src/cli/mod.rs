//! The `rve` command-line tool: argument parsing and the subcommands. A module of the
//! binary only (declared by `src/main.rs`), so the library, and `librve.so` with it, does
//! not link clap; it uses the library through its public API (`rve::...`).

mod info_cmd;
mod mesh_cmd;
mod run_cmd;

use std::path::PathBuf;

use clap::{Parser, Subcommand};

use rve::error::{Error, Result};
use rve::scene::{Scene, DEFAULT_SCENE_NAME, DEFAULT_SCENE_TOML};

#[derive(Parser, Debug)]
#[command(
    name = "rve",
    version,
    about = "Mesoscale RVE of concrete: meshes, solves, homogenizes"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Build the RVE mesh of a scene and print its statistics.
    Mesh(mesh_cmd::MeshArgs),
    /// Follow the scene's strain path and write DIR/response.csv.
    Run(run_cmd::RunArgs),
    /// Print a scene's RVE size, state bytes and umat_nstatv (the UMAT's *DEPVAR: at
    /// least umat_nstatv; umat_nstatv + 5 with the mirrors).
    Info(info_cmd::InfoArgs),
}

/// Loads `path`, or the embedded paper scene when no path is given.
fn load_scene(path: Option<&PathBuf>) -> Result<(Scene, String)> {
    match path {
        Some(p) => Ok((Scene::from_file(p)?, p.display().to_string())),
        None => Ok((Scene::embedded_default()?, DEFAULT_SCENE_NAME.to_string())),
    }
}

/// Loads `path` (the embedded paper scene when none is given) with each `KEY=VALUE` of
/// `sets` applied: `KEY` a dotted scene key (`solver.step_tolerance`,
/// `materials.itz.sigma_c`, `path.0.increments` for an entry of an array; tables that
/// are missing are created), `VALUE` a TOML value (`0.5`, `true`, `"lu"`, `[1, 2]`) or, when it
/// does not parse as one, a string. The scene is then validated as a file would be.
fn load_scene_with(path: Option<&PathBuf>, sets: &[String]) -> Result<(Scene, String)> {
    if sets.is_empty() {
        return load_scene(path);
    }
    let (text, base, name) = match path {
        Some(p) => (
            std::fs::read_to_string(p).map_err(|source| Error::Io {
                path: p.clone(),
                source,
            })?,
            p.parent().map(PathBuf::from).unwrap_or_default(),
            p.display().to_string(),
        ),
        None => (
            DEFAULT_SCENE_TOML.to_string(),
            PathBuf::from("."),
            DEFAULT_SCENE_NAME.to_string(),
        ),
    };
    let parse = |e: toml::de::Error| Error::SceneParse(format!("{name}: {e}"));
    let mut table: toml::Table = text.parse().map_err(parse)?;
    for set in sets {
        set_key(&mut table, set)?;
    }
    let edited = toml::to_string(&table).map_err(|e| Error::SceneParse(e.to_string()))?;
    let with = format!("{name} with --set {}", sets.join(" --set "));
    let scene = Scene::from_toml_str(&edited, base).map_err(|e| match e {
        // Its line numbers are those of the edited scene, which TOML re-serialized.
        Error::SceneParse(msg) => Error::SceneParse(format!("{with}: {msg}")),
        other => other,
    })?;
    Ok((scene, with))
}

/// The part `part` of a key below `node`: a table's entry (created as a table when
/// missing), an array's entry by its index from 0 (`path.0`); `None` otherwise.
fn child<'a>(node: &'a mut toml::Value, part: &str) -> Option<&'a mut toml::Value> {
    match node {
        toml::Value::Table(t) => Some(
            t.entry(part.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new())),
        ),
        toml::Value::Array(a) => a.get_mut(part.parse::<usize>().ok()?),
        _ => None,
    }
}

/// Applies one `KEY=VALUE` of `--set` to `table`; `KEY=` (no value) removes the key.
fn set_key(table: &mut toml::Table, set: &str) -> Result<()> {
    let bad = |why: &str| Error::SceneParse(format!("--set {set}: {why}"));
    let (key, text) = set.split_once('=').ok_or_else(|| bad("not KEY=VALUE"))?;
    if text.trim().is_empty() {
        return remove_key(table, key.trim()).ok_or_else(|| bad("no such key to remove"));
    }
    let value = format!("v = {}", text.trim())
        .parse::<toml::Table>()
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(text.trim().to_string()));
    let parts: Vec<&str> = key.trim().split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err(bad("an empty part in the key"));
    }
    let (first, rest) = parts.split_first().expect("split gives one part at least");
    let Some((leaf, middle)) = rest.split_last() else {
        table.insert(first.to_string(), value);
        return Ok(());
    };
    let new_table = || toml::Value::Table(toml::Table::new());
    let mut node = table.entry(first.to_string()).or_insert_with(new_table);
    for part in middle {
        node = child(node, part).ok_or_else(|| bad(&format!("no `{part}` there")))?;
    }
    match node {
        toml::Value::Table(t) => {
            t.insert(leaf.to_string(), value);
        }
        toml::Value::Array(a) => {
            let entry = leaf.parse::<usize>().ok().and_then(|i| a.get_mut(i));
            *entry.ok_or_else(|| bad(&format!("no entry `{leaf}` in the array")))? = value;
        }
        _ => return Err(bad("the key goes through a value that is not a table")),
    }
    Ok(())
}

/// Removes the dotted `key` (tables only); `None` when it is not there.
fn remove_key(table: &mut toml::Table, key: &str) -> Option<()> {
    let (parents, leaf) = match key.rsplit_once('.') {
        Some((parents, leaf)) => (Some(parents), leaf),
        None => (None, key),
    };
    let mut node = table;
    for part in parents.into_iter().flat_map(|p| p.split('.')) {
        node = node.get_mut(part)?.as_table_mut()?;
    }
    node.remove(leaf).map(|_| ())
}

/// Entry point of the `rve` binary; returns the process exit code.
pub fn main() -> i32 {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Mesh(args) => mesh_cmd::run(&args),
        Command::Run(args) => run_cmd::run(&args),
        Command::Info(args) => info_cmd::run(&args),
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("rve: error: {e}");
            1
        }
    }
}

//! The `rve` command-line tool: argument parsing and the subcommands. A module of the
//! binary only (declared by `src/main.rs`), so the library, and `librve.so` with it, does
//! not link clap; it uses the library through its public API (`rve::...`).

mod info_cmd;
mod mesh_cmd;
mod run_cmd;

use std::path::PathBuf;

use clap::{Parser, Subcommand};

use rve::error::Result;
use rve::scene::{Scene, DEFAULT_SCENE_NAME};

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
    /// Print a scene's RVE size, state bytes and umat_nstatv (the UMAT's *DEPVAR).
    Info(info_cmd::InfoArgs),
}

/// Loads `path`, or the embedded paper scene when no path is given.
fn load_scene(path: Option<&PathBuf>) -> Result<(Scene, String)> {
    match path {
        Some(p) => Ok((Scene::from_file(p)?, p.display().to_string())),
        None => Ok((Scene::embedded_default()?, DEFAULT_SCENE_NAME.to_string())),
    }
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

//! The `rve` command-line tool: argument parsing and the subcommands.

mod mesh_cmd;
mod run_cmd;

pub use run_cmd::{path_points, CSV_HEADER};

use std::path::PathBuf;

use clap::{Parser, Subcommand};

use crate::error::Result;
use crate::scene::{Scene, DEFAULT_SCENE_NAME};

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
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("rve: error: {e}");
            1
        }
    }
}

//! The `rve` command-line tool: runs a scene's strain path (`rve run`), meshes a cell
//! (`rve mesh`) and prints a scene's facts (`rve info`), over the `mesorve` library
//! (`rve::...`). The only crate of the workspace with clap and indicatif, so that
//! `librve.so` links neither.

mod cli;

fn main() {
    std::process::exit(cli::main());
}

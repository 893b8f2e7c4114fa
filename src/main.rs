//! The `rve` command-line tool. The CLI is a module of this binary, not of the library.

mod cli;

fn main() {
    std::process::exit(cli::main());
}

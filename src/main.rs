//! The `rve` command-line tool.
fn main() {
    std::process::exit(rve::cli::main());
}

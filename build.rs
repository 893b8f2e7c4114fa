//! Generates `include/rve.h` from `src/ffi/` with cbindgen.
//!
//! The header is committed; CI regenerates it and fails when `git diff` shows a change.
//! cbindgen only rewrites the file when its content changes, so a fresh checkout stays
//! clean. Set `MESORVE_SKIP_HEADER=1` to skip generation (e.g. `cargo package` verification).

use std::env;
use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=src/ffi");
    println!("cargo:rerun-if-changed=cbindgen.toml");
    println!("cargo:rerun-if-env-changed=MESORVE_SKIP_HEADER");
    if env::var_os("MESORVE_SKIP_HEADER").is_some() {
        return;
    }
    let crate_dir = PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("cargo sets this"));
    let config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml"))
        .expect("cbindgen.toml is valid");
    match cbindgen::Builder::new()
        .with_crate(&crate_dir)
        .with_config(config)
        .generate()
    {
        Ok(bindings) => {
            bindings.write_to_file(crate_dir.join("include/rve.h"));
        }
        Err(e) => panic!("cbindgen failed to generate include/rve.h: {e}"),
    }
}

//! Generates `include/rve.h` from `src/ffi/` with cbindgen.
//!
//! The header is committed; CI regenerates it and fails when `git diff` shows a change.
//! cbindgen only rewrites the file when its content changes, so a fresh checkout stays
//! clean. Set `MESORVE_SKIP_HEADER=1` to skip generation (e.g. `cargo package` verification).

use std::env;
use std::path::PathBuf;

// `ABI_VERSION`, the soname suffix, declared once for the library and this script.
include!("src/ffi/abi_version.rs");

fn main() {
    println!("cargo:rerun-if-changed=src");
    println!("cargo:rerun-if-changed=cbindgen.toml");
    println!("cargo:rerun-if-env-changed=MESORVE_SKIP_HEADER");
    // Versioned soname, so hosts link against `librve.so.<abi>`.
    println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,librve.so.{ABI_VERSION}");
    if env::var_os("MESORVE_SKIP_HEADER").is_some() {
        return;
    }
    let crate_dir = PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("cargo sets this"));
    let mut config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml"))
        .expect("cbindgen.toml is valid");
    // Version macros come from Cargo.toml so header and library cannot disagree.
    let version = env::var("CARGO_PKG_VERSION").expect("cargo sets this");
    let major = env::var("CARGO_PKG_VERSION_MAJOR").expect("cargo sets this");
    let minor = env::var("CARGO_PKG_VERSION_MINOR").expect("cargo sets this");
    let patch = env::var("CARGO_PKG_VERSION_PATCH").expect("cargo sets this");
    config.after_includes = Some(format!(
        "\n#define RVE_VERSION \"{version}\"\n#define RVE_VERSION_MAJOR {major}\n\
         #define RVE_VERSION_MINOR {minor}\n#define RVE_VERSION_PATCH {patch}\n\
         /* ABI version: the soname suffix; bumped on any incompatible change. */\n\
         #define RVE_ABI_VERSION {ABI_VERSION}\n"
    ));
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

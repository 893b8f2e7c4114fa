//! The committed header matches the crate: version macros, ABI version, exported items.

mod common;

#[test]
fn header_version_macros_match_cargo_toml() {
    let header = std::fs::read_to_string(common::repo("include/rve.h")).unwrap();
    let expect = [
        format!("#define RVE_VERSION \"{}\"", env!("CARGO_PKG_VERSION")),
        format!(
            "#define RVE_VERSION_MAJOR {}",
            env!("CARGO_PKG_VERSION_MAJOR")
        ),
        format!(
            "#define RVE_VERSION_MINOR {}",
            env!("CARGO_PKG_VERSION_MINOR")
        ),
        format!(
            "#define RVE_VERSION_PATCH {}",
            env!("CARGO_PKG_VERSION_PATCH")
        ),
        format!("#define RVE_ABI_VERSION {}", rve::ffi::ABI_VERSION),
    ];
    for line in expect {
        assert!(header.contains(&line), "include/rve.h lacks `{line}`");
    }
    for f in [
        "rve_version(void)",
        "rve_version_number(void)",
        "rve_status_message(uint32_t code)",
    ] {
        assert!(header.contains(f), "include/rve.h lacks `{f}`");
    }
    assert!(header.contains("RVE_STATUS_BAD_SCENE = 2"));
}

#[test]
fn version_functions_agree() {
    let v = unsafe { std::ffi::CStr::from_ptr(rve::ffi::rve_version()) };
    assert_eq!(v.to_str().unwrap(), rve::VERSION);
    assert_eq!(rve::ffi::rve_version_number(), 400); // 0.4.0
}

/// Every function `rve.h` declares is re-exported by `rve::ffi` (`src/ffi/mod.rs`), so a
/// Rust bench or test never declares an entry point again.
#[test]
fn every_header_function_is_re_exported() {
    let header = std::fs::read_to_string(common::repo("include/rve.h")).unwrap();
    let module = std::fs::read_to_string(common::repo("src/ffi/mod.rs")).unwrap();
    let exported: String = module
        .split("pub use ")
        .skip(1)
        .map(|s| s.split(';').next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join(" ");
    let words: Vec<&str> = exported
        .split(|c: char| !(c.is_alphanumeric() || c == '_'))
        .collect();
    let declared: Vec<&str> = header
        .lines()
        .filter(|l| l.starts_with(|c: char| c.is_ascii_alphabetic()) && !l.starts_with("typedef"))
        .filter_map(|l| l.split('(').next()?.split([' ', '*']).next_back())
        .filter(|name| name.starts_with("rve_"))
        .collect();
    assert!(
        declared.len() >= 25,
        "functions found in rve.h: {declared:?}"
    );
    let missing: Vec<&&str> = declared.iter().filter(|f| !words.contains(f)).collect();
    assert!(
        missing.is_empty(),
        "rve.h functions rve::ffi does not re-export: {missing:?}"
    );
}

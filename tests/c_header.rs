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
    assert_eq!(rve::ffi::rve_version_number(), 300); // 0.3.0
}

//! The C driver (c_examples/rve_driver.c, built by scripts/build-c-examples) and `rve run`
//! follow the paper's section 5.2.2 cycle; every shared value must agree to the last bit.

mod common;

use std::path::Path;
use std::process::Command;

fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()).collect())
        .collect();
    (header, rows)
}

#[test]
fn c_driver_is_bit_identical_to_rve_run_on_the_cycle() {
    // `cargo test` builds the rlib, not the cdylib the driver links: build the shared
    // library from the same sources and stage it, so the driver never runs a stale copy.
    let st = Command::new(env!("CARGO"))
        .args(["build", "--release", "--lib", "--quiet"])
        .current_dir(common::repo(""))
        .status()
        .unwrap();
    assert!(st.success(), "cargo build --release --lib failed");
    let st = Command::new(common::repo("scripts/build-c-examples"))
        .status()
        .unwrap();
    assert!(st.success(), "scripts/build-c-examples failed");
    let driver = common::repo("target/c_examples/bin/rve_driver");
    let scene = common::repo("scenes/paper_rve_cycle.toml");
    let dir = std::env::temp_dir().join(format!("mesorve-c-driver-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let st = Command::new(env!("CARGO_BIN_EXE_rve"))
        .args(["run", "--quiet", "--out"])
        .arg(&dir)
        .arg(&scene)
        .status()
        .unwrap();
    assert!(st.success());
    let c_csv = dir.join("driver.csv");
    let st = Command::new(&driver)
        .arg(&scene)
        .arg(&c_csv)
        .status()
        .unwrap();
    assert!(st.success());
    let (rh, rust) = read_csv(&dir.join("response.csv"));
    let (ch, c) = read_csv(&c_csv);
    assert_eq!(
        rh[..ch.len()],
        ch[..],
        "the driver's columns are a prefix of rve run's"
    );
    assert_eq!(ch.len(), 20);
    assert_eq!(rust.len(), 60);
    assert_eq!(rust.len(), c.len());
    for (k, (r, c)) in rust.iter().zip(&c).enumerate() {
        for j in 0..ch.len() {
            assert_eq!(
                r[j].to_bits(),
                c[j].to_bits(),
                "step {}, column {}: rve run {:e}, C driver {:e}",
                k + 1,
                ch[j],
                r[j],
                c[j]
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

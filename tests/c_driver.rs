//! The C driver (c_examples/rve_driver.c, built by scripts/build-c-examples) and `rve run`
//! follow the paper's section 5.2.2 cycle; every shared value must agree to the last bit.
//! c_examples/implex_time.c's IMPL-EX path with non-uniform time increments through
//! `rve_update_timed` equals `Instance::update_timed` to the last bit.
//! c_examples/share_batch.c's batch with answer sharing through `rve_update_batch_timed`
//! equals `update_batch` on the same points to the last bit, `shared_from` included.

mod common;

use std::path::Path;
use std::process::Command;
use std::sync::{Arc, Once};

use mesorve_core::solver::TangentRequest;
use rve::{Instance, Model, Scene};

/// Builds the shared library from these sources and the C examples against it, once per
/// test binary (`cargo test` builds the rlib, not the cdylib the examples link: the
/// examples must never run a stale copy).
fn build_examples() {
    static BUILT: Once = Once::new();
    BUILT.call_once(|| {
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
    });
}

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

/// Runs `rve run` and the C driver on `scene` (None: the embedded paper RVE, which the
/// driver creates with `rve_init(NULL)`) and compares every shared value bit for bit;
/// returns the number of increments.
fn compare(scene: Option<&Path>, tag: &str) -> usize {
    let driver = common::repo("target/c_examples/bin/rve_driver");
    let dir = std::env::temp_dir().join(format!("mesorve-c-driver-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut run = Command::new(common::rve_exe());
    run.args(["run", "--quiet", "--out"]).arg(&dir);
    if let Some(scene) = scene {
        run.arg(scene);
    }
    assert!(run.status().unwrap().success());
    let c_csv = dir.join("driver.csv");
    let st = Command::new(&driver)
        .arg(scene.unwrap_or(Path::new("-")))
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
    assert_eq!(rust.len(), c.len());
    for (k, (r, c)) in rust.iter().zip(&c).enumerate() {
        for j in 0..ch.len() {
            assert_eq!(
                r[j].to_bits(),
                c[j].to_bits(),
                "{tag}, step {}, column {}: rve run {:e}, C driver {:e}",
                k + 1,
                ch[j],
                r[j],
                c[j]
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
    rust.len()
}

#[test]
fn c_driver_is_bit_identical_to_rve_run_on_the_cycle_and_the_embedded_scene() {
    build_examples();
    let cycle = common::repo("scenes/paper_rve_cycle.toml");
    assert_eq!(compare(Some(&cycle), "cycle"), 60);
    // rve_init(NULL): the embedded scene, the one `rve run` solves without an argument.
    assert_eq!(compare(None, "embedded"), 20);
}

#[test]
fn implex_time_through_c_is_bit_identical_to_instance_update_timed() {
    build_examples();
    let scene = common::repo("scenes/paper_rve_host_implex.toml");
    let csv = std::env::temp_dir().join(format!("mesorve-implex-time-{}.csv", std::process::id()));
    // The program's own checks (scaled times, unit times against none, the path's times
    // against none) must pass too.
    let st = Command::new(common::repo("target/c_examples/bin/implex_time"))
        .arg(&scene)
        .arg(&csv)
        .status()
        .unwrap();
    assert!(st.success(), "implex_time failed");
    let (header, rows) = read_csv(&csv);
    std::fs::remove_file(&csv).ok();
    assert_eq!(header[2], "dtime");
    assert_eq!(rows.len(), 64);
    let model =
        Arc::new(Model::from_scene(&common::scene("scenes/paper_rve_host_implex.toml")).unwrap());
    let mut instance = Instance::new(model.clone());
    let mut ws = model.workspace();
    for (k, row) in rows.iter().enumerate() {
        let eps = [row[3], row[4], row[5]];
        let r = instance
            .update_timed(eps, row[2], &mut ws, TangentRequest::Consistent)
            .unwrap();
        instance.commit().unwrap();
        let rust = r.stress.iter().chain(&r.tangent);
        for (j, (a, b)) in rust.zip(&row[6..18]).enumerate() {
            assert_eq!(
                a.to_bits(),
                b.to_bits(),
                "increment {}, column {}: Instance::update_timed {a:e}, C {b:e}",
                k + 1,
                header[6 + j]
            );
        }
        assert_eq!(
            r.report.factorizations as f64,
            row[20],
            "increment {}",
            k + 1
        );
    }
}

/// The IMPL-EX host scene with `share_tolerance` and `sigma_c` set, as share_batch.c
/// makes its two materials.
fn sharing_model(tol: &str, sigma_c: &str) -> Arc<Model> {
    let text = std::fs::read_to_string(common::repo("scenes/paper_rve_host_implex.toml"))
        .unwrap()
        .replace(
            "[solver]\n",
            &format!("[solver]\nshare_tolerance = {tol}\n"),
        )
        .replace("sigma_c = 4.0", &format!("sigma_c = {sigma_c}"));
    let scene = Scene::from_toml_str(&text, common::repo("scenes")).unwrap();
    Arc::new(Model::from_scene(&scene).unwrap())
}

#[test]
fn share_batch_through_c_is_bit_identical_to_update_batch() {
    build_examples();
    let csv = std::env::temp_dir().join(format!("mesorve-share-batch-{}.csv", std::process::id()));
    // The program's own checks (sharing off = the exact path, 1 = 2 threads, within the
    // tolerance) must pass too.
    let st = Command::new(common::repo("target/c_examples/bin/share_batch"))
        .arg(common::repo("scenes/paper_rve_host_implex.toml"))
        .arg("0.02")
        .arg(&csv)
        .status()
        .unwrap();
    assert!(st.success(), "share_batch failed");
    let (header, rows) = read_csv(&csv);
    std::fs::remove_file(&csv).ok();
    assert_eq!(header[3], "shared_from");
    let models = [sharing_model("0.02", "4.0"), sharing_model("0.02", "4.5")];
    let n = rows.iter().filter(|r| r[0] == 1.0).count();
    assert_eq!((n, rows.len() % n), (32, 0));
    let mut points: Vec<Instance> = rows[..n]
        .iter()
        .map(|r| Instance::new(models[r[2] as usize].clone()))
        .collect();
    let mut shared = 0;
    for increment in rows.chunks(n) {
        let strains: Vec<[f64; 3]> = increment.iter().map(|r| [r[4], r[5], r[6]]).collect();
        let (stresses, reports) = common::batch_consistent(&mut points, &strains, 2);
        points.iter_mut().for_each(|p| p.commit().unwrap());
        for (k, r) in increment.iter().enumerate() {
            let from = reports[k].shared_from.map_or(0.0, |j| (j + 1) as f64);
            assert_eq!(from, r[3], "increment {}, point {k}: shared_from", r[0]);
            shared += usize::from(from > 0.0);
            for j in 0..3 {
                assert_eq!(
                    stresses[k][j].to_bits(),
                    r[7 + j].to_bits(),
                    "increment {}, point {k}, {}: update_batch {:e}, C {:e}",
                    r[0],
                    header[7 + j],
                    stresses[k][j],
                    r[7 + j]
                );
            }
        }
    }
    assert!(shared > 0, "the C run shared nothing");
}

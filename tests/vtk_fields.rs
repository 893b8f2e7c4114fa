//! The micro fields of `rve run --vtk` and `Model::write_vtu`: the area average of the
//! per-triangle stresses is the homogenized stress, the ITZ fields follow the law, writing
//! leaves the state alone, and the CLI's CSV does not change with `--vtk`.

mod common;

use std::process::Command;
use std::sync::Arc;

use rve::io::{BRANCH_CONTACT, BRANCH_LOADING, BRANCH_UNLOADING};
use rve::scene::path_points;
use rve::{Instance, Model, TangentRequest};

/// Along the paper's load-unload-contact cycle: every committed state's area-averaged
/// cell stress equals the homogenized stress (the same sum in another order: round-off).
#[test]
fn area_average_of_cell_stresses_is_the_homogenized_stress() {
    let scene = common::scene("scenes/paper_rve_cycle.toml");
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut instance = Instance::new(model.clone());
    let mut ws = model.workspace();
    let mut seen = [false; 3];
    let mut worst = 0.0f64;
    for eps in path_points(&scene.spec.path) {
        let r = instance.update(eps, &mut ws, TangentRequest::None).unwrap();
        instance.commit().unwrap();
        let fields = model.fields(instance.committed()).unwrap();
        assert_eq!(fields.stress.len(), model.mesh().triangles.len());
        assert_eq!(fields.itz.len(), model.mesh().interfaces.len());
        let avg = fields.average_stress(model.discretization().volume);
        let scale = fields
            .stress
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        for k in 0..3 {
            let err = (avg[k] - r.stress[k]).abs() / scale;
            worst = worst.max(err);
            assert!(
                err <= 1e-12,
                "{eps:?}: component {k}: {avg:?} vs {:?}",
                r.stress
            );
        }
        for e in &fields.itz {
            let m = e.measures;
            assert!(m.max_opening_ratio >= 0.0 && (0.0..1.0).contains(&m.damage));
            assert!(e.closed_points <= model.discretization().points_per_interface());
            match e.branch {
                BRANCH_LOADING => seen[0] = true,
                BRANCH_UNLOADING => seen[1] = true,
                BRANCH_CONTACT => {
                    assert!(e.closed_points > 0);
                    seen[2] = true;
                }
                b => panic!("branch {b}"),
            }
        }
    }
    assert_eq!(seen, [true; 3], "the cycle visits every branch");
    eprintln!("max relative error of the area-averaged stress: {worst:.1e}");
}

/// At a committed state an open point has `delta <= delta_max` (equal on the loading
/// branch), so an element without closed points has mean `delta/delta_c` at most its
/// mean `delta_max/delta_c`; on the monotonic path some elements load.
#[test]
fn open_elements_do_not_exceed_their_delta_max() {
    let scene = common::scene("scenes/paper_rve.toml");
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut instance = Instance::new(model.clone());
    let mut ws = model.workspace();
    let mut checked = 0;
    for eps in path_points(&scene.spec.path) {
        instance.update(eps, &mut ws, TangentRequest::None).unwrap();
        instance.commit().unwrap();
        for e in model.fields(instance.committed()).unwrap().itz {
            if e.closed_points == 0 {
                let m = e.measures;
                assert!(m.opening_ratio <= m.max_opening_ratio * (1.0 + 1e-12));
                checked += usize::from(e.branch == BRANCH_LOADING);
            }
        }
    }
    assert!(checked > 0);
}

/// Writing a VTK file reads the state only; an unwritable path is a typed I/O error.
#[test]
fn write_vtu_leaves_the_state_and_reports_bad_paths() {
    let scene = common::scene("scenes/paper_rve.toml");
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut instance = Instance::new(model.clone());
    let mut ws = model.workspace();
    instance
        .update([1e-4, 0.0, 0.0], &mut ws, TangentRequest::None)
        .unwrap();
    instance.commit().unwrap();
    let before = instance.committed().clone();
    let dir = std::env::temp_dir().join(format!("rve_vtk_fields_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("state.vtu");
    model.write_vtu(instance.committed(), &path).unwrap();
    assert_eq!(instance.committed(), &before);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(r#"Name="max_opening_ratio""#));
    let err = model
        .write_vtu(instance.committed(), &dir.join("missing/dir/state.vtu"))
        .unwrap_err();
    assert!(matches!(err, rve::Error::Io { .. }), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--vtk` adds files and changes nothing else: response.csv is the same but for the
/// timing column; one .vtu per row and the index.
#[test]
fn cli_vtk_series_leaves_the_csv_unchanged() {
    let dir = std::env::temp_dir().join(format!("rve_vtk_cli_{}", std::process::id()));
    let scene = common::repo("scenes/paper_rve.toml");
    let run = |out: &str, vtk: bool| {
        let out = dir.join(out);
        let mut cmd = Command::new(common::rve_exe());
        cmd.args(["run", scene.to_str().unwrap(), "--quiet", "--out"])
            .arg(&out);
        if vtk {
            cmd.arg("--vtk").arg(out.join("vtk"));
        }
        let o = cmd.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let csv = std::fs::read_to_string(out.join("response.csv")).unwrap();
        let header = csv.lines().next().unwrap();
        let seconds = header.split(',').position(|c| c == "seconds").unwrap();
        csv.lines()
            .map(|l| {
                let mut cols: Vec<&str> = l.split(',').collect();
                cols.remove(seconds);
                cols.join(",")
            })
            .collect::<Vec<_>>()
    };
    let plain = run("plain", false);
    let with_vtk = run("vtk", true);
    assert_eq!(plain, with_vtk);
    let vtk = dir.join("vtk/vtk");
    let n = std::fs::read_dir(&vtk)
        .unwrap()
        .filter(|e| e.as_ref().unwrap().path().extension().unwrap() == "vtu")
        .count();
    assert_eq!(n, plain.len() - 1);
    let pvd = std::fs::read_to_string(vtk.join("series.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet ").count(), n);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Off a terminal `rve run` prints a line per increment and no progress bar; `--quiet`
/// prints nothing.
#[test]
fn no_progress_bar_off_a_terminal_and_silence_with_quiet() {
    let dir = std::env::temp_dir().join(format!("rve_progress_{}", std::process::id()));
    let scene = common::repo("scenes/paper_rve.toml");
    let run = |quiet: bool| {
        let mut cmd = Command::new(common::rve_exe());
        cmd.args(["run", scene.to_str().unwrap(), "--out"])
            .arg(&dir);
        if quiet {
            cmd.arg("--quiet");
        }
        let o = cmd.output().unwrap();
        assert!(o.status.success());
        String::from_utf8(o.stderr).unwrap()
    };
    let loud = run(false);
    assert_eq!(loud.lines().filter(|l| l.starts_with("step ")).count(), 20);
    assert!(
        !loud.contains("increments,"),
        "a progress bar off a terminal"
    );
    assert_eq!(run(true), "");
    std::fs::remove_dir_all(&dir).unwrap();
}

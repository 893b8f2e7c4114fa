//! The `rve` binary: `rve mesh` JSON statistics, VTK and SVG output, error exit codes.

#[path = "../../../tests/common/paths.rs"]
mod common;

use std::process::Command;

fn rve(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rve"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn mesh_json_has_the_documented_keys() {
    let scene = common::repo("scenes/paper_rve.toml");
    let out = rve(&["mesh", scene.to_str().unwrap(), "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for key in [
        "nodes",
        "triangles",
        "matrix_triangles",
        "inclusion_triangles",
        "interface_elements",
        "inclusion_area_fraction",
        "min_angle_deg",
        "periodic_sides_match",
    ] {
        assert!(v.get(key).is_some(), "missing key {key}");
    }
    assert_eq!(v["periodic_sides_match"], serde_json::Value::Bool(true));
    let t = v["triangles"].as_u64().unwrap();
    assert_eq!(
        t,
        v["matrix_triangles"].as_u64().unwrap() + v["inclusion_triangles"].as_u64().unwrap()
    );
}

#[test]
fn embedded_default_writes_vtk_and_svg() {
    let dir = std::env::temp_dir().join(format!("rve-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (vtu, svg) = (dir.join("rve.vtu"), dir.join("rve.svg"));
    let out = rve(&[
        "mesh",
        "--json",
        "--vtk",
        vtu.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let (tri, itz) = (
        v["triangles"].as_u64().unwrap(),
        v["interface_elements"].as_u64().unwrap(),
    );

    let vtk = std::fs::read_to_string(&vtu).unwrap();
    assert!(vtk.contains(&format!("NumberOfCells=\"{}\"", tri + itz)));
    assert!(vtk.contains(&format!("NumberOfPoints=\"{}\"", v["nodes"])));
    // Cell types: tri triangles (5) then itz quads (9).
    let types = vtk
        .split("Name=\"types\" format=\"ascii\">")
        .nth(1)
        .unwrap();
    let types: Vec<&str> = types
        .split("</DataArray>")
        .next()
        .unwrap()
        .split_whitespace()
        .collect();
    assert_eq!(types.iter().filter(|t| **t == "5").count() as u64, tri);
    assert_eq!(types.iter().filter(|t| **t == "9").count() as u64, itz);
    assert!(vtk.trim_end().ends_with("</VTKFile>"));

    let pic = std::fs::read_to_string(&svg).unwrap();
    assert_eq!(pic.matches("<polygon").count() as u64, tri);
    assert_eq!(pic.matches("<line").count() as u64, itz);
    std::fs::remove_dir_all(&dir).ok();
}

/// A fresh temporary directory `NAME-<pid>` and in it the paper scene with one
/// replacement, `scene.toml`.
fn edited_paper_scene(
    name: &str,
    replace: (&str, &str),
) -> (std::path::PathBuf, std::path::PathBuf) {
    let dir = std::env::temp_dir().join(format!("{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scene.toml");
    std::fs::write(&path, common::paper_scene_with(&[replace])).unwrap();
    (dir, path)
}

#[test]
fn bad_scene_exits_nonzero_with_the_key_in_the_message() {
    let (dir, path) = edited_paper_scene("rve-cli-bad", ("delta_c = 0.0002", "delta_c = 0.0"));
    let out = rve(&["mesh", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("materials.itz.delta_c"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Parses `response.csv` into (header, rows).
fn read_csv(path: &std::path::Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
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
fn run_follows_the_unilateral_cycle_and_writes_the_csv() {
    let dir = std::env::temp_dir().join(format!("rve-run-{}", std::process::id()));
    let scene = common::repo("scenes/paper_rve_cycle.toml");
    let out = rve(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (header, rows) = read_csv(&dir.join("response.csv"));
    let expected = [
        "step",
        "eps_xx",
        "eps_yy",
        "gamma_xy",
        "sig_xx",
        "sig_yy",
        "sig_xy",
        "D11",
        "D12",
        "D13",
        "D21",
        "D22",
        "D23",
        "D31",
        "D32",
        "D33",
        "iterations",
        "substeps",
    ];
    assert_eq!(&header[..expected.len()], &expected.map(String::from)[..]);
    assert_eq!(rows.len(), 60, "section 5.2.2 has 60 increments");
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (eps, sig, d11) = (col("eps_xx"), col("sig_xx"), col("D11"));
    // The path: up to 2.3e-4 at increment 20, then down to -4.5e-4.
    assert_eq!(rows[19][eps], 2.3e-4);
    assert_eq!(rows[59][eps], -4.5e-4);
    // Unilateral effect: the unloading stiffness (damaged, secant to the origin) is well
    // below the virgin one, and closure in compression recovers it.
    let virgin = rows[0][d11];
    let unloading = rows[25][d11];
    let compression = rows[50][d11];
    assert!(
        unloading < 0.8 * virgin,
        "unloading {unloading} vs virgin {virgin}"
    );
    assert!(
        compression > 0.95 * virgin,
        "compression {compression} vs virgin {virgin}"
    );
    // Secant unloading passes through the origin: stress and strain shrink together.
    let (e25, s25) = (rows[25][eps], rows[25][sig]);
    let (e30, s30) = (rows[30][eps], rows[30][sig]);
    assert!(
        (s25 / e25 - s30 / e30).abs() < 1e-6 * (s25 / e25),
        "unloading is not secant"
    );
    assert!(rows[59][sig] < 0.0);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn info_gives_the_umat_nstatv_that_keeps_the_state() {
    for (scene, integration) in [
        ("scenes/paper_rve.toml", "implicit"),
        ("scenes/paper_rve_host_implex.toml", "implex"),
    ] {
        let path = common::repo(scene);
        let out = rve(&["info", path.to_str().unwrap(), "--json"]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let model = rve::Model::from_scene(&common::scene(scene)).unwrap();
        let nstatv = v["umat_nstatv"].as_u64().unwrap() as usize;
        assert_eq!(nstatv, model.statev_len());
        assert_eq!(v["unknowns"].as_u64(), Some(722));
        assert_eq!(v["itz_points"].as_u64(), Some(288));
        assert_eq!(v["integration"], integration);
        // The target: the paper RVE's state in at most 800 host state variables.
        assert!(nstatv <= 800, "{scene}: {nstatv}");
        assert!(v["instance_bytes"].as_u64().unwrap() > v["checkpoint_bytes"].as_u64().unwrap());
    }
    let text = rve(&["info"]);
    assert!(text.status.success());
    assert!(String::from_utf8_lossy(&text.stdout).contains("umat_nstatv"));
}

/// `rve run --set KEY=VALUE` gives the run of the scene whose file says so: the same
/// `response.csv` (but `seconds`) as an edited copy, and another than the scene's own.
#[test]
fn run_set_equals_the_edited_scene() {
    let (dir, edited) = edited_paper_scene("rve-run-set", ("sigma_c = 4.0", "sigma_c = 3.5"));
    let run = |name: &str, extra: &[&str]| {
        let out_dir = dir.join(name);
        let mut args = vec!["run", "--out", out_dir.to_str().unwrap(), "--quiet"];
        args.extend_from_slice(extra);
        let out = rve(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let (header, rows) = read_csv(&out_dir.join("response.csv"));
        let seconds = header.iter().position(|h| h == "seconds").unwrap();
        rows.into_iter()
            .map(|mut r| {
                r.remove(seconds);
                r
            })
            .collect::<Vec<Vec<f64>>>()
    };
    let by_file = run("file", &[edited.to_str().unwrap()]);
    let by_set = run("set", &["--set", "materials.itz.sigma_c=3.5"]);
    let own = run("own", &[]);
    assert_eq!(by_set, by_file);
    assert_ne!(by_set, own);
    let (path_dir, shorter) =
        edited_paper_scene("rve-run-set-path", ("increments = 20", "increments = 7"));
    let by_path_file = run("path_file", &[shorter.to_str().unwrap()]);
    let by_path_set = run("path_set", &["--set", "path.0.increments=7"]);
    assert_eq!(by_path_set.len(), 7);
    assert_eq!(by_path_set, by_path_file);
    for (set, why) in [
        ("materials.itz.sigma_c", "not KEY=VALUE"),
        ("materials.itz.sigma_c=-1", "sigma_c"),
        ("materials..young=1", "an empty part"),
        ("path.3.increments=7", "no `3`"),
    ] {
        let out = rve(&[
            "run",
            "--out",
            dir.join("bad").to_str().unwrap(),
            "--quiet",
            "--set",
            set,
        ]);
        assert_eq!(out.status.code(), Some(1), "--set {set}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(why), "--set {set}: {err}");
    }
    std::fs::remove_dir_all(&path_dir).ok();
    std::fs::remove_dir_all(&dir).ok();
}

/// `rve mesh --set` and `rve info --set` read the scene a file with the key would be:
/// the same statistics as the edited file, and a bad key is refused as by `rve run`.
#[test]
fn mesh_and_info_set_equal_the_edited_scene() {
    let (dir, edited) = edited_paper_scene("mesh_set", ("size = 0.84", "size = 1.6"));
    let json = |args: &[&str]| -> serde_json::Value {
        let out = rve(args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let paper = common::repo("scenes/paper_rve.toml");
    let paper = paper.to_str().unwrap();
    let by_file = json(&["mesh", edited.to_str().unwrap(), "--json"]);
    let by_set = json(&["mesh", paper, "--set", "mesh.size=1.6", "--json"]);
    let plain = json(&["mesh", paper, "--json"]);
    for key in ["nodes", "triangles", "interface_elements"] {
        assert_eq!(by_set[key], by_file[key], "{key}");
    }
    assert_ne!(
        by_set["triangles"], plain["triangles"],
        "the edit changes the mesh"
    );
    let info = json(&[
        "info",
        paper,
        "--set",
        "solver.integration=\"implex\"",
        "--json",
    ]);
    assert_eq!(info["integration"], "implex");
    let out = rve(&["info", paper, "--set", "solver.integraton=\"implex\""]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("integraton"));
    std::fs::remove_dir_all(&dir).ok();
}

/// `--set KEY=` removes the key: the failing scene without its paste cracks meshes the
/// ITZ alone, as the same cell without the table does; a key that is not there is refused.
#[test]
fn set_with_no_value_removes_the_key() {
    let json = |args: &[&str]| -> serde_json::Value {
        let out = rve(args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let fracture = common::repo("scenes/concrete_fracture.toml");
    let fracture = fracture.to_str().unwrap();
    let whole = json(&["mesh", fracture, "--json"]);
    let itz_only = json(&[
        "mesh",
        fracture,
        "--set",
        "effects.paste_cracking=false",
        "--set",
        "materials.paste_crack=",
        "--json",
    ]);
    assert!(
        whole["interface_elements"].as_u64() > itz_only["interface_elements"].as_u64(),
        "{whole} against {itz_only}"
    );
    // The same geometry and mesh keys as the host scene, whose cell has the ITZ alone.
    let host = common::repo("scenes/paper_rve_host_implex.toml");
    let host = json(&["mesh", host.to_str().unwrap(), "--json"]);
    for key in ["nodes", "triangles", "interface_elements"] {
        assert_eq!(itz_only[key], host[key], "{key}");
    }
    let out = rve(&["mesh", fracture, "--set", "materials.paste_crak="]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no such key to remove"));
}

//! Regression tests for what the fuzzing of `tests/fuzz/` found, and the up-front refusal
//! of legitimate but enormous requests (each names its limit).

mod common;

use std::io::Write;
use std::path::{Path, PathBuf};

use mesorve_core::mesh::gmsh::{parse_msh, read_msh, MAX_DECLARED_ITEMS, MAX_FILE_BYTES};
use rve::scene::{MAX_PATH_INCREMENTS, MAX_TRIANGLES};
use rve::{Error, Model, Scene, TangentRequest};

fn scene_error(text: &str) -> Error {
    match Scene::from_toml_str(text, common::repo("scenes")) {
        Err(e) => e,
        Ok(_) => panic!("the scene must be refused"),
    }
}

/// Fuzz case scene_text seed 118320: Young's moduli of 1e-300 and 5e-324 (positive and
/// finite, so valid) gave a model with a NaN elastic tangent and successful updates with
/// a NaN tangent. Now the model is refused, naming the non-finite result.
#[test]
fn a_model_or_update_never_hands_out_a_non_finite_tangent() {
    let text = std::fs::read_to_string(common::repo("tests/data/scenes/two_circles.toml"))
        .unwrap()
        .replacen("young = 25000.0", "young = 1e-300", 1)
        .replacen("young = 30000.0", "young = 5e-324", 1);
    let scene = Scene::from_toml_str(&text, common::repo("tests/data/scenes")).unwrap();
    match Model::from_scene(&scene) {
        Err(Error::Solve { reason, .. }) => assert!(reason.contains("not finite"), "{reason}"),
        Err(e) => panic!("expected a solver error naming the non-finite result, got {e}"),
        Ok(model) => {
            let (mut ws, mut trial) = (model.workspace(), model.new_state());
            let r = model.update(
                &model.new_state(),
                [1e-5, 0.0, 0.0],
                &mut ws,
                &mut trial,
                TangentRequest::Consistent,
            );
            panic!(
                "model accepted, elastic tangent {:?}, update {r:?}",
                model.elastic_tangent()
            );
        }
    }
}

#[test]
fn a_path_of_more_than_a_million_increments_is_refused() {
    let one = "[[path]]\nto = [1e-4, 0.0, 0.0]\nincrements = 600000\n";
    let e = scene_error(&common::paper_scene_with(&[(
        "[[path]]",
        &format!("{one}{one}[[path]]"),
    )]));
    let msg = e.to_string();
    assert!(
        msg.contains("path[1].increments")
            && msg.contains("1200000")
            && msg.contains(&MAX_PATH_INCREMENTS.to_string()),
        "{msg}"
    );
    // 10^9 increments in one segment.
    let e = scene_error(&common::paper_scene_with(&[(
        "increments = 20",
        "increments = 1000000000",
    )]));
    assert!(e.to_string().contains("path[0].increments"), "{e}");
}

#[test]
fn a_mesh_of_10_to_the_8_triangles_is_refused_before_meshing() {
    // 10 x 10 mm at h = 0.0015: about 1e8 triangles.
    let e = scene_error(&common::paper_scene_with(&[
        ("size = 0.84", "size = 0.0015"),
        ("interface_size = 0.48", "interface_size = 0.0015"),
    ]));
    let msg = e.to_string();
    assert!(
        msg.contains("mesh.size") && msg.contains("2000000"),
        "{msg}"
    );
    assert_eq!(MAX_TRIANGLES, 2_000_000);
}

fn gmsh_error(text: &str) -> (usize, String) {
    match parse_msh(text, Path::new("x.msh"), "matrix", &["aggregate".into()]) {
        Err(Error::Gmsh { line, reason, .. }) => (line, reason),
        other => panic!("expected a Gmsh error, got {other:?}"),
    }
}

const HEADER_22: &str = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
const HEADER_41: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";

#[test]
fn huge_declared_counts_are_refused_with_the_limit() {
    let limit = MAX_DECLARED_ITEMS.to_string();
    let huge = "100000000000";
    let cases = [
        (
            format!("{HEADER_22}$Nodes\n{huge}\n1 0 0 0\n"),
            5,
            "number of nodes",
        ),
        (
            format!("{HEADER_22}$Nodes\n0\n$EndNodes\n$Elements\n{huge}\n"),
            8,
            "number of elements",
        ),
        (
            format!("{HEADER_41}$Nodes\n1 {huge} 1 {huge}\n"),
            5,
            "number of nodes",
        ),
        (
            format!("{HEADER_41}$Nodes\n1 1 1 1\n2 1 0 {huge}\n"),
            6,
            "in the block",
        ),
        (
            format!("{HEADER_41}$Nodes\n0 0 0 0\n$EndNodes\n$Elements\n1 1 1 1\n2 1 2 {huge}\n"),
            9,
            "in the block",
        ),
    ];
    for (text, line, what) in cases {
        let (l, reason) = gmsh_error(&text);
        assert_eq!(l, line, "{reason}");
        assert!(
            reason.contains(what) && reason.contains(huge) && reason.contains(&limit),
            "{reason}"
        );
    }
    // The largest count allowed is read as usual (and found truncated).
    let (_, reason) = gmsh_error(&format!("{HEADER_22}$Nodes\n{MAX_DECLARED_ITEMS}\n"));
    assert!(reason.contains("truncated"), "{reason}");
}

#[test]
fn an_msh_file_over_the_size_limit_is_refused_unread() {
    let path: PathBuf = Path::new(env!("CARGO_TARGET_TMPDIR")).join("huge_sparse.msh");
    let mut f = std::fs::File::create(&path).unwrap();
    f.write_all(HEADER_22.as_bytes()).unwrap();
    // Sparse: no disk space is used and nothing is read.
    f.set_len(MAX_FILE_BYTES + 1).unwrap();
    drop(f);
    let e = read_msh(&path, "matrix", &["aggregate".into()]).unwrap_err();
    let _ = std::fs::remove_file(&path);
    let msg = e.to_string();
    assert!(
        msg.contains(&(MAX_FILE_BYTES + 1).to_string()) && msg.contains("limit"),
        "{msg}"
    );
}

/// Fuzz case call_sequences seed 40: an update refused for a bad argument (an unknown
/// tangent request, a NULL output) left the previous successful trial in place, so a
/// following commit accepted it, against the header's "after any failure there is no
/// trial to commit".
#[test]
fn an_update_refused_for_its_arguments_discards_the_trial() {
    use rve::ffi::*;
    use std::ffi::CString;
    let ok = RveStatus::Ok as u32;
    let path = CString::new(common::repo("scenes/paper_rve.toml").to_str().unwrap()).unwrap();
    let mut h = 0;
    assert_eq!(unsafe { rve_init_file(path.as_ptr(), &mut h) }, ok);
    let e = [2e-5, 0.0, 0.0];
    let (mut stress, mut tangent) = ([0.0; 3], [0.0; 9]);
    let consistent = RveTangentRequest::Consistent as i32;
    let mut good = || unsafe {
        rve_update(
            h,
            e.as_ptr(),
            stress.as_mut_ptr(),
            tangent.as_mut_ptr(),
            consistent,
        )
    };
    assert_eq!(good(), ok);
    let mut stress2 = [0.0; 3];
    let bad_request =
        unsafe { rve_update(h, e.as_ptr(), stress2.as_mut_ptr(), std::ptr::null_mut(), 7) };
    assert_eq!(bad_request, RveStatus::InvalidArgument as u32);
    assert_eq!(rve_commit(h), RveStatus::NoTrial as u32);
    assert_eq!(good(), ok);
    let null_stress = unsafe {
        rve_update(
            h,
            e.as_ptr(),
            std::ptr::null_mut(),
            [0.0f64; 9].as_mut_ptr(),
            consistent,
        )
    };
    assert_eq!(null_stress, RveStatus::NullArgument as u32);
    assert_eq!(rve_commit(h), RveStatus::NoTrial as u32);
    assert_eq!(good(), ok);
    assert_eq!(rve_commit(h), ok);
    assert_eq!(rve_free(h), ok);
}

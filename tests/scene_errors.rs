//! Every bad scene gets an error that names the key and the reason; nothing panics.

mod common;

use rve::model::build_microstructure;
use rve::scene::Scene;

/// Parses (and meshes, if parsing succeeds) a variation of the paper scene and returns
/// the error text.
fn error_of(replacements: &[(&str, &str)]) -> String {
    let text = common::paper_scene_with(replacements);
    match Scene::from_toml_str(&text, common::repo("scenes")) {
        Err(e) => e.to_string(),
        Ok(scene) => match build_microstructure(&scene) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("scene was accepted: {replacements:?}"),
        },
    }
}

fn assert_mentions(err: &str, needles: &[&str]) {
    for n in needles {
        assert!(err.contains(n), "error `{err}` does not mention `{n}`");
    }
}

#[test]
fn unknown_keys_are_named() {
    assert_mentions(
        &error_of(&[("seed = 7", "seed = 7\nsed = 3")]),
        &["unknown field `sed`"],
    );
    assert_mentions(
        &error_of(&[("[boundary]", "[boundry]")]),
        &["unknown field `boundry`"],
    );
    assert_mentions(
        &error_of(&[("delta_c = 0.0002", "delta_c = 0.0002, gamma = 1.0")]),
        &["unknown field `gamma`"],
    );
}

/// `solver.contact_status`: the two modes parse, anything else is named with the choices.
#[test]
fn contact_status_values() {
    use rve::scene::ContactStatusSpec;
    for (text, mode) in [
        ("active_set", ContactStatusSpec::ActiveSet),
        ("per_iteration", ContactStatusSpec::PerIteration),
    ] {
        let scene = common::paper_scene_with(&[(
            "[solver]",
            &format!("[solver]\ncontact_status = \"{text}\""),
        )]);
        let scene = Scene::from_toml_str(&scene, common::repo("scenes")).unwrap();
        assert_eq!(scene.spec.solver.contact_status, mode);
    }
    assert_eq!(
        common::scene("scenes/paper_rve.toml")
            .spec
            .solver
            .contact_status,
        ContactStatusSpec::ActiveSet
    );
    assert_mentions(
        &error_of(&[("[solver]", "[solver]\ncontact_status = \"per_step\"")]),
        &[
            "solver.contact_status",
            "unknown variant `per_step`",
            "`active_set` or `per_iteration`",
        ],
    );
    assert_mentions(
        &error_of(&[("[solver]", "[solver]\ncontact_state = \"active_set\"")]),
        &["unknown field `contact_state`", "contact_status"],
    );
}

#[test]
fn missing_keys_are_named() {
    assert_mentions(
        &error_of(&[("area_fraction = 0.45\n", "")]),
        &["missing field `area_fraction`"],
    );
    assert_mentions(
        &error_of(&[("analysis = \"plane_stress\"\n", "")]),
        &["missing field `analysis`"],
    );
    assert_mentions(
        &error_of(&[("aggregate = { young = 30000.0, poisson = 0.2 }\n", "")]),
        &["materials.aggregate", "missing"],
    );
    assert_mentions(
        &error_of(&[("itz = { sigma_c = 4.0, delta_c = 0.0002, beta = 0.707, penalty = { lambda_p = 1e5 } }\n", "")]),
        &["materials.itz", "missing", "materials.linear_itz"],
    );
}

/// The interface laws come from one registry: two laws given, or a bad constant of
/// either, are named by their keys.
#[test]
fn interface_laws_are_checked_by_key() {
    let itz =
        "itz = { sigma_c = 4.0, delta_c = 0.0002, beta = 0.707, penalty = { lambda_p = 1e5 } }\n";
    let linear =
        |ks: &str| format!("linear_itz = {{ shear_stiffness = {ks}, normal_stiffness = 1e4 }}\n");
    assert_mentions(
        &error_of(&[(itz, &format!("{itz}{}", linear("1e4")))]),
        &["materials.linear_itz", "one interface law", "not several"],
    );
    assert_mentions(
        &error_of(&[(itz, &linear("-1.0"))]),
        &["materials.linear_itz.shear_stiffness", "positive"],
    );
    assert_mentions(
        &error_of(&[("lambda_p = 1e5 }", "lambda_p = 1e5, stiffness = 1e6 }")]),
        &["materials.itz.penalty", "exactly one"],
    );
}

#[test]
fn wrong_magnitudes_are_named() {
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "size = [10.0, 10.0]",
            "size = [-10.0, 10.0]",
            &["cell.size[0]", "positive"],
        ),
        ("size = 0.84", "size = -0.5", &["mesh.size", "positive"]),
        ("size = 0.84", "size = 1e-5", &["mesh.size", "triangles"]),
        (
            "area_fraction = 0.45",
            "area_fraction = 0.8",
            &["geometry.area_fraction", "0.7"],
        ),
        (
            "delta_c = 0.0002",
            "delta_c = 0.0",
            &["materials.itz.delta_c", "positive"],
        ),
        (
            "delta_c = 0.0002",
            "delta_c = -1e-4",
            &["materials.itz.delta_c"],
        ),
        ("sigma_c = 4.0", "sigma_c = nan", &["materials.itz.sigma_c"]),
        (
            "young = 25000.0, poisson = 0.2",
            "young = 25000.0, poisson = 0.5",
            &["materials.matrix.poisson"],
        ),
        (
            "diameter = [2.5, 5.0]",
            "diameter = [5.0, 2.5]",
            &["geometry.diameter", "min"],
        ),
        (
            "diameter = [2.5, 5.0]",
            "diameter = [2.5, 12.0]",
            &["geometry.diameter", "does not fit"],
        ),
        ("tolerance = 1e-6", "tolerance = 0.0", &["solver.tolerance"]),
        ("increments = 20", "increments = 0", &["path[0].increments"]),
        (
            "lambda_p = 1e5",
            "lambda_p = 1e5, stiffness = 1e6",
            &["materials.itz.penalty", "exactly one"],
        ),
        ("cohesive = true", "cohesive = false", &["effects.contact"]),
        ("gap = 0.3", "gap = -0.1", &["geometry.gap"]),
    ];
    for (from, to, needles) in cases {
        assert_mentions(&error_of(&[(from, to)]), needles);
    }
}

#[test]
fn wrong_types_and_syntax_point_at_the_line() {
    assert_mentions(
        &error_of(&[("seed = 7", "seed = \"seven\"")]),
        &["line", "seed"],
    );
    assert_mentions(
        &error_of(&[("kind = \"random\"", "kind = \"voronoi\"")]),
        &["voronoi"],
    );
    assert_mentions(
        &error_of(&[("[cell]", "[cell")]),
        &["TOML parse error at line"],
    );
}

#[test]
fn impossible_explicit_geometry() {
    let random = "kind = \"random\"\nshape = \"circle\"\ndiameter = [2.5, 5.0]\narea_fraction = 0.45\nseed = 7\ngap = 0.3\nmargin = 0.3";
    assert_mentions(
        &error_of(&[(random, "kind = \"explicit\"\ninclusions = [{ center = [3.0, 3.0], radius = 2.0 }, { center = [4.0, 3.0], radius = 1.0 }]")]),
        &["geometry.inclusions[1]", "overlaps geometry.inclusions[0]"],
    );
    assert_mentions(
        &error_of(&[(
            random,
            "kind = \"explicit\"\ninclusions = [{ center = [1.0, 3.0], radius = 2.0 }]",
        )]),
        &["geometry.inclusions[0]", "boundary"],
    );
    assert_mentions(
        &error_of(&[(
            random,
            "kind = \"explicit\"\ninclusions = [{ center = [5.0, 5.0] }]",
        )]),
        &["geometry.inclusions[0]", "radius"],
    );
}

#[test]
fn missing_gmsh_file_is_reported_with_its_path() {
    let random = "kind = \"random\"\nshape = \"circle\"\ndiameter = [2.5, 5.0]\narea_fraction = 0.45\nseed = 7\ngap = 0.3\nmargin = 0.3";
    let err = error_of(&[(random, "kind = \"gmsh\"\nfile = \"no_such.msh\"\nmatrix = \"matrix\"\ninclusions = [\"aggregate\"]")]);
    assert_mentions(&err, &["no_such.msh"]);
}

#[test]
fn scene_file_errors_name_the_file() {
    let err = Scene::from_file(common::repo("scenes/does_not_exist.toml"))
        .unwrap_err()
        .to_string();
    assert_mentions(&err, &["does_not_exist.toml"]);
}

#[test]
fn embedded_default_scene_is_valid() {
    Scene::embedded_default().unwrap();
}

#[test]
fn straight_interface_position_is_checked() {
    let scene = std::fs::read_to_string(common::repo("scenes/single_interface.toml")).unwrap();
    for bad in ["x = 0.0", "x = 2.0", "x = -1.0", "x = nan"] {
        let text = scene.replace("x = 1.0", bad);
        let err = Scene::from_toml_str(&text, ".").unwrap_err().to_string();
        assert_mentions(&err, &["geometry.x", "0 < x < 2"]);
    }
    let err = Scene::from_toml_str(&scene.replace("x = 1.0", "x = \"a\""), ".")
        .unwrap_err()
        .to_string();
    assert_mentions(&err, &["geometry.x"]);
    let err = Scene::from_toml_str(&scene.replace("x = 1.0", "x = 1.0\ny = 2.0"), ".")
        .unwrap_err()
        .to_string();
    assert_mentions(&err, &["unknown field `y`"]);
    let err = Scene::from_toml_str(&scene.replace("x = 1.0\n", ""), ".")
        .unwrap_err()
        .to_string();
    assert_mentions(&err, &["missing field `x`"]);
}

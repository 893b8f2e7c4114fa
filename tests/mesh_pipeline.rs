//! Meshes of the shipped scenes: areas, ITZ topology and orientation, periodic sides,
//! quality, and the paper's element counts.

mod common;

use std::collections::HashSet;

use mesorve_core::mesh::{Mesh, MeshStats, Phase};
use rve::model::build_microstructure;
use rve::scene::Scene;

fn centroid(mesh: &Mesh, nodes: [usize; 3]) -> [f64; 2] {
    let p = nodes.map(|i| mesh.nodes[i]);
    [
        (p[0][0] + p[1][0] + p[2][0]) / 3.0,
        (p[0][1] + p[1][1] + p[2][1]) / 3.0,
    ]
}

/// Every structural invariant of a mesh with ITZ elements.
fn check_mesh(mesh: &Mesh, expected_inclusion_area: Option<f64>) {
    let stats = MeshStats::of(mesh);
    // Areas: positive triangles that fill the cell.
    let mut inclusion_area = 0.0;
    for t in &mesh.triangles {
        let a = mesh.triangle_area(t);
        assert!(a > 0.0, "triangle {t:?} is not counter-clockwise");
        if t.phase == Phase::Inclusion {
            inclusion_area += a;
        }
    }
    assert!(
        (stats.area_ratio - 1.0).abs() < 1e-12,
        "area ratio {}",
        stats.area_ratio
    );
    if let Some(expected) = expected_inclusion_area {
        // Polygons are area-preserving, so the only error is round-off.
        assert!((inclusion_area - expected).abs() < 1e-9 * expected);
    }
    assert!(
        stats.min_angle_deg >= 20.0,
        "min angle {}",
        stats.min_angle_deg
    );

    // ITZ: coincident sides, side A on inclusion triangles only, side B on matrix only,
    // normal out of the inclusion.
    let duplicates: HashSet<usize> = mesh
        .interfaces
        .iter()
        .flat_map(|e| [e.nodes[2], e.nodes[3]])
        .collect();
    let originals: HashSet<usize> = mesh
        .interfaces
        .iter()
        .flat_map(|e| [e.nodes[0], e.nodes[1]])
        .collect();
    for t in &mesh.triangles {
        for n in t.nodes {
            match t.phase {
                Phase::Inclusion => assert!(!duplicates.contains(&n)),
                Phase::Matrix => assert!(!originals.contains(&n)),
            }
        }
    }
    for e in &mesh.interfaces {
        let [a0, a1, b0, b1] = e.nodes;
        assert_eq!(mesh.nodes[a0], mesh.nodes[b0]);
        assert_eq!(mesh.nodes[a1], mesh.nodes[b1]);
        let (p, q) = (mesh.nodes[a0], mesh.nodes[a1]);
        let len = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
        assert!((len - e.length).abs() < 1e-14 * len.max(1.0));
        assert!(
            (e.normal[0] - e.tangent[1]).abs() < 1e-15
                && (e.normal[1] + e.tangent[0]).abs() < 1e-15
        );
        let mid = [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0];
        let side = |tri_nodes: [usize; 3]| {
            let c = centroid(mesh, tri_nodes);
            (c[0] - mid[0]) * e.normal[0] + (c[1] - mid[1]) * e.normal[1]
        };
        let inc = mesh
            .triangles
            .iter()
            .find(|t| t.nodes.contains(&a0) && t.nodes.contains(&a1))
            .expect("inclusion triangle on side A");
        let mat = mesh
            .triangles
            .iter()
            .find(|t| t.nodes.contains(&b0) && t.nodes.contains(&b1))
            .expect("matrix triangle on side B");
        assert_eq!(inc.phase, Phase::Inclusion);
        assert_eq!(mat.phase, Phase::Matrix);
        assert!(
            side(inc.nodes) < 0.0,
            "normal does not point out of the inclusion"
        );
        assert!(side(mat.nodes) > 0.0);
    }

    // Periodic sides.
    let b = &mesh.boundary;
    assert!(b.sides_match && stats.periodic_sides_match);
    assert!(!b.left.is_empty() && b.left.len() == b.right.len() && b.bottom.len() == b.top.len());
    for (&l, &r) in b.left.iter().zip(&b.right) {
        assert_eq!(mesh.nodes[l][1], mesh.nodes[r][1]);
        assert_eq!((mesh.nodes[l][0], mesh.nodes[r][0]), (0.0, mesh.width));
    }
    for (&l, &r) in b.bottom.iter().zip(&b.top) {
        assert_eq!(mesh.nodes[l][0], mesh.nodes[r][0]);
    }
}

/// Within `tol` relative of the paper's count.
fn near(count: usize, paper: usize, tol: f64) -> bool {
    (count as f64 - paper as f64).abs() <= tol * paper as f64
}

#[test]
fn paper_rve_matches_section_5_2_counts() {
    let micro = build_microstructure(&common::scene("scenes/paper_rve.toml")).unwrap();
    let area: f64 = micro.inclusions.iter().map(|i| i.area()).sum();
    check_mesh(&micro.mesh, Some(area));
    let s = MeshStats::of(&micro.mesh);
    assert!(near(s.triangles, 520, 0.1), "{} triangles", s.triangles);
    assert!(
        near(s.interface_elements, 95, 0.1),
        "{} ITZ",
        s.interface_elements
    );
    assert!((s.inclusion_area_fraction - 0.45).abs() < 0.0045);
}

#[test]
fn fine_and_ellipse_rves_match_the_papers_counts() {
    for (file, tri, itz) in [
        ("scenes/paper_rve_fine.toml", 8088, 364),
        ("scenes/paper_rve_ellipses.toml", 851, 94),
    ] {
        let micro = build_microstructure(&common::scene(file)).unwrap();
        let area: f64 = micro.inclusions.iter().map(|i| i.area()).sum();
        check_mesh(&micro.mesh, Some(area));
        let s = MeshStats::of(&micro.mesh);
        assert!(
            near(s.triangles, tri, 0.1),
            "{file}: {} triangles",
            s.triangles
        );
        assert!(
            near(s.interface_elements, itz, 0.1),
            "{file}: {} ITZ",
            s.interface_elements
        );
    }
}

#[test]
fn single_interface_scene_has_a_full_height_itz() {
    let micro = build_microstructure(&common::scene("scenes/single_interface.toml")).unwrap();
    let mesh = &micro.mesh;
    // Left half is the aggregate phase: 1 x 2 mm.
    check_mesh(mesh, Some(2.0));
    let s = MeshStats::of(mesh);
    assert_eq!(s.interface_elements, 10);
    assert!((s.interface_length - 2.0).abs() < 1e-14);
    assert_eq!(micro.geometric_area_fraction, Some(0.5));
    for e in &mesh.interfaces {
        assert!((e.length - 0.2).abs() < 1e-14 && e.normal == [1.0, 0.0]);
        assert!(e.nodes.iter().all(|&n| mesh.nodes[n][0] == 1.0));
    }
    // The interface ends on the bottom and top sides: two copies there, paired alike.
    let b = &mesh.boundary;
    for side in [&b.bottom, &b.top] {
        assert_eq!(side.iter().filter(|&&n| mesh.nodes[n][0] == 1.0).count(), 2);
    }
    // Off-centre, other sizes, both periodic-matching.
    for (x, size, itz) in [("0.3", "0.2", "0.1"), ("1.85", "0.3", "0.25")] {
        let text = std::fs::read_to_string(common::repo("scenes/single_interface.toml"))
            .unwrap()
            .replace("x = 1.0", &format!("x = {x}"))
            .replace("size = 0.15", &format!("size = {size}"))
            .replace("interface_size = 0.2", &format!("interface_size = {itz}"));
        let micro = build_microstructure(&Scene::from_toml_str(&text, ".").unwrap()).unwrap();
        let x: f64 = x.parse().unwrap();
        check_mesh(&micro.mesh, Some(2.0 * x));
    }
}

#[test]
fn random_seeds_and_sizes_give_valid_meshes() {
    for seed in [1, 2, 3, 5, 8, 13] {
        for (size, itz) in [("0.84", "0.48"), ("0.5", "0.3")] {
            let text = common::paper_scene_with(&[
                ("seed = 7", &format!("seed = {seed}")),
                ("size = 0.84", &format!("size = {size}")),
                ("interface_size = 0.48", &format!("interface_size = {itz}")),
            ]);
            let micro = build_microstructure(&Scene::from_toml_str(&text, ".").unwrap()).unwrap();
            let area: f64 = micro.inclusions.iter().map(|i| i.area()).sum();
            check_mesh(&micro.mesh, Some(area));
        }
    }
}

#[test]
fn same_scene_gives_the_same_mesh() {
    let a = build_microstructure(&common::scene("scenes/paper_rve.toml"))
        .unwrap()
        .mesh;
    let b = build_microstructure(&common::scene("scenes/paper_rve.toml"))
        .unwrap()
        .mesh;
    assert_eq!(a.nodes, b.nodes);
    assert_eq!(a.triangles, b.triangles);
    assert_eq!(a.interfaces, b.interfaces);
}

#[test]
fn perfect_bonding_inserts_no_interfaces() {
    let text = common::paper_scene_with(&[(
        "cohesive = true\ncontact = true",
        "cohesive = false\ncontact = false",
    )]);
    let micro = build_microstructure(&Scene::from_toml_str(&text, ".").unwrap()).unwrap();
    assert!(micro.mesh.interfaces.is_empty());
    let with = build_microstructure(&common::scene("scenes/paper_rve.toml"))
        .unwrap()
        .mesh;
    // Same triangulation, minus the duplicated nodes.
    assert_eq!(micro.mesh.triangles.len(), with.triangles.len());
    let dups: HashSet<usize> = with
        .interfaces
        .iter()
        .flat_map(|e| [e.nodes[2], e.nodes[3]])
        .collect();
    assert_eq!(micro.mesh.nodes.len() + dups.len(), with.nodes.len());
}

#[test]
fn explicit_inclusions_and_homogeneous_cells() {
    let text = common::paper_scene_with(&[(
        "kind = \"random\"\nshape = \"circle\"\ndiameter = [2.5, 5.0]\narea_fraction = 0.45\nseed = 7\ngap = 0.3\nmargin = 0.3",
        "kind = \"explicit\"\ninclusions = [{ center = [3.0, 3.0], radius = 2.0 }, { center = [7.0, 6.5], semi_axes = [2.0, 1.0], angle = 30.0 }]",
    )]);
    let micro = build_microstructure(&Scene::from_toml_str(&text, ".").unwrap()).unwrap();
    let expected = std::f64::consts::PI * (4.0 + 2.0);
    check_mesh(&micro.mesh, Some(expected));

    let text = common::paper_scene_with(&[(
        "kind = \"random\"\nshape = \"circle\"\ndiameter = [2.5, 5.0]\narea_fraction = 0.45\nseed = 7\ngap = 0.3\nmargin = 0.3",
        "kind = \"homogeneous\"",
    )]);
    let micro = build_microstructure(&Scene::from_toml_str(&text, ".").unwrap()).unwrap();
    assert!(micro
        .mesh
        .triangles
        .iter()
        .all(|t| t.phase == Phase::Matrix));
    assert!(micro.mesh.interfaces.is_empty());
    check_mesh(&micro.mesh, None);
}

#[test]
fn gmsh_scene_gets_itz_elements_between_the_mapped_phases() {
    let micro = build_microstructure(&common::scene("scenes/gmsh_two_circles.toml")).unwrap();
    check_mesh(&micro.mesh, None);
    assert!(!micro.mesh.interfaces.is_empty());
    // The ITZ is closed around each aggregate: every side-A node has exactly two ITZ edges.
    let mut degree = std::collections::HashMap::new();
    for e in &micro.mesh.interfaces {
        *degree.entry(e.nodes[0]).or_insert(0) += 1;
        *degree.entry(e.nodes[1]).or_insert(0) += 1;
    }
    assert!(degree.values().all(|&d| d == 2));
}

#[test]
fn our_mesh_survives_a_gmsh_22_and_41_round_trip() {
    use mesorve_core::mesh::gmsh::{parse_msh, write_msh22, write_msh41};
    use mesorve_core::mesh::{insert_itz, triangulate};
    let scene = common::scene("scenes/paper_rve.toml");
    let micro = build_microstructure(&scene).unwrap();
    let polygons: Vec<Vec<[f64; 2]>> = micro.inclusions.iter().map(|i| i.polygon(0.48)).collect();
    let phase_mesh = triangulate(10.0, 10.0, &polygons, 0.84, 25.0).unwrap();
    for version in ["2.2", "4.1"] {
        let mut bytes = Vec::new();
        if version == "2.2" {
            write_msh22(&phase_mesh, &mut bytes).unwrap();
        } else {
            write_msh41(&phase_mesh, &mut bytes).unwrap();
        }
        let text = String::from_utf8(bytes).unwrap();
        let back = parse_msh(
            &text,
            std::path::Path::new("roundtrip.msh"),
            "matrix",
            &["aggregate".to_string()],
        )
        .unwrap();
        assert_eq!(back.nodes.len(), phase_mesh.nodes.len(), "{version}");
        let mesh = insert_itz(back, 10.0, 10.0).unwrap();
        assert_eq!(mesh.nodes.len(), micro.mesh.nodes.len(), "{version}");
        assert_eq!(
            mesh.triangles.len(),
            micro.mesh.triangles.len(),
            "{version}"
        );
        assert_eq!(
            mesh.interfaces.len(),
            micro.mesh.interfaces.len(),
            "{version}"
        );
        let (a, b) = (MeshStats::of(&mesh), MeshStats::of(&micro.mesh));
        assert!((a.inclusion_area_fraction - b.inclusion_area_fraction).abs() < 1e-12);
        // The text format keeps coordinates to full precision: ITZ geometry is identical.
        let mut la: Vec<f64> = mesh.interfaces.iter().map(|e| e.length).collect();
        let mut lb: Vec<f64> = micro.mesh.interfaces.iter().map(|e| e.length).collect();
        la.sort_by(f64::total_cmp);
        lb.sort_by(f64::total_cmp);
        assert_eq!(la, lb, "{version}");
        check_mesh(&mesh, None);
    }
}

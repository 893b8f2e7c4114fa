//! Random and explicit microstructures: overlaps, gaps, margins, fractions, seeds.

mod common;

use mesorve_core::geometry::{place_random, Inclusion};
use rve::scene::{GeometrySpec, RandomSpec, Scene};

fn random_spec(text: &str) -> RandomSpec {
    match Scene::from_toml_str(text, ".").unwrap().spec.geometry {
        GeometrySpec::Random(r) => r,
        other => panic!("not random: {other:?}"),
    }
}

/// Checks gap, margin and fraction of a placement against its spec.
fn check_placement(spec: &RandomSpec, inclusions: &[Inclusion], fraction: f64) {
    let (w, h) = (10.0, 10.0);
    for (i, a) in inclusions.iter().enumerate() {
        let [hx, hy] = a.half_extents();
        let [cx, cy] = a.center;
        let m = spec.margin - 1e-12;
        assert!(cx - hx >= m && cx + hx <= w - m, "margin x of {i}");
        assert!(cy - hy >= m && cy + hy <= h - m, "margin y of {i}");
        let d_major = 2.0 * a.semi_axes[0].max(a.semi_axes[1]);
        assert!(d_major >= spec.diameter[0] - 1e-9 && d_major <= spec.diameter[1] + 1e-9);
        for (j, b) in inclusions.iter().enumerate().skip(i + 1) {
            assert!(
                a.separated_from(b, spec.gap * (1.0 - 1e-9)),
                "{i} and {j} closer than gap"
            );
            // Independent check with dense boundary sampling: no point of b inside a.
            for k in 0..720 {
                let t = k as f64 * std::f64::consts::PI / 360.0;
                let (s, c) = b.angle.sin_cos();
                let (x, y) = (b.semi_axes[0] * t.cos(), b.semi_axes[1] * t.sin());
                let p = [b.center[0] + c * x - s * y, b.center[1] + s * x + c * y];
                assert!(!a.contains(p), "{j} overlaps {i}");
            }
        }
    }
    let exact: f64 = inclusions.iter().map(Inclusion::area).sum::<f64>() / (w * h);
    assert!((exact - fraction).abs() < 1e-12);
    assert!(
        (fraction - spec.area_fraction).abs() <= 0.01 * spec.area_fraction,
        "fraction {fraction} vs target {}",
        spec.area_fraction
    );
}

#[test]
fn circles_reach_the_papers_45_percent_for_many_seeds() {
    for seed in 0..12 {
        let text = common::paper_scene_with(&[("seed = 7", &format!("seed = {seed}"))]);
        let spec = random_spec(&text);
        let p = place_random(&spec, 10.0, 10.0).unwrap();
        check_placement(&spec, &p.inclusions, p.area_fraction);
        // Largest first.
        let d: Vec<f64> = p.inclusions.iter().map(|i| i.semi_axes[0]).collect();
        assert!(
            d.windows(2).all(|w| w[0] >= w[1]),
            "not largest first: {d:?}"
        );
    }
}

#[test]
fn ellipses_random_and_fixed_orientation() {
    let text = std::fs::read_to_string(common::repo("scenes/paper_rve_ellipses.toml")).unwrap();
    let spec = random_spec(&text);
    let p = place_random(&spec, 10.0, 10.0).unwrap();
    check_placement(&spec, &p.inclusions, p.area_fraction);
    for inc in &p.inclusions {
        let ratio = inc.semi_axes[0] / inc.semi_axes[1];
        assert!((ratio - 1.5).abs() < 1e-12);
    }
    let fixed = text.replace("orientation = \"random\"", "orientation = 30.0");
    let fixed = fixed.replace("area_fraction = 0.45", "area_fraction = 0.35");
    let spec = random_spec(&fixed);
    let p = place_random(&spec, 10.0, 10.0).unwrap();
    check_placement(&spec, &p.inclusions, p.area_fraction);
    assert!(p
        .inclusions
        .iter()
        .all(|i| (i.angle - 30f64.to_radians()).abs() < 1e-15));
}

#[test]
fn placement_is_reproducible_from_the_seed() {
    let spec = random_spec(&common::paper_scene_with(&[]));
    let a = place_random(&spec, 10.0, 10.0).unwrap();
    let b = place_random(&spec, 10.0, 10.0).unwrap();
    assert_eq!(a.inclusions, b.inclusions);
    let other = random_spec(&common::paper_scene_with(&[("seed = 7", "seed = 8")]));
    let c = place_random(&other, 10.0, 10.0).unwrap();
    assert_ne!(a.inclusions, c.inclusions);
}

#[test]
fn impossible_request_fails_quickly_with_a_clear_error() {
    let text = common::paper_scene_with(&[
        ("area_fraction = 0.45", "area_fraction = 0.68"),
        ("gap = 0.3", "gap = 0.5"),
        ("seed = 7", "seed = 7\nmax_attempts = 2000\nmax_rounds = 5"),
    ]);
    let spec = random_spec(&text);
    let start = std::time::Instant::now();
    let err = place_random(&spec, 10.0, 10.0).unwrap_err().to_string();
    assert!(err.contains("could not place area fraction 0.68"), "{err}");
    assert!(err.contains("lower geometry.area_fraction"), "{err}");
    assert!(start.elapsed().as_secs() < 60);
}

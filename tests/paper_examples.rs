//! The numerical examples of Pituba & Souza Neto (2015), sections 5.1 and 5.2, as checks
//! of what this library computes: one test per qualitative finding of the paper.
//!
//! Each test states the paper's claim, measures the library's number and asserts what is
//! true. Where the library disagrees with the paper the test asserts the library's
//! behaviour and says so; `docs/paper_examples.md` (made by `studies/paper-examples/run`) has
//! the tables, the plots and the same verdicts. Run with `--nocapture` to see the numbers.
//!
//! Scenes: the shipped `scenes/paper_rve*.toml` and the variants in `scenes/paper/`; the
//! penalty sweep edits `lambda_p` (and `contact_shear`) of `scenes/paper_rve_cycle.toml`.
//!
//! Peak stresses. The paper reads its peaks off 20-increment curves. Near the peak the
//! RVE's equilibrium path has a limit point followed by a snap-back, so the largest stress
//! of a 20-increment path depends on where the increments fall (0.1 N/mm², 2 %, on the
//! paper's path). The tests that compare peaks use the limit point instead: 16 increments
//! of 1.1e-5 to 1.76e-4 (every ITZ point is still on its loading envelope there, so the
//! state does not depend on the increments), then steps of 1.375e-6 (= 2.2e-4 / 160) until
//! the stress has dropped 5 % below its maximum or the solver gives up (it cannot always
//! follow a snap-back with such small steps; see `limit_point`). Halving the fine step
//! moves the x-peak by 3e-4 N/mm².

mod common;

use std::sync::{Arc, OnceLock};

use rve::{Instance, Model, Scene, TangentRequest};

/// `materials.itz.delta_c` of every scene used here (mm).
const DELTA_C: f64 = 2e-4;
/// Section 5.2.1: "a close-up view in the ITZ corresponding to sigma_x = 4.8 N/mm²" (Fig. 10).
const FIG_10_SIGMA_X: f64 = 4.8;
const X: [f64; 3] = [1.0, 0.0, 0.0];
const Y: [f64; 3] = [0.0, 1.0, 0.0];

// ---------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------

/// The text of a scene file with exact text replacements (each must occur once).
fn scene_text(rel: &str, replacements: &[(&str, &str)]) -> String {
    let mut text = std::fs::read_to_string(common::repo(rel)).unwrap();
    for (from, to) in replacements {
        assert_eq!(text.matches(from).count(), 1, "{rel}: `{from}`");
        text = text.replacen(from, to, 1);
    }
    text
}

fn model(rel: &str, replacements: &[(&str, &str)]) -> Arc<Model> {
    let scene = Scene::from_toml_str(&scene_text(rel, replacements), common::repo("scenes"))
        .unwrap_or_else(|e| panic!("{rel}: {e}"));
    Arc::new(Model::from_scene(&scene).unwrap_or_else(|e| panic!("{rel}: {e}")))
}

/// The strain at every increment of a scene's `[[path]]`.
fn path_of(rel: &str) -> Vec<[f64; 3]> {
    rve::scene::path_points(&common::scene(rel).spec.path)
}

/// One converged increment.
#[derive(Clone, Debug)]
struct Point {
    eps: [f64; 3],
    stress: [f64; 3],
    tangent: [f64; 9],
    iterations: u32,
    contact: usize,
    /// Interface quadrature points whose history has gone past `delta_c` (the peak of the
    /// traction-separation envelope: softening, a crack in the usual sense).
    cracked: usize,
}

/// A followed path: the converged increments and, if the solver gave up, where and why.
struct Curve {
    points: Vec<Point>,
    failure: Option<(usize, String)>,
}

/// Follows `strains` (update, commit) until the end or the first failed increment.
fn follow(model: &Arc<Model>, strains: &[[f64; 3]]) -> Curve {
    let mut inst = Instance::new(model.clone());
    let mut ws = model.workspace();
    let mut points = Vec::new();
    for (k, eps) in strains.iter().enumerate() {
        match inst.update(*eps, &mut ws, TangentRequest::Consistent) {
            Ok(r) => {
                inst.commit().unwrap();
                let cracked = inst
                    .committed()
                    .history
                    .iter()
                    .filter(|&&delta_max| delta_max > DELTA_C)
                    .count();
                points.push(Point {
                    eps: *eps,
                    stress: r.stress,
                    tangent: r.tangent,
                    iterations: r.report.iterations,
                    contact: r.report.contact,
                    cracked,
                });
            }
            Err(e) => {
                return Curve {
                    points,
                    failure: Some((k + 1, e.to_string())),
                }
            }
        }
    }
    Curve {
        points,
        failure: None,
    }
}

/// Follows a scene's own path and requires every increment to converge.
fn run(rel: &str, replacements: &[(&str, &str)]) -> Vec<Point> {
    let curve = follow(&model(rel, replacements), &path_of(rel));
    if let Some((k, e)) = curve.failure {
        panic!("{rel} {replacements:?}: increment {k} failed: {e}");
    }
    curve.points
}

/// A threshold of `tests/data/paper_verdicts.toml` ("fig7.elastic_secant_above"): the one
/// place that `studies/paper-examples/paper_examples_report.py` reads too, so the document's verdicts and
/// these assertions cannot drift apart.
fn limit(key: &str) -> f64 {
    static T: OnceLock<toml::Table> = OnceLock::new();
    let table = T.get_or_init(|| {
        let path = common::repo("tests/data/paper_verdicts.toml");
        std::fs::read_to_string(&path).unwrap().parse().unwrap()
    });
    let (section, name) = key.split_once('.').unwrap();
    table
        .get(section)
        .and_then(|s| s.get(name))
        .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
        .unwrap_or_else(|| panic!("paper_verdicts.toml has no number `{key}`"))
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The limit point of monotonic loading along `dir` (component `c` of the stress).
#[derive(Clone, Copy, Debug)]
struct Peak {
    stress: f64,
    strain: f64,
}

fn limit_point(model: &Arc<Model>, dir: [f64; 3], label: &str) -> Peak {
    let c = dir.iter().position(|&d| d == 1.0).unwrap();
    let coarse_end = 16.0 * 1.1e-5;
    let mut levels: Vec<f64> = (1..=16).map(|k| 1.1e-5 * k as f64).collect();
    levels.extend((1..=90).map(|k| coarse_end + 1.375e-6 * k as f64));
    let mut inst = Instance::new(model.clone());
    let mut ws = model.workspace();
    let mut best = Peak {
        stress: f64::NEG_INFINITY,
        strain: 0.0,
    };
    let mut ended = None;
    for level in levels {
        let eps = dir.map(|d| d * level);
        let Ok(r) = inst.update(eps, &mut ws, TangentRequest::None) else {
            ended = Some("the solver gave up");
            break;
        };
        inst.commit().unwrap();
        if r.stress[c] > best.stress {
            best = Peak {
                stress: r.stress[c],
                strain: level,
            };
        }
        if r.stress[c] < 0.95 * best.stress {
            ended = Some("the stress dropped 5 %");
            break;
        }
    }
    // A genuine interior maximum: reached after the coarse stage and followed by a drop
    // or by the end of the equilibrium branch the solver can follow.
    let ended = ended.unwrap_or_else(|| panic!("{label}: no limit point up to 3e-4"));
    assert!(
        best.strain > coarse_end,
        "{label}: peak in the coarse stage"
    );
    println!(
        "{label}: limit point {:.4} N/mm² at {:.4e} ({ended})",
        best.stress, best.strain
    );
    best
}

/// Limit points used by several tests, computed once.
fn peak_x_periodic() -> Peak {
    static P: OnceLock<Peak> = OnceLock::new();
    *P.get_or_init(|| limit_point(&model("scenes/paper_rve.toml", &[]), X, "x periodic"))
}

fn peak_y_periodic() -> Peak {
    static P: OnceLock<Peak> = OnceLock::new();
    *P.get_or_init(|| limit_point(&model("scenes/paper_rve.toml", &[]), Y, "y periodic"))
}

fn peak_x_linear() -> Peak {
    static P: OnceLock<Peak> = OnceLock::new();
    *P.get_or_init(|| limit_point(&model("scenes/paper/rve_linear.toml", &[]), X, "x linear"))
}

// ---------------------------------------------------------------------------------------
// Section 5.1: the single interface (Table 1), Figs. 6 and 7
// ---------------------------------------------------------------------------------------

/// Section 5.1 on `scenes/single_interface.toml` (one straight ITZ, plane strain, Table 1).
/// `tests/closed_form_interface.rs` already checks every loading case and sigma_c of Table
/// 1 and the cycle of Fig. 8 against the closed-form response; this test asserts the two
/// qualitative remarks of the paper on them:
///
/// - Fig. 7: with sigma_c = 40 "the behavior of the RVE seems like an elastic RVE", with
///   sigma_c = 0.4 it is "a medium with a strong fracture without a transition process".
/// - Fig. 6: "the behavior more damaged of the RVE when the loading conditions are
///   increased" (case 3 adds the shear 5e-4 to case 2), read on what Fig. 6 plots,
///   sigma_x against eps_x: the curve is lower from case 1 to case 2 to case 3.
#[test]
fn section_5_1_sigma_c_and_loading_cases() {
    const SCENE: &str = "scenes/single_interface.toml";
    let cases: [(&str, [f64; 3]); 3] = [
        ("case 1", [8e-5, 0.0, 0.0]),
        ("case 2", [8e-5, -8e-5, 0.0]),
        ("case 3", [8e-5, -8e-5, 5e-4]),
    ];
    // Plane strain D11 of Table 1 (E = 30000, nu = 0.2).
    let d11 = 30000.0 * 0.8 / (1.2 * 0.6);
    let along = |to: [f64; 3]| -> Vec<[f64; 3]> {
        (1..=20).map(|k| to.map(|v| v * k as f64 / 20.0)).collect()
    };
    // Case 1 for each sigma_c: secant s_xx / eps_xx at the end, tangent at increment 1.
    let mut secant = Vec::new();
    for sigma_c in ["4.0", "40.0", "0.4"] {
        let m = model(SCENE, &[("sigma_c = 4.0", &format!("sigma_c = {sigma_c}"))]);
        let curve = follow(&m, &along(cases[0].1));
        assert!(curve.failure.is_none(), "sigma_c {sigma_c}");
        let (first, last) = (&curve.points[0], curve.points.last().unwrap());
        let s = last.stress[0] / last.eps[0] / d11;
        println!(
            "sigma_c {sigma_c:>4}: secant s_xx/eps_xx = {s:.3} D11, first tangent {:.3} D11",
            first.tangent[0] / d11
        );
        secant.push((s, first.tangent[0] / d11));
    }
    let [(s4, _), (s40, _), (s04, t04)] = [secant[0], secant[1], secant[2]];
    // Elastic-like: the intact interface (initial stiffness e sigma_c / delta_c =
    // 5.4e5 N/mm³ for sigma_c = 40) in series with the 2 mm cell gives
    // 1 / (1 + D11 / (5.4e5 * 2)) = 0.970 D11 before any softening.
    assert!(
        s40 > limit("fig7.elastic_secant_above"),
        "sigma_c = 40 is not elastic-like: {s40}"
    );
    // Strong fracture: at sigma_c = 0.4 the interface is past its peak at the end of the
    // path and the secant has lost most of the stiffness; already the first increment
    // (eps = 4e-6) is far from elastic (no transition).
    assert!(
        s04 < limit("fig7.fractured_secant_below")
            && t04 < limit("fig7.fractured_first_tangent_below"),
        "sigma_c = 0.4: {s04}, {t04}"
    );
    assert!(s40 > s4 && s4 > s04);

    // Loading cases with sigma_c = 4: s_xx at the end and the largest opening reached
    // (delta_max / delta_c).
    let m = model(SCENE, &[]);
    let (mut sigma_x, mut opening) = (Vec::new(), Vec::new());
    for (name, to) in cases {
        let mut inst = Instance::new(m.clone());
        let mut ws = m.workspace();
        let mut stress = [0.0; 3];
        for eps in along(to) {
            stress = inst
                .update(eps, &mut ws, TangentRequest::None)
                .unwrap()
                .stress;
            inst.commit().unwrap();
        }
        sigma_x.push(stress[0]);
        let d = inst
            .committed()
            .history
            .iter()
            .fold(0.0f64, |a, &delta_max| a.max(delta_max))
            / DELTA_C;
        println!("{name}: s_xx {:.4}, delta_max = {d:.3} delta_c", stress[0]);
        opening.push(d);
    }
    // The paper's measure: sigma_x at the end falls from case 1 to case 3.
    assert!(
        sigma_x[0] > sigma_x[1] && sigma_x[1] > sigma_x[2],
        "{sigma_x:?}"
    );
    // Case 3 (with shear) opens the interface far more than cases 1 and 2.
    assert!(opening[2] > 2.0 * opening[0] && opening[2] > 2.0 * opening[1]);
    // But sigma_x is not a damage measure: case 2 opens the interface LESS than case 1.
    // The ITZ is vertical (normal x); eps_yy = -8e-5 lowers s_xx by D12 * 8e-5 and so
    // the normal traction, so case 2's lower sigma_x is the Poisson coupling, and by its
    // opening case 2 is the less damaged one.
    assert!(opening[1] < opening[0]);
}

// ---------------------------------------------------------------------------------------
// Section 5.2.1: elastic-fracture behaviour
// ---------------------------------------------------------------------------------------

/// Fig. 10: "a close-up view in the ITZ corresponding to sigma_x = 4.8 N/mm²", and "the
/// non-linearity of the response is linked to the increase of the number of cracks in the
/// ITZ".
///
/// Our RVE (seed 7) does not reach 4.8 N/mm²: its limit point under eps_xx is 4.53 N/mm²
/// (5.6 % below), and no variant of it reaches 4.8. The paper's RVE is another random
/// sample, so the question is where 4.8 falls among samples of the same specification:
/// `studies/fig10-ensemble/fig10_ensemble.py` runs this limit-point path on many seeds (and the
/// plane-strain and zero-margin variants), and docs/paper_examples.md scores the finding
/// on that spread. This test asserts seed 7's side of it.
#[test]
fn fig_10_peak_is_of_the_order_of_4_8() {
    let peak = peak_x_periodic();
    println!(
        "peak {:.3} N/mm² = {:.3} x the paper's 4.8",
        peak.stress,
        peak.stress / FIG_10_SIGMA_X
    );
    assert!(
        peak.stress < FIG_10_SIGMA_X,
        "the peak reaches 4.8: update the docs"
    );
    // Same order. (Where 4.8 falls among random samples of this RVE's specification:
    // studies/fig10-ensemble/fig10_ensemble.py, docs/paper_examples.md.)
    assert!(
        peak.stress > limit("fig10.same_order_fraction") * FIG_10_SIGMA_X,
        "peak {:.3}",
        peak.stress
    );

    // Cracks (points past delta_c) along the paper's path: none while the response is
    // still below 90 % of the peak, although the secant has already lost several %; the
    // intrinsic law softens the ITZ from the first increment (every point is on its
    // loading envelope, "a fracture created in the beginning"), cracks in the sense of
    // softening points appear only in the last increments before the peak and multiply
    // at the snap after it.
    let points = run("scenes/paper_rve.toml", &[]);
    let elastic = model("scenes/paper_rve.toml", &[]).elastic_tangent()[0];
    let top = (0..points.len())
        .max_by(|&a, &b| points[a].stress[0].total_cmp(&points[b].stress[0]))
        .unwrap();
    let mut first_crack = None;
    for (k, p) in points.iter().enumerate() {
        let secant = p.stress[0] / p.eps[0] / elastic;
        println!(
            "  {:2} eps {:.3e} s_xx {:.4} secant {:.3} cracked {}",
            k + 1,
            p.eps[0],
            p.stress[0],
            secant,
            p.cracked
        );
        if k <= top && p.stress[0] < limit("fig10.uncracked_below_peak_fraction") * peak.stress {
            assert_eq!(p.cracked, 0, "increment {}", k + 1);
        }
        if p.cracked > 0 && first_crack.is_none() {
            first_crack = Some(k);
        }
    }
    // Before any crack the secant is already 5 % below the virgin stiffness...
    let k = first_crack.expect("no crack along the path");
    let before = &points[k - 1];
    assert!(before.stress[0] / before.eps[0] / elastic < 0.95);
    // ...and after the peak (the last increment) more than a fifth of the ITZ points are
    // cracked.
    let n = model("scenes/paper_rve.toml", &[])
        .discretization()
        .history_len();
    assert!(5 * points.last().unwrap().cracked > n, "of {n}");
}

/// Section 5.2.2 (end): "the problems have presented up to four iterations to obtain an
/// accurate response even dealing with contact problems", and section 5.2.1: "mainly at
/// the peak of the sigma x epsilon curve when there are many cracks at the ITZ, the
/// iterative process presents a increasing of iterations".
///
/// In agreement with both: at most four iterations on every increment up to the peak
/// (`tests/newton_convergence.rs` asserts it, with the quadratic rate, on the 5.2.1 and
/// 5.2.2 paths), and more at the peak: the increment across the snap after it jumps to
/// the post-peak branch and needs path following and sub-steps (tens of iterations;
/// docs/paper_examples.md has the count).
#[test]
fn newton_iterations_across_the_snap() {
    let p = run("scenes/paper_rve.toml", &[]);
    let iterations: Vec<u32> = p.iter().map(|q| q.iterations).collect();
    println!("iterations per increment: {iterations:?}");
    let top = (0..p.len())
        .max_by(|&a, &b| p[a].stress[0].total_cmp(&p[b].stress[0]))
        .unwrap();
    let most = limit("newton.most_iterations") as u32;
    assert!(iterations[..=top].iter().all(|&i| i <= most));
    // The increment after the largest stress crosses the snap (the stress falls by a
    // quarter) and takes more than four iterations.
    assert!(p[top + 1].stress[0] < 0.75 * p[top].stress[0]);
    assert!(iterations[top + 1] > most, "{iterations:?}");
}

/// Fig. 11: loading along x and along y "the difference between the responses arises at
/// peak stress region".
#[test]
fn anisotropy_appears_only_near_the_peak() {
    let m = model("scenes/paper_rve.toml", &[]);
    let d = m.elastic_tangent();
    let elastic = rel(d[4], d[0]);
    let x = run("scenes/paper_rve.toml", &[]);
    let y = run("scenes/paper/rve_y.toml", &[]);
    // Largest difference of s_xx(eps_xx) and s_yy(eps_yy) over the first half of the path
    // (eps <= 1.1e-4, where the tangent is still above 90 % of the elastic one).
    let first_half = x
        .iter()
        .zip(&y)
        .take(10)
        .map(|(a, b)| rel(b.stress[1], a.stress[0]))
        .fold(0.0f64, f64::max);
    let (px, py) = (peak_x_periodic(), peak_y_periodic());
    let at_peak = rel(py.stress, px.stress);
    let (ex, ey) = (x.last().unwrap(), y.last().unwrap());
    let post = rel(ey.stress[1], ex.stress[0]);
    println!(
        "elastic D22 vs D11 {elastic:.1e}; first half {first_half:.1e}; limit points x {:.4} \
         at {:.3e}, y {:.4} at {:.3e}: {at_peak:.1e}; at 2.2e-4 x {:.4} y {:.4}: {post:.1e}",
        px.stress, px.strain, py.stress, py.strain, ex.stress[0], ey.stress[1]
    );
    // Nearly isotropic at first: the four aggregates give D11 and D22 within 1e-4, and
    // the curves agree to 5e-4 over the first half of the path.
    let early = limit("fig11.early_rel_below");
    assert!(elastic < early, "elastic anisotropy {elastic:.1e}");
    assert!(first_half < early, "{first_half:.1e}");
    // At the peak the two directions differ by 2 %, more than ten times the early
    // difference (40 times measured), and after it by several % (6 % measured).
    assert!(
        at_peak > limit("fig11.peak_rel_above"),
        "peaks differ by {at_peak:.1e}"
    );
    assert!(at_peak > limit("fig11.peak_over_early") * first_half.max(elastic));
    assert!(
        post > limit("fig11.post_peak_rel_above"),
        "post-peak differ by {post:.1e}"
    );
}

/// Fig. 13: "the numerical responses did not change" from the coarse (Fig. 9) to the fine
/// mesh (8088 triangles, 364 ITZ elements in the paper; 8176 / 362 here), "a linear
/// condition has been imposed on the boundary": decided with linear BC, as the paper ran
/// it; periodic BC is checked before the peak too.
///
/// In agreement: up to increment 18 (98 % of the peak) the curves agree to half a
/// percent, and the limit points to 2 %. After the peak the meshes are compared by their
/// limit points, not increment by increment: across a snap-back an increment lands on
/// whichever branch its end strain reaches first, so the stresses of one increment can
/// sit on different branches (with periodic BC the coarse mesh has snapped at increment
/// 19 and the fine one not yet).
#[test]
fn mesh_objectivity_with_linear_bc() {
    let before = limit("fig13.before_peak_rel");
    for (bc, coarse, fine) in [
        (
            "periodic",
            "scenes/paper_rve.toml",
            "scenes/paper_rve_fine.toml",
        ),
        (
            "linear",
            "scenes/paper/rve_linear.toml",
            "scenes/paper/rve_fine_linear.toml",
        ),
    ] {
        let (c, f) = (run(coarse, &[]), run(fine, &[]));
        let pre = c
            .iter()
            .zip(&f)
            .take(18)
            .map(|(a, b)| rel(b.stress[0], a.stress[0]))
            .fold(0.0, f64::max);
        println!("{bc}: coarse vs fine, increments 1-18: {pre:.2e}");
        // 0.5 %: 0.02 N/mm² on the paper's 0-5 N/mm² plot, under a line width (the mesh
        // error of the elastic tangent at the first increment, growing towards the peak).
        assert!(pre < before, "{bc}: {pre:.2e}");
    }
    let fine = limit_point(
        &model("scenes/paper/rve_fine_linear.toml", &[]),
        X,
        "x linear, fine mesh",
    );
    let coarse = peak_x_linear();
    assert!(
        rel(fine.stress, coarse.stress) < limit("fig13.limit_point_rel"),
        "{coarse:?} {fine:?}"
    );
}

/// Fig. 15: "the homogenized response seems more flexible for ellipsoid shape than for
/// circular shape". Two elliptic RVEs against the circles, on eps = [3e-4, 0, 0]:
///
/// - `scenes/paper/rve_ellipses_same_centres.toml`: the paper's construction, the four
///   circles replaced by ellipses (a/b = 1.5) of the same centres and areas;
/// - `scenes/paper_rve_ellipses.toml`: an independent random sample of ellipses (6
///   aggregates, seed 4), the shipped scene of Fig. 14.
///
/// Partly in agreement. Both elliptic RVEs are more compliant in the elastic range on
/// average (D11 + D22: the ellipses have more ITZ per aggregate area); past the peak the
/// same-centre ellipses carry less stress. But the same-centre ellipses are as stiff as
/// the circles along x before the peak (+0.3 %), and the independent sample is 2-3 %
/// more compliant before the peak yet has a higher peak (+3 %).
#[test]
fn ellipses_against_circles() {
    let circles = model("scenes/paper_rve.toml", &[]);
    let same = model("scenes/paper/rve_ellipses_same_centres.toml", &[]);
    let sample = model("scenes/paper_rve_ellipses.toml", &[]);

    // The same-centre scene is what it says: centres and areas of the circles.
    let (ci, ei) = (
        &circles.microstructure().inclusions,
        &same.microstructure().inclusions,
    );
    assert_eq!(ci.len(), ei.len());
    for (c, e) in ci.iter().zip(ei) {
        assert!((c.center[0] - e.center[0]).abs() < 1e-12);
        assert!((c.center[1] - e.center[1]).abs() < 1e-12);
        let (ac, ae) = (
            c.semi_axes[0] * c.semi_axes[1],
            e.semi_axes[0] * e.semi_axes[1],
        );
        assert!(rel(ae, ac) < 1e-12 && rel(e.semi_axes[0] / e.semi_axes[1], 1.5) < 1e-12);
    }

    let trace = |m: &Model| m.elastic_tangent()[0] + m.elastic_tangent()[4];
    let (tc, ts, tr) = (trace(&circles), trace(&same), trace(&sample));
    println!(
        "elastic D11 / D22: circles {:.0} / {:.0}, same centres {:.0} / {:.0}, sample {:.0} / {:.0}",
        circles.elastic_tangent()[0],
        circles.elastic_tangent()[4],
        same.elastic_tangent()[0],
        same.elastic_tangent()[4],
        sample.elastic_tangent()[0],
        sample.elastic_tangent()[4]
    );
    // More compliant on average in the elastic range (measured -0.3 % and -2.8 %).
    assert!(ts < tc && tr < tc);
    // Along x, the same-centre ellipses are slightly STIFFER (+0.25 %): not the paper.
    assert!(same.elastic_tangent()[0] > circles.elastic_tangent()[0]);
    // The independent sample is more compliant along x by more than 1 % (2.1 %).
    assert!(sample.elastic_tangent()[0] < 0.99 * circles.elastic_tangent()[0]);

    let c = run("scenes/paper/rve_circles_3e-4.toml", &[]);
    let s = run("scenes/paper/rve_ellipses_same_centres.toml", &[]);
    let r = run("scenes/paper_rve_ellipses.toml", &[]);
    for k in 0..20 {
        println!(
            "  {:2} eps {:.3e} circles {:.4} same centres {:.4} sample {:.4}",
            k + 1,
            c[k].eps[0],
            c[k].stress[0],
            s[k].stress[0],
            r[k].stress[0]
        );
    }
    // Before the peak (increments 1-13, eps <= 1.95e-4): the same-centre ellipses within
    // 0.5 % of the circles (as for the meshes above), the sample below the circles.
    for k in 0..13 {
        assert!(
            rel(s[k].stress[0], c[k].stress[0]) < limit("fig15.same_centres_before_peak_rel"),
            "increment {}",
            k + 1
        );
        assert!(r[k].stress[0] < c[k].stress[0], "increment {}", k + 1);
    }
    // After the peak (increments 14-20): the same-centre ellipses carry less stress at
    // every increment, on average by more than 5 % (measured: 15 % falling to 7.6 %, mean
    // 9 %; the circles snap at increment 14, as with `contact_shear = "cohesive"`. Before
    // the contact status was held within a Newton iteration the trace of that increment
    // was lost on the paper's law and the secant iterations found the circles still on
    // their pre-peak branch, 33 % falling to 5 %, mean 16 %).
    let mut deficit = 0.0;
    for k in 13..20 {
        assert!(s[k].stress[0] < c[k].stress[0], "increment {}", k + 1);
        deficit += (1.0 - s[k].stress[0] / c[k].stress[0]) / 7.0;
    }
    println!("post-peak mean deficit of the same-centre ellipses {deficit:.3}");
    assert!(
        deficit > limit("fig15.same_centres_post_peak_deficit"),
        "{deficit}"
    );
    // Limit points: same-centre ellipses 0.6 % below the circles; the sample ABOVE them.
    let pc = peak_x_periodic();
    let ps = limit_point(&same, X, "same-centre ellipses");
    let pr = limit_point(&sample, X, "ellipse sample");
    assert!(
        ps.stress < pc.stress
            && rel(ps.stress, pc.stress) < limit("fig15.same_centres_limit_point_rel")
    );
    assert!(
        pr.stress > pc.stress,
        "the sample's peak is not higher any more"
    );
}

// ---------------------------------------------------------------------------------------
// Section 5.2.2: unilateral effect
// ---------------------------------------------------------------------------------------

/// Fig. 16: the cycle [2.3e-4, 0, 0] -> [-4.5e-4, 0, 0] in 60 increments: a damaged,
/// secant unloading in tension, stiffness recovery when the cracks close, and "the
/// proposed modeling is not capable to capture the dissipation processes ... in
/// compression".
#[test]
fn unilateral_effect_on_the_cycle() {
    let m = model("scenes/paper_rve_cycle.toml", &[]);
    let virgin = m.elastic_tangent()[0];
    let n = m.discretization().history_len();
    let p = run("scenes/paper_rve_cycle.toml", &[]);
    assert_eq!(p.len(), 60);
    // Unloading (increments 21-33, eps from 2.13e-4 down to 9e-6): secant to the origin.
    let secants: Vec<f64> = p[20..33].iter().map(|q| q.stress[0] / q.eps[0]).collect();
    let unload = secants[0];
    for (q, s) in p[20..33].iter().zip(&secants) {
        // Every point unloads on its secant or sits closed on the (linear) penalty: the
        // response is linear through the origin, so the secant is the tangent. 1e-6 is
        // the Newton tolerance (relative to the load).
        assert!(rel(*s, unload) < 1e-6 && rel(q.tangent[0], unload) < 1e-6);
    }
    // Compression (increments 34-60): every ITZ point is closed.
    let comp = &p[33..];
    assert!(comp.iter().all(|q| q.contact == n), "not all closed");
    let recovered = comp[0].tangent[0];
    println!(
        "virgin D11 {virgin:.0}; unloading secant {unload:.0} = {:.3} virgin; \
         compression D11 {recovered:.0} = {:.4} virgin",
        unload / virgin,
        recovered / virgin
    );
    // Damage: the unloading secant has lost 41 % of the virgin stiffness.
    assert!(unload < limit("fig16.unloading_secant_below") * virgin);
    // Recovery: closed cracks give back the virgin stiffness within 2 % (+0.2 %
    // measured). The penalty lambda_p l_e = 1e5 * 0.48 = 4.8e4 N/mm³ is close to the
    // intact ITZ's initial stiffness (e sigma_c / delta_c = 5.4e4 normal, half that in
    // shear), so the closed RVE is nearly the virgin one; see the penalty study for
    // larger lambda_p.
    assert!(rel(recovered, virgin) < limit("fig16.recovered_rel"));
    // No dissipation in compression: the branch is linear (constant tangent, stress
    // increments equal to tangent times strain increments).
    for w in comp.windows(2) {
        assert!(rel(w[1].tangent[0], recovered) < 1e-9);
        let ds = w[1].stress[0] - w[0].stress[0];
        assert!(rel(ds, recovered * (w[1].eps[0] - w[0].eps[0])) < 1e-6);
    }
}

/// Section 5.2.2, on the cycle of Fig. 16: "initially, the numerical responses are very
/// similar, but when the dissipation processes take place ... a difference between the
/// periodic and linear conditions is more evident. The linear condition gives the
/// stiffest solution."
///
/// Partly in agreement, on the cycle where the paper states it: similar at first, the gap
/// growing with dissipation, and linear stiffer at every increment but one. At increment
/// 18 (eps_xx = 2.07e-4) the linear RVE is already past its limit point (2.0625e-4) and
/// the periodic one not yet (2.076e-4), so there the periodic stress is 35 % higher. The
/// limit-point stresses themselves differ by less than 0.1 % (linear the higher). On the
/// section 5.2.1 path linear is stiffer at every increment.
#[test]
fn linear_bc_is_stiffer_than_periodic() {
    let (mp, ml) = (
        model("scenes/paper_rve.toml", &[]),
        model("scenes/paper/rve_linear.toml", &[]),
    );
    let elastic = (ml.elastic_tangent()[0] - mp.elastic_tangent()[0]) / mp.elastic_tangent()[0];
    // The spaces of fluctuations are nested: linear >= periodic in the elastic range
    // (tests/solver_verification.rs checks the whole ordering).
    assert!(elastic > 0.0, "{elastic:.1e}");

    // The cycle of Fig. 16 with both BCs: linear minus periodic, relative to periodic,
    // signed so that positive is stiffer in tension and in compression.
    let cp = run("scenes/paper_rve_cycle.toml", &[]);
    let cl = run("scenes/paper/cycle_linear.toml", &[]);
    let gap: Vec<f64> = cp
        .iter()
        .zip(&cl)
        .map(|(p, l)| (l.stress[0] - p.stress[0]) * p.eps[0].signum() / p.stress[0].abs())
        .collect();
    let shown: Vec<String> = gap.iter().map(|g| format!("{g:.1e}")).collect();
    println!("elastic D11 gap {elastic:.2e}; s_xx gap along the cycle {shown:?}");
    let below: Vec<usize> = (0..60).filter(|&k| gap[k] <= 0.0).map(|k| k + 1).collect();
    assert_eq!(below, [18], "increments where linear is not the stiffer");
    // Very similar at first, more evident with dissipation: at increment 17 (97 % of the
    // peak) the gap is an order of magnitude larger than at the first, and after the
    // snap (increments 19-20) above 1 %.
    assert!(gap[0] < limit("linear_bc.first_gap_below"), "{shown:?}");
    assert!(gap[16] > limit("linear_bc.growth") * gap[0], "{shown:?}");
    let post = limit("linear_bc.post_peak_gap");
    assert!(gap[18] > post && gap[19] > post, "{shown:?}");
    // The exception: linear has passed its limit point, periodic not yet.
    assert!(cp[17].stress[0] > 1.3 * cl[17].stress[0]);
    let (pp, pl) = (peak_x_periodic(), peak_x_linear());
    assert!(pl.strain < cp[17].eps[0] && cp[17].eps[0] < pp.strain);
    assert!(pl.stress > pp.stress, "{pp:?} {pl:?}");
    assert!(
        rel(pl.stress, pp.stress) < limit("linear_bc.limit_point_rel"),
        "{pp:?} {pl:?}"
    );

    // The section 5.2.1 path: linear stiffer at every increment.
    let per = run("scenes/paper_rve.toml", &[]);
    let lin = run("scenes/paper/rve_linear.toml", &[]);
    assert!(
        per.iter().zip(&lin).all(|(a, b)| b.stress[0] > a.stress[0]),
        "linear below periodic somewhere on the 5.2.1 path"
    );
}

/// Fig. 17: lambda_p from 1e4 to 1e9 N/mm on the cycle; "for high values, the penalty
/// factor does not influence the behavior of the numerical responses ... 10^7 can be
/// considered as a reasonable penalty factor".
///
/// In agreement with both contact laws, each swept over every lambda_p: the paper's
/// (`contact_shear = "penalty"`, the shipped scenes' law: the penalty on both components,
/// sliding measured from the reference configuration) and `contact_shear = "cohesive"`
/// (the project's own law, penalty on the normal only). Every value goes through with
/// the contact status held within a Newton iteration (the default;
/// docs/contact-algorithm.md).
#[test]
fn penalty_study() {
    const CYCLE: &str = "scenes/paper_rve_cycle.toml";
    let lambdas = ["1e4", "1e5", "1e6", "1e7", "1e8", "1e9"];
    // Largest stress difference to lambda_p = 1e9 over the cycle, relative to the largest
    // stress, for one contact law; every value of lambda_p must go through.
    let study = |shear: &str| -> (Vec<Vec<Point>>, Vec<f64>) {
        let curves: Vec<Vec<Point>> = lambdas
            .iter()
            .map(|lp| {
                let to = format!("lambda_p = {lp} }}, contact_shear = \"{shear}\"");
                run(CYCLE, &[("lambda_p = 1e5 }", &to)])
            })
            .collect();
        let reference = curves.last().unwrap();
        let scale = reference
            .iter()
            .map(|q| q.stress[0].abs())
            .fold(0.0, f64::max);
        let dist: Vec<f64> = curves
            .iter()
            .map(|c| {
                c.iter()
                    .zip(reference)
                    .map(|(a, b)| (a.stress[0] - b.stress[0]).abs())
                    .fold(0.0, f64::max)
                    / scale
            })
            .collect();
        for (lp, (d, c)) in lambdas.iter().zip(dist.iter().zip(&curves)) {
            println!(
                "{shear}: lambda_p {lp}: distance to 1e9 {d:.2e}, compression D11 {:.0}, \
                 iterations at closure {}",
                c[59].tangent[0], c[33].iterations
            );
        }
        (curves, dist)
    };

    let (converged, off_1e4, off_1e5) = (
        limit("fig17.converged"),
        limit("fig17.off_1e4"),
        limit("fig17.off_1e5"),
    );
    // Cohesive contact shear. Converged from 1e7 up, while 1e4 and 1e5 are far off.
    let (_, dist) = study("cohesive");
    assert!(
        dist[3] < converged && dist[4] < limit("fig17.cohesive_1e8"),
        "{dist:?}"
    );
    assert!(dist[0] > off_1e4 && dist[1] > off_1e5, "{dist:?}");
    // The penalty error decays like 1 / lambda_p.
    for k in 0..4 {
        assert!(
            dist[k + 1] < dist[k] / limit("fig17.decay_per_decade"),
            "{dist:?}"
        );
    }

    // The paper's law: every value goes through, and from 1e7 up the response is within
    // `converged` of 1e9 (the largest difference is after the snap, where the increments
    // land on different post-snap equilibria), while 1e4 and 1e5 are far off. At the end
    // of the compression branch the stress converges first order in 1 / lambda_p.
    let (paper, dist) = study("penalty");
    assert!(dist[3] < converged && dist[4] < converged, "{dist:?}");
    assert!(dist[0] > off_1e4 && dist[1] > off_1e5, "{dist:?}");
    let end: Vec<f64> = paper
        .iter()
        .map(|c| (c[59].stress[0] - paper[5][59].stress[0]).abs() / paper[5][59].stress[0].abs())
        .collect();
    assert!(
        end[3] < limit("fig17.end_1e7")
            && end[4] < limit("fig17.end_1e8")
            && end[4] < end[3] / limit("fig17.decay_per_decade"),
        "{end:?}"
    );
    // Its compression stiffness converges above the cohesive shear's (28246 against
    // 26978 measured): a closed point sticks in shear.
    let stiff: Vec<f64> = paper.iter().map(|c| c[59].tangent[0]).collect();
    assert!(stiff[1] > 1.5 * stiff[0], "{stiff:?}");
    assert!((stiff[5] - stiff[3]).abs() < 0.01 * stiff[5], "{stiff:?}");
}

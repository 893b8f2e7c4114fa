//! The host seam (`rve::host`): the NTENS 3/4/6 maps against the RVE's own answer, the
//! UMAT's DDSDDE against finite differences of its STRESS (the `s_zz` row included), the
//! increment protocol (commit on a new increment, revert on a cut-back, repeats answered
//! without a solve), scene lookup and PROPS, a missing scene (the embedded RVE's elastic
//! tangent in DDSDDE; a scene written later is found), the damage and opening mirrors,
//! and threads.

mod common;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use rve::host::{Hypothesis, SearchPath, Umat, UmatCall, UmatFailure, UmatOutputs};
use rve::model::cache;
use rve::{Error, Instance, Model, TangentRequest};

/// A directory of scenes for one test: the paper RVE in plane stress (`PAPER`), in plane
/// strain with a more contractile aggregate and a tight tolerance (`STRAIN`: the phases'
/// Poisson ratios differ, so `s_zz` is not `nu (s_xx + s_yy)`), and a variant of it that
/// fails at the first hard increment (`FRAGILE`: the paper's tolerance, three Newton
/// iteration, no remedies).
fn scene_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mesorve-host-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let strain = common::paper_scene_with(&[
        ("analysis = \"plane_stress\"", "analysis = \"plane_strain\""),
        (
            "aggregate = { young = 30000.0, poisson = 0.2 }",
            "aggregate = { young = 30000.0, poisson = 0.3 }",
        ),
        ("tolerance = 1e-6", "tolerance = 1e-12"),
    ]);
    let fragile = strain
        .replace("tolerance = 1e-12", "tolerance = 1e-6")
        .replace(
            "max_iterations = 40",
            "max_iterations = 3\npath_following = false\nmax_secant_iterations = 0\n\
         max_substep_depth = 0",
        );
    std::fs::write(dir.join("paper.toml"), common::paper_scene_with(&[])).unwrap();
    std::fs::write(dir.join("strain.toml"), strain).unwrap();
    std::fs::write(dir.join("fragile.toml"), fragile).unwrap();
    dir
}

fn model(dir: &Path, name: &str) -> Arc<Model> {
    cache::model_for_file(&dir.join(format!("{name}.toml"))).unwrap()
}

/// One UMAT call's inputs besides the strain.
#[derive(Clone, Copy)]
struct At {
    noel: i32,
    npt: i32,
    kstep: i32,
    kinc: i32,
    /// TIME(2) at the start of the increment.
    start: f64,
    dtime: f64,
    /// PNEWDT as the host hands it in (Abaqus: large; CalculiX: -1).
    pnewdt: f64,
}

fn at(noel: i32, kinc: i32) -> At {
    At {
        noel,
        npt: 1,
        kstep: 1,
        kinc,
        start: 0.1 * f64::from(kinc - 1),
        dtime: 0.1,
        pnewdt: 1e36,
    }
}

struct Answer {
    result: Result<rve::host::Outcome, UmatFailure>,
    stress: Vec<f64>,
    ddsdde: Vec<f64>,
    statev: [f64; 5],
    pnewdt: f64,
}

const UNTOUCHED: f64 = 7.0;

/// Calls the UMAT the way Abaqus does: `STRAN` the strain at the start of the increment
/// (here: `start`), `DSTRAN` the rest up to `strain`.
fn call(
    umat: &Umat,
    cmname: &str,
    props: &[f64],
    h: Hypothesis,
    start: &[f64],
    strain: &[f64],
    a: At,
) -> Answer {
    let n = h.ntens();
    let dstran: Vec<f64> = strain.iter().zip(start).map(|(e, s)| e - s).collect();
    let mut stress = vec![UNTOUCHED; n];
    let mut ddsdde = vec![UNTOUCHED; n * n];
    let mut statev = [0.0; 5];
    let mut pnewdt = a.pnewdt;
    let c = UmatCall {
        cmname,
        props,
        hypothesis: h,
        stran: start,
        dstran: &dstran,
        time: [a.start, a.start],
        dtime: a.dtime,
        noel: a.noel,
        npt: a.npt,
        kstep: a.kstep,
        kinc: a.kinc,
        celent: None,
    };
    let result = umat.call(
        &c,
        &mut UmatOutputs {
            stress: &mut stress,
            ddsdde: &mut ddsdde,
            statev: &mut statev,
            pnewdt: &mut pnewdt,
        },
    );
    Answer {
        result,
        stress,
        ddsdde,
        statev,
        pnewdt,
    }
}

fn ok(a: Answer) -> Answer {
    if let Err(f) = &a.result {
        panic!("UMAT failed: {f}");
    }
    a
}

/// `[11, 22, 33, 12]` or `[11, 22, 33, 12, 13, 23]` from an in-plane strain.
fn host_strain(h: Hypothesis, e: [f64; 3]) -> Vec<f64> {
    match h {
        Hypothesis::PlaneStress => e.to_vec(),
        Hypothesis::PlaneStrain => vec![e[0], e[1], 0.0, e[2]],
        Hypothesis::Tridimensional => vec![e[0], e[1], 0.0, e[2], 0.0, 0.0],
    }
}

const DIR: [f64; 3] = [1.0, 0.3, 0.5];

fn scaled(s: f64) -> [f64; 3] {
    DIR.map(|d| d * s)
}

#[test]
fn ntens_3_4_6_return_the_rve_answer_in_the_host_layout() {
    let dir = scene_dir("layouts");
    let umat = Umat::new(SearchPath::new([dir.clone()]));
    let eps = scaled(1.2e-4);

    // NTENS 3, plane stress: the RVE's stress and tangent, DDSDDE(i, j) = D[3 i + j].
    let paper = model(&dir, "paper");
    let mut reference = Instance::new(paper.clone());
    let r = reference
        .update(eps, &mut paper.workspace(), TangentRequest::Consistent)
        .unwrap();
    let a = ok(call(
        &umat,
        "PAPER",
        &[],
        Hypothesis::PlaneStress,
        &[0.0; 3],
        &eps,
        at(1, 1),
    ));
    assert_eq!(a.stress, r.stress.to_vec());
    for i in 0..3 {
        for j in 0..3 {
            assert_eq!(
                a.ddsdde[i + 3 * j],
                r.tangent[3 * i + j],
                "DDSDDE({i}, {j})"
            );
        }
    }
    assert_eq!(a.statev[0], 1.0, "STATEV(1) mirrors the point's id");
    assert_eq!(a.statev[1], f64::from(r.report.iterations));

    // NTENS 4 and 6 on the plane-strain RVE: one answer, s_zz in position 3.
    let strain = model(&dir, "strain");
    let mut reference = Instance::new(strain.clone());
    let r = reference
        .update(eps, &mut strain.workspace(), TangentRequest::Consistent)
        .unwrap();
    assert!(
        r.s_zz.abs() > 0.1 * r.stress[0].abs(),
        "plane strain has an s_zz"
    );
    for (noel, h) in [
        (2, Hypothesis::PlaneStrain),
        (3, Hypothesis::Tridimensional),
    ] {
        let zero = vec![0.0; h.ntens()];
        let a = ok(call(
            &umat,
            "STRAIN",
            &[],
            h,
            &zero,
            &host_strain(h, eps),
            at(noel, 1),
        ));
        let mut want = vec![r.stress[0], r.stress[1], r.s_zz, r.stress[2]];
        want.resize(h.ntens(), 0.0);
        assert_eq!(a.stress, want, "{h:?}");
        let n = h.ntens();
        let d = |i: usize, j: usize| a.ddsdde[(i - 1) + n * (j - 1)];
        let host = [1, 2, 4];
        for (i, &hi) in host.iter().enumerate() {
            for (j, &hj) in host.iter().enumerate() {
                assert_eq!(d(hi, hj), r.tangent[3 * i + j], "{h:?} DDSDDE({hi}, {hj})");
            }
            assert_eq!(d(3, hi), r.s_zz_tangent[i], "{h:?} DDSDDE(3, {hi})");
            assert_eq!(d(hi, 3), r.s_zz_tangent[i], "{h:?} DDSDDE({hi}, 3)");
        }
        let el = strain.elastic_tangent();
        assert_eq!(d(3, 3), 0.5 * (el[0] + el[4]));
        if n == 6 {
            assert_eq!((d(5, 5), d(6, 6)), (el[8], el[8]));
        }
    }

    // A host in the other plane state, or with an out-of-plane strain, is refused with
    // PNEWDT < 1, STRESS untouched and the elastic tangent in DDSDDE.
    let wrong = call(
        &umat,
        "PAPER",
        &[],
        Hypothesis::PlaneStrain,
        &[0.0; 4],
        &host_strain(Hypothesis::PlaneStrain, eps),
        at(4, 1),
    );
    let f = wrong.result.as_ref().unwrap_err();
    assert!(matches!(*f.error, Error::HostConvention(_)), "{f}");
    assert!(
        f.to_string().contains("cell.analysis = \"plane_strain\""),
        "{f}"
    );
    assert_eq!(wrong.pnewdt, 0.25);
    assert!(wrong.stress.iter().all(|&s| s == UNTOUCHED));
    assert_eq!(wrong.ddsdde[0], paper.elastic_tangent()[0]);
    let mut bent = host_strain(Hypothesis::Tridimensional, eps);
    bent[4] = 1e-5;
    let bad = call(
        &umat,
        "STRAIN",
        &[],
        Hypothesis::Tridimensional,
        &[0.0; 6],
        &bent,
        at(5, 1),
    );
    let f = bad.result.as_ref().unwrap_err();
    assert!(f.to_string().contains("gamma_13 = 1e-5"), "{f}");
    assert_eq!(bad.pnewdt, 0.25);
    std::fs::remove_dir_all(&dir).ok();
}

/// DDSDDE of the UMAT against central differences of its STRESS in each in-plane strain
/// component, every perturbed call a trial of the same increment: the in-plane block and
/// the `s_zz` row (exact `d s_zz / d eps`), on the virgin RVE and after pre-peak damage.
#[test]
fn ddsdde_matches_finite_differences_of_stress_in_plane_strain() {
    let dir = scene_dir("fd");
    let umat = Umat::new(SearchPath::new([dir.clone()]));
    let h = Hypothesis::PlaneStrain;
    let host = [0usize, 1, 3];
    let mut start = vec![0.0; 4];
    // Damage: four increments along DIR, committed by the protocol (KINC 1..4).
    for (k, level) in [0.4e-4, 0.8e-4, 1.2e-4, 1.5e-4].into_iter().enumerate() {
        let e = host_strain(h, scaled(level));
        ok(call(
            &umat,
            "STRAIN",
            &[],
            h,
            &start,
            &e,
            at(1, k as i32 + 1),
        ));
        start = e;
    }
    assert_eq!(umat.stats().commits, 3);
    let nu_formula_error;
    {
        // KINC 5: the base trial and its neighbours.
        let kinc = 5;
        let eps = scaled(1.55e-4);
        let base = ok(call(
            &umat,
            "STRAIN",
            &[],
            h,
            &start,
            &host_strain(h, eps),
            at(1, kinc),
        ));
        let d = |i: usize, j: usize| base.ddsdde[i + 4 * j];
        let fd = |step: f64| {
            let mut out = [[0.0; 4]; 3];
            for (j, col) in out.iter_mut().enumerate() {
                let mut plus = eps;
                let mut minus = eps;
                plus[j] += step;
                minus[j] -= step;
                let p = ok(call(
                    &umat,
                    "STRAIN",
                    &[],
                    h,
                    &start,
                    &host_strain(h, plus),
                    at(1, kinc),
                ));
                let m = ok(call(
                    &umat,
                    "STRAIN",
                    &[],
                    h,
                    &start,
                    &host_strain(h, minus),
                    at(1, kinc),
                ));
                for (i, c) in col.iter_mut().enumerate() {
                    *c = (p.stress[i] - m.stress[i]) / (2.0 * step);
                }
            }
            out
        };
        let step = 1e-5 * 1.55e-4;
        let (f1, f2) = (fd(step), fd(2.0 * step));
        let scale = (0..4)
            .flat_map(|i| host.map(|j| d(i, j).abs()))
            .fold(0.0f64, f64::max);
        let (mut error, mut fd_change) = (0.0f64, 0.0f64);
        for (jj, &j) in host.iter().enumerate() {
            for i in 0..4 {
                error = error.max((d(i, j) - f1[jj][i]).abs() / scale);
                fd_change = fd_change.max((f2[jj][i] - f1[jj][i]).abs() / scale);
            }
        }
        println!("DDSDDE vs FD: {error:.1e} (FD converged to {fd_change:.1e})");
        assert!(fd_change < 1e-7, "FD not converged: {fd_change:.2e}");
        assert!(error < 1e-6, "DDSDDE differs from FD by {error:.2e}");
        // The s_zz row is not nu (D_1j + D_2j) for either phase's nu: the phases'
        // Poisson ratios differ, and the row above is the exact one.
        nu_formula_error = [0.2, 0.3]
            .map(|nu| {
                host.iter()
                    .map(|&j| (nu * (d(0, j) + d(1, j)) - d(2, j)).abs() / scale)
                    .fold(0.0f64, f64::max)
            })
            .into_iter()
            .fold(f64::INFINITY, f64::min);
    }
    println!("nu (D_1j + D_2j) misses the s_zz row by {nu_formula_error:.1e}");
    assert!(nu_formula_error > 1e-3, "{nu_formula_error:.2e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_new_increment_commits_a_cutback_reverts_a_repeat_is_not_solved() {
    let dir = scene_dir("protocol");
    let strain_model = model(&dir, "strain");
    let umat = Umat::new(SearchPath::new([dir.clone()]));
    let h = Hypothesis::PlaneStrain;
    let (e1, e2, e3) = (scaled(0.8e-4), scaled(1.2e-4), scaled(1.4e-4));
    let abandoned = scaled(1.9e-4);
    let hs = |e: [f64; 3]| host_strain(h, e);
    // The reference: commit e1, commit e2, trial e3.
    let mut reference = Instance::new(strain_model.clone());
    let mut ws = strain_model.workspace();
    for e in [e1, e2] {
        reference
            .update(e, &mut ws, TangentRequest::Consistent)
            .unwrap();
        reference.commit().unwrap();
    }
    let want = reference
        .update(e3, &mut ws, TangentRequest::Consistent)
        .unwrap();

    let zero = vec![0.0; 4];
    // KINC 1: two iterations (the second converged at e1), a repeated call.
    ok(call(
        &umat,
        "STRAIN",
        &[],
        h,
        &zero,
        &hs(scaled(0.5e-4)),
        at(1, 1),
    ));
    ok(call(&umat, "STRAIN", &[], h, &zero, &hs(e1), at(1, 1)));
    let again = ok(call(&umat, "STRAIN", &[], h, &zero, &hs(e1), at(1, 1)));
    assert!(
        !again.result.unwrap().solved,
        "a repeated strain is not solved again"
    );
    // KINC 2: commits e1; a first attempt to the abandoned strain, then the host cuts
    // back (smaller DTIME, same KINC and start) and converges at e2.
    let first = ok(call(
        &umat,
        "STRAIN",
        &[],
        h,
        &hs(e1),
        &hs(abandoned),
        at(1, 2),
    ));
    assert!(first.result.as_ref().unwrap().committed);
    let mut retry = at(1, 2);
    retry.dtime = 0.05;
    // CalculiX passes TIME(2) as (t + dt) - dt: the retry's start moves by an ulp.
    retry.start = (0.1 + retry.dtime) - retry.dtime;
    assert_ne!(retry.start, 0.1);
    let r = ok(call(&umat, "STRAIN", &[], h, &hs(e1), &hs(e2), retry));
    assert!(
        r.result.as_ref().unwrap().reverted,
        "a smaller DTIME in the same increment reverts"
    );
    // KINC 3 (start time rounded differently from KINC 2's end: still a new increment).
    let mut third = at(1, 3);
    third.start = 0.1 + 0.05;
    let got = ok(call(&umat, "STRAIN", &[], h, &hs(e2), &hs(e3), third));
    assert_eq!(
        got.stress,
        vec![want.stress[0], want.stress[1], want.s_zz, want.stress[2]]
    );
    let s = umat.stats();
    assert_eq!(
        (s.commits, s.reverts, s.repeats, s.solves, s.failures),
        (2, 1, 1, 5, 0)
    );

    // Our own failure: a solver failure sets PNEWDT < 1 and leaves STRESS; the retry of
    // the same increment reverts and starts from the committed state.
    let fragile = model(&dir, "fragile");
    let big = scaled(3e-4);
    let failed = call(&umat, "FRAGILE", &[], h, &zero, &hs(big), at(9, 1));
    let f = failed.result.as_ref().unwrap_err();
    assert!(matches!(*f.error, Error::Solve { .. }), "{f}");
    assert!(
        failed.pnewdt > 0.0 && failed.pnewdt < 1.0,
        "{}",
        failed.pnewdt
    );
    assert!(failed.stress.iter().all(|&s| s == UNTOUCHED));
    assert_eq!(
        failed.ddsdde[0],
        fragile.elastic_tangent()[0],
        "elastic DDSDDE on failure"
    );
    let small = scaled(0.2e-4);
    let mut retry = at(9, 1);
    retry.dtime *= failed.pnewdt;
    let again = ok(call(&umat, "FRAGILE", &[], h, &zero, &hs(small), retry));
    assert!(again.result.as_ref().unwrap().reverted);
    let mut virgin = Instance::new(fragile.clone());
    let r = virgin
        .update(small, &mut fragile.workspace(), TangentRequest::Consistent)
        .unwrap();
    assert_eq!(again.stress[0], r.stress[0]);
    // Time advancing with the same KINC (a host without increment numbers) commits.
    let mut later = at(9, 1);
    later.start = 1.0;
    let next = ok(call(
        &umat,
        "FRAGILE",
        &[],
        h,
        &hs(small),
        &hs(small),
        later,
    ));
    assert!(next.result.unwrap().committed);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn scenes_are_found_by_material_name_and_props_override_keys() {
    let dir = scene_dir("lookup");
    let other = dir.join("elsewhere");
    std::fs::create_dir_all(&other).unwrap();
    let umat = Umat::new(SearchPath::new([other.clone(), dir.clone()]));
    let eps = scaled(1.0e-4);
    let h = Hypothesis::PlaneStress;
    // CalculiX's name (upper case, the library selector, a tag) finds paper.toml.
    let a = ok(call(
        &umat,
        "@ABAQUS_RVE_UMAT@PAPER@1",
        &[],
        h,
        &[0.0; 3],
        &eps,
        at(1, 1),
    ));
    let b = ok(call(
        &umat,
        "paper",
        &[0.0; 6],
        h,
        &[0.0; 3],
        &eps,
        at(2, 1),
    ));
    assert_eq!(a.stress, b.stress, "PROPS of zeros keep the scene");
    // The embedded paper RVE: the same scene as paper.toml.
    let c = ok(call(
        &umat,
        "@ABAQUS_RVE_UMAT",
        &[],
        h,
        &[0.0; 3],
        &eps,
        at(3, 1),
    ));
    assert_eq!(a.stress, c.stress);
    // PROPS(1) halves sigma_c: a different (weaker) material at a strain near the peak.
    let near_peak = scaled(1.5e-4);
    let strong = ok(call(
        &umat,
        "PAPER",
        &[],
        h,
        &[0.0; 3],
        &near_peak,
        at(4, 1),
    ));
    let weak = ok(call(
        &umat,
        "PAPER@WEAK",
        &[2.0],
        h,
        &[0.0; 3],
        &near_peak,
        at(5, 1),
    ));
    assert!(
        weak.stress[0] < 0.9 * strong.stress[0],
        "{:?} {:?}",
        weak.stress,
        strong.stress
    );
    // PROPS(6) = 1: the elastic tangent of the virgin RVE, the same stress.
    let mut props = [0.0; 6];
    props[5] = 1.0;
    let el = ok(call(
        &umat,
        "PAPER@ELASTIC",
        &props,
        h,
        &[0.0; 3],
        &near_peak,
        at(6, 1),
    ));
    assert_eq!(el.stress, strong.stress);
    let paper = model(&dir, "paper");
    assert_eq!(
        el.ddsdde[..3],
        [
            paper.elastic_tangent()[0],
            paper.elastic_tangent()[3],
            paper.elastic_tangent()[6]
        ]
    );
    assert_ne!(el.ddsdde, strong.ddsdde);
    // A point keeps its material.
    let moved = call(&umat, "PAPER@WEAK", &[2.0], h, &[0.0; 3], &eps, at(4, 1));
    let f = moved.result.unwrap_err();
    assert!(f.to_string().contains("keeps its material"), "{f}");
    // A bad PROPS is refused with the key named.
    let bad = call(
        &umat,
        "PAPER@SEED",
        &[0.0, 0.0, 1.5],
        h,
        &[0.0; 3],
        &eps,
        at(7, 1),
    );
    let f = bad.result.unwrap_err();
    assert!(f.to_string().contains("PROPS(3) (geometry.seed)"), "{f}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Table mode: `STATEV(4..5)` mirror the RVE's damage and largest ITZ opening, those of
/// the state the call leaves (`rve::host::mirrors`), growing past the peak.
#[test]
fn mirrors_hold_the_rve_damage_and_largest_opening() {
    let dir = scene_dir("mirrors");
    let umat = Umat::new(SearchPath::new([dir.clone()]));
    let paper = model(&dir, "paper");
    let mut reference = Instance::new(paper.clone());
    let mut ws = paper.workspace();
    let mut start = [0.0; 3];
    let mut last = (0.0, 0.0);
    for (k, level) in [0.5e-4, 1.5e-4, 2.5e-4, 3.5e-4].into_iter().enumerate() {
        let eps = [level, 0.0, 0.0];
        let kinc = k as i32 + 1;
        let a = ok(call(
            &umat,
            "PAPER",
            &[],
            Hypothesis::PlaneStress,
            &start,
            &eps,
            at(1, kinc),
        ));
        reference
            .update(eps, &mut ws, TangentRequest::Consistent)
            .unwrap();
        let m = rve::host::RveMeasures::of(&paper, reference.trial_history());
        reference.commit().unwrap();
        assert_eq!(
            [a.statev[3], a.statev[4]],
            [m.damage, m.max_opening],
            "increment {kinc}"
        );
        assert!(
            (0.0..1.0).contains(&m.damage) && m.damage >= last.0,
            "{m:?}"
        );
        assert!(m.max_opening >= last.1, "{m:?}");
        last = (m.damage, m.max_opening);
        start = eps;
    }
    // Past the RVE's peak (about 2.2e-4): ITZ points beyond delta_c (2e-4 mm), damage well
    // above its value at the first increment.
    assert!(last.1 > 2e-4 && last.0 > 0.1, "{last:?}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_missing_scene_is_a_clear_error_reported_once() {
    let dir = scene_dir("missing");
    let umat = Umat::new(SearchPath::new([dir.clone()]));
    let h = Hypothesis::PlaneStress;
    let eps = scaled(1.0e-4);
    let a = call(
        &umat,
        "@ABAQUS_RVE_UMAT@NO_SUCH_SCENE",
        &[],
        h,
        &[0.0; 3],
        &eps,
        at(1, 1),
    );
    let f = a.result.unwrap_err();
    match &*f.error {
        Error::SceneNotFound { name, searched } => {
            assert_eq!(name, "NO_SUCH_SCENE");
            assert_eq!(
                searched,
                &vec![
                    dir.join("NO_SUCH_SCENE.toml"),
                    dir.join("no_such_scene.toml")
                ]
            );
        }
        other => panic!("{other}"),
    }
    let text = f.to_string();
    assert!(
        text.contains("element 1, point 1") && text.contains("no_such_scene.toml"),
        "{text}"
    );
    assert!(f.first_report);
    assert_eq!(a.pnewdt, 0.25);
    assert!(a.stress.iter().all(|&s| s == UNTOUCHED));
    // DDSDDE: the embedded paper RVE's elastic tangent (docs/umat.md, "Failures"), so
    // that a host assembling it gets a regular matrix, in its own layout.
    let d = cache::model_for_text(rve::scene::DEFAULT_SCENE_TOML, None)
        .unwrap()
        .elastic_tangent();
    for i in 0..3 {
        for j in 0..3 {
            assert_eq!(a.ddsdde[i + 3 * j], d[3 * i + j], "DDSDDE({i}, {j})");
        }
    }
    assert!(d[0] > 1e4 && d[4] > 1e4 && d[8] > 1e3, "{d:?}");
    // NTENS 6 (CalculiX's 2D elements): in-plane block at [11, 22, 12], (D11 + D22) / 2
    // on 33, D33 on 13 and 23, zero elsewhere (the embedded RVE is in plane stress: no
    // s_zz row).
    let t = call(
        &umat,
        "@ABAQUS_RVE_UMAT@NO_SUCH_SCENE",
        &[],
        Hypothesis::Tridimensional,
        &[0.0; 6],
        &host_strain(Hypothesis::Tridimensional, eps),
        at(5, 1),
    );
    assert!(t.result.is_err());
    let mut want = [0.0; 36];
    for (i, &hi) in [0, 1, 3].iter().enumerate() {
        for (j, &hj) in [0, 1, 3].iter().enumerate() {
            want[hi + 6 * hj] = d[3 * i + j];
        }
    }
    want[2 + 6 * 2] = 0.5 * (d[0] + d[4]);
    want[4 + 6 * 4] = d[8];
    want[5 + 6 * 5] = d[8];
    assert_eq!(
        t.ddsdde,
        want.to_vec(),
        "NTENS 6 DDSDDE of the embedded RVE"
    );
    assert!(t.stress.iter().all(|&s| s == UNTOUCHED));
    let b = call(
        &umat,
        "@ABAQUS_RVE_UMAT@NO_SUCH_SCENE",
        &[],
        h,
        &[0.0; 3],
        &eps,
        at(2, 1),
    );
    let f = b.result.unwrap_err();
    assert!(!f.first_report, "the same material error is reported once");
    assert_eq!(umat.stats().failures, 3);
    assert_eq!(umat.stats().points, 0);
    // A scene file written after the failures is found at the next call.
    std::fs::copy(dir.join("paper.toml"), dir.join("no_such_scene.toml")).unwrap();
    let c = call(
        &umat,
        "@ABAQUS_RVE_UMAT@NO_SUCH_SCENE",
        &[],
        h,
        &[0.0; 3],
        &eps,
        at(3, 1),
    );
    assert!(c.result.is_ok(), "the scene written later is used");
    assert_eq!(umat.stats().points, 1);
    std::fs::remove_dir_all(&dir).ok();
}

/// Several threads, each on its own points, give the answers of one thread, bit for bit.
#[test]
fn distinct_points_from_threads_match_one_thread() {
    let dir = scene_dir("threads");
    let h = Hypothesis::Tridimensional;
    let path = [0.6e-4, 1.2e-4, 1.6e-4, 0.8e-4];
    let run = |umat: &Umat, noel: i32| -> Vec<Vec<f64>> {
        let mut start = vec![0.0; 6];
        let mut out = Vec::new();
        for (k, level) in path.iter().enumerate() {
            let e = host_strain(h, scaled(level * (1.0 + 0.1 * f64::from(noel))));
            let a = ok(call(
                umat,
                "STRAIN",
                &[],
                h,
                &start,
                &e,
                at(noel, k as i32 + 1),
            ));
            out.push(a.stress.iter().chain(&a.ddsdde).copied().collect());
            start = e;
        }
        out
    };
    let serial = Umat::new(SearchPath::new([dir.clone()]));
    let want: Vec<_> = (1..=4).map(|noel| run(&serial, noel)).collect();
    let shared = Umat::new(SearchPath::new([dir.clone()]));
    let got: Vec<_> = std::thread::scope(|s| {
        let handles: Vec<_> = [[1, 3], [2, 4]]
            .map(|noels| {
                let shared = &shared;
                s.spawn(move || noels.map(|noel| (noel, run(shared, noel))))
            })
            .into_iter()
            .collect();
        let mut all: Vec<_> = handles
            .into_iter()
            .flat_map(|h| h.join().unwrap())
            .collect();
        all.sort_by_key(|(noel, _)| *noel);
        all.into_iter().map(|(_, r)| r).collect()
    });
    for (noel, (w, g)) in want.iter().zip(&got).enumerate() {
        for (k, (a, b)) in w.iter().zip(g).enumerate() {
            assert!(
                a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()),
                "element {}, increment {}",
                noel + 1,
                k + 1
            );
        }
    }
    assert_eq!(shared.stats().points, 4);
    assert_eq!(shared.stats().commits, 4 * 3);
    std::fs::remove_dir_all(&dir).ok();
}

/// The paper's RVE pulled to 1.5e-4 in ten increments, then to 2.25e-4 in one, lands
/// beyond its snap-back on a branch that smaller steps do not reach: the step check
/// flags the last increment and the UMAT asks for half the step whatever `PNEWDT` it
/// was handed, unless an earlier point of the increment asked for less: Abaqus hands a
/// large value, CalculiX -1 (which must not be taken as a request, nor kept).
#[test]
fn a_step_over_a_snap_back_asks_for_half_the_step_from_any_host() {
    let dir = scene_dir("pnewdt");
    let umat = Umat::new(SearchPath::new([dir.clone()]));
    let uniaxial = |e: f64| [e, 0.0, 0.0];
    for (noel, handed_in, expected) in [
        (1, 1e36, 0.5),
        (2, -1.0, 0.5),
        (3, 0.75, 0.5),
        (4, 0.25, 0.25),
    ] {
        let mut start = [0.0; 3];
        for kinc in 1..=10 {
            let strain = uniaxial(1.5e-5 * f64::from(kinc));
            let a = ok(call(
                &umat,
                "PAPER",
                &[],
                Hypothesis::PlaneStress,
                &start,
                &strain,
                At {
                    pnewdt: handed_in,
                    ..at(noel, kinc)
                },
            ));
            assert_eq!(a.pnewdt, handed_in, "increment {kinc} is not flagged");
            start = strain;
        }
        let last = ok(call(
            &umat,
            "PAPER",
            &[],
            Hypothesis::PlaneStress,
            &start,
            &uniaxial(2.25e-4),
            At {
                pnewdt: handed_in,
                ..at(noel, 11)
            },
        ));
        assert_eq!(last.pnewdt, expected, "PNEWDT handed in as {handed_in}");
    }
}

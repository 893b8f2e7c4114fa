//! `solver.step_tolerance`: an IMPL-EX update estimates its integration error and suggests
//! a step ratio (docs/step_control.md). The estimate changes no answer; a host that follows
//! the ratio (here `rve run`) dissipates closer to the implicit reference the tighter the
//! tolerance; the ratio reaches the UMAT as `PNEWDT` below 1 only.

mod common;

use std::path::Path;
use std::process::Command;
use std::sync::Arc;

use rve::host::{Hypothesis, SearchPath, Umat, UmatCall, UmatOutputs};
use rve::scene::{path_points, Scene};
use rve::{Instance, Model, Response};

/// The paper's RVE (§5.2.1) integrated by IMPL-EX, with `extra` added under `[solver]`.
fn implex_text(extra: &str) -> String {
    common::paper_scene_with(&[(
        "[solver]\n",
        &format!("[solver]\nintegration = \"implex\"\n{extra}"),
    )])
}

/// The §5.2.1 path's increment, as a strain norm (the time `rve run` passes).
const INCREMENT: f64 = 2.2e-4 / 20.0;

/// `solver.step_tolerance = tolerance` with a floor (which the scene requires) below
/// `rve run`'s own smallest step (1/1024 of the path's increment) and below any step
/// these tests take: the control as if it had none.
fn control(tolerance: f64) -> String {
    format!(
        "step_tolerance = {tolerance}\nsmallest_step = {:e}\n",
        INCREMENT / 16384.0
    )
}

/// The §5.2.1 path, each increment's time its strain norm (as `rve run` passes it), every
/// increment committed (a host that ignores the ratio); the responses and the instance's
/// count of kept increments it was asked to redo.
fn follow(text: &str) -> (Vec<Response>, u64) {
    let scene = Scene::from_toml_str(text, common::repo("scenes")).unwrap();
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut instance = Instance::new(model);
    let responses = common::follow_committed(&mut instance, &path_points(&scene.spec.path));
    (responses, instance.ignored_redos().0)
}

/// Without a tolerance nothing is estimated and the ratio is 1; with one, the answers
/// are the same bits, every increment has an estimate, and some increment of the crack
/// exceeds 0.01 (the path's 20 increments are too coarse for it) while the first,
/// elastic one offers to grow. A host that commits every increment is counted as having
/// kept each one it was asked to redo, and only those: not the implicit step check's.
#[test]
fn the_estimate_changes_no_answer_and_kept_redos_are_counted() {
    let (plain, none_ignored) = follow(&implex_text(""));
    let (controlled, ignored) = follow(&implex_text(&control(0.01)));
    for (a, b) in plain.iter().zip(&controlled) {
        assert_eq!(a.stress, b.stress);
        assert_eq!(a.tangent, b.tangent);
        assert_eq!(a.report.error_estimate, None);
        assert_eq!(a.report.suggested_step_ratio(), 1.0);
        assert!(b.report.error_estimate.is_some());
    }
    assert!(controlled[0].report.suggested_step_ratio() > 1.0);
    let asked = controlled
        .iter()
        .filter(|r| r.report.suggested_step_ratio() < 1.0)
        .inspect(|r| assert!(r.report.exceeds_tolerance() && r.report.substepped()))
        .count();
    assert!(asked > 0);
    assert_eq!((none_ignored, ignored), (0, asked as u64));
    // tests/step_check.rs: the last of these increments lands beyond the snap-back.
    let (implicit, implicit_ignored) = follow(&common::paper_scene_with(&[(
        "to = [2.2e-4, 0.0, 0.0]\nincrements = 20",
        "to = [1.5e-4, 0.0, 0.0]\nincrements = 10\n\n[[path]]\nto = [2.25e-4, 0.0, 0.0]\nincrements = 1",
    )]));
    assert!(implicit.iter().any(|r| r.report.step_too_large));
    assert_eq!(implicit_ignored, 0);
}

/// The scene's tolerance must be a relative error and needs IMPL-EX and a floor.
#[test]
fn a_bad_tolerance_is_refused() {
    for (text, what) in [
        (implex_text("step_tolerance = 0.0\n"), "positive"),
        (implex_text("step_tolerance = 1.5\n"), "below 1"),
        (
            common::paper_scene_with(&[("[solver]\n", "[solver]\nstep_tolerance = 0.01\n")]),
            "implex",
        ),
    ] {
        let e = Scene::from_toml_str(&text, common::repo("scenes"))
            .err()
            .unwrap_or_else(|| panic!("accepted: {what}"));
        let message = e.to_string();
        assert!(message.contains("solver.step_tolerance"), "{message}");
    }
    for (text, what) in [
        (
            implex_text("step_tolerance = 0.01\nsmallest_step = 0.0\n"),
            "positive",
        ),
        (
            implex_text("smallest_step = 1e-6\n"),
            "needs solver.step_tolerance",
        ),
        (
            implex_text("step_tolerance = 0.01\n"),
            "1/16 of the host's time increment",
        ),
    ] {
        let e = Scene::from_toml_str(&text, common::repo("scenes"))
            .err()
            .unwrap_or_else(|| panic!("accepted: {what}"));
        let message = e.to_string();
        assert!(
            message.contains("solver.smallest_step") && message.contains(what),
            "{message}"
        );
    }
}

/// `solver.smallest_step` is the control's floor: `rve run` following the ratio on §5.2.1
/// never steps below it except to land on a path point, keeps every step at the floor
/// whatever its estimate (ratio 1), and so takes fewer steps through the snap-back than
/// with a floor below `rve run`'s own (which goes down to 1/1024 of the path's increment).
#[test]
fn the_smallest_step_is_the_controls_floor() {
    let dir = std::env::temp_dir().join(format!("mesorve-step-floor-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let increment = INCREMENT;
    let floor = increment / 16.0;
    let without = rve_run(&dir, "without", &implex_text(&control(0.01)));
    let with = rve_run(
        &dir,
        "with",
        &implex_text(&format!(
            "step_tolerance = 0.01\nsmallest_step = {floor:e}\n"
        )),
    );
    let (mut previous, mut at_floor) = (0.0, 0);
    for (e, _, [estimate, ratio]) in &with {
        let step = e[0] - previous;
        previous = e[0];
        let on_path_point = ((e[0] / increment).round() * increment - e[0]).abs() < 1e-12;
        assert!(
            step >= floor * (1.0 - 1e-9) || on_path_point,
            "{step:e} below the floor at {e:?}"
        );
        if *estimate > 1.0 {
            assert!(
                step <= floor * (1.0 + 1e-9) && *ratio == 1.0 || on_path_point,
                "{e:?}: {estimate} {ratio}"
            );
            at_floor += 1;
        }
    }
    eprintln!(
        "{} steps with the floor, {} without; {at_floor} kept above the tolerance at it",
        with.len(),
        without.len()
    );
    assert!(at_floor > 0, "the snap-back never reached the floor");
    assert!(with.len() < without.len());
    std::fs::remove_dir_all(&dir).ok();
}

/// (strain, stress, [error estimate, step ratio]) of a row of `response.csv`.
type Row = ([f64; 3], [f64; 3], [f64; 2]);

/// Rows of an `rve run` of `text`.
fn rve_run(dir: &Path, name: &str, text: &str) -> Vec<Row> {
    let scene = dir.join(format!("{name}.toml"));
    std::fs::write(&scene, text).unwrap();
    let out = dir.join(name);
    let status = Command::new(common::rve_exe())
        .args(["run", "--quiet", "--out"])
        .arg(&out)
        .arg(&scene)
        .status()
        .unwrap();
    assert!(status.success(), "rve run {name}");
    let csv = std::fs::read_to_string(out.join("response.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let names = "eps_xx eps_yy gamma_xy sig_xx sig_yy sig_xy error_estimate step_ratio";
    let cols: Vec<usize> = names.split(' ').map(col).collect();
    lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            (
                [v[cols[0]], v[cols[1]], v[cols[2]]],
                [v[cols[3]], v[cols[4]], v[cols[5]]],
                [v[cols[6]], v[cols[7]]],
            )
        })
        .collect()
}

/// `W - sigma . eps / 2` at the path's end, `W` by the trapezoidal rule.
fn dissipated(rows: &[Row]) -> f64 {
    let (mut work, mut pe, mut ps) = (0.0, [0.0; 3], [0.0; 3]);
    for (e, s, _) in rows {
        work += (0..3)
            .map(|c| 0.5 * (s[c] + ps[c]) * (e[c] - pe[c]))
            .sum::<f64>();
        (pe, ps) = (*e, *s);
    }
    work - 0.5 * (0..3).map(|c| ps[c] * pe[c]).sum::<f64>()
}

/// §5.2.1 snaps back at 95 % of its path. IMPL-EX at the path's 20 increments dissipates
/// far less than the implicit scheme at 320; `rve run` following the ratio at
/// `step_tolerance` 0.03, then 0.01, comes closer each time. Every increment it kept above
/// the tolerance had a ratio of 1 (within the snap the estimate did not fall when the step
/// was cut: docs/step_control.md) or is one of its smallest (1/1024 of the path's).
#[test]
fn a_tighter_tolerance_gives_a_smaller_error_through_the_snap_back() {
    let dir = std::env::temp_dir().join(format!("mesorve-step-control-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let fine = common::paper_scene_with(&[("increments = 20", "increments = 320")]);
    let reference = dissipated(&rve_run(&dir, "implicit", &fine));
    let mut last = f64::INFINITY;
    for (name, extra) in [
        ("none", String::new()),
        ("loose", control(0.03)),
        ("tight", control(0.01)),
    ] {
        let rows = rve_run(&dir, name, &implex_text(&extra));
        let error = (dissipated(&rows) - reference).abs() / reference;
        eprintln!(
            "{name}: {} increments, dissipated energy {:+.2} %",
            rows.len(),
            100.0 * error
        );
        assert!(error < last, "{name}: {error} against {last}");
        last = error;
        let mut previous = 0.0;
        for (e, _, [estimate, ratio]) in &rows {
            let step = e[0] - previous;
            previous = e[0];
            let smallest = step <= INCREMENT / 1024.0 * (1.0 + 1e-6);
            let kept = *estimate <= 1.0 || *ratio == 1.0 || smallest;
            assert!(kept, "{name}: kept above the tolerance at {e:?}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Through the UMAT, CalculiX's way (`PNEWDT` handed in as -1, `DTIME` 0.05) on §5.2.1's
/// first 20 increments with `extra` under `[solver]`: each call's `PNEWDT` on return.
fn umat_pnewdts(extra: &str) -> Vec<f64> {
    let dir = std::env::temp_dir().join(format!(
        "mesorve-step-umat-{}-{}",
        std::process::id(),
        extra.len()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("paper.toml"), implex_text(extra)).unwrap();
    let umat = Umat::new(SearchPath::new([dir.clone()]));
    let mut start = [0.0; 3];
    let pnewdts = (1..=20)
        .map(|kinc| {
            let strain = [1.1e-5 * f64::from(kinc), 0.0, 0.0];
            let dstran: Vec<f64> = strain.iter().zip(&start).map(|(e, s)| e - s).collect();
            let (mut stress, mut ddsdde, mut statev, mut pnewdt) =
                ([0.0; 3], [0.0; 9], [0.0; 3], -1.0);
            let call = UmatCall {
                cmname: "PAPER",
                props: &[],
                hypothesis: Hypothesis::PlaneStress,
                stran: &start,
                dstran: &dstran,
                time: [0.05 * f64::from(kinc - 1); 2],
                dtime: 0.05,
                noel: 1,
                npt: 1,
                kstep: 1,
                kinc,
                celent: None,
            };
            let outputs = &mut UmatOutputs {
                stress: &mut stress,
                ddsdde: &mut ddsdde,
                statev: &mut statev,
                pnewdt: &mut pnewdt,
            };
            umat.call(&call, outputs).unwrap();
            start = strain;
            pnewdt
        })
        .collect();
    std::fs::remove_dir_all(&dir).ok();
    pnewdts
}

/// The increments of the crack get `PNEWDT` in (0, 1), the others keep -1 (no request),
/// and no call ever gets 1 or more (ccx would redo the increment). With
/// `solver.smallest_step` the request is never below it (three quarters of `DTIME`
/// here), and at `DTIME` itself there is none.
#[test]
fn the_ratio_reaches_the_umat_below_one_only() {
    let pnewdts = umat_pnewdts("step_tolerance = 0.01\nsmallest_step = 1e-6\n");
    for (kinc, pnewdt) in pnewdts.iter().enumerate() {
        assert!(
            *pnewdt == -1.0 || (*pnewdt > 0.0 && *pnewdt < 1.0),
            "increment {}: {pnewdt}",
            kinc + 1
        );
    }
    let asked: Vec<usize> = (0..20).filter(|&k| pnewdts[k] > 0.0).collect();
    assert!(
        !asked.is_empty(),
        "no increment of the crack asked for a smaller step"
    );
    assert!(
        asked.iter().any(|&k| pnewdts[k] < 0.75),
        "no request below the floor to come"
    );
    let floored = umat_pnewdts("step_tolerance = 0.01\nsmallest_step = 0.0375\n");
    for &k in &asked {
        assert!(
            floored[k] >= 0.75 - 1e-12 && floored[k] < 1.0,
            "increment {}: {}",
            k + 1,
            floored[k]
        );
    }
    let at_floor = umat_pnewdts("step_tolerance = 0.01\nsmallest_step = 0.05\n");
    assert!(at_floor.iter().all(|&p| p == -1.0), "{at_floor:?}");
}

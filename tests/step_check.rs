//! An implicit increment across the RVE's snap-back lands on an equilibrium that depends
//! on its size (a large step converges onto the upper branch that continuous loading never
//! reaches); the step check flags exactly those increments, so `RveInfo` and the UMAT can
//! ask the host for a smaller step.

mod common;

use std::sync::Arc;

use mesorve_core::solver::TangentRequest;
use rve::scene::{path_points, Scene};
use rve::{Instance, Model, Response};

/// The paper's RVE (section 5.2.1) pulled to 1.5e-4 in 10 increments, then to 2.25e-4
/// in `last` increments, with or without the step check.
fn run(last: usize, check: bool) -> Vec<Response> {
    let mut text = std::fs::read_to_string(common::repo("scenes/paper_rve.toml")).unwrap();
    let path = text.find("[[path]]").unwrap();
    text.truncate(path);
    text.push_str(&format!(
        "[[path]]\nto = [1.5e-4, 0.0, 0.0]\nincrements = 10\n\n\
         [[path]]\nto = [2.25e-4, 0.0, 0.0]\nincrements = {last}\n"
    ));
    if !check {
        text = text.replacen("[solver]\n", "[solver]\nstep_check = false\n", 1);
    }
    let scene = Scene::from_toml_str(&text, common::repo("scenes")).unwrap();
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut instance = Instance::new(model.clone());
    let mut ws = model.workspace();
    path_points(&scene.spec.path)
        .into_iter()
        .map(|eps| {
            let r = instance
                .update(eps, &mut ws, TangentRequest::Consistent)
                .unwrap();
            instance.commit().unwrap();
            r
        })
        .collect()
}

/// In 1 or 3 increments the last step lands on the upper branch (about 25 % more stress
/// than in 15 or 60) and is flagged; in 15 or 60 increments the last step agrees with the
/// other and is not flagged. (Earlier increments of a fine run may be flagged: where a
/// step lands past the point at which its halves localize, the answer there depends on
/// the step too.) The check changes no answer.
#[test]
fn a_step_over_a_skipped_snap_is_flagged() {
    let fine = run(60, true);
    let reference = fine.last().unwrap().stress[0];
    for last in [1, 3, 15, 60] {
        let checked = run(last, true);
        let plain = run(last, false);
        for (a, b) in checked.iter().zip(&plain) {
            assert_eq!(a.stress, b.stress, "the check changes no answer");
            assert!(!b.report.step_too_large && b.report.check_factorizations == 0);
        }
        let end = checked.last().unwrap();
        let gap = (end.stress[0] - reference).abs() / reference;
        let flagged = checked.iter().filter(|r| r.report.step_too_large).count();
        let cost: u32 = checked.iter().map(|r| r.report.check_factorizations).sum();
        let solve: u32 = checked.iter().map(|r| r.report.factorizations).sum();
        eprintln!(
            "{last} increments: s_xx {:.4} ({:+.1} % of 60 increments), last flagged {}, \
             {flagged} flagged in all, {cost} check factorizations besides {solve}",
            end.stress[0],
            100.0 * gap,
            end.report.step_too_large
        );
        assert_eq!(
            end.report.step_too_large,
            gap > 0.05,
            "{last} increments: {gap}"
        );
    }
}

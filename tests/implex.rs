//! IMPL-EX integration (`solver.integration = "implex"`) on the paper's RVE and law: its
//! tangent is the derivative of its stress within a step, one factorization answers a
//! step, the kept step gives the same answers as a new one, the time increment scales the
//! extrapolation, and on the section 5.2.2 cycle its error falls at first order in the
//! step against the implicit scheme.

mod common;

use std::sync::Arc;

use mesorve_core::solver::TangentRequest;
use rve::scene::{path_points, Scene};
use rve::{Instance, Model, Response};

/// The section 5.2.2 cycle scene with IMPL-EX and `per_segment` increments in its two
/// segments (the scene's own: 20 and 40), optionally without the fast path.
fn cycle_text(implex: bool, scale: usize, fast_path: bool) -> String {
    let text = std::fs::read_to_string(common::repo("scenes/paper_rve_cycle.toml")).unwrap();
    let mut parts = text.split("increments = ");
    let head = parts.next().unwrap();
    let tension = parts
        .next()
        .unwrap()
        .replacen("20", &(20 * scale).to_string(), 1);
    let rest = parts
        .next()
        .unwrap()
        .replacen("40", &(40 * scale).to_string(), 1);
    let mut solver = String::from("[solver]\n");
    if implex {
        solver.push_str("integration = \"implex\"\n");
    }
    if !fast_path {
        solver.push_str("fast_path = false\n");
    }
    format!("{head}increments = {tension}increments = {rest}").replacen("[solver]\n", &solver, 1)
}

fn model(text: &str) -> (Arc<Model>, Vec<[f64; 3]>) {
    let scene = Scene::from_toml_str(text, common::repo("scenes")).unwrap();
    let points = path_points(&scene.spec.path);
    (Arc::new(Model::from_scene(&scene).unwrap()), points)
}

/// Follows `points`, each increment's time step the norm of its strain increment (as `rve
/// run` does), and returns every committed response.
fn follow(model: &Arc<Model>, points: &[[f64; 3]]) -> Vec<Response> {
    common::follow_committed(&mut Instance::new(model.clone()), points)
}

/// Within a step (same committed state, same time increment), the stress is linear in the
/// strain and the tangent is its derivative (central differences), symmetric positive
/// definite; the step's first update factorizes once, the later ones not at all, and the
/// answers equal those of a model without the kept step (fast path off) bit for bit.
#[test]
fn implex_tangent_is_the_derivative_of_its_stress_within_a_step() {
    let (kept, points) = model(&cycle_text(true, 1, true));
    let (fresh, _) = model(&cycle_text(true, 1, false));
    // Into the softening: 21 of the 60 increments (the peak of the cycle is at 20).
    let mut a = Instance::new(kept.clone());
    let mut b = Instance::new(fresh.clone());
    let (mut wa, mut wb) = (kept.workspace(), fresh.workspace());
    let dt = 1.0;
    for &eps in &points[..21] {
        a.update_timed(eps, dt, &mut wa, TangentRequest::Consistent)
            .unwrap();
        a.commit().unwrap();
        b.update_timed(eps, dt, &mut wb, TangentRequest::Consistent)
            .unwrap();
        b.commit().unwrap();
    }
    assert_eq!(a.save_state().unwrap(), b.save_state().unwrap());
    let eps = points[21];
    let base = a
        .update_timed(eps, dt, &mut wa, TangentRequest::Consistent)
        .unwrap();
    assert_eq!(base.report.factorizations, 1);
    assert!(
        base.report.loading > 0,
        "the step must load some ITZ points"
    );
    let d = base.tangent;
    for i in 0..3 {
        for j in 0..3 {
            assert_eq!(d[3 * i + j], d[3 * j + i], "symmetric");
        }
    }
    let minors = [
        d[0],
        d[0] * d[4] - d[1] * d[3],
        d[0] * (d[4] * d[8] - d[5] * d[7]) - d[1] * (d[3] * d[8] - d[5] * d[6])
            + d[2] * (d[3] * d[7] - d[4] * d[6]),
    ];
    assert!(
        minors.iter().all(|&m| m > 0.0),
        "positive definite: {minors:?}"
    );
    let h = 1e-7;
    let scale = d.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for j in 0..3 {
        let (mut plus, mut minus) = (eps, eps);
        plus[j] += h;
        minus[j] -= h;
        let rp = a
            .update_timed(plus, dt, &mut wa, TangentRequest::Consistent)
            .unwrap();
        let rm = a
            .update_timed(minus, dt, &mut wa, TangentRequest::Consistent)
            .unwrap();
        assert_eq!((rp.report.factorizations, rm.report.factorizations), (0, 0));
        let bp = b
            .update_timed(plus, dt, &mut wb, TangentRequest::Consistent)
            .unwrap();
        assert_eq!(
            bp.report.factorizations, 1,
            "no kept step without the fast path"
        );
        assert_eq!(rp.stress.map(f64::to_bits), bp.stress.map(f64::to_bits));
        for i in 0..3 {
            let fd = (rp.stress[i] - rm.stress[i]) / (2.0 * h);
            assert!(
                (fd - d[3 * i + j]).abs() <= 1e-6 * scale,
                "D{i}{j}: {fd} vs {}",
                d[3 * i + j]
            );
        }
    }
    // The trial committed after the probes is the last update's, the same in both.
    a.update_timed(eps, dt, &mut wa, TangentRequest::Consistent)
        .unwrap();
    b.update_timed(eps, dt, &mut wb, TangentRequest::Consistent)
        .unwrap();
    a.commit().unwrap();
    b.commit().unwrap();
    assert_eq!(a.save_state().unwrap(), b.save_state().unwrap());
}

/// The time increment scales the extrapolation: the same strain step taken with twice
/// the last time increment extrapolates further, so it softens more; with no time given
/// (0) the step counts as long as the last.
#[test]
fn implex_time_increment_scales_the_extrapolation() {
    let (model, points) = model(&cycle_text(true, 1, true));
    let mut instance = Instance::new(model.clone());
    let mut ws = model.workspace();
    for &eps in &points[..19] {
        instance
            .update_timed(eps, 0.5, &mut ws, TangentRequest::None)
            .unwrap();
        instance.commit().unwrap();
    }
    let eps = points[19];
    let same = instance
        .update_timed(eps, 0.5, &mut ws, TangentRequest::None)
        .unwrap();
    let untimed = instance
        .update_timed(eps, 0.0, &mut ws, TangentRequest::None)
        .unwrap();
    let longer = instance
        .update_timed(eps, 1.0, &mut ws, TangentRequest::None)
        .unwrap();
    assert_eq!(same.stress, untimed.stress);
    assert!(longer.stress[0] < same.stress[0], "{longer:?} vs {same:?}");
}

/// Dissipated energy up to increment `upto`: the external work less the energy that
/// unloading would return, `W - sigma . eps / 2` (exact on a state whose ITZ points all
/// sit on branches through the origin, as at the end of the cycle: closed in compression).
fn dissipated(responses: &[Response], points: &[[f64; 3]]) -> f64 {
    let (mut work, mut prev_eps, mut prev_sig) = (0.0, [0.0; 3], [0.0; 3]);
    for (r, eps) in responses.iter().zip(points) {
        for c in 0..3 {
            work += 0.5 * (r.stress[c] + prev_sig[c]) * (eps[c] - prev_eps[c]);
        }
        (prev_eps, prev_sig) = (*eps, r.stress);
    }
    work - 0.5 * (0..3).map(|c| prev_sig[c] * prev_eps[c]).sum::<f64>()
}

/// Against the implicit scheme at 16 times the paper's 60 increments, the dissipated
/// energy of IMPL-EX at 60, 120 and 240 increments falls at an observed order near 1 (the
/// first order the name claims, asserted on the energy), and the stress error (L1 along
/// the strain path) at 480 increments is less than half that at 60: a weaker check, as
/// the snap-back makes the stress error a jump in strain that IMPL-EX reaches a few
/// steps late (the L1 norm sees its lag, a max norm would not fall).
#[test]
fn implex_cycle_dissipation_converges_at_first_order() {
    let (reference, ref_points) = model(&cycle_text(false, 16, true));
    let exact = follow(&reference, &ref_points);
    let d_exact = dissipated(&exact, &ref_points);
    let mut energy_errors = Vec::new();
    let mut stress_errors = Vec::new();
    for scale in [1, 2, 4, 8] {
        let (m, points) = model(&cycle_text(true, scale, true));
        let responses = follow(&m, &points);
        let d = dissipated(&responses, &points);
        energy_errors.push((d - d_exact).abs() / d_exact);
        let stride = 16 / scale;
        let step = 2.3e-4 / (20 * scale) as f64;
        let l1: f64 = responses
            .iter()
            .enumerate()
            .map(|(k, r)| {
                let e = &exact[(k + 1) * stride - 1];
                assert_eq!(ref_points[(k + 1) * stride - 1], points[k]);
                (r.stress[0] - e.stress[0]).abs() * step
            })
            .sum();
        stress_errors.push(l1);
    }
    let orders: Vec<f64> = energy_errors
        .windows(2)
        .map(|w| (w[0] / w[1]).log2())
        .collect();
    eprintln!("dissipated energy errors {energy_errors:?}, orders {orders:?}");
    eprintln!("stress L1 errors {stress_errors:?}");
    let order = (energy_errors[0] / energy_errors[2]).log2() / 2.0;
    assert!(
        (0.75..=1.5).contains(&order),
        "observed order {order} from N to 4N"
    );
    assert!(
        stress_errors[3] < 0.5 * stress_errors[0],
        "{stress_errors:?}"
    );
}

/// Over the whole cycle, the kept steps (later updates of a step, and steps that carry
/// the last one over: unloading and closed RVEs whose history and contact status have
/// not changed) give the responses and states of a model that factorizes every update,
/// bit for bit, with fewer factorizations.
#[test]
fn kept_steps_change_nothing_over_the_cycle() {
    let (kept, points) = model(&cycle_text(true, 1, true));
    let (fresh, _) = model(&cycle_text(true, 1, false));
    let a = follow(&kept, &points);
    let b = follow(&fresh, &points);
    for (k, (ra, rb)) in a.iter().zip(&b).enumerate() {
        assert_eq!(
            ra.stress.map(f64::to_bits),
            rb.stress.map(f64::to_bits),
            "increment {k}"
        );
        assert_eq!(
            ra.tangent.map(f64::to_bits),
            rb.tangent.map(f64::to_bits),
            "increment {k}"
        );
        assert_eq!(rb.report.factorizations, 1);
    }
    let factorized = a.iter().filter(|r| r.report.factorizations == 1).count();
    eprintln!("{factorized} of {} increments factorized", a.len());
    assert!(
        factorized < a.len() / 2 + 1,
        "unloading and compression carry over"
    );
}

/// The micro fields of a state whose step was carried over (its unknowns formed at an
/// earlier increment) are rebuilt from the step's frozen branches: on the cycle, every
/// committed state's displacements equal those of a run that factorizes every step, to
/// round-off. And a mixed-control trial that reused its step at another strain forms its
/// unknowns after `Instance::refactor_step`, with the same answer.
#[test]
fn carried_states_give_the_fields_of_their_step() {
    let (kept, points) = model(&cycle_text(true, 1, true));
    let (fresh, _) = model(&cycle_text(true, 1, false));
    let (mut a, mut b) = (Instance::new(kept.clone()), Instance::new(fresh.clone()));
    let (mut wa, mut wb) = (kept.workspace(), fresh.workspace());
    let (mut previous, mut rebuilt) = ([0.0; 3], 0);
    for (k, &eps) in points.iter().enumerate() {
        let dt = (0..3)
            .map(|c| (eps[c] - previous[c]).powi(2))
            .sum::<f64>()
            .sqrt();
        previous = eps;
        let request = TangentRequest::Consistent;
        a.update_timed(eps, dt, &mut wa, request).unwrap();
        b.update_timed(eps, dt, &mut wb, request).unwrap();
        a.commit().unwrap();
        b.commit().unwrap();
        rebuilt += usize::from(!a.committed().unknowns_are_current());
        let (fa, fb) = (
            kept.fields(a.committed()).unwrap(),
            fresh.fields(b.committed()).unwrap(),
        );
        let scale = fb
            .displacement
            .iter()
            .fold(0.0f64, |m, u| m.max(u[0].abs()).max(u[1].abs()));
        for (ua, ub) in fa.displacement.iter().zip(&fb.displacement) {
            for c in 0..2 {
                assert!(
                    (ua[c] - ub[c]).abs() <= 1e-10 * scale,
                    "increment {k}: {ua:?} against {ub:?}"
                );
            }
        }
    }
    eprintln!(
        "{rebuilt} of {} states rebuilt from their step",
        points.len()
    );
    assert!(rebuilt > 8, "too few carried states to check: {rebuilt}");

    // A repeated trial at another strain of the step lags; refactor_step forms it.
    let mut c = Instance::new(kept.clone());
    let mut ws = kept.workspace();
    let request = TangentRequest::Consistent;
    for &eps in &points[..21] {
        c.update_timed(eps, 1.0, &mut ws, request).unwrap();
        c.commit().unwrap();
    }
    let next = points[21];
    let nearby = next.map(|e| 0.9 * e);
    c.update_timed(nearby, 1.0, &mut ws, request).unwrap();
    let lagging = c.update_timed(next, 1.0, &mut ws, request).unwrap();
    assert_eq!(lagging.report.factorizations, 0, "the step is reused");
    assert!(!c.trial_unknowns_are_current());
    c.refactor_step();
    let formed = c.update_timed(next, 1.0, &mut ws, request).unwrap();
    assert_eq!(formed.report.factorizations, 1);
    assert!(c.trial_unknowns_are_current());
    let close = |x: &[f64], y: &[f64]| {
        x.iter()
            .zip(y)
            .all(|(p, q)| (p - q).abs() <= 1e-9 * (1.0 + q.abs()))
    };
    assert!(
        close(&formed.stress, &lagging.stress),
        "{:?} against {:?}",
        formed.stress,
        lagging.stress
    );
    assert!(close(&formed.tangent, &lagging.tangent));
}

//! The fast path (`mesorve_core::solver::fast_path`): an update that keeps every ITZ point
//! on the linear branch of its last full solve is answered as `D_b eps` without Newton.
//!
//! Every increment of every path here is computed twice from the same committed state:
//! by an instance whose model has the fast path, and by an instance of the same scene with
//! `solver.fast_path = false`, loaded with the first one's committed state bytes (so the
//! full solve starts from exactly the state the fast path saw, lazy unknowns included).
//! Where the fast path answered, the full solve must agree to 1e-12 relative in stress and
//! tangent, end with no loading point, no point held against its gap and the same contact
//! count, and commit the same history bit for bit; where it did not, both solved and
//! must agree bit for bit (the switch changes nothing else).

mod common;

use std::sync::Arc;

use mesorve_core::interface::ContactShear;
use mesorve_core::solver::Answer;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rve::scene::Scene;
use rve::{Instance, Model, Response, TangentRequest};

/// The relative agreement of the fast path with the full solve.
const AGREEMENT: f64 = 1e-12;

/// What one path showed.
#[derive(Debug, Default)]
struct PathStats {
    increments: usize,
    fast: usize,
    /// Increments solved right after a fast one, where the full solve found a loading
    /// point or another contact status: the path left the branch set.
    fell_back: usize,
    /// Largest relative difference of stress and tangent on fast increments.
    worst: f64,
    /// Fast increments whose full solve ended with a point held against its gap.
    full_held: usize,
}

/// The committed state of `inst` moved to `eps` as a fast commit would (same history,
/// unknowns lazy).
fn trial_state(inst: &Instance, eps: [f64; 3]) -> rve::State {
    let mut state = inst.committed().clone();
    state.strain = eps;
    state
}

/// `||R(x; eps)|| / reference` with every contact status read from its gap (the law as the
/// paper states it) and the history `history`.
fn residual_with_gaps(model: &Model, x: &[f64], eps: &[f64; 3], history: &[f64]) -> f64 {
    let problem = mesorve_core::solver::Problem {
        disc: model.discretization(),
        linear: model.linear_solver(),
        settings: model.settings(),
        predictor: model.elastic_sensitivity(),
    };
    let mut trial = history.to_vec();
    let mut r = vec![0.0; x.len()];
    let counts = model
        .discretization()
        .evaluate(x, eps, history, &mut trial, &mut r, None);
    assert_eq!(counts.loading, 0, "a loading point at the fast answer");
    assert_eq!(trial, history, "the history moved at the fast answer");
    r.iter().map(|v| v * v).sum::<f64>().sqrt() / problem.reference(eps)
}

fn models(scene: &Scene) -> (Arc<Model>, Arc<Model>) {
    let fast = Arc::new(Model::from_scene(scene).unwrap());
    let mut off = scene.clone();
    off.spec.solver.fast_path = false;
    (fast, Arc::new(Model::from_scene(&off).unwrap()))
}

fn bits(r: &Response) -> Vec<u64> {
    r.stress
        .iter()
        .chain(&r.tangent)
        .chain([&r.s_zz])
        .map(|v| v.to_bits())
        .collect()
}

/// Follows `targets` with the fast path, checking every increment against the full solve
/// from the same committed state (see the module docs).
fn check_path(fast: &Arc<Model>, full: &Arc<Model>, targets: &[[f64; 3]], name: &str) -> PathStats {
    let mut ws = fast.workspace();
    let mut ws_full = full.workspace();
    let mut inst = Instance::new(fast.clone());
    let mut stats = PathStats::default();
    let mut previous_fast = false;
    for (k, &eps) in targets.iter().enumerate() {
        let mut reference = Instance::new(full.clone());
        reference.load_state(&inst.save_state().unwrap()).unwrap();
        let r = inst
            .update(eps, &mut ws, TangentRequest::Consistent)
            .unwrap_or_else(|e| panic!("{name}: increment {}: {e}", k + 1));
        let rf = reference
            .update(eps, &mut ws_full, TangentRequest::Consistent)
            .unwrap_or_else(|e| panic!("{name}: increment {} (full): {e}", k + 1));
        assert_eq!(rf.report.answer, Answer::Solved);
        let at = format!("{name}: increment {} at {eps:?}", k + 1);
        if r.report.answer == Answer::FastPath && rf.report.held_points > 0 {
            // The full solve ended with a point held against its gap (the active set's
            // switch limit, `solver::contact`): not an equilibrium of the law with the
            // status read from the gaps. The fast answer is one: check its residual.
            let moved = trial_state(&inst, eps);
            let x = fast.current_state(&moved).unwrap();
            let residual = residual_with_gaps(fast, &x.unknowns, &eps, &inst.committed().history);
            assert!(
                residual <= 1e-9,
                "{at}: fast answer's residual {residual:e}"
            );
            stats.full_held += 1;
        } else if r.report.answer == Answer::FastPath {
            let stress = common::max_rel_diff(&r.stress, &rf.stress);
            let tangent = common::max_rel_diff(&r.tangent, &rf.tangent);
            assert!(
                stress <= AGREEMENT && tangent <= AGREEMENT,
                "{at}: fast vs full: stress {stress:e}, tangent {tangent:e}\nfast {r:?}\nfull {rf:?}"
            );
            stats.worst = stats.worst.max(stress).max(tangent);
            let rep = rf.report;
            assert_eq!(
                (rep.loading, rep.held_points, rep.contact),
                (0, 0, r.report.contact),
                "{at}: the fast path answered, the full solve left the branch set"
            );
            stats.fast += 1;
        } else {
            assert_eq!(bits(&r), bits(&rf), "{at}: solved both ways");
            let left = rf.report.loading > 0
                || rf.report.contact
                    != inst
                        .committed()
                        .linear
                        .closed
                        .iter()
                        .filter(|&&c| c)
                        .count();
            if previous_fast && left {
                stats.fell_back += 1;
            }
        }
        if std::env::var("FAST_PATH_TRACE").is_ok() {
            let rep = rf.report;
            println!(
                "{at}: {:?}; full solve: loading {} unloading {} contact {} held {} \
                 iterations {}; fast-path data before: {}",
                r.report.answer,
                rep.loading,
                rep.unloading,
                rep.contact,
                rep.held_points,
                rep.iterations,
                inst.committed().linear.valid
            );
        }
        inst.commit().unwrap();
        reference.commit().unwrap();
        assert_eq!(
            inst.committed().history,
            reference.committed().history,
            "{at}: committed history"
        );
        let a = fast.current_state(inst.committed()).unwrap();
        let b = full.current_state(reference.committed()).unwrap();
        assert!(
            rf.report.held_points > 0 || common::max_rel_diff(&a.unknowns, &b.unknowns) <= 1e-9,
            "{at}: committed fluctuation differs by {:e}",
            common::max_rel_diff(&a.unknowns, &b.unknowns)
        );
        previous_fast = r.report.answer == Answer::FastPath;
        stats.increments += 1;
    }
    stats
}

/// Section 5.2.2's cycle: tension through the snap-back, unloading, compression. The
/// unloading and compression increments are answered by the fast path, but the first of
/// each (a crack closes); a checkpoint taken between fast updates (lazy unknowns)
/// continues bit for bit.
#[test]
fn section_5_2_2_cycle_fast_versus_full() {
    let scene = common::scene("scenes/paper_rve_cycle.toml");
    let (fast, full) = models(&scene);
    let targets = rve::scene::path_points(&scene.spec.path);
    let stats = check_path(&fast, &full, &targets, "cycle");
    println!("cycle: {stats:?}");
    assert!(stats.fast >= 36, "{stats:?}");

    // Save after increment 28 (five fast commits since the last solve), load into a new
    // instance and continue: the same bits, answered the same way.
    let mut ws = fast.workspace();
    let mut a = Instance::new(fast.clone());
    for &eps in &targets[..28] {
        a.update(eps, &mut ws, TangentRequest::Consistent).unwrap();
        a.commit().unwrap();
    }
    assert!(!a.committed().unknowns_are_current());
    let mut b = Instance::new(fast.clone());
    b.load_state(&a.save_state().unwrap()).unwrap();
    for (k, &eps) in targets.iter().enumerate().skip(28) {
        let ra = a.update(eps, &mut ws, TangentRequest::Consistent).unwrap();
        let rb = b.update(eps, &mut ws, TangentRequest::Consistent).unwrap();
        assert_eq!(bits(&ra), bits(&rb), "increment {}", k + 1);
        assert_eq!(ra.report, rb.report, "increment {}", k + 1);
        a.commit().unwrap();
        b.commit().unwrap();
        assert_eq!(a.save_state().unwrap(), b.save_state().unwrap());
    }
}

/// From an unloaded state of the cycle (fast-path data valid): a strain inside the branch
/// set is answered fast; reloading past the old peak (points load) and a jump into
/// compression (cracks close) fall back to the full solve.
#[test]
fn leaving_the_branch_set_falls_back_to_the_full_solve() {
    let scene = common::scene("scenes/paper_rve_cycle.toml");
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut ws = model.workspace();
    let mut inst = Instance::new(model.clone());
    for &eps in &rve::scene::path_points(&scene.spec.path)[..25] {
        inst.update(eps, &mut ws, TangentRequest::Consistent)
            .unwrap();
        inst.commit().unwrap();
    }
    assert!(inst.committed().linear.valid);
    let mut answer = |eps: [f64; 3]| {
        let r = inst
            .update(eps, &mut ws, TangentRequest::Consistent)
            .unwrap();
        inst.revert();
        r.report
    };
    let inside = answer([1.0e-4, 0.0, 0.0]);
    assert_eq!(inside.answer, Answer::FastPath);
    let beyond = answer([2.6e-4, 0.0, 0.0]);
    assert_eq!(beyond.answer, Answer::Solved);
    assert!(beyond.loading > 0, "{beyond:?}");
    let closed = answer([-1.0e-4, 0.0, 0.0]);
    assert_eq!(closed.answer, Answer::Solved);
    assert!(closed.contact > inside.contact, "{closed:?}");
    // The refused trials changed nothing: inside is still fast.
    assert_eq!(answer([1.0e-4, 0.0, 0.0]).answer, Answer::FastPath);
}

/// A repeated call returns the pending trial, bit for bit, and counts as fast; a commit
/// in between ends the repeat.
#[test]
fn a_repeated_trial_is_returned_without_a_solve() {
    let scene = common::scene("scenes/paper_rve.toml");
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut ws = model.workspace();
    let mut inst = Instance::new(model.clone());
    let eps = [1.2e-4, 0.0, 0.0];
    let first = inst
        .update(eps, &mut ws, TangentRequest::Consistent)
        .unwrap();
    assert_eq!(first.report.answer, Answer::Solved);
    let again = inst
        .update(eps, &mut ws, TangentRequest::Consistent)
        .unwrap();
    assert_eq!(again.report.answer, Answer::Repeated);
    assert_eq!(bits(&first), bits(&again));
    assert_eq!(inst.fast_updates(), 1);
    // Another request solves again (a trial without tangent keeps no sensitivity).
    let stress_only = inst.update(eps, &mut ws, TangentRequest::None).unwrap();
    assert_eq!(stress_only.report.answer, Answer::Solved);
    assert_eq!(
        stress_only.stress.map(f64::to_bits),
        first.stress.map(f64::to_bits)
    );
    inst.commit().unwrap();
    let after = inst.update(eps, &mut ws, TangentRequest::None).unwrap();
    assert_ne!(
        after.report.answer,
        Answer::Repeated,
        "a commit ends the repeat"
    );
}

/// The linear interface law (no history, no contact) is linear everywhere: after the
/// first update every update is fast, and equal to the full solve.
#[test]
fn a_linear_interface_is_answered_by_the_fast_path() {
    let text = common::paper_scene_with(&[(
        "itz = {",
        "linear_itz = { shear_stiffness = 2e4, normal_stiffness = 5e4 }\nunused_itz = {",
    )]);
    let text = text.replace("unused_itz", "# itz");
    let scene = match Scene::from_toml_str(&text, ".") {
        Ok(scene) => scene,
        Err(e) => panic!("{e}\n{text}"),
    };
    let (fast, full) = models(&scene);
    let targets: Vec<[f64; 3]> = (1..=6)
        .map(|k| [1e-4 * k as f64, -3e-5 * k as f64, 2e-5 * (k % 3) as f64])
        .collect();
    let stats = check_path(&fast, &full, &targets, "linear interface");
    assert_eq!(stats.fast, targets.len() - 1, "{stats:?}");
}

/// A seeded path a host could hand an unloading point: load along a random direction past
/// the peak, unload part way or to zero, compress, reload below the old peak, then beyond
/// it (leaving the branch set); one in three paths also shears on the way back.
fn unload_reload_path(rng: &mut ChaCha8Rng) -> Vec<[f64; 3]> {
    let theta: f64 = rng.random_range(0.0..std::f64::consts::PI);
    let (s, c) = theta.sin_cos();
    let dir = [c * c, s * s, 2.0 * c * s];
    let at = |a: f64, shear: f64| [a * dir[0], a * dir[1], a * dir[2] + shear];
    let peak = rng.random_range(2.6e-4..4.0e-4);
    let down = rng.random_range(0.0..0.6) * peak;
    let shear = if rng.random_bool(0.33) {
        rng.random_range(-5e-5..5e-5)
    } else {
        0.0
    };
    let compress = -rng.random_range(0.5..1.5) * peak;
    let mut path = Vec::new();
    let mut segment = |from: [f64; 3], to: [f64; 3], n: u32| {
        for k in 1..=n {
            let f = k as f64 / n as f64;
            path.push(std::array::from_fn(|i| from[i] + f * (to[i] - from[i])));
        }
    };
    segment([0.0; 3], at(peak, 0.0), 14);
    segment(at(peak, 0.0), at(down, shear), 6);
    segment(at(down, shear), at(compress, shear), 6);
    segment(at(compress, shear), at(0.7 * peak, 0.0), 6);
    segment(at(0.7 * peak, 0.0), at(1.2 * peak, 0.0), 4);
    path
}

/// Randomized unload/reload/compress paths on the paper's RVE (circles and ellipses),
/// with `lambda_p` from 1e5 to 1e9 and both contact laws: every fast answer agrees with
/// the full solve, the fast path answers most unloading and compression increments, and
/// every path falls back to the full solve where it leaves the branch set (a crack that
/// closes or opens, reloading past `delta_max`).
#[test]
fn randomized_unload_reload_compress_paths() {
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    let mut total = PathStats::default();
    for case in 0..16 {
        let ellipses = case % 4 == 3;
        let lambda_p = [1e5, 1e7, 1e9][case % 3];
        let contact_shear = if case % 2 == 0 {
            ContactShear::Penalty
        } else {
            ContactShear::Cohesive
        };
        let base = if ellipses {
            "scenes/paper_rve_ellipses.toml"
        } else {
            "scenes/paper_rve.toml"
        };
        let mut scene = common::scene(base);
        let itz = scene.spec.materials.itz.as_mut().expect("the paper's ITZ");
        itz.penalty.lambda_p = Some(lambda_p);
        itz.contact_shear = contact_shear;
        let (fast, full) = models(&scene);
        let targets = unload_reload_path(&mut rng);
        let name = format!("case {case} ({base}, lambda_p {lambda_p:e}, {contact_shear:?})");
        let stats = check_path(&fast, &full, &targets, &name);
        println!("{name}: {stats:?}");
        // Every path has a stretch on one branch set (the compression plateau at least).
        assert!(stats.fast >= 1, "{name}: {stats:?}");
        assert!(stats.fell_back >= 1, "{name}: never fell back: {stats:?}");
        total.increments += stats.increments;
        total.fast += stats.fast;
        total.fell_back += stats.fell_back;
        total.worst = total.worst.max(stats.worst);
        total.full_held += stats.full_held;
    }
    println!("all cases: {total:?}");
    // Measured 137 of 576 (docs/fast_path.md); about a quarter of that is the floor.
    assert!(total.fast >= 35, "{total:?}");
}

//! Coulomb friction on a closed crack (`effects.friction`, `interface::Frictional`) on the
//! cell cut by one straight interface (`scenes/single_interface.toml`), where the fields
//! are uniform and the response has a closed form: the interface's normal traction is
//! `sigma_xx`, its shear traction `sigma_xy`, and its slip adds `delta_s / W` to
//! `gamma_xy`.
//!
//! The interface is first opened far past its strength (damage 1 to round-off), then
//! closed in compression at a fixed `eps_xx` and sheared through a cycle. The macro shear
//! response is then an elastic-perfectly plastic spring: elastic compliance
//! `c = 1/G + 1/(W beta^2 K_0)` (the bulk in series with the damaged part's stick
//! stiffness, `K_0 = e sigma_c / delta_c`) and yield stress `tau = mu |sigma_xx|`.
//! - Stick until `|sigma_xy| = tau`, slide there; `sigma_xx` does not move while sheared.
//! - Every increment's stress equals the closed form's on the same strains, and so does the
//!   loop's area (the dissipation per unit volume) by the same quadrature.
//! - Without friction the same cycle dissipates nothing.
//! - While it slides the homogenized tangent is not symmetric and matches central
//!   differences.

mod common;

use std::sync::Arc;

use rve::{Instance, Model, Scene, TangentRequest};

const SCENE: &str = "scenes/single_interface.toml";
const WIDTH: f64 = 2.0;
const MU: f64 = 0.5;
/// `E / (2 (1 + nu))` of the scene's bulk.
const SHEAR_MODULUS: f64 = 30000.0 / 2.4;
const SIGMA_C: f64 = 4.0;
const DELTA_C: f64 = 2e-4;
const BETA: f64 = 0.707;

fn model(friction: bool) -> Arc<Model> {
    let mut text = std::fs::read_to_string(common::repo(SCENE)).unwrap();
    let itz = "beta = 0.707, penalty";
    assert!(text.contains(itz));
    text = text.replacen(
        itz,
        "beta = 0.707, contact_shear = \"cohesive\", penalty",
        1,
    );
    if friction {
        text = text.replacen("contact = true", "contact = true\nfriction = true", 1);
        text = text.replacen(
            "[effects]",
            &format!("friction = {{ coefficient = {MU} }}\n\n[effects]"),
            1,
        );
    }
    let scene = Scene::from_toml_str(&text, common::repo("scenes")).unwrap();
    Arc::new(Model::from_scene(&scene).unwrap())
}

/// Follows `strains` from the instance's state, committing each: the stresses.
fn follow(inst: &mut Instance, ws: &mut rve::Workspace, strains: &[[f64; 3]]) -> Vec<[f64; 3]> {
    strains
        .iter()
        .enumerate()
        .map(|(k, &eps)| {
            let r = inst
                .update(eps, ws, TangentRequest::Consistent)
                .unwrap_or_else(|e| panic!("increment {}: {e}", k + 1));
            inst.commit().unwrap();
            r.stress
        })
        .collect()
}

fn segment(from: [f64; 3], to: [f64; 3], n: usize) -> Vec<[f64; 3]> {
    (1..=n)
        .map(|k| {
            let s = k as f64 / n as f64;
            [0, 1, 2].map(|i| from[i] + s * (to[i] - from[i]))
        })
        .collect()
}

/// Opens the interface to `35 delta_c` and closes it at `eps_xx = CLOSED`.
const OPEN: f64 = 3.5e-3;
const CLOSED: f64 = -2e-4;

fn opened_and_closed(model: &Arc<Model>) -> (Instance, rve::Workspace) {
    let mut inst = Instance::new(model.clone());
    let mut ws = model.workspace();
    let mut path = segment([0.0; 3], [OPEN, 0.0, 0.0], 70);
    path.extend(segment([OPEN, 0.0, 0.0], [CLOSED, 0.0, 0.0], 40));
    follow(&mut inst, &mut ws, &path);
    (inst, ws)
}

/// The shear cycle at `eps_xx = CLOSED`: 0 -> +a -> -a -> +a, `n` increments a quarter.
fn shear_cycle(amplitude: f64, n: usize) -> Vec<[f64; 3]> {
    let at = |g: f64| [CLOSED, 0.0, g];
    let mut path = segment(at(0.0), at(amplitude), n);
    path.extend(segment(at(amplitude), at(-amplitude), 2 * n));
    path.extend(segment(at(-amplitude), at(amplitude), 2 * n));
    path
}

/// The closed form: an elastic-perfectly plastic spring of compliance `compliance` and
/// yield stress `tau` along the shear strains `gammas`.
fn elastic_plastic(gammas: &[f64], compliance: f64, tau: f64) -> Vec<f64> {
    let (mut plastic, mut out) = (0.0, Vec::new());
    for &g in gammas {
        let trial = (g - plastic) / compliance;
        let stress = trial.clamp(-tau, tau);
        plastic = g - stress * compliance;
        out.push(stress);
    }
    out
}

/// The loop's area by the trapezoid rule over the closed part of the cycle (from the
/// first reversal on).
fn loop_area(gammas: &[f64], stresses: &[f64], first: usize) -> f64 {
    (first + 1..gammas.len())
        .map(|k| 0.5 * (stresses[k] + stresses[k - 1]) * (gammas[k] - gammas[k - 1]))
        .sum()
}

#[test]
fn a_closed_crack_sticks_then_slides_at_mu_sigma_n_with_the_closed_form_loop() {
    let model = model(true);
    let (mut inst, mut ws) = opened_and_closed(&model);
    let k0 = std::f64::consts::E * SIGMA_C / DELTA_C;
    let compliance = 1.0 / SHEAR_MODULUS + 1.0 / (WIDTH * BETA * BETA * k0);
    let n = 100;
    let path = shear_cycle(8e-4, n);
    let stresses = follow(&mut inst, &mut ws, &path);
    let sigma_n = stresses[0][0];
    assert!(sigma_n < -1.0, "closed: sigma_xx {sigma_n}");
    let tau = MU * sigma_n.abs();
    let gammas: Vec<f64> = path.iter().map(|e| e[2]).collect();
    let expected = elastic_plastic(&gammas, compliance, tau);
    let shear: Vec<f64> = stresses.iter().map(|s| s[2]).collect();
    let (mut worst, mut normal_drift, mut sliding) = (0.0f64, 0.0f64, 0);
    for (k, s) in stresses.iter().enumerate() {
        worst = worst.max((shear[k] - expected[k]).abs() / tau);
        normal_drift = normal_drift.max((s[0] - sigma_n).abs() / sigma_n.abs());
        sliding += usize::from((expected[k].abs() - tau).abs() <= 1e-12 * tau);
    }
    assert!(sliding > n, "the cycle slides ({sliding} increments)");
    assert!(
        worst <= 1e-6,
        "shear against the closed form: {worst:e} of tau"
    );
    assert!(normal_drift <= 1e-9, "sigma_xx moved by {normal_drift:e}");
    let area = loop_area(&gammas, &shear, n);
    let closed_form = loop_area(&gammas, &expected, n);
    let exact = 4.0 * tau * (8e-4 - tau * compliance);
    assert!(
        (area - closed_form).abs() <= 1e-6 * closed_form,
        "loop {area} against {closed_form}"
    );
    assert!(
        (closed_form - exact).abs() <= 1e-2 * exact,
        "quadrature {closed_form} vs {exact}"
    );
}

#[test]
fn without_friction_the_same_cycle_dissipates_nothing() {
    let model = model(false);
    let (mut inst, mut ws) = opened_and_closed(&model);
    let n = 50;
    let path = shear_cycle(8e-4, n);
    let stresses = follow(&mut inst, &mut ws, &path);
    let gammas: Vec<f64> = path.iter().map(|e| e[2]).collect();
    let shear: Vec<f64> = stresses.iter().map(|s| s[2]).collect();
    let largest = shear.iter().fold(0.0f64, |m, s| m.max(s.abs()));
    let area = loop_area(&gammas, &shear, n);
    let tau = MU * stresses[0][0].abs();
    assert!(
        area.abs() <= 1e-9 * tau * 8e-4,
        "loop {area:e} (largest shear {largest})"
    );
    assert!(largest < 1e-3 * tau, "the open crack's shear {largest}");
}

/// Central differences of the stress in every strain component, from the committed
/// state, with every trial on the base's branches.
fn fd_tangent(inst: &mut Instance, ws: &mut rve::Workspace, eps: [f64; 3], h: f64) -> [f64; 9] {
    let mut fd = [0.0; 9];
    for j in 0..3 {
        let mut stress = [[0.0; 3]; 2];
        for (k, sign) in [1.0, -1.0].into_iter().enumerate() {
            let mut e = eps;
            e[j] += sign * h;
            stress[k] = inst.update(e, ws, TangentRequest::None).unwrap().stress;
        }
        for i in 0..3 {
            fd[3 * i + j] = (stress[0][i] - stress[1][i]) / (2.0 * h);
        }
    }
    fd
}

#[test]
fn the_sliding_tangent_is_not_symmetric_and_matches_finite_differences() {
    let model = model(true);
    let (mut inst, mut ws) = opened_and_closed(&model);
    let path = segment([CLOSED, 0.0, 0.0], [CLOSED, 0.0, 4e-4], 40);
    follow(&mut inst, &mut ws, &path);
    let eps = [CLOSED, 0.0, 4.2e-4];
    let r = inst
        .update(eps, &mut ws, TangentRequest::Consistent)
        .unwrap();
    assert!(r.report.contact > 0);
    let d = r.tangent;
    let h = 1e-9;
    let fd = fd_tangent(&mut inst, &mut ws, eps, h);
    let scale = d.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let error = d
        .iter()
        .zip(&fd)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
        / scale;
    assert!(error <= 1e-6, "D_hom {d:?} against {fd:?}: {error:e}");
    // Sliding: d sigma_xy / d eps_xx = mu (sign) d sigma_xx / d eps_xx, while
    // d sigma_xx / d gamma_xy = 0.
    let coupling = d[6] / (MU * d[0]);
    assert!(
        (coupling.abs() - 1.0).abs() <= 1e-6,
        "D31 / (mu D11) = {coupling}"
    );
    assert!(d[2].abs() <= 1e-9 * scale, "D13 = {}", d[2]);
}

/// A checkpoint taken while the crack slides continues bit for bit, and the slip is part
/// of it: a checkpoint of the model without friction is refused by the one with it.
#[test]
fn a_checkpoint_in_the_sliding_continues_bit_for_bit() {
    let model = model(true);
    let (mut a, mut ws) = opened_and_closed(&model);
    let path = shear_cycle(8e-4, 20);
    let (first, rest) = path.split_at(30);
    follow(&mut a, &mut ws, first);
    let bytes = a.save_state().unwrap();
    let mut b = Instance::new(model.clone());
    b.load_state(&bytes).unwrap();
    let (sa, sb) = (follow(&mut a, &mut ws, rest), follow(&mut b, &mut ws, rest));
    for (k, (x, y)) in sa.iter().zip(&sb).enumerate() {
        assert_eq!(x.map(f64::to_bits), y.map(f64::to_bits), "increment {k}");
    }
    let (plain, _) = opened_and_closed(&self::model(false));
    let foreign = plain.save_state().unwrap();
    assert!(Instance::new(model).load_state(&foreign).is_err());
}

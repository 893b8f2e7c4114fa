//! Why the paper's contact law (eq. 47, status read from the gap at every evaluation) has
//! no RVE equilibrium on some paths: the experiment of `docs/contact-algorithm.md`.
//!
//! ```text
//! cargo run --release --example contact_diagnosis [-- SCENE [DIR_XX DIR_YY DIR_XY STEP]]
//! ```
//! Path: `t [DIR_XX, DIR_YY, DIR_XY]` in increments of `STEP` in `t` (40 of them), or the
//! scene's own `[[path]]` when only the scene is given. Default: `scenes/paper_rve.toml`,
//! the uniaxial-stress-like direction `[1, -0.1935, -3.6e-4]`, increments of 1e-5.
//!
//! 1. The library's solver, with the status read from the gap at every evaluation
//!    (`solver.contact_status = "per_iteration"`), follows the path by increments, halving
//!    a failed increment (each update already bisects ten times inside) down to 1e-20 of
//!    the step: the last converged strain and the smallest increment that still fails.
//! 2. At that failing target, from the last converged state, a Newton loop with the
//!    contact status of every ITZ point *held fixed* (the law is then continuous and the
//!    loop converges) is wrapped in the active-set fixed point: solve, re-read the status
//!    from the gaps, repeat. A status set that reproduces itself is an equilibrium of the
//!    literal law; the printout shows the sets cycling instead.
//! 3. For the points whose status changes along the cycle, every assignment of their
//!    statuses (the others as in the cycle) is solved, and its inconsistencies counted: a
//!    point held closed whose gap comes out open, or held open whose gap comes out closed.
//!    If no assignment is consistent, the literal law has no equilibrium with those
//!    statuses, whatever the solver.
//! 4. For every cycling point: its sliding, its gap under each status, and the shear
//!    traction it carries just open (`k beta^2 delta_s`) and just closed (`k_p delta_s`).

#[path = "support/fixed_status.rs"]
mod fixed_status;

use fixed_status::solve_fixed;
use mesorve_core::interface::{CohesiveHistory, CohesiveLaw, Penalty};
use rve::{Model, Scene, TangentRequest};

/// Jumps `[delta_s, delta_n]` of every interface point at `x`.
fn jumps(model: &Model, x: &[f64]) -> Vec<[f64; 2]> {
    let disc = &model.discretization();
    let q = disc.quadrature;
    let np = q.num_points();
    let mut out = Vec::new();
    for (g, dofs) in disc.interfaces.iter().zip(disc.interface_dofs.iter()) {
        let u = nalgebra::SVector::<f64, 8>::from_fn(|i, _| {
            let d = dofs[i];
            if (d as usize) < x.len() {
                x[d as usize]
            } else {
                0.0
            }
        });
        out.extend_from_slice(&mesorve_core::element::interface4::local_jumps(g, q, &u)[..np]);
    }
    out
}

/// The scene's cohesive-contact law (as `model::from_scene` builds it).
fn cohesive_law(scene: &Scene) -> CohesiveLaw {
    let spec = &scene.spec;
    let itz = spec
        .materials
        .itz
        .expect("the scene has a cohesive ITZ law");
    CohesiveLaw {
        sigma_c: itz.sigma_c,
        delta_c: itz.delta_c,
        beta: itz.beta,
        penalty: match (itz.penalty.lambda_p, itz.penalty.stiffness) {
            (Some(lambda_p), _) => Penalty::PerLength { lambda_p },
            (None, stiffness) => Penalty::PerArea {
                stiffness: stiffness.unwrap_or(0.0),
            },
        },
        contact: spec.effects.contact,
        contact_shear: itz.contact_shear,
    }
}

fn status_of(model: &Model, x: &[f64]) -> Vec<bool> {
    let mut s = vec![false; model.discretization().interface_points()];
    model.discretization().contact_status(x, &mut s);
    s
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene_path = args.first().map_or("scenes/paper_rve.toml", |s| s.as_str());
    // The path: a direction and a step, or (a scene alone) the scene's own path.
    let direction: Option<([f64; 3], f64)> = if args.len() >= 5 {
        let v: Vec<f64> = args[1..5]
            .iter()
            .map(|a| a.parse().expect("number"))
            .collect();
        Some(([v[0], v[1], v[2]], v[3]))
    } else if args.is_empty() {
        Some(([1.0, -0.1935, -3.6e-4], 1e-5))
    } else {
        None
    };
    let text = std::fs::read_to_string(scene_path).expect("scene");
    // The solver's own bisection is off: the loop below bisects, and stops at the first
    // increment that fails at 1/1024 of the step (the solver's default depth of 10).
    let text = text.replace(
        "[solver]",
        "[solver]\ncontact_status = \"per_iteration\"\nmax_substep_depth = 0",
    );
    let scene = Scene::from_toml_str(&text, ".").expect("scene");
    let model = Model::from_scene(&scene).expect("model");
    let law = cohesive_law(&scene);
    // Increment targets: (start, end) of each of the path's increments.
    let mut increments: Vec<([f64; 3], [f64; 3])> = Vec::new();
    match direction {
        Some((dir, step)) => {
            for k in 0..40 {
                let at = |k: f64| [k * step * dir[0], k * step * dir[1], k * step * dir[2]];
                increments.push((at(k as f64), at(k as f64 + 1.0)));
            }
        }
        None => {
            let mut from = [0.0; 3];
            for seg in &scene.spec.path {
                let n = seg.increments as f64;
                for k in 0..seg.increments {
                    let at =
                        |k: f64| std::array::from_fn(|c| from[c] + k / n * (seg.to[c] - from[c]));
                    increments.push((at(k as f64), at(k as f64 + 1.0)));
                }
                from = seg.to;
            }
        }
    }
    println!(
        "scene {scene_path}: {} unknowns, {} ITZ points; path {}",
        model.discretization().n(),
        model.discretization().history_len(),
        match direction {
            Some((dir, step)) => format!("t {dir:?}, increments of t = {step:e}"),
            None => "of the scene".to_string(),
        }
    );

    // 1. The solver along the path.
    let mut ws = model.workspace();
    let mut committed = model.new_state();
    let mut trial = model.new_state();
    let mut updates = 0;
    let mut failing = None;
    'path: for (number, &(start, end)) in increments.iter().enumerate() {
        let (mut s, mut h) = (0.0f64, 1.0f64);
        while s < 1.0 {
            let to = (s + h).min(1.0);
            let eps: [f64; 3] = std::array::from_fn(|c| start[c] + to * (end[c] - start[c]));
            match model.update(&committed, eps, &mut ws, &mut trial, TangentRequest::None) {
                Ok(_) => {
                    committed = trial.clone();
                    s = to;
                    h = (2.0 * h).min(1.0);
                    updates += 1;
                }
                Err(e) => {
                    if h <= 1.0 / 1024.0 {
                        println!(
                            "converged to eps = {:?} (increment {} of the path, {updates} \
                             updates); the next update, {h:e} of the increment, fails: {e}",
                            committed.strain,
                            number + 1,
                        );
                        failing = Some(eps);
                        break 'path;
                    }
                    h *= 0.5;
                }
            }
        }
    }
    let Some(failing) = failing else {
        println!("the path completes ({updates} updates)");
        return;
    };
    let closed_at_start = committed.history.len()
        - status_of(&model, &committed.unknowns)
            .iter()
            .filter(|c| !**c)
            .count();
    println!("closed points at the last converged state: {closed_at_start}");

    // 2. The active-set fixed point at the failing target.
    let mut status = status_of(&model, &committed.unknowns);
    let mut seen: Vec<Vec<bool>> = vec![status.clone()];
    let mut cycle_start = None;
    for pass in 1..=30 {
        let Some(sol) = solve_fixed(
            &model,
            &committed.unknowns,
            &committed.history,
            &failing,
            &status,
            &mut ws,
        ) else {
            println!("pass {pass}: Newton with the status fixed did not converge");
            return;
        };
        let read = status_of(&model, &sol.x);
        let to_closed: Vec<usize> = (0..read.len()).filter(|&i| read[i] && !status[i]).collect();
        let to_open: Vec<usize> = (0..read.len()).filter(|&i| !read[i] && status[i]).collect();
        println!(
            "pass {pass}: {} closed held, Newton {} iterations (rel. residual {:.1e}); \
             inconsistent: {} open held with a closed gap {:?}, {} closed held with an open gap {:?}",
            status.iter().filter(|c| **c).count(),
            sol.iterations,
            sol.rel_residual,
            to_closed.len(),
            to_closed,
            to_open.len(),
            to_open
        );
        if to_closed.is_empty() && to_open.is_empty() {
            println!("consistent: an equilibrium of the literal law");
            return;
        }
        status = read;
        if let Some(k) = seen.iter().position(|s| *s == status) {
            println!("the status set of pass {pass} is that of pass {k}: a cycle");
            cycle_start = Some(k);
            break;
        }
        seen.push(status.clone());
    }
    let Some(k) = cycle_start else {
        println!("no cycle within 30 passes");
        return;
    };
    let cycle = &seen[k..];
    let flipping: Vec<usize> = (0..status.len())
        .filter(|&i| cycle.iter().any(|s| s[i] != cycle[0][i]))
        .collect();
    println!("points whose status changes along the cycle: {flipping:?}");

    // 3. Every assignment of the cycling points.
    if flipping.len() > 16 {
        println!("too many to enumerate");
        return;
    }
    let mut best = usize::MAX;
    let mut per_assignment = Vec::new();
    for mask in 0u32..(1 << flipping.len()) {
        let mut s = cycle[0].clone();
        for (b, &i) in flipping.iter().enumerate() {
            s[i] = mask & (1 << b) != 0;
        }
        let Some(sol) = solve_fixed(
            &model,
            &committed.unknowns,
            &committed.history,
            &failing,
            &s,
            &mut ws,
        ) else {
            per_assignment.push((mask, None));
            continue;
        };
        let read = status_of(&model, &sol.x);
        let bad = (0..s.len()).filter(|&i| read[i] != s[i]).count();
        best = best.min(bad);
        per_assignment.push((mask, Some(bad)));
    }
    println!(
        "assignments of the {} cycling points: {}; inconsistent points per assignment \
         (bit b = point {:?}[b] held closed): {:?}",
        flipping.len(),
        per_assignment.len(),
        flipping,
        per_assignment
    );
    println!(
        "fewest inconsistent points over all assignments: {best} ({})",
        if best == 0 {
            "some assignment is an equilibrium"
        } else {
            "no equilibrium of the literal law with these statuses"
        }
    );

    // 4. The cycling points under each status.
    let np = model.discretization().points_per_interface();
    for &i in &flipping {
        let e = i / np;
        let length = model.discretization().interfaces[e].length;
        let hist = CohesiveHistory {
            delta_max: committed.history[i],
        };
        let k_open = law.unloading_secant(&hist);
        let mut line = format!(
            "point {i} (element {e}, point {}): delta_max = {:.3e} ({:.2} delta_c)",
            i % np,
            hist.delta_max,
            hist.delta_max / law.delta_c
        );
        for closed in [false, true] {
            let mut s = cycle[0].clone();
            for &j in &flipping {
                s[j] = closed;
            }
            if let Some(sol) = solve_fixed(
                &model,
                &committed.unknowns,
                &committed.history,
                &failing,
                &s,
                &mut ws,
            ) {
                let j = jumps(&model, &sol.x)[i];
                let p = law.evaluate_as(&hist, j, length, closed);
                line += &format!(
                    "; all held {}: delta_s = {:+.3e}, delta_n = {:+.3e}, t_s = {:+.4}, t_n = {:+.4}, secant k = {:.3e}",
                    if closed { "closed" } else { "open" },
                    j[0],
                    j[1],
                    p.traction[0],
                    p.traction[1],
                    p.secant
                );
                let _ = sol.hist;
            }
        }
        line += &format!(
            "; k_p = {:.3e}, k_open beta^2 = {:.3e} (loading secant at the start: {:.3e})",
            law.contact_stiffness(length),
            k_open * law.beta * law.beta,
            k_open
        );
        println!("{line}");
    }
}

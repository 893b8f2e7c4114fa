//! Runs the seeded hard cases of `tests/common/hard_paths.rs` and prints, per case and in
//! total: completion, iterations, factorizations, the slowest increment, and how far each
//! converged state is from an equilibrium of the paper's law with the contact status read
//! from the gaps (`docs/contact-algorithm.md`). Where the converged state holds points at a
//! status their gap contradicts (`solver.contact_status = "active_set"`), the step is
//! solved again with those points' statuses flipped and held (Newton from the converged
//! state): the stress difference between the two brackets what the choice of status at
//! those points can change, and if the flipped solution is consistent the held scheme
//! missed an equilibrium of the literal law.
//!
//! ```text
//! cargo run --release --example hard_cases -- [FIRST_SEED COUNT [STATUS]]
//! ```
//! `STATUS`: `active_set` or `per_iteration` (`solver.contact_status`; default: the
//! scene default).

#[path = "support/fixed_status.rs"]
mod fixed_status;
#[path = "../tests/common/hard_paths.rs"]
mod hard_paths;

use std::time::Instant;

use rve::{Model, Scene, TangentRequest};

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|a| a * a).sum::<f64>().sqrt()
}

/// `||R(x; eps)|| / max(||G eps||, 1e-8 ||G||)` with the status read from the gaps and the
/// converged history `base` (which gives the converged tractions whatever sub-steps led
/// there: loading points sit on their `delta_max`): the relative residual of the literal
/// law.
fn literal_residual(model: &Model, x: &[f64], eps: &[f64; 3], base: &[f64]) -> f64 {
    let disc = &model.discretization();
    let n = disc.n();
    let mut r = vec![0.0; n];
    let mut trial = base.to_vec();
    disc.evaluate(x, eps, base, &mut trial, &mut r, None);
    let mut ge = vec![0.0; n];
    for (c, e) in eps.iter().enumerate() {
        for (g, gc) in ge.iter_mut().zip(&disc.g[c * n..(c + 1) * n]) {
            *g += gc * e;
        }
    }
    norm(&r) / norm(&ge).max(1e-8 * norm(&disc.g))
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let first: u64 = args.first().map_or(0, |a| a.parse().expect("seed"));
    let count: u64 = args.get(1).map_or(40, |a| a.parse().expect("count"));
    let status = args.get(2).cloned();
    let (mut done, mut failed) = (0, 0);
    let (mut iterations, mut factorizations, mut increments) = (0u64, 0u64, 0u64);
    let mut slowest = (0.0f64, 0u64);
    let mut increment_ms = Vec::new();
    let mut worst_literal = 0.0f64;
    let mut inconsistent_increments = 0;
    let (mut mismatched, mut most_off, mut missed, mut unsolved) = (0, 0, 0, 0);
    let mut brackets: Vec<f64> = Vec::new();
    let total = Instant::now();
    for seed in first..first + count {
        let case = hard_paths::case(seed);
        let mut text = case.scene.clone();
        if let Some(s) = &status {
            text = text.replace("[solver]", &format!("[solver]\ncontact_status = \"{s}\""));
        }
        let scene = Scene::from_toml_str(&text, ".").expect("scene");
        let model = match Model::from_scene(&scene) {
            Ok(m) => m,
            Err(e) => {
                println!("seed {seed:3}: model fails: {e}");
                failed += 1;
                continue;
            }
        };
        let mut ws = model.workspace();
        let mut committed = model.new_state();
        let mut trial = model.new_state();
        let (mut its, mut facts, mut worst_ms, mut worst_its) = (0u64, 0u64, 0.0f64, 0u32);
        let mut literal = 0.0f64;
        let mut outcome = "ok".to_string();
        for (k, &eps) in case.targets.iter().enumerate() {
            let start = Instant::now();
            let result = model.update(
                &committed,
                eps,
                &mut ws,
                &mut trial,
                TangentRequest::Consistent,
            );
            let ms = start.elapsed().as_secs_f64() * 1e3;
            match result {
                Ok(r) => {
                    its += u64::from(r.report.iterations);
                    facts += u64::from(r.report.factorizations);
                    worst_its = worst_its.max(r.report.iterations);
                    worst_ms = worst_ms.max(ms);
                    increment_ms.push(ms);
                    let lit = literal_residual(&model, &trial.unknowns, &eps, &trial.history);
                    if let Some(held) = ws.held_contact_status().map(|s| s.to_vec()) {
                        let mut read = vec![false; held.len()];
                        model
                            .discretization()
                            .contact_status(&trial.unknowns, &mut read);
                        let off: Vec<usize> =
                            (0..read.len()).filter(|&i| read[i] != held[i]).collect();
                        if !off.is_empty() {
                            mismatched += 1;
                            most_off = most_off.max(off.len());
                            let mut flipped = held.clone();
                            off.iter().for_each(|&i| flipped[i] = !flipped[i]);
                            let base = ws.history_start().to_vec();
                            match fixed_status::solve_fixed(
                                &model,
                                &trial.unknowns,
                                &base,
                                &eps,
                                &flipped,
                                &mut ws,
                            ) {
                                Some(sol) => {
                                    let (other, _) = model.homogenizer().stress(
                                        model.discretization(),
                                        &eps,
                                        &sol.x,
                                    );
                                    let scale = r.stress.iter().fold(0.4f64, |m, v| m.max(v.abs()));
                                    let d = (0..3)
                                        .map(|i| (other[i] - r.stress[i]).abs())
                                        .fold(0.0, f64::max)
                                        / scale;
                                    brackets.push(d);
                                    if std::env::var_os("HARD_CASES_VERBOSE").is_some() {
                                        println!("  seed {seed} increment {}: {} points held against their gap, bracket {d:.2e}, literal residual {lit:.1e}", k + 1, off.len());
                                    }
                                    let mut again = vec![false; read.len()];
                                    model.discretization().contact_status(&sol.x, &mut again);
                                    if again == flipped {
                                        missed += 1;
                                    }
                                }
                                None => unsolved += 1,
                            }
                        }
                    }
                    if lit > 1e-6 {
                        inconsistent_increments += 1;
                    }
                    literal = literal.max(lit);
                    std::mem::swap(&mut committed, &mut trial);
                }
                Err(e) => {
                    outcome = format!(
                        "FAILS at increment {} of {}: {e}",
                        k + 1,
                        case.targets.len()
                    );
                    break;
                }
            }
        }
        if outcome == "ok" {
            done += 1;
        } else {
            failed += 1;
        }
        iterations += its;
        factorizations += facts;
        increments += case.targets.len() as u64;
        if worst_ms > slowest.0 {
            slowest = (worst_ms, seed);
        }
        worst_literal = worst_literal.max(literal);
        println!(
            "seed {seed:3} {:20} {:55} {:3} incs: {its:5} it {facts:5} fact, worst {worst_its:4} it {worst_ms:7.1} ms, literal residual {literal:.1e}  {outcome}",
            case.kind,
            case.setup,
            case.targets.len()
        );
    }
    increment_ms.sort_by(f64::total_cmp);
    brackets.sort_by(f64::total_cmp);
    println!(
        "increments ending with points held against their gap: {mismatched} (at most {most_off} \
         points); stress change when those points are flipped and the step solved again: \
         median {:.1e}, 90 % {:.1e}, max {:.1e} (relative to max(|sigma|, 0.4)); flipped \
         solutions consistent with their gaps (missed equilibria of the literal law): {missed}; \
         flipped solves that did not converge: {unsolved}",
        brackets.get(brackets.len() / 2).copied().unwrap_or(0.0),
        brackets
            .get(brackets.len() * 9 / 10)
            .copied()
            .unwrap_or(0.0),
        brackets.last().copied().unwrap_or(0.0),
    );
    let median = increment_ms
        .get(increment_ms.len() / 2)
        .copied()
        .unwrap_or(0.0);
    println!(
        "total: {done} completed, {failed} failed; {increments} increments, {iterations} iterations, \
         {factorizations} factorizations; median increment {median:.2} ms, slowest {:.1} ms (seed {}); \
         increments off the literal law's equilibrium (relative residual > 1e-6): \
         {inconsistent_increments}, largest {worst_literal:.1e}; {:.1} s",
        slowest.0,
        slowest.1,
        total.elapsed().as_secs_f64()
    );
}

//! A Newton loop with the contact status of every ITZ point held fixed, for the examples
//! `contact_diagnosis` and `hard_cases` (see `docs/contact-algorithm.md`).

use mesorve_core::interface::TangentKind;
use rve::{Model, Workspace};

#[allow(dead_code)]
pub struct Solved {
    pub x: Vec<f64>,
    pub hist: Vec<f64>,
    pub iterations: usize,
    pub rel_residual: f64,
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|a| a * a).sum::<f64>().sqrt()
}

/// Newton at macro strain `eps` from the unknowns `x0` and the step's start history
/// `base`, with the contact status `status` held fixed.
pub fn solve_fixed(
    model: &Model,
    x0: &[f64],
    base: &[f64],
    eps: &[f64; 3],
    status: &[bool],
    ws: &mut Workspace,
) -> Option<Solved> {
    let disc = &model.discretization();
    let n = disc.n();
    let mut gr = vec![0.0; n];
    for (c, e) in eps.iter().enumerate() {
        for (g, gc) in gr.iter_mut().zip(&disc.g[c * n..(c + 1) * n]) {
            *g += gc * e;
        }
    }
    let reference = norm(&gr).max(1e-8 * norm(&disc.g));
    let tol = model.settings().tolerance * reference;
    let mut x = x0.to_vec();
    let mut hist = base.to_vec();
    let (mut r, mut k) = (vec![0.0; n], vec![0.0; disc.pattern.nnz()]);
    let eval = |x: &[f64], hist: &mut Vec<f64>, r: &mut Vec<f64>, k: &mut Vec<f64>| {
        disc.evaluate_with(
            x,
            eps,
            base,
            hist,
            r,
            Some(k),
            TangentKind::Consistent,
            Some(status),
        );
        norm(r)
    };
    let mut rn = eval(&x, &mut hist, &mut r, &mut k);
    for it in 0..60 {
        if rn <= tol {
            return Some(Solved {
                x,
                hist,
                iterations: it,
                rel_residual: rn / reference,
            });
        }
        ws.factorization()
            .factorize(
                model.linear_solver(),
                &disc.pattern.symbolic,
                &k,
                mesorve_core::solver::FactorUse::Reusable,
                true,
            )
            .ok()?;
        let mut dx: Vec<f64> = r.iter().map(|v| -v).collect();
        ws.factorization().solve(model.linear_solver(), &mut dx, 1);
        // Backtracking on ||R|| (the law is continuous with the status fixed, but has the
        // loading/unloading kinks).
        let mut alpha = 1.0;
        loop {
            let xt: Vec<f64> = x.iter().zip(&dx).map(|(a, d)| a + alpha * d).collect();
            let (mut ht, mut rt, mut kt) = (hist.clone(), r.clone(), k.clone());
            let nt = eval(&xt, &mut ht, &mut rt, &mut kt);
            if nt < rn || alpha < 1.0 / 64.0 {
                (x, hist, r, k, rn) = (xt, ht, rt, kt, nt);
                break;
            }
            alpha *= 0.5;
        }
    }
    None
}

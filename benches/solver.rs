//! Solver benchmark: `cargo bench --bench solver` prints one table row per RVE.
//!
//! For each scene, on one core: the median and mean time of a converged increment along
//! the section 5.2.1 path (`eps_xx` to 2.2e-4 in 20 increments; the mean carries the
//! post-peak increments), the iterations per increment, the median numeric factorization
//! of the converged tangent as the solver does it (LDL^T, a checked LBL^T when that fails,
//! LU last) with the share of each kind, and `FactorMethod::Lu` alone for comparison, the solve times with
//! 1, 3 and 4 right-hand sides (the widths the solver uses: a chord correction, the
//! tangent's sweep, a Newton correction with the tangent's columns), the bytes of one
//! instance's state, and two ratios per increment (medians):
//! - `update time / (iterations x factorization + solves)`, the definition, which
//!   assumes one factorization per Newton iteration; `solves` is the time of the solves
//!   the update did (counted by width by the solver, `NumericFactor::solves`, and priced
//!   at the widths' times), since an update solves for the tangent's columns too. With
//!   one 1-column solve instead, a one-iteration update of the paper RVE would read 2.0;
//! - `update time / (factorizations x factorization + solves)`, the factorizations
//!   actually done (chord corrections reuse one, the tangent may add one): how much an
//!   update costs beyond the linear algebra it did.
//!
//! A second table times, per scene, one factorization and a one-column solve of the
//! tangent at `eps_xx = 1e-4` made non-symmetric (the entries `(i, j)`, `i < j`,
//! `i + j` a multiple of 3, scaled by 1.3: a friction tangent's structure, symmetric
//! pattern and non-symmetric values) with `FactorMethod::Lu` (the LU without pivoting,
//! probe check included) and with faer's supernodal LU with partial pivoting (the
//! allocating fallback), against the LDL^T of the symmetric tangent, in the same run.
//!
//! Timing tests do not belong in the test suite (noisy machines); this is the place.

use std::sync::Arc;
use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu};
use faer::sparse::SparseColMatRef;
use faer::{Conj, MatMut, Par};
use mesorve_core::solver::{FactorKind, FactorMethod, LinearSolver};
use rve::{Instance, Model, Scene, TangentRequest};

/// Right-hand-side counts the solver's solves use, timed one by one.
const SOLVE_WIDTHS: [usize; 3] = [1, 3, 4];

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

struct Row {
    name: String,
    unknowns: usize,
    itz: usize,
    increment_ms: f64,
    iterations: f64,
    max_iterations: u32,
    factor_ms: f64,
    lu_ms: f64,
    ldlt_share: f64,
    indefinite_ldlt_share: f64,
    lblt_share: f64,
    mean_increment_ms: f64,
    solve_ms: [f64; 3],
    solve_columns: f64,
    state_bytes: usize,
    ratio: f64,
    factorizations: f64,
    mean_factorizations: f64,
    overhead: f64,
}

fn bench(path: &str) -> Row {
    let scene = Scene::from_file(path).expect("scene");
    let model = Arc::new(Model::from_scene(&scene).expect("model"));
    let mut ws = model.workspace();
    // Buffers of the timed factorizations and solves, beside the workspace's own.
    let mut numeric = model.linear_solver().numeric();
    let mut stack = faer::dyn_stack::MemBuffer::new(model.linear_solver().scratch(4));
    let mut rhs4 = vec![0.0; 4 * model.discretization().n()];
    let steps = 20;
    let mut times = Vec::new();
    let mut iterations = Vec::new();
    let mut ratios = Vec::new();
    let mut factorizations = Vec::new();
    let mut overheads = Vec::new();
    let mut factor_times = Vec::new();
    let mut solve_times: [Vec<f64>; 3] = Default::default();
    let mut solve_columns = Vec::new();
    let mut max_iterations = 0;
    let mut lu_times = Vec::new();
    let mut ldlt_count = 0usize;
    let mut indefinite_ldlt_count = 0usize;
    let mut lblt_count = 0usize;
    // Repeat the path to get stable medians (more often for the small RVE, whose
    // increments are short enough for machine noise to matter).
    let repeats = if model.discretization().n() < 2000 {
        15
    } else {
        3
    };
    for _ in 0..repeats {
        let mut inst = Instance::new(model.clone());
        for k in 1..=steps {
            let eps = [2.2e-4 * k as f64 / steps as f64, 0.0, 0.0];
            let solves_before = ws.factorization().numeric().solves;
            let t0 = Instant::now();
            let r = inst
                .update(eps, &mut ws, TangentRequest::Consistent)
                .expect("update");
            let dt = t0.elapsed().as_secs_f64();
            inst.commit().expect("commit");
            let solves: Vec<f64> = (0..5)
                .map(|w| (ws.factorization().numeric().solves[w] - solves_before[w]) as f64)
                .collect();
            // Factorization and solves of the converged tangent, timed on their own.
            let (mut ft, mut lt) = (Vec::new(), Vec::new());
            let mut st: [Vec<f64>; 3] = Default::default();
            for _ in 0..5 {
                let t = Instant::now();
                let kind = model
                    .linear_solver()
                    .factorize(
                        &model.discretization().pattern.symbolic,
                        ws.tangent_values(),
                        &mut numeric,
                        FactorMethod::SymmetricFirst,
                        MemStack::new(&mut stack),
                    )
                    .expect("factorization");
                ft.push(t.elapsed().as_secs_f64());
                match kind {
                    FactorKind::Ldlt => ldlt_count += 1,
                    FactorKind::LdltIndefinite => indefinite_ldlt_count += 1,
                    FactorKind::Lblt => lblt_count += 1,
                    FactorKind::Lu => {}
                }
                let n = model.discretization().n();
                for (times, width) in st.iter_mut().zip(SOLVE_WIDTHS) {
                    let rhs = &mut rhs4[..width * n];
                    rhs[..n].copy_from_slice(ws.residual());
                    rhs[n..].copy_from_slice(&model.discretization().g[..(width - 1) * n]);
                    let t = Instant::now();
                    model.linear_solver().solve_in_place(
                        &mut numeric,
                        rhs,
                        width,
                        MemStack::new(&mut stack),
                    );
                    times.push(t.elapsed().as_secs_f64());
                }
                let t = Instant::now();
                model
                    .linear_solver()
                    .factorize(
                        &model.discretization().pattern.symbolic,
                        ws.tangent_values(),
                        &mut numeric,
                        FactorMethod::Lu,
                        MemStack::new(&mut stack),
                    )
                    .expect("lu");
                lt.push(t.elapsed().as_secs_f64());
            }
            let f = median(&mut ft);
            let width_times = st.each_mut().map(|t| median(t));
            // The update's solves priced by width (the solver has no 2-column solve).
            assert_eq!(solves[2], 0.0, "a 2-column solve: time that width too");
            let solve_time = solves[1] * width_times[0]
                + solves[3] * width_times[1]
                + solves[4] * width_times[2];
            factor_times.push(f);
            for (all, t) in solve_times.iter_mut().zip(width_times) {
                all.push(t);
            }
            solve_columns.push((1..5).map(|w| w as f64 * solves[w]).sum::<f64>());
            lu_times.push(median(&mut lt));
            times.push(dt);
            iterations.push(r.report.iterations as f64);
            max_iterations = max_iterations.max(r.report.iterations);
            ratios.push(dt / (r.report.iterations.max(1) as f64 * f + solve_time));
            factorizations.push(r.report.factorizations as f64);
            overheads.push(dt / (r.report.factorizations as f64 * f + solve_time));
        }
    }
    // A converged state with its sensitivity and path curvature (a virgin state has
    // neither; the first increment fills the sensitivity, the second the curvature).
    let mut inst = Instance::new(model.clone());
    let mut ws = model.workspace();
    for eps in [1e-5, 2e-5] {
        inst.update([eps, 0.0, 0.0], &mut ws, TangentRequest::Consistent)
            .expect("pre-peak increment");
        inst.commit().unwrap();
    }
    Row {
        name: path.rsplit('/').next().unwrap_or(path).to_string(),
        unknowns: model.discretization().n(),
        itz: model.discretization().interfaces.len(),
        mean_increment_ms: 1e3 * times.iter().sum::<f64>() / times.len() as f64,
        increment_ms: 1e3 * median(&mut times),
        iterations: median(&mut iterations),
        max_iterations,
        ldlt_share: ldlt_count as f64 / (5 * factor_times.len()) as f64,
        indefinite_ldlt_share: indefinite_ldlt_count as f64 / (5 * factor_times.len()) as f64,
        lblt_share: lblt_count as f64 / (5 * factor_times.len()) as f64,
        factor_ms: 1e3 * median(&mut factor_times),
        lu_ms: 1e3 * median(&mut lu_times),
        solve_ms: solve_times.each_mut().map(|t| 1e3 * median(t)),
        solve_columns: median(&mut solve_columns),
        state_bytes: inst.committed().bytes(),
        ratio: median(&mut ratios),
        mean_factorizations: factorizations.iter().sum::<f64>() / factorizations.len() as f64,
        factorizations: median(&mut factorizations),
        overhead: median(&mut overheads),
    }
}

/// Medians (ms) of one factorization and one-column solve of the paper path's tangent at
/// `eps_xx = 1e-4`: LDL^T of the tangent, and of its non-symmetric variant (module docs)
/// `FactorMethod::Lu` and faer's supernodal LU with partial pivoting.
struct LuRow {
    name: String,
    unknowns: usize,
    ldlt_ms: f64,
    static_lu_ms: f64,
    pivoted_lu_ms: f64,
    /// Whether every `FactorMethod::Lu` was the LU without pivoting.
    static_accepted: bool,
}

fn lu_bench(path: &str) -> LuRow {
    let model =
        Arc::new(Model::from_scene(&Scene::from_file(path).expect("scene")).expect("model"));
    let mut ws = model.workspace();
    let mut inst = Instance::new(model.clone());
    inst.update([1e-4, 0.0, 0.0], &mut ws, TangentRequest::Consistent)
        .expect("update");
    let pattern = &model.discretization().pattern.symbolic;
    let n = pattern.nrows();
    let symmetric = ws.tangent_values().to_vec();
    let mut values = symmetric.clone();
    let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
    for j in 0..n {
        for k in col_ptr[j]..col_ptr[j + 1] {
            if row_idx[k] < j && (row_idx[k] + j) % 3 == 0 {
                values[k] *= 1.3;
            }
        }
    }
    // The analysis a model with friction has (the paper's cell has none).
    let solver = LinearSolver::for_non_symmetric(pattern, true).expect("analysis");
    let mut numeric = solver.numeric();
    let mut stack = MemBuffer::new(solver.scratch(1));
    let rhs0: Vec<f64> = ws.residual().to_vec();
    let mut rhs = rhs0.clone();
    let repeats = if n < 2000 { 200 } else { 20 };
    let mut time = |values: &[f64], method: FactorMethod| {
        let mut times = Vec::new();
        for _ in 0..repeats {
            rhs.copy_from_slice(&rhs0);
            let t = Instant::now();
            solver
                .factorize(
                    pattern,
                    values,
                    &mut numeric,
                    method,
                    MemStack::new(&mut stack),
                )
                .expect("factorization");
            solver.solve_in_place(&mut numeric, &mut rhs, 1, MemStack::new(&mut stack));
            times.push(t.elapsed().as_secs_f64());
        }
        1e3 * median(&mut times)
    };
    let ldlt_ms = time(&symmetric, FactorMethod::SymmetricFirst);
    let static_lu_ms = time(&values, FactorMethod::Lu);
    let static_accepted = numeric.lu_count == 0 && numeric.static_lu_count == repeats as u64;
    let pivoted_lu_ms = pivoted_lu_time(pattern, &values, &rhs0, repeats);
    LuRow {
        name: path.rsplit('/').next().unwrap_or(path).to_string(),
        unknowns: n,
        ldlt_ms,
        static_lu_ms,
        pivoted_lu_ms,
        static_accepted,
    }
}

/// Median (ms) of faer's supernodal LU with partial pivoting (COLAMD, as
/// `LinearSolver`'s fallback) and a one-column solve.
fn pivoted_lu_time(
    pattern: &faer::sparse::SymbolicSparseColMat<usize>,
    values: &[f64],
    rhs0: &[f64],
    repeats: usize,
) -> f64 {
    let symbolic = factorize_symbolic_lu(pattern.as_ref(), Default::default()).expect("analysis");
    let mut lu = NumericLu::new();
    let mut stack = MemBuffer::new(StackReq::any_of(&[
        symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()),
        symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
    ]));
    let a = SparseColMatRef::new(pattern.as_ref(), values);
    let mut rhs = rhs0.to_vec();
    let mut times = Vec::new();
    for _ in 0..repeats {
        rhs.copy_from_slice(rhs0);
        let t = Instant::now();
        let factor_stack = MemStack::new(&mut stack);
        symbolic
            .factorize_numeric_lu(&mut lu, a, Par::Seq, factor_stack, Default::default())
            .expect("LU");
        let x = MatMut::from_column_major_slice_mut(&mut rhs, rhs0.len(), 1);
        LuRef::new_unchecked(&symbolic, &lu).solve_in_place_with_conj(
            Conj::No,
            x,
            Par::Seq,
            MemStack::new(&mut stack),
        );
        times.push(t.elapsed().as_secs_f64());
    }
    1e3 * median(&mut times)
}

fn main() {
    let root = env!("CARGO_MANIFEST_DIR");
    let scenes = [
        format!("{root}/scenes/paper_rve.toml"),
        format!("{root}/scenes/paper_rve_fine.toml"),
    ];
    println!(
        "| scene | unknowns | ITZ | median increment (ms) | mean increment (ms) | iterations (median / max) | factorizations (median / mean) | factorization used (ms) | LDL^T SPD / indefinite / LBL^T share | LU alone (ms) | solve 1 / 3 / 4 columns (ms) | columns solved (median) | state bytes | update / (it x fact + solves) | update / (fact x factorizations + solves) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for s in &scenes {
        let r = bench(s);
        println!(
            "| {} | {} | {} | {:.3} | {:.3} | {} / {} | {} / {:.2} | {:.3} | {:.0} % / {:.0} % / {:.0} % | {:.3} | {:.3} / {:.3} / {:.3} | {} | {} | {:.2} | {:.2} |",
            r.name,
            r.unknowns,
            r.itz,
            r.increment_ms,
            r.mean_increment_ms,
            r.iterations,
            r.max_iterations,
            r.factorizations,
            r.mean_factorizations,
            r.factor_ms,
            100.0 * r.ldlt_share,
            100.0 * r.indefinite_ldlt_share,
            100.0 * r.lblt_share,
            r.lu_ms,
            r.solve_ms[0],
            r.solve_ms[1],
            r.solve_ms[2],
            r.solve_columns,
            r.state_bytes,
            r.ratio,
            r.overhead
        );
    }
    println!();
    println!(
        "| scene | unknowns | LDL^T, symmetric tangent (ms) | FactorMethod::Lu, non-symmetric (ms) | faer supernodal LU, non-symmetric (ms) | FactorMethod::Lu / LDL^T | faer LU / FactorMethod::Lu | LU without pivoting accepted |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for s in &scenes {
        let r = lu_bench(s);
        println!(
            "| {} | {} | {:.3} | {:.3} | {:.3} | {:.2} | {:.2} | {} |",
            r.name,
            r.unknowns,
            r.ldlt_ms,
            r.static_lu_ms,
            r.pivoted_lu_ms,
            r.static_lu_ms / r.ldlt_ms,
            r.pivoted_lu_ms / r.static_lu_ms,
            if r.static_accepted {
                "always"
            } else {
                "not always"
            }
        );
    }
}

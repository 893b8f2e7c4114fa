//! The LU of non-symmetric tangents (`FactorMethod::Lu`, used when a point slides under
//! friction) allocates nothing once the workspace exists: its LU without pivoting works
//! in buffers sized by the analysis of the pattern. The matrix is the paper RVE's
//! converged tangent with the entries of some positions above the diagonal scaled, so
//! that it is no longer symmetric (the pattern stays structurally symmetric, as the
//! assembled ones are).
//!
//! `faer_lu_allocations` (ignored: it prints, it asserts nothing) counts the allocations
//! of faer's own LU factorizations after a warm-up, supernodal and simplicial, for
//! `docs/solver.md`: `cargo test --release --test lu_no_alloc -- --ignored --nocapture`.

mod common;
#[path = "common/counting_alloc.rs"]
mod counting_alloc;

use std::sync::Arc;

use counting_alloc::count_allocations;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, LuSymbolicParams, NumericLu};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par};
use mesorve_core::solver::{FactorKind, FactorMethod, LinearSolver, NumericFactor};
use rve::{Instance, Model, TangentRequest};

/// The model of `scene` and its tangent at `eps_xx = 1e-4`, made non-symmetric: the entry
/// `(i, j)` with `i < j` and `i + j` a multiple of 3 scaled by 1.3.
fn non_symmetric_tangent(scene: &str) -> (Arc<Model>, Vec<f64>) {
    let model = Arc::new(Model::from_scene(&common::scene(scene)).unwrap());
    let mut ws = model.workspace();
    let mut inst = Instance::new(model.clone());
    inst.update([1e-4, 0.0, 0.0], &mut ws, TangentRequest::Consistent)
        .unwrap();
    let pattern = &model.discretization().pattern.symbolic;
    let mut values = ws.tangent_values().to_vec();
    let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
    for j in 0..pattern.ncols() {
        for k in col_ptr[j]..col_ptr[j + 1] {
            if row_idx[k] < j && (row_idx[k] + j) % 3 == 0 {
                values[k] *= 1.3;
            }
        }
    }
    (model, values)
}

/// `||b - A x|| / ||b||` for `A` given by its pattern and values.
fn relative_residual(a: SparseColMatRef<'_, usize, f64>, x: &[f64], b: &[f64]) -> f64 {
    let mut r = b.to_vec();
    for (j, &xj) in x.iter().enumerate() {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            r[i] -= v * xj;
        }
    }
    let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
    norm(&r) / norm(b)
}

/// One `FactorMethod::Lu` factorization of `values` on `pattern` and one solve of `x` in
/// place: the kind of factorization.
fn lu_and_solve(
    solver: &LinearSolver,
    pattern: &SymbolicSparseColMat<usize>,
    values: &[f64],
    numeric: &mut NumericFactor,
    stack: &mut MemBuffer,
    x: &mut [f64],
) -> FactorKind {
    let kind = solver
        .factorize(
            pattern,
            values,
            numeric,
            FactorMethod::Lu,
            MemStack::new(stack),
        )
        .unwrap();
    solver.solve_in_place(numeric, x, 1, MemStack::new(stack));
    kind
}

#[test]
fn non_symmetric_factorization_and_solve_do_not_allocate() {
    let (model, values) = non_symmetric_tangent("scenes/paper_rve.toml");
    let pattern = &model.discretization().pattern.symbolic;
    let n = pattern.nrows();
    let b: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
    // The analysis a model with friction has (the paper's cell has none).
    let solver = &LinearSolver::for_non_symmetric(pattern, true).unwrap();
    let mut numeric = solver.numeric();
    let mut stack = MemBuffer::new(solver.scratch(4));
    let mut x = b.clone();
    let mut run = |x: &mut [f64]| {
        x.copy_from_slice(&b);
        lu_and_solve(solver, pattern, &values, &mut numeric, &mut stack, x)
    };
    assert_eq!(run(&mut x), FactorKind::Lu);
    let mut kind = None;
    let allocations = count_allocations(|| kind = Some(run(&mut x)));
    assert_eq!(kind, Some(FactorKind::Lu));
    assert_eq!(
        allocations, 0,
        "{allocations} allocations in an LU and its solve"
    );
    assert_eq!((numeric.static_lu_count, numeric.lu_count), (2, 0));
    let residual = relative_residual(SparseColMatRef::new(pattern.as_ref(), &values), &x, &b);
    assert!(residual < 1e-12, "relative residual {residual:e}");
}

/// Prints, per scene, the allocations of one factorization and solve after a warm-up with
/// `LinearSolver` (`FactorMethod::Lu`) and with faer's supernodal and simplicial LU.
#[test]
#[ignore = "a measurement for docs/solver.md, not a check: prints the allocation counts \
            (cargo test --release --test lu_no_alloc -- --ignored --nocapture)"]
fn faer_lu_allocations() {
    for scene in ["scenes/paper_rve.toml", "scenes/paper_rve_fine.toml"] {
        let (model, values) = non_symmetric_tangent(scene);
        let pattern = &model.discretization().pattern.symbolic;
        let n = pattern.nrows();
        let solver = &LinearSolver::for_non_symmetric(pattern, true).unwrap();
        let mut numeric = solver.numeric();
        let mut stack = MemBuffer::new(solver.scratch(1));
        let mut rhs = vec![1.0; n];
        let mut run = || {
            lu_and_solve(solver, pattern, &values, &mut numeric, &mut stack, &mut rhs);
        };
        run();
        let allocations = count_allocations(&mut run);
        println!(
            "{scene} ({n} unknowns): LinearSolver, FactorMethod::Lu: {allocations} allocations \
             (LU without pivoting accepted {} times, pivoted LU {})",
            numeric.static_lu_count, numeric.lu_count
        );
        for (name, threshold) in [
            ("supernodal", SupernodalThreshold::FORCE_SUPERNODAL),
            ("simplicial", SupernodalThreshold::FORCE_SIMPLICIAL),
        ] {
            let params = LuSymbolicParams {
                supernodal_flop_ratio_threshold: threshold,
                ..Default::default()
            };
            let symbolic = factorize_symbolic_lu(pattern.as_ref(), params).unwrap();
            let mut lu = NumericLu::new();
            let mut stack = MemBuffer::new(StackReq::any_of(&[
                symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()),
                symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
            ]));
            let a = SparseColMatRef::new(pattern.as_ref(), &values);
            let mut run = || {
                let factor_stack = MemStack::new(&mut stack);
                symbolic
                    .factorize_numeric_lu(&mut lu, a, Par::Seq, factor_stack, Default::default())
                    .unwrap();
                let x = MatMut::from_column_major_slice_mut(&mut rhs, n, 1);
                LuRef::new_unchecked(&symbolic, &lu).solve_in_place_with_conj(
                    Conj::No,
                    x,
                    Par::Seq,
                    MemStack::new(&mut stack),
                );
            };
            run();
            println!(
                "{scene} ({n} unknowns): faer {name} LU: {} allocations",
                count_allocations(&mut run)
            );
        }
    }
}

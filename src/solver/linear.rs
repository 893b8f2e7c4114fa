//! Sparse LU with partial pivoting (faer), symbolic analysis once per model.
//!
//! Why LU: after the peak of the cohesive law the RVE tangent is symmetric but indefinite,
//! and the minimal BC adds a saddle point. faer's LBL^T pivots only in its supernodal
//! variant and can return NaN silently on small simplicial problems (see TOOLCHAIN.md);
//! LU with partial pivoting is robust for all four BCs. The numeric factorization writes
//! into a reusable `NumericLu` and a preallocated stack: no allocation per iteration once
//! the buffers have grown to their size (first call).

use faer::dyn_stack::MemStack;
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::sparse::linalg::LuError;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par};

use crate::error::{Error, Result};

/// Symbolic LU analysis (COLAMD ordering) of the pattern: once per model.
pub fn symbolic_lu(pattern: &SymbolicSparseColMat<usize>) -> Result<SymbolicLu<usize>> {
    factorize_symbolic_lu(pattern.as_ref(), Default::default())
        .map_err(|e| Error::Mesh(format!("symbolic LU analysis failed: {e:?}")))
}

/// Numeric LU of the matrix with `values` on `pattern`, into `numeric`.
pub fn factorize(
    symbolic: &SymbolicLu<usize>,
    pattern: &SymbolicSparseColMat<usize>,
    values: &[f64],
    numeric: &mut NumericLu<usize, f64>,
    stack: &mut MemStack,
) -> std::result::Result<(), LuError> {
    let a = SparseColMatRef::new(pattern.as_ref(), values);
    symbolic
        .factorize_numeric_lu(numeric, a, Par::Seq, stack, Default::default())
        .map(|_| ())
}

/// Solves `A X = B` in place for `ncols` right-hand sides stored column-major in `rhs`,
/// with the factorization last written by [`factorize`].
pub fn solve_in_place(
    symbolic: &SymbolicLu<usize>,
    numeric: &NumericLu<usize, f64>,
    rhs: &mut [f64],
    ncols: usize,
    stack: &mut MemStack,
) {
    let n = rhs.len() / ncols;
    let lu = LuRef::new_unchecked(symbolic, numeric);
    let b = MatMut::from_column_major_slice_mut(rhs, n, ncols);
    lu.solve_in_place_with_conj(Conj::No, b, Par::Seq, stack);
}

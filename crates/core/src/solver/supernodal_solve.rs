//! Forward and back substitution with a supernodal LDL^T factor, one right-hand side at a
//! time, in plain loops.
//!
//! faer's `LdltRef::solve_in_place_with_conj` does the same arithmetic through its generic
//! dense kernels: a triangular solve and a matrix product per supernode and direction.
//! On the RVE tangents the supernodes are small (722 unknowns in 89 supernodes on the
//! paper RVE), so the kernels' dispatch costs more than their arithmetic; these loops do
//! the same operations in the same order per supernode (the sums in the products in
//! another order, so the results agree to round-off). Measured in `docs/solver.md`.
//!
//! With `P A P^T = L D L^T` (the fill-reducing permutation `P` of the analysis, `L` unit
//! lower triangular, stored per supernode as a dense column-major block: the diagonal
//! block, its unit diagonal holding `D`, above the rows of the supernode's pattern):
//! ```text
//! y = P b,   L z = y,   w = D^-1 z,   L^T v = w,   x = P^T v
//! ```

use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;

/// Scratch length [`solve_ldlt`] needs with the analysis `s`: the permuted column and the
/// longest supernode pattern.
pub(super) fn scratch_len(s: &SymbolicSupernodalCholesky<usize>) -> usize {
    let row_ptr = s.col_ptr_for_row_idx();
    let longest = (0..s.n_supernodes())
        .map(|k| row_ptr[k + 1] - row_ptr[k])
        .max()
        .unwrap_or(0);
    s.nrows() + longest
}

/// Solves `A x = b` in place for the `ncols` columns of `rhs` (column-major), one at a
/// time, with the LDL^T factor values `l` of the analysis `s` and its permutation `perm`.
/// `scratch` has at least [`scratch_len`] entries. Allocates nothing. (Substituting
/// several columns together, each block read once, is no faster: `docs/solver.md`.)
pub(super) fn solve_ldlt(
    s: &SymbolicSupernodalCholesky<usize>,
    perm: Option<PermRef<'_, usize>>,
    l: &[f64],
    rhs: &mut [f64],
    ncols: usize,
    scratch: &mut [f64],
) {
    let n = s.nrows();
    let (y, tmp) = scratch.split_at_mut(n);
    let arch = pulp::Arch::new();
    for b in rhs.chunks_exact_mut(n).take(ncols) {
        match perm {
            Some(p) => {
                let (forward, inverse) = p.arrays();
                for (yi, &f) in y.iter_mut().zip(forward) {
                    *yi = b[f];
                }
                arch.dispatch(Substitute { s, l, y, tmp });
                for (bi, &i) in b.iter_mut().zip(inverse) {
                    *bi = y[i];
                }
            }
            None => arch.dispatch(Substitute { s, l, y: b, tmp }),
        }
    }
}

/// [`substitute`] as a `pulp` operation: inlined into the dispatch, so that its loops are
/// compiled for the instruction set found at run time (AVX2/AVX-512), as faer's kernels.
struct Substitute<'a> {
    s: &'a SymbolicSupernodalCholesky<usize>,
    l: &'a [f64],
    y: &'a mut [f64],
    tmp: &'a mut [f64],
}

impl pulp::WithSimd for Substitute<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        substitute(self.s, self.l, self.y, self.tmp);
    }
}

/// `y = (L D L^T)^-1 y` in the permuted ordering.
#[inline(always)]
fn substitute(s: &SymbolicSupernodalCholesky<usize>, l: &[f64], y: &mut [f64], tmp: &mut [f64]) {
    let (begin, end) = (s.supernode_begin(), s.supernode_end());
    let (row_ptr, row_idx, value_ptr) = (s.col_ptr_for_row_idx(), s.row_idx(), s.col_ptr_for_val());
    let supernode = |k: usize| {
        let width = end[k] - begin[k];
        let pattern = &row_idx[row_ptr[k]..row_ptr[k + 1]];
        let block = &l[value_ptr[k]..value_ptr[k + 1]];
        (begin[k], width, width + pattern.len(), pattern, block)
    };
    // L z = y: the diagonal block, then the rows below it.
    for k in 0..s.n_supernodes() {
        let (first, width, rows, pattern, block) = supernode(k);
        let tmp = &mut tmp[..pattern.len()];
        tmp.fill(0.0);
        for j in 0..width {
            let column = &block[j * rows..(j + 1) * rows];
            let yj = y[first + j];
            for (yi, lij) in y[first + j + 1..first + width]
                .iter_mut()
                .zip(&column[j + 1..width])
            {
                *yi -= lij * yj;
            }
            for (t, lij) in tmp.iter_mut().zip(&column[width..]) {
                *t += lij * yj;
            }
        }
        for (t, &i) in tmp.iter().zip(pattern) {
            y[i] -= t;
        }
    }
    // w = D^-1 z.
    for k in 0..s.n_supernodes() {
        let (first, width, rows, _, block) = supernode(k);
        for j in 0..width {
            y[first + j] /= block[j * rows + j];
        }
    }
    // L^T v = w: the rows below the diagonal block, then the block.
    for k in (0..s.n_supernodes()).rev() {
        let (first, width, rows, pattern, block) = supernode(k);
        let tmp = &mut tmp[..pattern.len()];
        for (t, &i) in tmp.iter_mut().zip(pattern) {
            *t = y[i];
        }
        for j in (0..width).rev() {
            let column = &block[j * rows..(j + 1) * rows];
            let below = dot(&column[width..], tmp);
            let inside = dot(&column[j + 1..width], &y[first + j + 1..first + width]);
            y[first + j] -= below + inside;
        }
    }
}

/// `a . b` with four partial sums (lets the compiler vectorize it).
#[inline(always)]
pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let (a4, b4) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = a4
        .remainder()
        .iter()
        .zip(b4.remainder())
        .map(|(x, y)| x * y)
        .sum();
    let mut acc = [0.0; 4];
    for (x, y) in a4.zip(b4) {
        for i in 0..4 {
            acc[i] += x[i] * y[i];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

//! Supernodal LU without pivoting on a structure fixed once per pattern: the
//! allocation-free factorization of non-symmetric tangents.
//!
//! faer's sparse LU pivots by rows as it eliminates, so the structure of its factors is
//! only known during the numeric factorization, and it allocates that structure (and its
//! update buffers) at every call. Elimination in the diagonal order of a fill-reducing
//! symmetric permutation `P` instead has a structure known in advance: with `P A P^T = L U`
//! (`L` unit lower triangular, `U` upper triangular), the pattern of `L` is contained in
//! the Cholesky pattern of `P (A + A^T) P^T` and that of `U` in its transpose. The
//! analysis is faer's supernodal symbolic Cholesky (AMD ordering) of the pattern of
//! `A + A^T`; the numeric factorization fills buffers sized by it, once.
//!
//! Layout, per supernode of columns `[f, f + w)` with `r` pattern rows `R` below them
//! (faer's supernodal layout): two dense column-major `(w + r) x w` blocks.
//! - `l`: the diagonal block holds the `w x w` LU of the supernode's diagonal block (`L`
//!   strictly below the diagonal, `U` on and above it); below it, `L[R, f..f+w]`;
//! - `ut`: below the diagonal block, `U[f..f+w, R]^T` (its diagonal block is unused).
//!
//! Left-looking: supernode `s` receives the updates of every earlier supernode `d` whose
//! pattern meets its columns `C = [f_s, f_s + w_s)`. With `R_d^>=` the rows of `R_d` from
//! `f_s` on and `R_d^C` those inside `C`:
//! ```text
//! A[R_d^>=, R_d^C] -= L[R_d^>=, d] U[d, R_d^C]      (into l: its L part and diagonal block)
//! A[R_d^C, R_d^>]  -= L[R_d^C, d]  U[d, R_d^>]      (into ut, as U^T; R_d^> below C)
//! ```
//! then the diagonal block `A_11 = L_11 U_11` is factorized in place without pivoting,
//! `L_21 = A_21 U_11^-1` and `U_12 = L_11^-1 A_12`.
//!
//! Without pivoting, a zero pivot stops the factorization, and small pivots can grow the
//! factors' elements without bound: the caller checks the factors by a probe solve
//! (`sparse_direct`), as it does for LDL^T without pivoting, and falls back to faer's
//! pivoted LU when they fail.

use std::ops::Range;

use super::supernodal_solve::dot;

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_unit_lower_triangular_in_place,
};
use faer::perm::PermRef;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{Pair, SymbolicSparseColMat};
use faer::{Accum, MatMut, MatRef, Par, Side};

use crate::error::LinearAlgebraError;

/// Diagonal blocks up to this order are factorized in plain loops; larger ones are split
/// in two (a recursive blocked LU whose products run in faer's matrix kernels).
const BLOCK: usize = 32;

/// The analysis of one pattern: ordering, supernodes, where each entry of `A` goes and
/// which supernode updates which.
pub(super) struct StaticLu {
    symbolic: SymbolicCholesky<usize>,
    /// For each stored entry of `A`, its slot in [`StaticLuFactor`]'s values (`l` first,
    /// then `ut`).
    slots: Vec<usize>,
    /// The updates supernode `s` receives: `updates[update_ptr[s]..update_ptr[s + 1]]`.
    update_ptr: Vec<usize>,
    updates: Vec<Update>,
    /// Largest update product (entries).
    work_len: usize,
}

/// Supernode `from`'s pattern rows `[start, mid)` (positions in its pattern) lie in the
/// columns of the supernode it updates; the rows from `start` on are the update's rows.
#[derive(Clone, Copy)]
struct Update {
    from: usize,
    start: usize,
    mid: usize,
}

/// Numeric buffers of a [`StaticLu`], sized once.
pub(super) struct StaticLuFactor {
    /// `l` blocks, then `ut` blocks (module docs).
    values: Vec<f64>,
    /// Position of each global row in the supernode being factorized.
    local: Vec<usize>,
    /// An update product.
    work: Vec<f64>,
    /// Substitutions: the permuted column and a supernode's pattern rows.
    scratch: Vec<f64>,
}

/// One supernode: first column, width, rows of its blocks (`width + pattern.len()`), its
/// pattern rows and the range of its blocks in `l` (and in `ut`).
struct Block<'a> {
    first: usize,
    width: usize,
    rows: usize,
    pattern: &'a [usize],
    values: Range<usize>,
}

impl StaticLu {
    /// Analyses the square `pattern` (AMD on the pattern of `A + A^T`, supernodal).
    pub(super) fn new(pattern: &SymbolicSparseColMat<usize>) -> Result<Self, LinearAlgebraError> {
        let analysis = |reason: String| LinearAlgebraError::Analysis {
            factorization: "static-pivot LU",
            reason,
        };
        let n = pattern.nrows();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let mut lower = Vec::with_capacity(row_idx.len());
        for j in 0..n {
            for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
                lower.push(Pair {
                    row: i.max(j),
                    col: i.min(j),
                });
            }
        }
        let (lower, _) = SymbolicSparseColMat::try_new_from_indices(n, n, &lower)
            .map_err(|e| analysis(format!("{e:?}")))?;
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(
            lower.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            params,
        )
        .map_err(|e| analysis(format!("{e:?}")))?;
        if !matches!(symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_)) {
            return Err(analysis("not supernodal".into()));
        }
        let mut lu = StaticLu {
            symbolic,
            slots: Vec::new(),
            update_ptr: Vec::new(),
            updates: Vec::new(),
            work_len: 0,
        };
        lu.slots = lu.entry_slots(pattern);
        lu.find_updates();
        Ok(lu)
    }

    fn supernodal(&self) -> &SymbolicSupernodalCholesky<usize> {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => s,
            SymbolicCholeskyRaw::Simplicial(_) => unreachable!("StaticLu::new refuses it"),
        }
    }

    fn block(&self, k: usize) -> Block<'_> {
        let s = self.supernodal();
        let (row_ptr, value_ptr) = (s.col_ptr_for_row_idx(), s.col_ptr_for_val());
        let (first, width) = (
            s.supernode_begin()[k],
            s.supernode_end()[k] - s.supernode_begin()[k],
        );
        let pattern = &s.row_idx()[row_ptr[k]..row_ptr[k + 1]];
        Block {
            first,
            width,
            rows: width + pattern.len(),
            pattern,
            values: value_ptr[k]..value_ptr[k + 1],
        }
    }

    /// `(forward, inverse)` of the permutation `P`: new index `inverse[i]` of row `i`.
    fn perm_arrays(&self) -> Option<(&[usize], &[usize])> {
        self.symbolic.perm().map(|p: PermRef<'_, usize>| p.arrays())
    }

    /// Supernode of each permuted column.
    fn supernode_of_columns(&self) -> Vec<usize> {
        let s = self.supernodal();
        let mut of = vec![0; s.nrows()];
        for k in 0..s.n_supernodes() {
            of[s.supernode_begin()[k]..s.supernode_end()[k]].fill(k);
        }
        of
    }

    /// The slot of each entry `(i, j)` of `A`, at `(p, q) = (P i, P j)` of `P A P^T`: for
    /// `p >= q` in `l` (column `q`'s supernode), for `p < q` as `U^T` (row `p`'s
    /// supernode): in `l`'s diagonal block when `q` is one of its columns, else in `ut`.
    fn entry_slots(&self, pattern: &SymbolicSparseColMat<usize>) -> Vec<usize> {
        let n = pattern.nrows();
        let of = self.supernode_of_columns();
        let identity: Vec<usize>;
        let inverse = match self.perm_arrays() {
            Some((_, inverse)) => inverse,
            None => {
                identity = (0..n).collect();
                &identity
            }
        };
        let len = self.supernodal().len_val();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let mut slots = Vec::with_capacity(row_idx.len());
        for j in 0..n {
            for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
                let (p, q) = (inverse[i], inverse[j]);
                let (column, row) = (p.min(q), p.max(q));
                let b = self.block(of[column]);
                let local = if row < b.first + b.width {
                    row - b.first
                } else {
                    b.width + b.pattern.binary_search(&row).expect("row in the pattern")
                };
                let in_ut = p < q && local >= b.width;
                let slot = if p < q && !in_ut {
                    // U's entry (p, q) inside the diagonal block: row p, column q.
                    b.values.start + (q - b.first) * b.rows + (p - b.first)
                } else {
                    b.values.start + (column - b.first) * b.rows + local
                };
                slots.push(slot + if in_ut { len } else { 0 });
            }
        }
        slots
    }

    /// Lists, for each supernode, the updates it receives, and sizes the update buffer.
    fn find_updates(&mut self) {
        let count = self.supernodal().n_supernodes();
        let of = self.supernode_of_columns();
        let mut per_target: Vec<Vec<Update>> = vec![Vec::new(); count];
        let mut work_len = 0;
        for from in 0..count {
            let pattern = self.block(from).pattern;
            let mut start = 0;
            while start < pattern.len() {
                let target = of[pattern[start]];
                let end = self.block(target).first + self.block(target).width;
                let mid = start + pattern[start..].partition_point(|&r| r < end);
                per_target[target].push(Update { from, start, mid });
                work_len = work_len.max((pattern.len() - start) * (mid - start));
                start = mid;
            }
        }
        self.update_ptr = std::iter::once(0)
            .chain(per_target.iter().scan(0, |total, u| {
                *total += u.len();
                Some(*total)
            }))
            .collect();
        self.updates = per_target.into_iter().flatten().collect();
        self.work_len = work_len;
    }

    /// Empty numeric buffers, of their final size.
    pub(super) fn numeric(&self) -> StaticLuFactor {
        let s = self.supernodal();
        let longest = (0..s.n_supernodes())
            .map(|k| self.block(k).pattern.len())
            .max()
            .unwrap_or(0);
        StaticLuFactor {
            values: vec![0.0; 2 * s.len_val()],
            local: vec![0; s.nrows()],
            work: vec![0.0; self.work_len],
            scratch: vec![0.0; s.nrows() + longest],
        }
    }

    /// Factorizes `P A P^T = L U` for the values `a` of `A` (on the pattern analysed) into
    /// `f`. False on a zero or non-finite pivot. Allocates nothing.
    pub(super) fn factorize(&self, a: &[f64], f: &mut StaticLuFactor) -> bool {
        f.values.fill(0.0);
        for (&slot, &v) in self.slots.iter().zip(a) {
            f.values[slot] += v;
        }
        let (l, ut) = f.values.split_at_mut(self.supernodal().len_val());
        for k in 0..self.supernodal().n_supernodes() {
            let b = self.block(k);
            for j in 0..b.width {
                f.local[b.first + j] = j;
            }
            for (i, &row) in b.pattern.iter().enumerate() {
                f.local[row] = b.width + i;
            }
            for u in &self.updates[self.update_ptr[k]..self.update_ptr[k + 1]] {
                self.apply_update(*u, &b, l, ut, &f.local, &mut f.work);
            }
            if !factorize_supernode(&b, l, ut) {
                return false;
            }
        }
        true
    }

    /// Subtracts supernode `u.from`'s contribution from the blocks of `target` (module
    /// docs): the two products `L[R^>=, d] U[d, R^C]` and `U[d, R^>]^T L[R^C, d]^T`, each
    /// computed densely into `work` and scattered through `local`.
    fn apply_update(
        &self,
        u: Update,
        target: &Block<'_>,
        l: &mut [f64],
        ut: &mut [f64],
        local: &[usize],
        work: &mut [f64],
    ) {
        let d = self.block(u.from);
        let (l_done, l_target) = l.split_at_mut(target.values.start);
        let (ut_done, ut_target) = ut.split_at_mut(target.values.start);
        let ld = MatRef::from_column_major_slice(&l_done[d.values.clone()], d.rows, d.width);
        let utd = MatRef::from_column_major_slice(&ut_done[d.values.clone()], d.rows, d.width);
        let (start, mid) = (d.width + u.start, d.width + u.mid);
        let columns = &d.pattern[u.start..u.mid];
        for (into_ut, from, with) in [(false, ld, utd), (true, utd, ld)] {
            let first = if into_ut { mid } else { start };
            let rows = &d.pattern[first - d.width..];
            let m = rows.len();
            if m == 0 {
                continue;
            }
            let product = &mut work[..m * columns.len()];
            let (lhs, rhs) = (from.subrows(first, m), with.subrows(start, columns.len()));
            matmul(
                MatMut::from_column_major_slice_mut(product, m, columns.len()),
                Accum::Replace,
                lhs,
                rhs.transpose(),
                1.0,
                Par::Seq,
            );
            let dest = if into_ut {
                &mut *ut_target
            } else {
                &mut *l_target
            };
            for (&c, product) in columns.iter().zip(product.chunks_exact(m)) {
                let column = &mut dest[(c - target.first) * target.rows..][..target.rows];
                for (&row, p) in rows.iter().zip(product) {
                    column[local[row]] -= p;
                }
            }
        }
    }

    /// Solves `A x = b` in place for the `ncols` columns of `rhs` (column-major) with the
    /// factors in `f`:
    /// ```text
    /// y = P b,   L z = y,   U v = z,   x = P^T v
    /// ```
    pub(super) fn solve(&self, f: &mut StaticLuFactor, rhs: &mut [f64], ncols: usize) {
        let n = self.supernodal().nrows();
        let (l, ut) = f.values.split_at(self.supernodal().len_val());
        let (y, tmp) = f.scratch.split_at_mut(n);
        let arch = pulp::Arch::new();
        for b in rhs.chunks_exact_mut(n).take(ncols) {
            match self.perm_arrays() {
                Some((forward, inverse)) => {
                    for (yi, &i) in y.iter_mut().zip(forward) {
                        *yi = b[i];
                    }
                    arch.dispatch(Substitute {
                        lu: self,
                        l,
                        ut,
                        y,
                        tmp,
                    });
                    for (bi, &i) in b.iter_mut().zip(inverse) {
                        *bi = y[i];
                    }
                }
                None => arch.dispatch(Substitute {
                    lu: self,
                    l,
                    ut,
                    y: b,
                    tmp,
                }),
            }
        }
    }
}

/// Factorizes supernode `b`'s updated blocks: the diagonal block in place, then
/// `L_21 = A_21 U_11^-1` (as `U_11^T L_21^T = A_21^T`) and `U_12 = L_11^-1 A_12` (on `ut`'s
/// `U_12^T`). False on a zero or non-finite pivot.
fn factorize_supernode(b: &Block<'_>, l: &mut [f64], ut: &mut [f64]) -> bool {
    let block = MatMut::from_column_major_slice_mut(&mut l[b.values.clone()], b.rows, b.width);
    let (mut diagonal, below) = block.split_at_row_mut(b.width);
    if !lu_in_place(diagonal.rb_mut()) {
        return false;
    }
    let diagonal = diagonal.rb();
    solve_lower_triangular_in_place(diagonal.transpose(), below.transpose_mut(), Par::Seq);
    let right = MatMut::from_column_major_slice_mut(&mut ut[b.values.clone()], b.rows, b.width);
    let (_, right) = right.split_at_row_mut(b.width);
    solve_unit_lower_triangular_in_place(diagonal, right.transpose_mut(), Par::Seq);
    true
}

/// Dense LU without pivoting of the square `a` in place (`L` unit lower below the
/// diagonal, `U` on and above it), recursively:
/// ```text
/// [A_11 A_12]   [L_11    0] [U_11 U_12]
/// [A_21 A_22] = [L_21 L_22] [   0 U_22],  U_12 = L_11^-1 A_12,  L_21 = A_21 U_11^-1,
/// L_22 U_22 = A_22 - L_21 U_12.
/// ```
/// False on a zero or non-finite pivot.
fn lu_in_place(mut a: MatMut<'_, f64>) -> bool {
    let n = a.nrows();
    if n <= BLOCK {
        for k in 0..n {
            let pivot = a[(k, k)];
            if pivot == 0.0 || !pivot.is_finite() {
                return false;
            }
            for i in k + 1..n {
                a[(i, k)] /= pivot;
            }
            for j in k + 1..n {
                let ukj = a[(k, j)];
                for i in k + 1..n {
                    let lik = a[(i, k)];
                    a[(i, j)] -= lik * ukj;
                }
            }
        }
        return true;
    }
    let h = n / 2;
    let (mut a11, mut a12, mut a21, a22) = a.rb_mut().split_at_mut(h, h);
    if !lu_in_place(a11.rb_mut()) {
        return false;
    }
    solve_unit_lower_triangular_in_place(a11.rb(), a12.rb_mut(), Par::Seq);
    solve_lower_triangular_in_place(a11.rb().transpose(), a21.rb_mut().transpose_mut(), Par::Seq);
    let mut a22 = a22;
    matmul(a22.rb_mut(), Accum::Add, a21.rb(), a12.rb(), -1.0, Par::Seq);
    lu_in_place(a22)
}

/// [`substitute`] as a `pulp` operation, compiled for the instruction set found at run
/// time (as `supernodal_solve`'s LDL^T substitutions).
struct Substitute<'a> {
    lu: &'a StaticLu,
    l: &'a [f64],
    ut: &'a [f64],
    y: &'a mut [f64],
    tmp: &'a mut [f64],
}

impl pulp::WithSimd for Substitute<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        substitute(self.lu, self.l, self.ut, self.y, self.tmp);
    }
}

/// `y = (L U)^-1 y` in the permuted ordering: `L z = y` supernode by supernode (the
/// diagonal block, then the pattern rows below it), then `U v = z` backwards (the pattern
/// columns right of the diagonal block, then the block).
#[inline(always)]
fn substitute(lu: &StaticLu, l: &[f64], ut: &[f64], y: &mut [f64], tmp: &mut [f64]) {
    let count = lu.supernodal().n_supernodes();
    for k in 0..count {
        let b = lu.block(k);
        let (block, f, w) = (&l[b.values.clone()], b.first, b.width);
        let tmp = &mut tmp[..b.pattern.len()];
        tmp.fill(0.0);
        for j in 0..w {
            let column = &block[j * b.rows..(j + 1) * b.rows];
            let yj = y[f + j];
            for (yi, lij) in y[f + j + 1..f + w].iter_mut().zip(&column[j + 1..w]) {
                *yi -= lij * yj;
            }
            for (t, lij) in tmp.iter_mut().zip(&column[w..]) {
                *t += lij * yj;
            }
        }
        for (t, &i) in tmp.iter().zip(b.pattern) {
            y[i] -= t;
        }
    }
    for k in (0..count).rev() {
        let b = lu.block(k);
        let (block, f, w) = (&l[b.values.clone()], b.first, b.width);
        let right = &ut[b.values.clone()];
        let tmp = &mut tmp[..b.pattern.len()];
        for (t, &i) in tmp.iter_mut().zip(b.pattern) {
            *t = y[i];
        }
        for j in 0..w {
            y[f + j] -= dot(&right[j * b.rows + w..(j + 1) * b.rows], tmp);
        }
        for j in (0..w).rev() {
            let column = &block[j * b.rows..j * b.rows + w];
            y[f + j] /= column[j];
            let yj = y[f + j];
            for (yi, uij) in y[f..f + j].iter_mut().zip(&column[..j]) {
                *yi -= uij * yj;
            }
        }
    }
}

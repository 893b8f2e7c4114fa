//! Sparse direct solves with faer: LDL^T without pivoting first, then a pivoted symmetric
//! indefinite LBL^T, both checked by a probe solve when the matrix is indefinite, then LU
//! with partial pivoting. Symbolic analyses once per model; numeric factors in reusable
//! buffers.
//!
//! Why this chain: before the peak of the cohesive law, on unloading and in contact, the
//! RVE tangent is symmetric positive definite; after the peak it can be indefinite, and
//! the minimal BC is a saddle point. The first try is faer's supernodal LDL^T on the AMD
//! analysis, with no pivoting: the cost of LL^T. When every pivot `d_i` is positive the
//! matrix is positive definite and the factorization is LL^T's up to the scaling
//! `L D^1/2`, as stable; it is accepted as it is. When some pivot is negative, the factors
//! still solve the system exactly in exact arithmetic (no zero pivot), but elimination
//! without pivoting can grow elements, so the factors are *checked*: a probe `b = A p`
//! with a fixed vector `p` is solved with them, and they are kept only if the residual
//! `||b - A p^||` is below [`PROBE_TOLERANCE`] `||b||` (cost: one product and one solve).
//! Past the peak this replaces an LL^T that ran until its first negative pivot and then
//! an LBL^T (measured in `docs/solver.md`).
//!
//! The next try is faer's intranode LBL^T (Bunch-Kaufman pivoting inside each supernode),
//! on the same analysis, forced supernodal (a simplicial LBL^T does not pivot and can
//! return NaN silently). Pivoting limited to a supernode is not backward stable in
//! general either, and it reports nothing, so it is checked by the same probe.
//!
//! LU (COLAMD, partial pivoting) is the last resort, robust for any regular matrix. The
//! numeric factorizations write into buffers that keep their size between calls: no
//! allocation per iteration once they have grown (first call), except inside faer's
//! supernodal LU.
//!
//! A non-symmetric matrix ([`FactorMethod::Lu`]) is factorized first by the supernodal LU
//! without pivoting of `super::lu`, on a structure fixed by an analysis of the pattern of
//! `A + A^T` (AMD): its buffers are sized once, so it allocates nothing, and its
//! arithmetic is twice an LDL^T's. Without pivoting it is checked by the same probe
//! solve as the indefinite LDL^T; when the probe fails, or a pivot is zero, faer's
//! pivoted LU takes over (and allocates). `NumericFactor::static_lu_count` and
//! `lu_count` count the two.
//!
//! LDL^T and LBL^T call faer's supernodal numeric kernels directly, on the lower triangle
//! of the AMD-permuted matrix, gathered through a map computed once per model
//! ([`PermutedLower`]): faer's `SymbolicCholesky::factorize_numeric_*` would permute the
//! matrix again at every factorization (a counting sort of the whole pattern). The gather
//! takes the same entries faer's permutation takes (the original lower triangle), so the
//! factors are bit-identical. Timings of the chain are in `docs/solver.md`.

use faer::dyn_stack::{MemStack, StackReq};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::supernodal::{self, SymbolicSupernodalCholesky};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, IntranodeLbltRef, LdltRef,
    SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

use super::lu::{StaticLu, StaticLuFactor};
use super::supernodal_solve;
use crate::error::{LinearAlgebraError, Result};

/// Which factorization a `NumericFactor` holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FactorKind {
    /// LDL^T without pivoting, every pivot positive: the matrix is positive definite.
    Ldlt,
    /// LDL^T without pivoting with negative pivots, checked by a probe solve.
    LdltIndefinite,
    /// Symmetric indefinite, pivoted within supernodes, checked by a probe solve.
    Lblt,
    /// LU: with [`FactorMethod::Lu`] the LU without pivoting on the fixed structure
    /// (`super::lu`), checked by a probe solve, else faer's LU with partial pivoting
    /// (`NumericFactor::static_lu_count` and `lu_count` tell which).
    Lu,
}

/// Largest relative residual `||b - A p^|| / ||b||` of the probe solve that accepts an
/// indefinite LDL^T or LBL^T factorization. A backward-stable solve leaves a residual of
/// a small multiple of the unit round-off whatever the conditioning (4e-15 to 5e-14
/// measured on the paper RVEs past the peak); element growth in an elimination not
/// pivoted, or pivoted only within supernodes, shows as far more.
pub const PROBE_TOLERANCE: f64 = 1e-10;

/// Numeric factors, per workspace.
pub struct NumericFactor {
    lu: NumericLu<usize, f64>,
    /// Factors of the LU without pivoting (`None` for an empty system).
    static_lu: Option<StaticLuFactor>,
    /// Whether an LU factorization is in `static_lu` rather than in `lu`.
    static_lu_current: bool,
    /// LDL^T or LBL^T factor values (same symbolic structure).
    l_values: Vec<f64>,
    /// The matrix's values on [`PermutedLower`]'s pattern, the kernels' input.
    permuted_values: Vec<f64>,
    /// LBL^T: subdiagonal of the block diagonal `B` and the pivoting permutation.
    lblt_subdiag: Vec<f64>,
    lblt_perm: Vec<usize>,
    lblt_perm_inv: Vec<usize>,
    /// Probe vector and its image for checking an indefinite factorization.
    probe: Vec<f64>,
    probe_image: Vec<f64>,
    /// Scratch of the LDL^T substitutions (`supernodal_solve`).
    solve_scratch: Vec<f64>,
    /// What the last successful factorization was, if any.
    pub current: Option<FactorKind>,
    /// Numeric factorizations of any kind done with these buffers so far (an LDL^T that
    /// fails its check is part of the LBL^T or LU that follows it).
    pub count: u64,
    /// faer's LU factorizations with partial pivoting done with these buffers so far: the
    /// last resort of [`FactorMethod::SymmetricFirst`], and of [`FactorMethod::Lu`] when
    /// the LU without pivoting fails its check. faer's supernodal LU allocates internally
    /// (every other factorization here does not), so this counts the factorizations that
    /// left the allocation-free path.
    pub lu_count: u64,
    /// LU factorizations without pivoting ([`FactorMethod::Lu`]) accepted by the probe
    /// check so far; they allocate nothing.
    pub static_lu_count: u64,
    /// Indefinite LDL^T factorizations accepted by the probe check so far.
    pub indefinite_ldlt_count: u64,
    /// LBL^T factorizations accepted by the probe check so far.
    pub lblt_count: u64,
    /// Solves done with these buffers so far, by number of right-hand sides
    /// (`solves[k]`, k = 1..=4; wider solves count in `solves[4]`): the solve work of an
    /// update, for `benches/solver.rs`'s cost model.
    pub solves: [u64; 5],
}

/// How [`LinearSolver::factorize`] factorizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FactorMethod {
    /// LDL^T first (when the pattern allows it), then LBL^T, then LU.
    SymmetricFirst,
    /// LU only, for a matrix that may be non-symmetric: the LU without pivoting, checked,
    /// then faer's LU with partial pivoting.
    Lu,
}

/// Symbolic analyses of one pattern, shared by every instance of a model.
pub struct LinearSolver {
    lu: SymbolicLu<usize>,
    /// The analysis of the LU without pivoting (`None` for an empty system).
    static_lu: Option<StaticLu>,
    /// `None` when the system can never be positive definite (minimal BC multipliers).
    /// The symmetric analysis that LDL^T and LBL^T share.
    symmetric: Option<SymmetricAnalysis>,
}

/// The LDL^T / LBL^T analysis: AMD ordering and supernodal structure, and where the
/// permuted lower triangle the numeric kernels read comes from.
struct SymmetricAnalysis {
    symbolic: SymbolicCholesky<usize>,
    permuted: PermutedLower,
}

impl SymmetricAnalysis {
    fn supernodal(&self) -> &SymbolicSupernodalCholesky<usize> {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => s,
            SymbolicCholeskyRaw::Simplicial(_) => {
                unreachable!("LinearSolver::new refuses a simplicial analysis")
            }
        }
    }

    /// Solves `A x = b` in place for the `ncols` columns of `rhs` with the LDL^T factor
    /// values `l` of this analysis, in the plain loops of `supernodal_solve`.
    fn solve_ldlt(&self, l: &[f64], rhs: &mut [f64], ncols: usize, scratch: &mut [f64]) {
        supernodal_solve::solve_ldlt(
            self.supernodal(),
            self.symbolic.perm(),
            l,
            rhs,
            ncols,
            scratch,
        );
    }
}

/// The lower triangle of `P A P^T` for the fill-reducing permutation `P` of the symmetric
/// analysis, as a pattern with sorted rows, and for each of its entries the index of the
/// value of `A` (full pattern, both triangles) it takes: entry `(i, j)` of `A` with
/// `i >= j` goes to `(max(p_i, p_j), min(p_i, p_j))`, as in faer's own permutation.
struct PermutedLower {
    pattern: SymbolicSparseColMat<usize>,
    source: Vec<usize>,
}

impl PermutedLower {
    fn new(a: &SymbolicSparseColMat<usize>, inverse: &[usize]) -> Self {
        let n = a.nrows();
        let (col_ptr, row_idx) = (a.col_ptr(), a.row_idx());
        let mut entries = Vec::new();
        for j in 0..n {
            let column = col_ptr[j]..col_ptr[j + 1];
            for (k, &i) in column.clone().zip(&row_idx[column]) {
                if i >= j {
                    let (pi, pj) = (inverse[i], inverse[j]);
                    entries.push((pi.min(pj), pi.max(pj), k));
                }
            }
        }
        entries.sort_unstable();
        let mut new_col_ptr = vec![0usize; n + 1];
        for &(col, _, _) in &entries {
            new_col_ptr[col + 1] += 1;
        }
        for j in 0..n {
            new_col_ptr[j + 1] += new_col_ptr[j];
        }
        let new_row_idx = entries.iter().map(|e| e.1).collect();
        let source = entries.iter().map(|e| e.2).collect();
        let pattern = SymbolicSparseColMat::new_checked(n, n, new_col_ptr, None, new_row_idx);
        PermutedLower { pattern, source }
    }

    /// Gathers `values` (on `A`'s pattern) into `out` (on the permuted lower pattern).
    fn gather(&self, values: &[f64], out: &mut [f64]) {
        for (o, &s) in out.iter_mut().zip(&self.source) {
            *o = values[s];
        }
    }
}

impl LinearSolver {
    /// Analyses `pattern` (COLAMD for LU, AMD for LDL^T). `spd_possible` is false for
    /// saddle-point systems. Without the analysis of [`LinearSolver::for_non_symmetric`],
    /// [`FactorMethod::Lu`] is faer's pivoted LU.
    pub fn new(pattern: &SymbolicSparseColMat<usize>, spd_possible: bool) -> Result<Self> {
        let mut solver = Self::analysed(pattern, spd_possible)?;
        solver.static_lu = None;
        Ok(solver)
    }

    /// [`LinearSolver::new`] for a model whose matrices may be non-symmetric (friction):
    /// also the structure of the allocation-free LU of `lu.rs`, whose buffers every
    /// workspace then holds.
    pub fn for_non_symmetric(
        pattern: &SymbolicSparseColMat<usize>,
        spd_possible: bool,
    ) -> Result<Self> {
        Self::analysed(pattern, spd_possible)
    }

    fn analysed(pattern: &SymbolicSparseColMat<usize>, spd_possible: bool) -> Result<Self> {
        // faer's pivoted LU, the last resort: supernodal where faer chooses it. Simplicial
        // LU would allocate nothing once its buffers hold the largest fill met, but is
        // much slower on these patterns (`docs/solver.md`).
        let lu = factorize_symbolic_lu(pattern.as_ref(), Default::default()).map_err(|e| {
            LinearAlgebraError::Analysis {
                factorization: "LU",
                reason: format!("{e:?}"),
            }
        })?;
        let static_lu = match pattern.nrows() {
            0 => None,
            _ => Some(StaticLu::new(pattern)?),
        };
        let symmetric = if spd_possible && pattern.nrows() > 0 {
            let symbolic = factorize_symbolic_cholesky(
                pattern.as_ref(),
                Side::Lower,
                SymmetricOrdering::Amd,
                CholeskySymbolicParams {
                    // Supernodal beats simplicial from the paper RVE's size up
                    // (`docs/solver.md`).
                    supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                    ..Default::default()
                },
            )
            .map_err(|e| LinearAlgebraError::Analysis {
                factorization: "Cholesky",
                reason: format!("{e:?}"),
            })?;
            // The numeric kernels called below are the supernodal ones.
            if !matches!(symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_)) {
                return Err(LinearAlgebraError::Analysis {
                    factorization: "Cholesky",
                    reason: "not supernodal".into(),
                }
                .into());
            }
            let identity: Vec<usize>;
            let inverse = match symbolic.perm() {
                Some(perm) => perm.arrays().1,
                None => {
                    identity = (0..pattern.nrows()).collect();
                    &identity[..]
                }
            };
            let permuted = PermutedLower::new(pattern, inverse);
            Some(SymmetricAnalysis { symbolic, permuted })
        } else {
            None
        };
        Ok(LinearSolver {
            lu,
            static_lu,
            symmetric,
        })
    }

    /// Empty numeric buffers for this solver.
    pub fn numeric(&self) -> NumericFactor {
        let n = self.lu.nrows();
        NumericFactor {
            lu: NumericLu::new(),
            static_lu: self.static_lu.as_ref().map(StaticLu::numeric),
            static_lu_current: false,
            l_values: vec![0.0; self.symmetric.as_ref().map_or(0, |c| c.symbolic.len_val())],
            permuted_values: vec![
                0.0;
                self.symmetric
                    .as_ref()
                    .map_or(0, |c| c.permuted.source.len())
            ],
            lblt_subdiag: vec![0.0; n],
            lblt_perm: vec![0; n],
            lblt_perm_inv: vec![0; n],
            probe: vec![0.0; n],
            probe_image: vec![0.0; n],
            solve_scratch: vec![
                0.0;
                self.symmetric
                    .as_ref()
                    .map_or(0, |c| supernodal_solve::scratch_len(c.supernodal()))
            ],
            current: None,
            count: 0,
            lu_count: 0,
            static_lu_count: 0,
            indefinite_ldlt_count: 0,
            lblt_count: 0,
            solves: [0; 5],
        }
    }

    /// Scratch memory for a factorization and a solve with `ncols` right-hand sides.
    pub fn scratch(&self, ncols: usize) -> StackReq {
        let mut reqs = vec![
            self.lu
                .factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()),
            self.lu.solve_in_place_scratch::<f64>(ncols, Par::Seq),
        ];
        if let Some(c) = &self.symmetric {
            let s = c.supernodal();
            reqs.push(supernodal::factorize_supernodal_numeric_ldlt_scratch::<
                usize,
                f64,
            >(s, Par::Seq, Default::default()));
            reqs.push(
                supernodal::factorize_supernodal_numeric_intranode_lblt_scratch::<usize, f64>(
                    s,
                    Par::Seq,
                    Default::default(),
                ),
            );
            reqs.push(c.symbolic.solve_in_place_scratch::<f64>(ncols, Par::Seq));
        }
        StackReq::any_of(&reqs)
    }

    /// Factorizes the matrix with `values` on `pattern`: with
    /// [`FactorMethod::SymmetricFirst`] LDL^T (accepted at once if positive definite, else
    /// checked), else a checked LBL^T, else LU with partial pivoting; with
    /// [`FactorMethod::Lu`] the checked LU without pivoting, else LU with partial pivoting.
    /// Returns the kind used.
    pub fn factorize(
        &self,
        pattern: &SymbolicSparseColMat<usize>,
        values: &[f64],
        numeric: &mut NumericFactor,
        method: FactorMethod,
        stack: &mut MemStack,
    ) -> std::result::Result<FactorKind, LinearAlgebraError> {
        numeric.current = None;
        numeric.static_lu_current = false;
        numeric.count += 1;
        let a = SparseColMatRef::new(pattern.as_ref(), values);
        if let (FactorMethod::SymmetricFirst, Some(c)) = (method, &self.symmetric) {
            c.permuted.gather(values, &mut numeric.permuted_values);
            if let Some(kind) = Self::ldlt(c, a, numeric, stack) {
                if kind == FactorKind::LdltIndefinite {
                    numeric.indefinite_ldlt_count += 1;
                }
                numeric.current = Some(kind);
                return Ok(kind);
            }
            if Self::lblt_checked(c, a, numeric, stack) {
                numeric.current = Some(FactorKind::Lblt);
                numeric.lblt_count += 1;
                return Ok(FactorKind::Lblt);
            }
        }
        if method == FactorMethod::Lu && self.static_lu_checked(a, numeric, stack) {
            numeric.current = Some(FactorKind::Lu);
            numeric.static_lu_current = true;
            numeric.static_lu_count += 1;
            return Ok(FactorKind::Lu);
        }
        self.lu
            .factorize_numeric_lu(&mut numeric.lu, a, Par::Seq, stack, Default::default())
            .map_err(|e| LinearAlgebraError::Numeric {
                reason: format!("{e:?}"),
            })?;
        numeric.current = Some(FactorKind::Lu);
        numeric.lu_count += 1;
        Ok(FactorKind::Lu)
    }

    /// LDL^T without pivoting of `a` (gathered into `numeric.permuted_values`): `Ldlt` if
    /// every pivot is positive, `LdltIndefinite` if some is negative and the probe solve
    /// is accurate, `None` on a zero pivot or a failed probe.
    fn ldlt(
        c: &SymmetricAnalysis,
        a: SparseColMatRef<'_, usize, f64>,
        numeric: &mut NumericFactor,
        stack: &mut MemStack,
    ) -> Option<FactorKind> {
        let lower = SparseColMatRef::new(c.permuted.pattern.as_ref(), &numeric.permuted_values);
        supernodal::factorize_supernodal_numeric_ldlt(
            &mut numeric.l_values,
            lower,
            Default::default(),
            c.supernodal(),
            Par::Seq,
            stack,
            Default::default(),
        )
        .ok()?;
        match pivot_signs(c.supernodal(), &numeric.l_values) {
            PivotSigns::Positive => Some(FactorKind::Ldlt),
            PivotSigns::Indefinite => {
                let (l, scratch) = (&numeric.l_values, &mut numeric.solve_scratch);
                let accurate = probe_solve_is_accurate(
                    a,
                    &mut numeric.probe,
                    &mut numeric.probe_image,
                    |rhs, _| c.solve_ldlt(l, rhs, 1, scratch),
                    stack,
                );
                accurate.then_some(FactorKind::LdltIndefinite)
            }
            PivotSigns::Singular => None,
        }
    }

    /// LU without pivoting of `a` into `numeric.static_lu`, accepted only if no pivot is
    /// zero and a probe solve is accurate (see the module docs).
    fn static_lu_checked(
        &self,
        a: SparseColMatRef<'_, usize, f64>,
        numeric: &mut NumericFactor,
        stack: &mut MemStack,
    ) -> bool {
        let (Some(lu), Some(factor)) = (&self.static_lu, &mut numeric.static_lu) else {
            return false;
        };
        if !lu.factorize(a.val(), factor) {
            return false;
        }
        probe_solve_is_accurate(
            a,
            &mut numeric.probe,
            &mut numeric.probe_image,
            |rhs, _| lu.solve(factor, rhs, 1),
            stack,
        )
    }

    /// Intranode LBL^T of `a` into `numeric`, accepted only if a probe solve is accurate
    /// (see the module docs).
    fn lblt_checked(
        c: &SymmetricAnalysis,
        a: SparseColMatRef<'_, usize, f64>,
        numeric: &mut NumericFactor,
        stack: &mut MemStack,
    ) -> bool {
        let n = a.nrows();
        // `numeric.permuted_values` still holds the gather of the refused LDL^T.
        let lower = SparseColMatRef::new(c.permuted.pattern.as_ref(), &numeric.permuted_values);
        supernodal::factorize_supernodal_numeric_intranode_lblt(
            &mut numeric.l_values,
            &mut numeric.lblt_subdiag,
            &mut numeric.lblt_perm,
            &mut numeric.lblt_perm_inv,
            lower,
            c.supernodal(),
            Par::Seq,
            stack,
            Default::default(),
        );
        let factor = IntranodeLbltRef::new(
            &c.symbolic,
            &numeric.l_values,
            &numeric.lblt_subdiag,
            PermRef::new_checked(&numeric.lblt_perm, &numeric.lblt_perm_inv, n),
        );
        probe_solve_is_accurate(
            a,
            &mut numeric.probe,
            &mut numeric.probe_image,
            |rhs, stack| {
                let rhs = MatMut::from_column_major_slice_mut(rhs, n, 1);
                factor.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, stack)
            },
            stack,
        )
    }

    /// Solves in place for `ncols` right-hand sides stored column-major in `rhs`, with the
    /// last factorization. Does nothing if there is none (callers check `current`).
    pub fn solve_in_place(
        &self,
        numeric: &mut NumericFactor,
        rhs: &mut [f64],
        ncols: usize,
        stack: &mut MemStack,
    ) {
        let n = rhs.len() / ncols.max(1);
        if numeric.current.is_some() {
            numeric.solves[ncols.min(4)] += 1;
        }
        let ldlt = matches!(
            numeric.current,
            Some(FactorKind::Ldlt | FactorKind::LdltIndefinite)
        );
        if let (Some(FactorKind::Lu), true) = (numeric.current, numeric.static_lu_current) {
            if let (Some(lu), Some(factor)) = (&self.static_lu, &mut numeric.static_lu) {
                lu.solve(factor, rhs, ncols);
            }
            return;
        }
        if let (true, 1, Some(c)) = (ldlt, ncols, &self.symmetric) {
            // One column: plain loops (`supernodal_solve`); faer's kernels pay off from
            // three columns on (measured in docs/solver.md).
            let (l, scratch) = (&numeric.l_values, &mut numeric.solve_scratch);
            c.solve_ldlt(l, rhs, 1, scratch);
            return;
        }
        let b = MatMut::from_column_major_slice_mut(rhs, n, ncols);
        match (numeric.current, &self.symmetric) {
            (Some(FactorKind::Ldlt | FactorKind::LdltIndefinite), Some(c)) => LdltRef::new(
                &c.symbolic,
                &numeric.l_values,
            )
            .solve_in_place_with_conj(Conj::No, b, Par::Seq, stack),
            (Some(FactorKind::Lblt), Some(c)) => IntranodeLbltRef::new(
                &c.symbolic,
                &numeric.l_values,
                &numeric.lblt_subdiag,
                PermRef::new_checked(&numeric.lblt_perm, &numeric.lblt_perm_inv, b.nrows()),
            )
            .solve_in_place_with_conj(Conj::No, b, Par::Seq, stack),
            (Some(FactorKind::Lu), _) => LuRef::new_unchecked(&self.lu, &numeric.lu)
                .solve_in_place_with_conj(Conj::No, b, Par::Seq, stack),
            _ => {}
        }
    }
}

/// The signs of the pivots `d_i` of a supernodal LDL^T.
#[derive(Debug, PartialEq, Eq)]
enum PivotSigns {
    Positive,
    /// Some pivot negative, none zero or not finite.
    Indefinite,
    /// Some pivot zero or not finite.
    Singular,
}

/// Reads the pivots of the LDL^T factor `l` (each supernode's diagonal block is unit lower
/// triangular with `D` stored on its diagonal).
fn pivot_signs(s: &SymbolicSupernodalCholesky<usize>, l: &[f64]) -> PivotSigns {
    let (begin, end, value_ptr) = (s.supernode_begin(), s.supernode_end(), s.col_ptr_for_val());
    let mut signs = PivotSigns::Positive;
    for k in 0..s.n_supernodes() {
        let width = end[k] - begin[k];
        let rows = (value_ptr[k + 1] - value_ptr[k]) / width;
        for j in 0..width {
            let d = l[value_ptr[k] + j * rows + j];
            if d == 0.0 || !d.is_finite() {
                return PivotSigns::Singular;
            } else if d < 0.0 {
                signs = PivotSigns::Indefinite;
            }
        }
    }
    signs
}

/// Solves the probe `b = A p`, `p_i = 1 + (i mod 7) / 7` (no structure shared with the
/// mesh ordering), with `solve` and tells whether `||b - A p^|| <= PROBE_TOLERANCE ||b||`.
/// `probe` and `image` are scratch of length `n`.
fn probe_solve_is_accurate(
    a: SparseColMatRef<'_, usize, f64>,
    probe: &mut [f64],
    image: &mut [f64],
    solve: impl FnOnce(&mut [f64], &mut MemStack),
    stack: &mut MemStack,
) -> bool {
    for (i, p) in probe.iter_mut().enumerate() {
        *p = 1.0 + (i % 7) as f64 / 7.0;
    }
    image.iter_mut().for_each(|v| *v = 0.0);
    add_product(a, 1.0, probe, image);
    let b_norm = norm(image);
    probe.copy_from_slice(image);
    solve(probe, stack);
    if probe.iter().any(|v| !v.is_finite()) {
        return false;
    }
    // Residual b - A p^, written over the image b.
    add_product(a, -1.0, probe, image);
    norm(image) <= PROBE_TOLERANCE * b_norm
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|a| a * a).sum::<f64>().sqrt()
}

/// `y += s A x` for a matrix stored with its full pattern (both triangles).
fn add_product(a: SparseColMatRef<'_, usize, f64>, s: f64, x: &[f64], y: &mut [f64]) {
    let (cp, ri, vals) = (a.col_ptr(), a.row_idx(), a.val());
    for (j, &xj) in x.iter().enumerate() {
        for k in cp[j]..cp[j + 1] {
            y[ri[k]] += s * vals[k] * xj;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::dyn_stack::MemBuffer;
    use faer::sparse::Pair;

    /// The `n x n` matrix with entries `(row, col, value)`: its pattern and values.
    fn from_triplets(
        n: usize,
        entries: &[(usize, usize, f64)],
    ) -> (SymbolicSparseColMat<usize>, Vec<f64>) {
        let pairs: Vec<_> = entries
            .iter()
            .map(|&(row, col, _)| Pair { row, col })
            .collect();
        let (symbolic, argsort) = SymbolicSparseColMat::try_new_from_indices(n, n, &pairs).unwrap();
        let entry_values: Vec<f64> = entries.iter().map(|e| e.2).collect();
        let matrix =
            faer::sparse::SparseColMat::new_from_argsort(symbolic.clone(), &argsort, &entry_values)
                .unwrap();
        (symbolic, matrix.val().to_vec())
    }

    /// 5-point Laplacian on an `m x m` grid shifted by `-shift`: positive definite for a
    /// shift below its smallest eigenvalue (0.045 for m = 20), indefinite for a shift inside
    /// the spectrum (0, 8).
    fn shifted_laplacian(m: usize, shift: f64) -> (SymbolicSparseColMat<usize>, Vec<f64>) {
        let n = m * m;
        let mut entries = Vec::new();
        for i in 0..m {
            for j in 0..m {
                let k = i * m + j;
                entries.push((k, k, 4.0 - shift));
                if i + 1 < m {
                    entries.push((k, k + m, -1.0));
                    entries.push((k + m, k, -1.0));
                }
                if j + 1 < m {
                    entries.push((k, k + 1, -1.0));
                    entries.push((k + 1, k, -1.0));
                }
            }
        }
        from_triplets(n, &entries)
    }

    /// A shifted Laplacian factorized by a solver with or without the symmetric analysis.
    struct Factorized {
        pattern: SymbolicSparseColMat<usize>,
        values: Vec<f64>,
        linear: LinearSolver,
        numeric: NumericFactor,
        stack: MemBuffer,
        kind: FactorKind,
    }

    fn factorized(m: usize, shift: f64, spd_possible: bool) -> Factorized {
        let (pattern, values) = shifted_laplacian(m, shift);
        factorized_with(pattern, values, spd_possible)
    }

    fn factorized_with(
        pattern: SymbolicSparseColMat<usize>,
        values: Vec<f64>,
        spd_possible: bool,
    ) -> Factorized {
        factorized_by(pattern, values, spd_possible, FactorMethod::SymmetricFirst)
    }

    fn factorized_by(
        pattern: SymbolicSparseColMat<usize>,
        values: Vec<f64>,
        spd_possible: bool,
        method: FactorMethod,
    ) -> Factorized {
        let linear = LinearSolver::for_non_symmetric(&pattern, spd_possible).unwrap();
        let mut numeric = linear.numeric();
        let mut stack = MemBuffer::new(linear.scratch(4));
        let kind = linear
            .factorize(
                &pattern,
                &values,
                &mut numeric,
                method,
                MemStack::new(&mut stack),
            )
            .unwrap();
        Factorized {
            pattern,
            values,
            linear,
            numeric,
            stack,
            kind,
        }
    }

    /// Factorizes, solves `A x = A p` and returns the kind and the relative error of `x`.
    fn solve_error(m: usize, shift: f64) -> (FactorKind, f64) {
        let mut f = factorized(m, shift, true);
        (f.kind, f.relative_solve_error())
    }

    impl Factorized {
        /// Solves `A x = A p` with the factors, `p_i = ((37 i) mod 11) - 5`, and returns
        /// `||x - p|| / ||p||`.
        fn relative_solve_error(&mut self) -> f64 {
            let n = self.pattern.nrows();
            let exact: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
            let a = SparseColMatRef::new(self.pattern.as_ref(), &self.values);
            let mut x = vec![0.0; n];
            add_product(a, 1.0, &exact, &mut x);
            self.linear.solve_in_place(
                &mut self.numeric,
                &mut x,
                1,
                MemStack::new(&mut self.stack),
            );
            let err: f64 = x.iter().zip(&exact).map(|(a, b)| (a - b) * (a - b)).sum();
            err.sqrt() / norm(&exact)
        }
    }

    #[test]
    fn positive_definite_uses_ldlt() {
        let (kind, err) = solve_error(20, 0.0);
        assert_eq!(kind, FactorKind::Ldlt);
        assert!(err < 1e-12, "error {err:e}");
    }

    #[test]
    fn indefinite_uses_checked_ldlt_and_solves_accurately() {
        // Shift 1.3 puts ~10 % of the 400 eigenvalues below zero; none near zero.
        let (kind, err) = solve_error(20, 1.3);
        assert_eq!(kind, FactorKind::LdltIndefinite);
        assert!(err < 1e-10, "error {err:e}");
    }

    /// The 2 x 2 blocks `[[d, 1], [1, d]]` on the diagonal, chained by small couplings:
    /// regular and indefinite for a small `d`.
    fn small_diagonal(blocks: usize, d: f64) -> (SymbolicSparseColMat<usize>, Vec<f64>) {
        let n = 2 * blocks;
        let mut entries = Vec::new();
        for k in 0..n {
            entries.push((k, k, d));
        }
        for b in 0..blocks {
            entries.push((2 * b, 2 * b + 1, 1.0));
            entries.push((2 * b + 1, 2 * b, 1.0));
            if b + 1 < blocks {
                entries.push((2 * b + 1, 2 * b + 2, 0.1));
                entries.push((2 * b + 2, 2 * b + 1, 0.1));
            }
        }
        from_triplets(n, &entries)
    }

    /// Without pivoting, a zero pivot stops LDL^T and a tiny one grows the factors by
    /// `1/d`: either way the pivoted LBL^T takes over, and solves accurately.
    #[test]
    fn a_zero_or_tiny_pivot_falls_back_to_checked_lblt() {
        for d in [0.0, 1e-13] {
            lblt_solves_small_diagonal(d);
        }
    }

    fn lblt_solves_small_diagonal(d: f64) {
        let (pattern, values) = small_diagonal(6, d);
        let mut f = factorized_with(pattern, values, true);
        assert_eq!(f.kind, FactorKind::Lblt);
        assert_eq!(
            (f.numeric.indefinite_ldlt_count, f.numeric.lblt_count),
            (0, 1)
        );
        let err = f.relative_solve_error();
        assert!(err < 1e-12, "d = {d:e}: error {err:e}");
    }

    #[test]
    fn gathered_kernel_input_gives_faers_own_factors_bit_for_bit() {
        // Upper-triangle values perturbed: faer's permutation reads the lower triangle
        // only, and so must the gather.
        let (pattern, mut values) = shifted_laplacian(12, 0.0);
        let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
        for j in 0..pattern.ncols() {
            for k in cp[j]..cp[j + 1] {
                if ri[k] < j {
                    values[k] *= 1.0 + 1e-3 * (k % 5) as f64;
                }
            }
        }
        let f = factorized_with(pattern.clone(), values.clone(), true);
        let c = f.linear.symmetric.as_ref().unwrap();
        let mut reference = vec![0.0; c.symbolic.len_val()];
        let mut stack = MemBuffer::new(
            c.symbolic
                .factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
        );
        c.symbolic
            .factorize_numeric_ldlt(
                &mut reference,
                SparseColMatRef::new(pattern.as_ref(), &values),
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut stack),
                Default::default(),
            )
            .unwrap();
        assert_eq!(f.kind, FactorKind::Ldlt);
        assert!(
            f.numeric.l_values == reference,
            "factors differ from faer's"
        );
    }

    /// The plain-loop substitutions agree with faer's `LdltRef` solve to round-off, column
    /// by column, on a definite and an indefinite factor.
    #[test]
    fn ldlt_substitutions_agree_with_faers_solve() {
        for (shift, kind) in [(0.0, FactorKind::Ldlt), (1.3, FactorKind::LdltIndefinite)] {
            let mut f = factorized(20, shift, true);
            assert_eq!(f.kind, kind);
            let n = f.pattern.nrows();
            for width in 1..=5 {
                let rhs: Vec<f64> = (0..n * width)
                    .map(|i| ((i * 29) % 13) as f64 - 6.0 + 0.1 * (i / n) as f64)
                    .collect();
                let c = f.linear.symmetric.as_ref().unwrap();
                let mut ours = rhs.clone();
                c.solve_ldlt(
                    &f.numeric.l_values,
                    &mut ours,
                    width,
                    &mut f.numeric.solve_scratch,
                );
                let mut faers = rhs.clone();
                let mut stack =
                    MemBuffer::new(c.symbolic.solve_in_place_scratch::<f64>(width, Par::Seq));
                LdltRef::new(&c.symbolic, &f.numeric.l_values).solve_in_place_with_conj(
                    Conj::No,
                    MatMut::from_column_major_slice_mut(&mut faers, n, width),
                    Par::Seq,
                    MemStack::new(&mut stack),
                );
                let diff: f64 = ours.iter().zip(&faers).map(|(a, b)| (a - b).powi(2)).sum();
                let rel = diff.sqrt() / norm(&faers);
                assert!(rel < 1e-13, "shift {shift}, width {width}: {rel:e}");
            }
        }
    }

    /// A shifted Laplacian with a convection term `c (x_{k+1} - x_{k-1})` along the grid's
    /// rows and columns: non-symmetric, with the Laplacian's pattern.
    fn convection_diffusion(
        m: usize,
        shift: f64,
        c: f64,
    ) -> (SymbolicSparseColMat<usize>, Vec<f64>) {
        let (pattern, mut values) = shifted_laplacian(m, shift);
        let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
        for j in 0..pattern.ncols() {
            for k in cp[j]..cp[j + 1] {
                match ri[k].cmp(&j) {
                    std::cmp::Ordering::Less => values[k] += c,
                    std::cmp::Ordering::Greater => values[k] -= c,
                    std::cmp::Ordering::Equal => {}
                }
            }
        }
        (pattern, values)
    }

    /// Definite (`A + A^T` positive definite) and indefinite (shift 1.3, as for the checked
    /// LDL^T: worse conditioned, so the error bound is looser) non-symmetric matrices,
    /// with and without the symmetric analysis.
    #[test]
    fn non_symmetric_matrix_is_solved_by_lu_without_pivoting() {
        for (shift, spd_possible, bound) in
            [(0.0, true, 1e-12), (0.0, false, 1e-12), (1.3, true, 1e-10)]
        {
            let (pattern, values) = convection_diffusion(20, shift, 0.3);
            let mut f = factorized_by(pattern, values, spd_possible, FactorMethod::Lu);
            assert_eq!(f.kind, FactorKind::Lu);
            assert_eq!((f.numeric.static_lu_count, f.numeric.lu_count), (1, 0));
            let err = f.relative_solve_error();
            assert!(err < bound, "shift {shift}: error {err:e}");
        }
    }

    /// A dense non-symmetric matrix: one supernode, wider than the plain-loop block of
    /// `lu::lu_in_place`, so its recursive split runs; solved for several columns.
    #[test]
    fn dense_non_symmetric_matrix_is_solved_for_several_columns() {
        let n = 90;
        let mut entries = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let v = ((i * 7 + j * 13) % 17) as f64 / 17.0 - 0.5
                    + if i == j { n as f64 } else { 0.0 };
                entries.push((i, j, v));
            }
        }
        let (pattern, values) = from_triplets(n, &entries);
        let mut f = factorized_by(pattern, values, true, FactorMethod::Lu);
        assert_eq!((f.kind, f.numeric.static_lu_count), (FactorKind::Lu, 1));
        let exact: Vec<f64> = (0..3 * n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
        let a = SparseColMatRef::new(f.pattern.as_ref(), &f.values);
        let mut x = vec![0.0; 3 * n];
        for (x, p) in x.chunks_exact_mut(n).zip(exact.chunks_exact(n)) {
            add_product(a, 1.0, p, x);
        }
        f.linear
            .solve_in_place(&mut f.numeric, &mut x, 3, MemStack::new(&mut f.stack));
        let err: f64 = x.iter().zip(&exact).map(|(a, b)| (a - b).powi(2)).sum();
        let err = err.sqrt() / norm(&exact);
        assert!(err < 1e-12, "error {err:e}");
    }

    /// Zero diagonal entries stop the LU without pivoting: faer's pivoted LU takes over.
    #[test]
    fn zero_pivot_falls_back_to_pivoted_lu() {
        let (pattern, mut values) = small_diagonal(6, 0.0);
        let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
        for j in 0..pattern.ncols() {
            for k in cp[j]..cp[j + 1] {
                if ri[k] < j {
                    values[k] *= 1.5;
                }
            }
        }
        let mut f = factorized_by(pattern, values, true, FactorMethod::Lu);
        assert_eq!(f.kind, FactorKind::Lu);
        assert_eq!((f.numeric.static_lu_count, f.numeric.lu_count), (0, 1));
        let err = f.relative_solve_error();
        assert!(err < 1e-12, "error {err:e}");
    }

    #[test]
    fn without_symmetric_analysis_lu_is_used() {
        let f = factorized(10, 1.3, false);
        assert_eq!(f.kind, FactorKind::Lu);
        assert_eq!((f.numeric.lu_count, f.numeric.lblt_count), (1, 0));
    }
}

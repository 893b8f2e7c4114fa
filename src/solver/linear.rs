//! Sparse direct solves with faer: Cholesky (LL^T) first, LU with partial pivoting as the
//! fallback. Symbolic analyses once per model; numeric factors in reusable buffers.
//!
//! Why this pair: before the peak of the cohesive law, on unloading and in contact, the
//! RVE tangent is symmetric positive definite, and LL^T is 4-8 times faster than LU here
//! (see TOOLCHAIN.md). After the peak the tangent can be indefinite and the minimal BC is
//! a saddle point. faer's LL^T *reports* a non-positive pivot (`LltError`), so a failed
//! LL^T is a reliable signal to switch to LU, which is robust for any regular matrix. The
//! LBL^T variant is avoided: it pivots only when supernodal and can return NaN silently
//! on small simplicial problems. The numeric factorizations write into buffers that keep
//! their size between calls: no allocation per iteration once they have grown (first call).

use faer::dyn_stack::{MemStack, StackReq};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

use crate::error::{Error, Result};

/// Which factorization a [`NumericFactor`] holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FactorKind {
    Cholesky,
    Lu,
}

/// Numeric factors, per workspace.
pub struct NumericFactor {
    lu: NumericLu<usize, f64>,
    l_values: Vec<f64>,
    /// What the last successful factorization was, if any.
    pub current: Option<FactorKind>,
    /// LU factorizations done with these buffers so far. faer's supernodal LU allocates
    /// internally (LL^T does not), so this counts the updates that left the
    /// allocation-free path.
    pub lu_count: u64,
}

/// Symbolic analyses of one pattern, shared by every instance of a model.
pub struct LinearSolver {
    lu: SymbolicLu<usize>,
    /// `None` when the system can never be positive definite (minimal BC multipliers).
    cholesky: Option<SymbolicCholesky<usize>>,
}

impl LinearSolver {
    /// Analyses `pattern` (COLAMD for LU, AMD for LL^T). `spd_possible` is false for
    /// saddle-point systems.
    pub fn new(pattern: &SymbolicSparseColMat<usize>, spd_possible: bool) -> Result<Self> {
        // Supernodal where faer chooses it: simplicial LU would allocate nothing but is
        // 5x (722 unknowns) to 12x (8.9k) slower (measured with benches/solver.rs), and LU
        // only runs on indefinite tangents, past the peak.
        let lu = factorize_symbolic_lu(pattern.as_ref(), Default::default())
            .map_err(|e| Error::Mesh(format!("symbolic LU analysis failed: {e:?}")))?;
        let cholesky = if spd_possible && pattern.nrows() > 0 {
            Some(
                factorize_symbolic_cholesky(
                    pattern.as_ref(),
                    Side::Lower,
                    SymmetricOrdering::Amd,
                    CholeskySymbolicParams {
                        // Measured (benches/solver.rs): supernodal is 2x faster than
                        // simplicial already at 722 unknowns, and faster at 9k.
                        supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                        ..Default::default()
                    },
                )
                .map_err(|e| Error::Mesh(format!("symbolic Cholesky analysis failed: {e:?}")))?,
            )
        } else {
            None
        };
        Ok(LinearSolver { lu, cholesky })
    }

    /// Empty numeric buffers for this solver.
    pub fn numeric(&self) -> NumericFactor {
        NumericFactor {
            lu: NumericLu::new(),
            l_values: vec![0.0; self.cholesky.as_ref().map_or(0, |c| c.len_val())],
            current: None,
            lu_count: 0,
        }
    }

    /// Scratch memory for a factorization and a solve with `ncols` right-hand sides.
    pub fn scratch(&self, ncols: usize) -> StackReq {
        let mut reqs = vec![
            self.lu
                .factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()),
            self.lu.solve_in_place_scratch::<f64>(ncols, Par::Seq),
        ];
        if let Some(c) = &self.cholesky {
            reqs.push(c.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()));
            reqs.push(c.solve_in_place_scratch::<f64>(ncols, Par::Seq));
        }
        StackReq::any_of(&reqs)
    }

    /// Factorizes the matrix with `values` on `pattern`: LL^T when `try_cholesky` and the
    /// matrix is positive definite, else LU. Returns the kind used.
    pub fn factorize(
        &self,
        pattern: &SymbolicSparseColMat<usize>,
        values: &[f64],
        numeric: &mut NumericFactor,
        try_cholesky: bool,
        stack: &mut MemStack,
    ) -> std::result::Result<FactorKind, String> {
        numeric.current = None;
        let a = SparseColMatRef::new(pattern.as_ref(), values);
        if let (true, Some(c)) = (try_cholesky, &self.cholesky) {
            let ok = c
                .factorize_numeric_llt(
                    &mut numeric.l_values,
                    a,
                    Side::Lower,
                    Default::default(),
                    Par::Seq,
                    stack,
                    Default::default(),
                )
                .is_ok();
            if ok {
                numeric.current = Some(FactorKind::Cholesky);
                return Ok(FactorKind::Cholesky);
            }
        }
        self.lu
            .factorize_numeric_lu(&mut numeric.lu, a, Par::Seq, stack, Default::default())
            .map_err(|e| format!("{e:?}"))?;
        numeric.current = Some(FactorKind::Lu);
        numeric.lu_count += 1;
        Ok(FactorKind::Lu)
    }

    /// Solves in place for `ncols` right-hand sides stored column-major in `rhs`, with the
    /// last factorization. Does nothing if there is none (callers check `current`).
    pub fn solve_in_place(
        &self,
        numeric: &NumericFactor,
        rhs: &mut [f64],
        ncols: usize,
        stack: &mut MemStack,
    ) {
        let n = rhs.len() / ncols.max(1);
        let b = MatMut::from_column_major_slice_mut(rhs, n, ncols);
        match (numeric.current, &self.cholesky) {
            (Some(FactorKind::Cholesky), Some(c)) => LltRef::new(c, &numeric.l_values)
                .solve_in_place_with_conj(Conj::No, b, Par::Seq, stack),
            (Some(FactorKind::Lu), _) => LuRef::new_unchecked(&self.lu, &numeric.lu)
                .solve_in_place_with_conj(Conj::No, b, Par::Seq, stack),
            _ => {}
        }
    }
}

//! The sparsity pattern of the RVE system and, for every element matrix entry, its slot
//! in the compressed-column value array. Built once per model; assembly then writes
//! values in place and never re-analyses the pattern.

use faer::sparse::{Pair, SymbolicSparseColMat};

use crate::constraint::{DofMap, FIXED};
use crate::error::{Error, Result};

/// Marker of an element matrix entry that touches a fixed dof.
pub const NO_SLOT: u32 = u32::MAX;

/// Pattern and scatter slots.
#[derive(Clone, Debug)]
pub struct Pattern {
    /// Number of unknowns (reduced dofs + multipliers).
    pub n: usize,
    pub symbolic: SymbolicSparseColMat<usize>,
    /// Slots of each triangle's 6x6 matrix, row-major.
    pub triangle_slots: Vec<[u32; 36]>,
    /// Slots of each interface element's 8x8 matrix, row-major.
    pub interface_slots: Vec<[u32; 64]>,
    /// Multiplier couplings: `(slot of (dof, multiplier), slot of (multiplier, dof), coefficient)`.
    pub constraint_slots: Vec<(u32, u32, f64)>,
    /// Slot of each diagonal entry.
    pub diagonal_slots: Vec<u32>,
}

fn pairs_of<const D: usize>(dofs: &[u32; D], out: &mut Vec<Pair<usize, usize>>) {
    for &r in dofs {
        for &c in dofs {
            if r != FIXED && c != FIXED {
                out.push(Pair {
                    row: r as usize,
                    col: c as usize,
                });
            }
        }
    }
}

impl Pattern {
    /// Builds the pattern from the element dof lists and the multiplier rows of `dofs`.
    pub fn build(dofs: &DofMap, triangles: &[[u32; 6]], interfaces: &[[u32; 8]]) -> Result<Self> {
        let n = dofs.n_unknowns();
        let mut pairs = Vec::with_capacity(36 * triangles.len() + 64 * interfaces.len());
        for t in triangles {
            pairs_of(t, &mut pairs);
        }
        for e in interfaces {
            pairs_of(e, &mut pairs);
        }
        for (k, row) in dofs.constraint_rows.iter().enumerate() {
            let m = dofs.n_reduced + k;
            for &(r, _) in row {
                pairs.push(Pair {
                    row: r as usize,
                    col: m,
                });
                pairs.push(Pair {
                    row: m,
                    col: r as usize,
                });
            }
        }
        // Multiplier diagonals are structural zeros; keeping them in the pattern lets the
        // pivoting LU see a square, structurally complete system.
        for k in 0..dofs.n_multipliers() {
            let m = dofs.n_reduced + k;
            pairs.push(Pair { row: m, col: m });
        }
        // Every unknown needs a diagonal entry (also isolated dofs, which a bad mesh could give).
        for i in 0..n {
            pairs.push(Pair { row: i, col: i });
        }
        let (symbolic, _argsort) = SymbolicSparseColMat::try_new_from_indices(n, n, &pairs)
            .map_err(|e| Error::Mesh(format!("sparsity pattern: {e:?}")))?;

        let slot = |r: u32, c: u32| -> u32 {
            if r == FIXED || c == FIXED {
                return NO_SLOT;
            }
            let (r, c) = (r as usize, c as usize);
            let start = symbolic.col_ptr()[c];
            let rows = &symbolic.row_idx()[start..symbolic.col_ptr()[c + 1]];
            match rows.binary_search(&r) {
                Ok(k) => (start + k) as u32,
                Err(_) => unreachable!("entry ({r}, {c}) was inserted into the pattern"),
            }
        };
        fn element_slots<const D: usize, const S: usize>(
            dofs: &[u32; D],
            slot: impl Fn(u32, u32) -> u32,
        ) -> [u32; S] {
            let mut s = [NO_SLOT; S];
            for i in 0..D {
                for j in 0..D {
                    s[i * D + j] = slot(dofs[i], dofs[j]);
                }
            }
            s
        }
        let triangle_slots = triangles.iter().map(|t| element_slots(t, slot)).collect();
        let interface_slots = interfaces.iter().map(|e| element_slots(e, slot)).collect();
        let mut constraint_slots = Vec::new();
        for (k, row) in dofs.constraint_rows.iter().enumerate() {
            let m = (dofs.n_reduced + k) as u32;
            for &(r, w) in row {
                constraint_slots.push((slot(r, m), slot(m, r), w));
            }
        }
        let diagonal_slots = (0..n as u32).map(|i| slot(i, i)).collect();
        Ok(Pattern {
            n,
            symbolic,
            triangle_slots,
            interface_slots,
            constraint_slots,
            diagonal_slots,
        })
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.symbolic.row_idx().len()
    }

    /// `y = A x` for a *symmetric* `A` with `values` on this pattern (every system matrix
    /// of the RVE is: bulk, interface tangents eqs. 45-47, multiplier couplings). Row `i`
    /// of `A` is then its column `i`, so each `y_i` is a dot product over one stored
    /// column: no scattered writes, faster than the column-scatter product
    /// (`docs/solver.md`).
    pub fn mul_symmetric(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        let (cp, ri) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        for (i, yi) in y.iter_mut().enumerate() {
            let range = cp[i]..cp[i + 1];
            *yi = ri[range.clone()]
                .iter()
                .zip(&values[range])
                .map(|(&r, &v)| v * x[r])
                .sum();
        }
    }

    /// [`Pattern::mul_symmetric`] on three columns at once (`x`, `y`: n x 3,
    /// column-major), reading the pattern once.
    pub fn mul_symmetric3(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        let n = self.n;
        let (cp, ri) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        let (x0, rest) = x.split_at(n);
        let (x1, x2) = rest.split_at(n);
        for i in 0..n {
            let range = cp[i]..cp[i + 1];
            let (mut s0, mut s1, mut s2) = (0.0, 0.0, 0.0);
            for (&r, &v) in ri[range.clone()].iter().zip(&values[range]) {
                s0 += v * x0[r];
                s1 += v * x1[r];
                s2 += v * x2[r];
            }
            y[i] = s0;
            y[n + i] = s1;
            y[2 * n + i] = s2;
        }
    }
}

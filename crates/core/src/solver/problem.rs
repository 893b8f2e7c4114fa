//! The RVE problem at one macro strain, as the solvers see it: the residual and tangent of
//! the discrete equilibrium (paper eq. 14)
//!
//! ```text
//! R(x; eps) = K_const x + G eps + F_itz(x) = 0,     K(x) = dR/dx
//! ```
//!
//! evaluated into a workspace, the convergence reference, and the factorization of `K`.
//! Newton, path following, the predictor and the condensed tangent all work through it,
//! and none of them through another.

use super::settings::Settings;
use super::sparse_direct::{FactorKind, LinearSolver};
use super::workspace::{Evaluation, FactorUse, Workspace};
use crate::assembly::Discretization;
use crate::error::LinearAlgebraError;
use crate::interface::TangentKind;

/// A macro strain `[eps_xx, eps_yy, gamma_xy]` (engineering shear).
pub type Strain = [f64; 3];

/// The fixed parts of one RVE problem, borrowed from its model.
#[derive(Clone, Copy)]
pub struct Problem<'a> {
    pub disc: &'a Discretization,
    pub linear: &'a LinearSolver,
    pub settings: &'a Settings,
    /// Elastic sensitivity `-K_el^-1 G` (n x 3, column-major), or empty: the fallback
    /// predictor `x_0 = x_n + X_el Delta eps` of a step (see `predictor`).
    pub predictor: &'a [f64],
}

impl Problem<'_> {
    /// Number of unknowns.
    pub fn n(&self) -> usize {
        self.disc.n()
    }

    /// The convergence reference `max(||G eps||, 1e-8 ||G||_F)`: an iterate converges when
    /// `||R|| <= tolerance * reference`, the residual relative to the load the macro strain
    /// puts on the RVE (`G eps` is the residual of the zero fluctuation without
    /// interfaces). The floor makes strains below 1e-8 count as 1e-8, so a zero strain
    /// still has a meaningful test.
    pub fn reference(&self, strain: &Strain) -> f64 {
        let (g, n) = (&self.disc.g, self.n());
        let mut sq = 0.0;
        for i in 0..n {
            let gi = g[i] * strain[0] + g[n + i] * strain[1] + g[2 * n + i] * strain[2];
            sq += gi * gi;
        }
        sq.sqrt().max(1e-8 * norm(g))
    }

    /// Evaluates `R` and `K` (of `kind`) at `x` into `out`, from the sub-step's start
    /// history `start`, with the contact status `status` held (or read from the gaps,
    /// `None`; see `contact`).
    pub(super) fn evaluate_into(
        &self,
        x: &[f64],
        strain: &Strain,
        start: &[f64],
        status: Option<&[bool]>,
        kind: TangentKind,
        out: &mut Evaluation,
    ) {
        out.counts = self.disc.evaluate_with(
            x,
            strain,
            start,
            &mut out.history,
            &mut out.r,
            Some(&mut out.k),
            kind,
            status,
        );
    }

    /// Evaluates `R` and `K` at `x` as the workspace's current evaluation.
    pub(super) fn evaluate(
        &self,
        x: &[f64],
        strain: &Strain,
        kind: TangentKind,
        ws: &mut Workspace,
    ) {
        let status = ws.contact.status();
        self.evaluate_into(x, strain, &ws.history_start, status, kind, &mut ws.current);
    }

    /// Evaluates `R` and `K` at `ws.x_try` as the candidate evaluation.
    pub(super) fn evaluate_candidate(
        &self,
        strain: &Strain,
        kind: TangentKind,
        ws: &mut Workspace,
    ) {
        self.evaluate_into(
            &ws.x_try,
            strain,
            &ws.history_start,
            ws.contact.status(),
            kind,
            &mut ws.candidate,
        );
    }

    /// Factorizes the current matrix; [`FactorUse::Reusable`]: it is the consistent tangent
    /// `dR/dx` and its factors may serve chord corrections and the condensed tangent.
    pub(super) fn factorize(
        &self,
        ws: &mut Workspace,
        use_: FactorUse,
    ) -> Result<FactorKind, LinearAlgebraError> {
        ws.factorization.factorize(
            self.linear,
            &self.disc.pattern.symbolic,
            &ws.current.k,
            use_,
            ws.current.counts.sliding == 0,
        )
    }

    /// The Newton correction `dx = -K^-1 R` of the current evaluation into `ws.dx`, with a
    /// fresh factorization that serves it alone.
    pub(super) fn one_use_correction(&self, ws: &mut Workspace) -> Result<(), LinearAlgebraError> {
        self.factorize(ws, FactorUse::OneUse)?;
        self.solve_correction(ws);
        Ok(())
    }

    /// `dx = -K_f^-1 R` of the current evaluation into `ws.dx`, with the kept factors.
    pub(super) fn solve_correction(&self, ws: &mut Workspace) {
        ws.dx
            .iter_mut()
            .zip(&ws.current.r)
            .for_each(|(d, r)| *d = -r);
        ws.factorization.solve(self.linear, &mut ws.dx, 1);
    }

    /// `out = G d` for a strain `d`: the load a strain step puts on the RVE.
    pub(super) fn load(&self, d: &Strain, out: &mut [f64]) {
        sensitivity_times(&self.disc.g, d, out);
    }
}

/// Takes the candidate evaluation as the current one.
pub(super) fn accept_candidate(ws: &mut Workspace) {
    std::mem::swap(&mut ws.current, &mut ws.candidate);
}

/// `out = X d` for an n x 3 column-major `X` (a sensitivity, or `G`) and a strain `d`.
pub(super) fn sensitivity_times(matrix: &[f64], d: &Strain, out: &mut [f64]) {
    let n = out.len();
    let (x0, rest) = matrix.split_at(n);
    let (x1, x2) = rest.split_at(n);
    for (i, o) in out.iter_mut().enumerate() {
        *o = x0[i] * d[0] + x1[i] * d[1] + x2[i] * d[2];
    }
}

pub(super) fn norm(v: &[f64]) -> f64 {
    v.iter().map(|a| a * a).sum::<f64>().sqrt()
}

pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

//! The data of the fast path (`solver::fast_path`) that a state keeps while every
//! interface point of its RVE sits on a linear branch of its law.

use serde::{Deserialize, Serialize};

/// Values of a point's jump operator in [`LinearBranch::jumps`].
pub const JUMP_OPERATOR_LEN: usize = 6;

/// The RVE of a state whose interface points are all on linear branches through the origin
/// (unloading to the origin, eq. 24; contact, eqs. 36-37) is linear in the macro strain:
/// with the branch set held, the equilibrium (eq. 14) `K_b x + G eps = 0` gives
/// ```text
/// x = X_b eps,   X_b = -K_b^-1 G,   sigma = D_b eps,   D_b = D_Taylor - G^T K_b^-1 G / V  (eq. 18)
/// ```
/// and the jump of every interface point `q` is `delta_q = A_q eps`, `A_q = J_q X_b`.
/// Kept here: `D_b`, the `s_zz` row, every `A_q` and every point's contact status, taken
/// from the full solve that found the branch set (the *anchor*), plus the strain at which
/// [`State::unknowns`](super::State) hold the fluctuation. A fast update moves the state's
/// strain and leaves the unknowns at the anchor, so they are *lazy*: `X_b eps` is formed
/// (one factorization of `K_b`) only when a full solve or an output needs it.
///
/// `valid` false (and no buffers): the state has no such data, the next update solves.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LinearBranch {
    pub valid: bool,
    /// `D_b`, row-major: the stress is `D_b eps` and the consistent tangent `D_b`.
    pub tangent: [f64; 9],
    /// `d s_zz / d eps` (plane strain): `s_zz = szz . eps`.
    pub szz: [f64; 3],
    /// `A_q` per interface point, element-major: `[s_xx, s_yy, s_xy, n_xx, n_yy, n_xy]`,
    /// the sliding and normal jumps per unit macro strain component, in f32 (the check
    /// bounds the rounding, see `solver::fast_path`).
    pub jumps: Vec<f32>,
    /// The contact status of every point on the branch set (true: closed).
    pub closed: Vec<bool>,
    /// The macro strain at which the state's unknowns hold the fluctuation (the anchor's).
    pub unknowns_strain: [f64; 3],
}

impl LinearBranch {
    /// Drops the data and its buffers.
    pub fn clear(&mut self) {
        *self = LinearBranch::default();
    }

    /// Marks the data not valid, zeroes it and empties its buffers (keeping their
    /// capacity), so that no stale data is saved with the state: states that mean the
    /// same have the same bytes.
    pub fn invalidate(&mut self) {
        self.valid = false;
        self.tangent = [0.0; 9];
        self.szz = [0.0; 3];
        self.jumps.clear();
        self.closed.clear();
        self.unknowns_strain = [0.0; 3];
    }

    /// Copies `other` in place (allocates only when the buffers are too short); the
    /// buffers of data that is not valid are not copied.
    pub fn copy_from(&mut self, other: &LinearBranch) {
        if !other.valid {
            self.invalidate();
            return;
        }
        self.valid = true;
        self.tangent = other.tangent;
        self.szz = other.szz;
        self.jumps.clone_from(&other.jumps);
        self.closed.clone_from(&other.closed);
        self.unknowns_strain = other.unknowns_strain;
    }

    /// Whether the buffers fit `points` interface points with finite values (or the data
    /// is not valid): what a decoder checks.
    pub fn is_consistent(&self, points: usize) -> bool {
        if !self.valid {
            return true;
        }
        self.jumps.len() == JUMP_OPERATOR_LEN * points
            && self.closed.len() == points
            && self.jumps.iter().all(|v| v.is_finite())
            && self
                .tangent
                .iter()
                .chain(&self.szz)
                .chain(&self.unknowns_strain)
                .all(|v| v.is_finite())
    }

    pub(super) fn bytes(&self) -> usize {
        self.jumps.capacity() * std::mem::size_of::<f32>() + self.closed.capacity()
    }
}

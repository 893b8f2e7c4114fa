//! The small state an RVE instance owns: the converged macro strain, fluctuation and
//! interface history. Everything else lives in the shared model.

use serde::{Deserialize, Serialize};

use super::linear_branch::LinearBranch;

/// Converged (or trial) state of one RVE instance.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// Macro strain `[eps_xx, eps_yy, gamma_xy]` this state is in equilibrium with.
    pub strain: [f64; 3],
    /// Unknowns: reduced fluctuation dofs, then the multipliers of the minimal BC.
    pub unknowns: Vec<f64>,
    /// The interface history: the interface law's values per quadrature point, points
    /// element-major (for the paper's law, `delta_max` per point).
    pub history: Vec<f64>,
    /// Fluctuation sensitivity `X = dx/d eps = -K^-1 G` at this state, kept to predict
    /// the next increment (see `Sensitivity`).
    pub sensitivity: Sensitivity,
    /// The second-order term of the fluctuation path, from the increment that led here
    /// (see `PathCurvature`).
    pub curvature: PathCurvature,
    /// The fast path's data while every interface point is on a linear branch (see
    /// `LinearBranch`); when valid, `unknowns` hold the fluctuation at
    /// `linear.unknowns_strain`, which may differ from `strain`.
    pub linear: LinearBranch,
    /// The interface points this state holds at a contact status their gap contradicts
    /// (the solver's active set, see `solver::contact`), one bit per history value (an
    /// upper bound on the points), point `i` in bit `i % 64` of word `i / 64`. The next
    /// update starts from the status this state is in equilibrium with: the gaps' status
    /// with these points flipped. All zero when every point agrees with its gap.
    pub held_contact: Vec<u64>,
    /// What IMPL-EX integration keeps besides `history` (see `ImplexHistory`); empty
    /// with implicit integration.
    pub implex: ImplexHistory,
}

/// The part of a converged state that IMPL-EX integration (`solver::implex`) needs for the
/// next extrapolation, `h_ex = h_n + (dt_{n+1}/dt_n) (h_n - h_{n-1})`, and the contact
/// status it holds for the step. Empty buffers stand for "as `history`" and "all open":
/// the virgin state and every implicit state.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ImplexHistory {
    /// `h_{n-1}`: the interface history one converged step before [`State::history`].
    pub previous: Vec<f64>,
    /// `dt_n`: the time increment of the step that led to this state; 0 when the host
    /// gave none.
    pub step: f64,
    /// The contact status of every interface point at this state (closed), one bit per
    /// point as in [`State::held_contact`].
    pub closed: Vec<u64>,
    /// The step that led here froze the history it started from (nothing to extrapolate):
    /// its kept data ([`State::linear`]) is then the matrix of a next step that starts
    /// from an unchanged history and contact status (`solver::implex::carries_over`).
    pub at_start: bool,
}

impl ImplexHistory {
    /// Whether point `point` is closed.
    pub fn is_closed(&self, point: usize) -> bool {
        status_bit(&self.closed, point)
    }

    fn copy_from(&mut self, other: &ImplexHistory) {
        self.previous.clone_from(&other.previous);
        self.step = other.step;
        self.closed.clone_from(&other.closed);
        self.at_start = other.at_start;
    }

    /// Whether the buffers fit `n_history` history values and `points` points (or are
    /// empty) with finite, admissible values: what a decoder checks.
    pub fn is_consistent(&self, n_history: usize, points: usize) -> bool {
        (self.previous.is_empty() || self.previous.len() == n_history)
            && (self.closed.is_empty() || self.closed.len() == held_contact_words(points))
            && self.step.is_finite()
            && self.step >= 0.0
            && self.previous.iter().all(|v| v.is_finite())
    }

    fn bytes(&self) -> usize {
        self.previous.capacity() * std::mem::size_of::<f64>()
            + self.closed.capacity() * std::mem::size_of::<u64>()
    }
}

/// Words of a [`State::held_contact`] bitset for `n_history` history values.
pub fn held_contact_words(n_history: usize) -> usize {
    n_history.div_ceil(64)
}

/// Bit `point` of status words laid out as [`held_contact_words`] counts them (point `i`
/// in bit `i % 64` of word `i / 64`); false past the words.
pub fn status_bit(words: &[u64], point: usize) -> bool {
    words
        .get(point / 64)
        .is_some_and(|w| w >> (point % 64) & 1 == 1)
}

/// Values per quantization block of a [`Quantized`] vector.
pub const SENSITIVITY_BLOCK: usize = 32;

/// A vector stored in 8-bit fixed point by blocks: block `b` of `SENSITIVITY_BLOCK`
/// consecutive values holds `round(127 v_i / scale_b)` with `scale_b = max |v_i|` over the
/// block (f32, rounded up so that `|v_i| / scale_b <= 1`). The error of a value is at most
/// half a step, `scale_b / 254`. Empty until first stored.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Quantized {
    pub scales: Vec<f32>,
    pub values: Vec<i8>,
}

impl Quantized {
    /// Stores `sign * src`; allocates the buffers the first time only. Returns false (and
    /// stores nothing) if a value is not finite.
    fn store(&mut self, src: &[f64], sign: f64) -> bool {
        if src.iter().any(|v| !v.is_finite()) {
            return false;
        }
        self.values.resize(src.len(), 0);
        self.scales
            .resize(src.len().div_ceil(SENSITIVITY_BLOCK), 0.0);
        for (b, scale_out) in self.scales.iter_mut().enumerate() {
            let block = b * SENSITIVITY_BLOCK..((b + 1) * SENSITIVITY_BLOCK).min(src.len());
            let max = block.clone().fold(0.0f64, |m, i| m.max(src[i].abs()));
            let scale = max as f32;
            let scale = if f64::from(scale) < max {
                f32::from_bits(scale.to_bits() + 1)
            } else {
                scale
            };
            *scale_out = scale;
            let factor = if scale > 0.0 {
                sign * 127.0 / f64::from(scale)
            } else {
                0.0
            };
            for i in block {
                self.values[i] = (src[i] * factor).round() as i8;
            }
        }
        true
    }

    /// Copies `other` into the buffers in place (a derived `clone_from` would allocate
    /// new ones); allocates only when they are too short.
    fn copy_from(&mut self, other: &Quantized) {
        self.scales.clone_from(&other.scales);
        self.values.clone_from(&other.values);
    }

    /// Calls `f(i, v_i)` for every stored value.
    fn for_each(&self, mut f: impl FnMut(usize, f64)) {
        for (b, &scale) in self.scales.iter().enumerate() {
            let step = f64::from(scale) / 127.0;
            let block = b * SENSITIVITY_BLOCK..((b + 1) * SENSITIVITY_BLOCK).min(self.values.len());
            for i in block {
                f(i, f64::from(self.values[i]) * step);
            }
        }
    }

    /// Whether the buffers hold `len` values (or nothing) with finite scales: what a
    /// decoder checks.
    pub fn is_consistent(&self, len: usize) -> bool {
        let sized = self.values.is_empty() && self.scales.is_empty()
            || self.values.len() == len && self.scales.len() == len.div_ceil(SENSITIVITY_BLOCK);
        sized && self.scales.iter().all(|v| v.is_finite())
    }

    fn bytes(&self) -> usize {
        self.values.capacity() * std::mem::size_of::<i8>()
            + self.scales.capacity() * std::mem::size_of::<f32>()
    }
}

/// The sensitivity `X = -K^-1 G` (n x 3, column-major) of a converged state, stored
/// [`Quantized`]. It only seeds the next increment's Newton loop
/// (`x_0 = x_n + X_n Delta eps`, a first-order predictor), where a relative error of
/// 0.4 % of the block's largest entry is of the order of the predictor's own
/// `O(Delta eps^2)` error. Blocks matter after the peak, where the largest entries sit at
/// the crack (measurements in `docs/solver.md`). It costs 3.1 bytes per unknown, and
/// nothing until a converged update with a tangent has filled it (`valid` false, no
/// buffers: the virgin state uses the model's elastic predictor). An update without
/// tangent keeps the one of the state it started from, which the predictor's residual
/// check then guards like any other prediction. (Serialized exactly as format 4's flat
/// `valid, scales, values`.)
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sensitivity {
    pub valid: bool,
    pub data: Quantized,
}

impl Sensitivity {
    fn empty() -> Self {
        Sensitivity {
            valid: false,
            data: Quantized::default(),
        }
    }

    /// Stores `X = -kg` (`kg = K^-1 G`, n x 3 column-major); not valid if `kg` is not.
    pub fn store_negated(&mut self, kg: &[f64]) {
        self.valid = kg.len() % 3 == 0 && self.data.store(kg, -1.0);
    }

    /// `out = X d` (nothing if not valid; returns whether it wrote).
    pub fn times(&self, d: &[f64; 3], out: &mut [f64]) -> bool {
        let n = out.len();
        if !self.valid || self.data.values.len() != 3 * n {
            return false;
        }
        out.iter_mut().for_each(|o| *o = 0.0);
        self.data.for_each(|i, v| out[i % n] += v * d[i / n]);
        true
    }
}

/// The error of the last increment's first-order prediction,
/// `e = x_{n} - x_{n-1} - X_{n-1} Delta eps_{n-1}`, and that increment's strain step: the
/// second-order term `x''[Delta eps, Delta eps] / 2` of the fluctuation path `x(eps)` (the
/// first-order one is the sensitivity's). On a path whose next step `Delta eps = s Delta
/// eps_{n-1}` keeps the direction, `x_{n+1} ~ x_n + X_n Delta eps + s^2 e` predicts to
/// third order (see `solver::predictor`'s module docs). Kept only after an increment that
/// started from the tangent predictor and converged in one Newton loop (`valid` false
/// otherwise), stored [`Quantized`] (1.1 bytes per unknown), allocated by the first
/// increment that fills it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PathCurvature {
    pub valid: bool,
    pub step: [f64; 3],
    pub data: Quantized,
}

impl PathCurvature {
    fn empty() -> Self {
        PathCurvature {
            valid: false,
            step: [0.0; 3],
            data: Quantized::default(),
        }
    }

    /// Stores the prediction error `error` of a step `step`; not valid if `error` is not
    /// finite.
    pub fn store(&mut self, error: &[f64], step: [f64; 3]) {
        self.valid = self.data.store(error, 1.0);
        self.step = step;
    }

    /// `out += s^2 e` for a step `s` times the stored one.
    pub fn add_scaled(&self, s: f64, out: &mut [f64]) {
        if self.valid && self.data.values.len() == out.len() {
            self.data.for_each(|i, v| out[i] += s * s * v);
        }
    }
}

impl State {
    /// The virgin state: zero strain, zero fluctuation, undamaged interfaces.
    pub fn virgin(n_unknowns: usize, n_history: usize) -> Self {
        State {
            strain: [0.0; 3],
            unknowns: vec![0.0; n_unknowns],
            history: vec![0.0; n_history],
            sensitivity: Sensitivity::empty(),
            curvature: PathCurvature::empty(),
            linear: LinearBranch::default(),
            held_contact: vec![0; held_contact_words(n_history)],
            implex: ImplexHistory::default(),
        }
    }

    /// Whether point `point` is held against its gap (see [`State::held_contact`]).
    pub fn is_held(&self, point: usize) -> bool {
        status_bit(&self.held_contact, point)
    }

    /// Whether `unknowns` hold the fluctuation at `strain` (false after fast updates: the
    /// fluctuation is then `X_b strain`, see `LinearBranch`).
    pub fn unknowns_are_current(&self) -> bool {
        !self.linear.valid || self.linear.unknowns_strain == self.strain
    }

    /// [`State::copy_from`] without the fast path's data, which is left not valid (a
    /// solve's start and trial states need none).
    pub fn copy_solution_from(&mut self, other: &State) {
        self.strain = other.strain;
        self.unknowns.copy_from_slice(&other.unknowns);
        self.history.copy_from_slice(&other.history);
        self.sensitivity.valid = other.sensitivity.valid;
        self.sensitivity.data.copy_from(&other.sensitivity.data);
        self.curvature.valid = other.curvature.valid;
        self.curvature.step = other.curvature.step;
        self.curvature.data.copy_from(&other.curvature.data);
        self.held_contact.copy_from_slice(&other.held_contact);
        self.implex.copy_from(&other.implex);
        self.linear.invalidate();
    }

    /// A state of `n_unknowns` and `n_history` values whose quantized buffers have the
    /// capacity of a filled state, so that copies into it allocate nothing (workspaces).
    pub fn with_capacity(n_unknowns: usize, n_history: usize) -> Self {
        let mut state = State::virgin(n_unknowns, n_history);
        let reserve = |q: &mut Quantized, len: usize| {
            q.values.reserve_exact(len);
            q.scales.reserve_exact(len.div_ceil(SENSITIVITY_BLOCK));
        };
        reserve(&mut state.sensitivity.data, 3 * n_unknowns);
        reserve(&mut state.curvature.data, n_unknowns);
        state
    }

    /// Copies `other` into `self` without reallocating (sizes must match), but for the
    /// quantized buffers the first time they arrive.
    pub fn copy_from(&mut self, other: &State) {
        self.copy_solution_from(other);
        self.linear.copy_from(&other.linear);
    }

    /// Heap and inline bytes of this state.
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.unknowns.capacity() * std::mem::size_of::<f64>()
            + self.history.capacity() * std::mem::size_of::<f64>()
            + self.sensitivity.data.bytes()
            + self.curvature.data.bytes()
            + self.linear.bytes()
            + self.held_contact.capacity() * std::mem::size_of::<u64>()
            + self.implex.bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The blocked 8-bit sensitivity reproduces `X d` to half a quantization step of each
    /// block's largest entry, and refuses non-finite input. The virgin state has no buffer.
    #[test]
    fn sensitivity_round_trip_and_refusal() {
        let n = 50;
        let kg: Vec<f64> = (0..3 * n)
            .map(|i| ((i * 7919) % 101) as f64 * 1e-3 - 0.05 * (i / n) as f64)
            .collect();
        let mut s = State::virgin(n, 0).sensitivity;
        assert!(!s.valid && s.data.values.is_empty() && s.data.scales.is_empty());
        let mut out = vec![0.0; n];
        assert!(!s.times(&[1.0, 0.0, 0.0], &mut out));
        s.store_negated(&kg);
        assert!(s.valid);
        assert_eq!(s.data.scales.len(), (3 * n).div_ceil(SENSITIVITY_BLOCK));
        for c in 0..3 {
            let mut d = [0.0; 3];
            d[c] = 1.0;
            assert!(s.times(&d, &mut out));
            for (row, o) in out.iter().enumerate() {
                let i = c * n + row;
                let b = i / SENSITIVITY_BLOCK;
                let block = b * SENSITIVITY_BLOCK..((b + 1) * SENSITIVITY_BLOCK).min(3 * n);
                let max = block.fold(0.0f64, |m, j| m.max(kg[j].abs()));
                assert!((o + kg[i]).abs() <= 0.5 / 127.0 * max * (1.0 + 1e-6));
            }
        }
        let mut bad = kg.clone();
        bad[3] = f64::NAN;
        s.store_negated(&bad);
        assert!(!s.valid);
    }

    /// The path curvature adds `s^2 e` to within half a quantization step (times `s^2`),
    /// is not valid before it is stored, and refuses non-finite input.
    #[test]
    fn curvature_adds_the_scaled_second_order_term() {
        let n = 70;
        let e: Vec<f64> = (0..n)
            .map(|i| ((i * 31) % 17) as f64 * 1e-6 - 8e-6)
            .collect();
        let mut c = State::virgin(n, 0).curvature;
        let mut out = vec![1.0; n];
        c.add_scaled(2.0, &mut out);
        assert!(
            out.iter().all(|&v| v == 1.0),
            "an empty curvature adds nothing"
        );
        c.store(&e, [1e-5, 0.0, 0.0]);
        assert!(c.valid && c.data.is_consistent(n) && c.step == [1e-5, 0.0, 0.0]);
        c.add_scaled(2.0, &mut out);
        for (i, o) in out.iter().enumerate() {
            let b = i / SENSITIVITY_BLOCK;
            let block = b * SENSITIVITY_BLOCK..((b + 1) * SENSITIVITY_BLOCK).min(n);
            let max = block.fold(0.0f64, |m, j| m.max(e[j].abs()));
            assert!((o - 1.0 - 4.0 * e[i]).abs() <= 4.0 * 0.5 / 127.0 * max * (1.0 + 1e-6));
        }
        let mut bad = e.clone();
        bad[5] = f64::INFINITY;
        c.store(&bad, [1e-5, 0.0, 0.0]);
        assert!(!c.valid);
    }
}

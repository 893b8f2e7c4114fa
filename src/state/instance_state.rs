//! The small state an RVE instance owns: the converged macro strain, fluctuation and
//! interface history. Everything else lives in the shared model.

use serde::{Deserialize, Serialize};

use crate::interface::CohesiveHistory;

/// Converged (or trial) state of one RVE instance.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// Macro strain `[eps_xx, eps_yy, gamma_xy]` this state is in equilibrium with.
    pub strain: [f64; 3],
    /// Unknowns: reduced fluctuation dofs, then the multipliers of the minimal BC.
    pub unknowns: Vec<f64>,
    /// `delta_max` per interface quadrature point, element-major (`t_max` follows from it,
    /// see [`CohesiveHistory`]).
    #[serde(with = "history_serde")]
    pub history: Vec<CohesiveHistory>,
    /// Fluctuation sensitivity `X = dx/d eps = -K^-1 G` at this state, kept to predict
    /// the next increment (see [`Sensitivity`]).
    pub sensitivity: Sensitivity,
}

/// The sensitivity `X = -K^-1 G` (n x 3, column-major) of a converged state, stored in
/// 8-bit fixed point by blocks: block `b` of [`SENSITIVITY_BLOCK`] consecutive values holds
/// `round(127 X_i / scale_b)` with `scale_b = max |X_i|` over the block (f32). It only
/// seeds the next increment's Newton loop (`x_0 = x_n + X_n Delta eps`, a first-order
/// predictor), where a relative error of 0.4 % of the block's largest entry is of the
/// order of the predictor's own `O(Delta eps^2)` error: on the paper path every increment
/// takes the iterations and factorizations it took with the 16-bit, per-column `X` of
/// format 3, and on the section 5.2.2 cycle one increment takes one more iteration (not
/// one more factorization). Blocks matter after the peak, where the largest entries sit at
/// the crack: one scale per column made the post-snap increment of the cycle take 7
/// iterations instead of 2. It costs 3.1 bytes per unknown instead of 24 (6 in format 3),
/// and nothing until a converged update with a tangent has filled it (`valid` false, no
/// buffers: the virgin state uses the model's elastic predictor). An update without
/// tangent keeps the one of the state it started from, which the predictor's residual
/// check then guards like any other prediction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sensitivity {
    pub valid: bool,
    /// One scale per block of [`SENSITIVITY_BLOCK`] values: the block's largest `|X|`.
    pub scales: Vec<f32>,
    pub values: Vec<i8>,
}

/// Values per quantization block of a [`Sensitivity`].
pub const SENSITIVITY_BLOCK: usize = 32;

impl Sensitivity {
    fn empty() -> Self {
        Sensitivity {
            valid: false,
            scales: Vec::new(),
            values: Vec::new(),
        }
    }

    /// Stores `X = -kg` (`kg = K^-1 G`, n x 3 column-major). Allocates the buffers the
    /// first time only.
    pub fn store_negated(&mut self, kg: &[f64]) {
        if kg.len() % 3 != 0 || kg.iter().any(|v| !v.is_finite()) {
            self.valid = false;
            return;
        }
        self.values.resize(kg.len(), 0);
        self.scales
            .resize(kg.len().div_ceil(SENSITIVITY_BLOCK), 0.0);
        for (b, scale_out) in self.scales.iter_mut().enumerate() {
            let block = b * SENSITIVITY_BLOCK..((b + 1) * SENSITIVITY_BLOCK).min(kg.len());
            // Rounded up to f32, so that |X| / scale <= 1 holds for every value.
            let max = block.clone().fold(0.0f64, |m, i| m.max(kg[i].abs()));
            let scale = max as f32;
            let scale = if f64::from(scale) < max {
                f32::from_bits(scale.to_bits() + 1)
            } else {
                scale
            };
            *scale_out = scale;
            let factor = if scale > 0.0 {
                127.0 / f64::from(scale)
            } else {
                0.0
            };
            for i in block {
                self.values[i] = (-kg[i] * factor).round() as i8;
            }
        }
        self.valid = true;
    }

    /// `out = X d` (nothing if not valid; returns whether it wrote).
    pub fn times(&self, d: &[f64; 3], out: &mut [f64]) -> bool {
        let n = out.len();
        if !self.valid || self.values.len() != 3 * n {
            return false;
        }
        out.iter_mut().for_each(|o| *o = 0.0);
        for (b, &scale) in self.scales.iter().enumerate() {
            let step = f64::from(scale) / 127.0;
            let block = b * SENSITIVITY_BLOCK..((b + 1) * SENSITIVITY_BLOCK).min(3 * n);
            for i in block {
                let (c, row) = (i / n, i % n);
                out[row] += f64::from(self.values[i]) * step * d[c];
            }
        }
        true
    }

    /// Copies `other`; allocates only the first time `self` receives a filled one.
    fn copy_from(&mut self, other: &Sensitivity) {
        self.valid = other.valid;
        self.scales.clone_from(&other.scales);
        self.values.clone_from(&other.values);
    }
}

impl State {
    /// The virgin state: zero strain, zero fluctuation, undamaged interfaces.
    pub fn virgin(n_unknowns: usize, n_history: usize) -> Self {
        State {
            strain: [0.0; 3],
            unknowns: vec![0.0; n_unknowns],
            history: vec![CohesiveHistory::default(); n_history],
            sensitivity: Sensitivity::empty(),
        }
    }

    /// Copies `other` into `self` without reallocating (sizes must match), but for the
    /// sensitivity's buffer the first time it arrives.
    pub fn copy_from(&mut self, other: &State) {
        self.strain = other.strain;
        self.unknowns.copy_from_slice(&other.unknowns);
        self.history.copy_from_slice(&other.history);
        self.sensitivity.copy_from(&other.sensitivity);
    }

    /// Heap and inline bytes of this state.
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.unknowns.capacity() * std::mem::size_of::<f64>()
            + self.history.capacity() * std::mem::size_of::<CohesiveHistory>()
            + self.sensitivity.values.capacity() * std::mem::size_of::<i8>()
            + self.sensitivity.scales.capacity() * std::mem::size_of::<f32>()
    }
}

/// History as a flat list of `delta_max` (the kernel type has no serde derive).
mod history_serde {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    use crate::interface::CohesiveHistory;

    pub fn serialize<S: Serializer>(h: &[CohesiveHistory], s: S) -> Result<S::Ok, S::Error> {
        let flat: Vec<f64> = h.iter().map(|p| p.delta_max).collect();
        flat.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<CohesiveHistory>, D::Error> {
        let flat = Vec::<f64>::deserialize(d)?;
        Ok(flat
            .into_iter()
            .map(|delta_max| CohesiveHistory { delta_max })
            .collect())
    }
}

/// The state as format 1 of the state bytes stored it: history as `[delta_max, t_max]`
/// pairs. Read by [`crate::ffi`]'s decoder so that saved checkpoints stay loadable; the
/// `t_max` column is dropped (it is `t(delta_max)` by construction).
#[derive(Deserialize)]
pub struct StateFormat1 {
    pub strain: [f64; 3],
    pub unknowns: Vec<f64>,
    pub history: Vec<[f64; 2]>,
}

impl From<StateFormat1> for State {
    fn from(old: StateFormat1) -> Self {
        State {
            strain: old.strain,
            sensitivity: Sensitivity::empty(),
            unknowns: old.unknowns,
            history: old
                .history
                .into_iter()
                .map(|[delta_max, _t_max]| CohesiveHistory { delta_max })
                .collect(),
        }
    }
}

/// The state as format 2 of the state bytes stored it: no sensitivity (the next increment
/// after loading starts from the elastic predictor).
#[derive(Deserialize)]
pub struct StateFormat2 {
    pub strain: [f64; 3],
    pub unknowns: Vec<f64>,
    #[serde(with = "history_serde")]
    pub history: Vec<CohesiveHistory>,
}

impl From<StateFormat2> for State {
    fn from(old: StateFormat2) -> Self {
        State {
            strain: old.strain,
            sensitivity: Sensitivity::empty(),
            unknowns: old.unknowns,
            history: old.history,
        }
    }
}

/// The state as format 3 of the state bytes stored it: format 2 plus a 16-bit sensitivity
/// `X` (not its deviation). Read without the sensitivity: the next increment after loading
/// starts from the elastic predictor, as after formats 1 and 2.
#[derive(Deserialize)]
pub struct StateFormat3 {
    pub strain: [f64; 3],
    pub unknowns: Vec<f64>,
    #[serde(with = "history_serde")]
    pub history: Vec<CohesiveHistory>,
    pub sensitivity: SensitivityFormat3,
}

/// The 16-bit sensitivity of format 3 (read, then dropped).
#[derive(Deserialize)]
pub struct SensitivityFormat3 {
    pub valid: bool,
    pub scale: [f64; 3],
    pub values: Vec<i16>,
}

impl From<StateFormat3> for State {
    fn from(old: StateFormat3) -> Self {
        State::from(StateFormat2 {
            strain: old.strain,
            unknowns: old.unknowns,
            history: old.history,
        })
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
        assert!(!s.valid && s.values.is_empty() && s.scales.is_empty());
        let mut out = vec![0.0; n];
        assert!(!s.times(&[1.0, 0.0, 0.0], &mut out));
        s.store_negated(&kg);
        assert!(s.valid);
        assert_eq!(s.scales.len(), (3 * n).div_ceil(SENSITIVITY_BLOCK));
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
}

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
/// 16-bit fixed point: column `c` holds `round(32767 X_ic / scale_c)` with
/// `scale_c = max_i |X_ic|`. It only seeds the next increment's Newton loop
/// (`x_0 = x_n + X_n Delta eps`, a first-order predictor), where a relative error of
/// 1.5e-5 of the column maximum is far below the predictor's own `O(Delta eps^2)` error,
/// and it costs 6 bytes per unknown instead of 24. `valid` is false until a converged
/// update with a tangent has filled it (the virgin state uses the model's elastic one); an
/// update without tangent keeps the one of the state it started from, which the
/// predictor's residual check then guards like any other prediction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sensitivity {
    pub valid: bool,
    pub scale: [f64; 3],
    pub values: Vec<i16>,
}

impl Sensitivity {
    fn empty(n_unknowns: usize) -> Self {
        Sensitivity {
            valid: false,
            scale: [0.0; 3],
            values: vec![0; 3 * n_unknowns],
        }
    }

    /// Stores `-kg` (`kg = K^-1 G`, n x 3 column-major) without reallocating.
    pub fn store_negated(&mut self, kg: &[f64]) {
        let n = self.values.len() / 3;
        if kg.len() != 3 * n || kg.iter().any(|v| !v.is_finite()) {
            self.valid = false;
            return;
        }
        for c in 0..3 {
            let col = &kg[c * n..(c + 1) * n];
            let scale = col.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            self.scale[c] = scale;
            let factor = if scale > 0.0 { 32767.0 / scale } else { 0.0 };
            for (q, v) in self.values[c * n..(c + 1) * n].iter_mut().zip(col) {
                *q = (-v * factor).round() as i16;
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
        let w = [
            d[0] * self.scale[0] / 32767.0,
            d[1] * self.scale[1] / 32767.0,
            d[2] * self.scale[2] / 32767.0,
        ];
        let (x0, rest) = self.values.split_at(n);
        let (x1, x2) = rest.split_at(n);
        for (i, o) in out.iter_mut().enumerate() {
            *o = f64::from(x0[i]) * w[0] + f64::from(x1[i]) * w[1] + f64::from(x2[i]) * w[2];
        }
        true
    }

    fn copy_from(&mut self, other: &Sensitivity) {
        self.valid = other.valid;
        self.scale = other.scale;
        self.values.copy_from_slice(&other.values);
    }
}

impl State {
    /// The virgin state: zero strain, zero fluctuation, undamaged interfaces.
    pub fn virgin(n_unknowns: usize, n_history: usize) -> Self {
        State {
            strain: [0.0; 3],
            unknowns: vec![0.0; n_unknowns],
            history: vec![CohesiveHistory::default(); n_history],
            sensitivity: Sensitivity::empty(n_unknowns),
        }
    }

    /// Copies `other` into `self` without reallocating (sizes must match).
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
            + self.sensitivity.values.capacity() * std::mem::size_of::<i16>()
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
            sensitivity: Sensitivity::empty(old.unknowns.len()),
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
            sensitivity: Sensitivity::empty(old.unknowns.len()),
            unknowns: old.unknowns,
            history: old.history,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 16-bit sensitivity reproduces `X d` to 1.5e-5 of each column's largest entry
    /// (half a quantization step), and refuses non-finite input.
    #[test]
    fn sensitivity_round_trip_and_refusal() {
        let n = 50;
        let kg: Vec<f64> = (0..3 * n)
            .map(|i| ((i * 7919) % 101) as f64 * 1e-3 - 0.05 * (i / n) as f64)
            .collect();
        let mut s = State::virgin(n, 0).sensitivity;
        assert!(!s.valid);
        let mut out = vec![0.0; n];
        assert!(!s.times(&[1.0, 0.0, 0.0], &mut out));
        s.store_negated(&kg);
        assert!(s.valid);
        for c in 0..3 {
            let mut d = [0.0; 3];
            d[c] = 1.0;
            assert!(s.times(&d, &mut out));
            let col = &kg[c * n..(c + 1) * n];
            let max = col.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (o, v) in out.iter().zip(col) {
                assert!((o + v).abs() <= 0.5 / 32767.0 * max * (1.0 + 1e-12));
            }
        }
        let mut bad = kg.clone();
        bad[3] = f64::NAN;
        s.store_negated(&bad);
        assert!(!s.valid);
    }
}

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
}

impl State {
    /// The virgin state: zero strain, zero fluctuation, undamaged interfaces.
    pub fn virgin(n_unknowns: usize, n_history: usize) -> Self {
        State {
            strain: [0.0; 3],
            unknowns: vec![0.0; n_unknowns],
            history: vec![CohesiveHistory::default(); n_history],
        }
    }

    /// Copies `other` into `self` without reallocating (sizes must match).
    pub fn copy_from(&mut self, other: &State) {
        self.strain = other.strain;
        self.unknowns.copy_from_slice(&other.unknowns);
        self.history.copy_from_slice(&other.history);
    }

    /// Heap and inline bytes of this state.
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.unknowns.capacity() * std::mem::size_of::<f64>()
            + self.history.capacity() * std::mem::size_of::<CohesiveHistory>()
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
            unknowns: old.unknowns,
            history: old
                .history
                .into_iter()
                .map(|[delta_max, _t_max]| CohesiveHistory { delta_max })
                .collect(),
        }
    }
}

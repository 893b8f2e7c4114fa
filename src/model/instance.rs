//! One material point: the committed state plus the last trial, over a shared model. The
//! one trial/commit lifecycle of the crate: `rve run`, the tests and the C interface (one
//! `Instance` behind each handle) all go through it, and so does checkpointing (the bytes
//! of [`crate::state::persist`]).

use std::sync::Arc;

use super::rve_model::{Model, Response};
use crate::error::{Error, Result};
use crate::solver::TangentRequest;
use crate::solver::Workspace;
use crate::state::persist::{self, StateSizes};
use crate::state::State;

/// An RVE instance: what a host keeps per integration point.
///
/// Lifecycle: [`update`](Self::update) computes a trial from the committed state and
/// never changes the committed one; [`commit`](Self::commit) accepts the last successful
/// trial, [`revert`](Self::revert) discards it, [`reset`](Self::reset) returns to the
/// virgin state. The committed state is only ever replaced whole (a swap or an
/// assignment), so a panic inside an update leaves it intact.
///
/// Memory: the trial state is allocated by the first update, so an instance that has
/// never been updated holds one state, not two (a host may create 10^5 of them).
#[derive(Debug)]
pub struct Instance {
    model: Arc<Model>,
    committed: State,
    /// The last trial's buffers; `None` until the first update.
    trial: Option<State>,
    /// Whether `trial` holds a successful update not yet committed or discarded.
    has_trial: bool,
}

impl Instance {
    /// A virgin instance of `model` (zero strain, undamaged).
    pub fn new(model: Arc<Model>) -> Self {
        let committed = model.new_state();
        Instance {
            model,
            committed,
            trial: None,
            has_trial: false,
        }
    }

    pub fn model(&self) -> &Arc<Model> {
        &self.model
    }

    /// The last committed state.
    pub fn committed(&self) -> &State {
        &self.committed
    }

    /// Whether a successful trial awaits [`commit`](Self::commit).
    pub fn has_trial(&self) -> bool {
        self.has_trial
    }

    /// Trial update at `strain` from the committed state (see [`Model::update`]). On
    /// failure the trial is discarded and the committed state is unchanged.
    pub fn update(
        &mut self,
        strain: [f64; 3],
        ws: &mut Workspace,
        request: TangentRequest,
    ) -> Result<Response> {
        self.has_trial = false;
        let model = &self.model;
        let trial = self.trial.get_or_insert_with(|| model.new_state());
        let out = model.update(&self.committed, strain, ws, trial, request);
        self.has_trial = out.is_ok();
        out
    }

    /// Accepts the last successful trial as the new converged state; `NoTrial` when
    /// there is none (no successful update since the last commit, revert, reset or load).
    pub fn commit(&mut self) -> Result<()> {
        match (&mut self.trial, self.has_trial) {
            (Some(trial), true) => {
                std::mem::swap(&mut self.committed, trial);
                self.has_trial = false;
                Ok(())
            }
            _ => Err(Error::NoTrial),
        }
    }

    /// Discards the last trial; the committed state stays.
    pub fn revert(&mut self) {
        self.has_trial = false;
    }

    /// Back to the virgin state, as a new instance (the trial's buffers are released).
    pub fn reset(&mut self) {
        self.committed = self.model.new_state();
        self.trial = None;
        self.has_trial = false;
    }

    /// The sizes the model's states have, as recorded in the state bytes.
    fn sizes(&self) -> StateSizes {
        StateSizes {
            unknowns: self.model.disc.n(),
            history: self.model.disc.history_len(),
        }
    }

    /// Bytes [`save_state`](Self::save_state) writes now. It depends on the state: the
    /// first updates with a tangent add the predictor's sensitivity and path curvature
    /// (see [`State`]).
    pub fn state_size(&self) -> Result<usize> {
        persist::encoded_len(&self.committed)
    }

    /// The committed state (not the trial) as versioned bytes, for checkpoint/restart:
    /// [`load_state`](Self::load_state) on an instance of the same scene, in this process
    /// or another, continues bit-identically.
    pub fn save_state(&self) -> Result<Vec<u8>> {
        persist::encode(&self.committed, self.sizes())
    }

    /// Replaces the committed state by the one in `bytes` (from
    /// [`save_state`](Self::save_state), this format version or an older readable one) and
    /// discards the trial. Refused with `BadState`, `StateVersion` or `StateMismatch` (a
    /// model of another scene, or a history the model's interface law does not admit); a
    /// refused load changes nothing, the trial included.
    pub fn load_state(&mut self, bytes: &[u8]) -> Result<()> {
        let state = persist::decode(bytes, self.sizes())?;
        if let Some(law) = &self.model.disc.law {
            if !law.history_is_valid(&state.history) {
                return Err(Error::BadState {
                    reason: "an interface history value the interface law does not admit \
                             (for the cohesive law: a negative delta_max)"
                        .into(),
                });
            }
        }
        self.committed = state;
        self.has_trial = false;
        Ok(())
    }

    /// Bytes owned by this instance (committed and, once allocated, trial states).
    pub fn state_bytes(&self) -> usize {
        self.committed.bytes() + self.trial.as_ref().map_or(0, State::bytes)
    }
}

//! One material point: committed state plus the last trial, over a shared model.

use std::sync::Arc;

use super::rve_model::{Model, Response};
use crate::error::{Error, Result};
use crate::solver::TangentRequest;
use crate::solver::Workspace;
use crate::state::State;

/// An RVE instance: what a host keeps per integration point.
#[derive(Debug)]
pub struct Instance {
    model: Arc<Model>,
    committed: State,
    trial: State,
    has_trial: bool,
}

impl Instance {
    pub fn new(model: Arc<Model>) -> Self {
        let committed = model.new_state();
        let trial = committed.clone();
        Instance {
            model,
            committed,
            trial,
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

    /// Trial update at `strain` from the committed state (see [`Model::update`]). On
    /// failure the trial is discarded and the committed state is unchanged.
    pub fn update(
        &mut self,
        strain: [f64; 3],
        ws: &mut Workspace,
        request: TangentRequest,
    ) -> Result<Response> {
        self.has_trial = false;
        let out = self
            .model
            .update(&self.committed, strain, ws, &mut self.trial, request);
        self.has_trial = out.is_ok();
        out
    }

    /// Accepts the last successful trial as the new converged state.
    pub fn commit(&mut self) -> Result<()> {
        if !self.has_trial {
            return Err(Error::NoTrial);
        }
        std::mem::swap(&mut self.committed, &mut self.trial);
        self.has_trial = false;
        Ok(())
    }

    /// Discards the last trial.
    pub fn revert(&mut self) {
        self.has_trial = false;
    }

    /// Back to the virgin state.
    pub fn reset(&mut self) {
        self.committed = self.model.new_state();
        self.has_trial = false;
    }

    /// Bytes owned by this instance (committed and trial states).
    pub fn state_bytes(&self) -> usize {
        self.committed.bytes() + self.trial.bytes()
    }
}

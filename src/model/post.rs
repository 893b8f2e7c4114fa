//! Post-processing of a state on its model: the micro fields and their VTK file.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use super::rve_model::Model;
use crate::error::{Error, Result};
use crate::io::{write_vtu_fields, RveFields};
use mesorve_core::state::State;

impl Model {
    /// The micro fields of `state` (a state of this model) on the mesh; a state left by
    /// fast updates has its unknowns formed first ([`Model::current_state`]).
    pub fn fields(&self, state: &State) -> Result<RveFields> {
        let state = self.current_state(state)?;
        Ok(RveFields::compute(self.mesh(), &self.disc, &state))
    }

    /// Writes the fields of `state` as a `.vtu` file at `path` (see
    /// [`crate::io::write_vtu_fields`]); reads `state` only.
    pub fn write_vtu(&self, state: &State, path: &Path) -> Result<()> {
        let io_err = |source| Error::Io {
            path: path.to_path_buf(),
            source,
        };
        let fields = self.fields(state)?;
        let mut w = BufWriter::new(File::create(path).map_err(io_err)?);
        write_vtu_fields(self.mesh(), &fields, &mut w).map_err(io_err)?;
        w.flush().map_err(io_err)
    }
}

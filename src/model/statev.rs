//! A state's committed core ([`mesorve_core::state::statev`]) and back: what a host that keeps
//! the RVE state in its own state variables stores, and the full state the solver starts
//! from, rebuilt from it alone.

use std::borrow::Cow;

use super::rve_model::Model;
use crate::error::{Error, Result};
use mesorve_core::solver::{equilibrium_unknowns, implex, ContactStatus, Integration, Workspace};
use mesorve_core::state::persist::StateSizes;
use mesorve_core::state::statev::{Core, CoreView};
use mesorve_core::state::{held_contact_words, State};

impl Model {
    /// The sizes of this model's states.
    pub fn state_sizes(&self) -> StateSizes {
        StateSizes {
            unknowns: self.disc.n(),
            history: self.disc.history_len(),
        }
    }

    /// Interface quadrature points (entries of a contact status).
    pub fn interface_points(&self) -> usize {
        self.disc.interface_points()
    }

    /// `STATEV` entries a host needs to keep this model's state (`statev::values_needed`,
    /// computed once when the model is built).
    pub fn statev_len(&self) -> usize {
        self.statev_len
    }

    /// The committed core of `state`: strain, history, the contact status every point is
    /// in equilibrium with, and IMPL-EX's data.
    pub fn core_of(&self, state: &State) -> Core {
        self.core_view_of(state).to_core()
    }

    /// [`core_of`](Self::core_of) borrowing the state's buffers (for [`mesorve_core::state::statev::write`]:
    /// no copy of the histories).
    pub fn core_view_of<'a>(&self, state: &'a State) -> CoreView<'a> {
        let points = self.disc.interface_points();
        let words = held_contact_words(points);
        let implex = self.solver.integration == Integration::Implex;
        let own = &state.implex.closed;
        // IMPL-EX's status in the core's layout (every word, no bit past the last point):
        // borrowed, so that writing a state's values allocates nothing.
        let spare = |w: &u64| points % 64 != 0 && w >> (points % 64) != 0;
        let closed = if implex && own.len() == words && !own.last().is_some_and(spare) {
            Cow::Borrowed(own.as_slice())
        } else {
            Cow::Owned(self.closed_words(state))
        };
        CoreView {
            strain: state.strain,
            history: &state.history,
            closed,
            previous: &state.implex.previous,
            step: state.implex.step,
            at_start: state.implex.at_start,
            time: None,
        }
    }

    /// The contact status of `state` in the core's layout (see
    /// [`core_view_of`](Self::core_view_of)).
    fn closed_words(&self, state: &State) -> Vec<u64> {
        let points = self.disc.interface_points();
        let mut closed = vec![0u64; held_contact_words(points)];
        let mut set = |q: usize| closed[q / 64] |= 1 << (q % 64);
        if self.solver.integration == Integration::Implex {
            // The same bit layout: the words, without bits past the last point.
            for (word, &status) in closed.iter_mut().zip(&state.implex.closed) {
                *word = status;
            }
            if let (Some(last), 1..) = (closed.last_mut(), points % 64) {
                *last &= (1 << (points % 64)) - 1;
            }
        } else if state.linear.valid {
            // Unknowns may be lazy (fast path): the branch set's status is the state's.
            let status = state.linear.closed.iter().enumerate();
            status.filter(|(_, &c)| c).for_each(|(q, _)| set(q));
        } else {
            let mut gaps = vec![false; points];
            self.disc.contact_status(&state.unknowns, &mut gaps);
            (0..points)
                .filter(|&q| gaps[q] ^ state.is_held(q))
                .for_each(set);
        }
        closed
    }

    /// The full state a committed `core` stands for (`None`: the virgin state), a function
    /// of the core alone, so that a host's restart, cut-back or new analysis gives what the
    /// uninterrupted run gives from the same values. Implicit integration forms the
    /// fluctuation by one secant solve (`implex::secant_unknowns`; with friction by Newton
    /// at the core's strain with its history, `equilibrium_unknowns`) and the points held
    /// against their gap; IMPL-EX needs no fluctuation (its step solves for it). No
    /// sensitivity, path curvature or fast-path data: the next update starts from the
    /// elastic predictor.
    pub fn expand_core(&self, core: Option<&Core>, ws: &mut Workspace) -> Result<State> {
        let mut state = self.new_state();
        let Some(core) = core else {
            return Ok(state);
        };
        self.check_core(core)?;
        state.strain = core.strain;
        state.history.clone_from(&core.history);
        state.implex.closed.clone_from(&core.closed);
        state.implex.previous.clone_from(&core.previous);
        state.implex.step = core.step;
        state.implex.at_start = core.at_start;
        if self.solver.integration == Integration::Implex || core.strain == [0.0; 3] {
            return Ok(state);
        }
        if ws.model_id() != self.workspace_id() {
            return Err(Error::WorkspaceMismatch);
        }
        let mut unknowns = std::mem::take(&mut state.unknowns);
        if self.scene.spec.effects.friction {
            // Friction's slip offsets a sticking point from the origin: no secant solve.
            equilibrium_unknowns(&self.problem(), &state, &core.strain, ws, &mut unknowns)?;
        } else {
            implex::secant_unknowns(&self.problem(), &state, &core.strain, ws, &mut unknowns)?;
        }
        state.unknowns = unknowns;
        let held = self.solver.contact_status == ContactStatus::ActiveSet
            && self
                .disc
                .law
                .as_ref()
                .is_some_and(|l| l.has_contact_status());
        if held {
            let points = self.disc.interface_points();
            let mut gaps = vec![false; points];
            self.disc.contact_status(&state.unknowns, &mut gaps);
            for q in (0..points).filter(|&q| gaps[q] != core.is_closed(q)) {
                state.held_contact[q / 64] |= 1 << (q % 64);
            }
        }
        // The implicit state keeps no IMPL-EX data.
        state.implex = Default::default();
        Ok(state)
    }

    /// Refuses a core of another model or with a history the law does not admit.
    fn check_core(&self, core: &Core) -> Result<()> {
        if !core.fits(self.state_sizes(), self.disc.interface_points()) {
            return Err(Error::BadState {
                reason: "a state core of another size than the model's, or not finite".into(),
            });
        }
        let np = self.disc.points_per_interface();
        let admissible = |h: &[f64]| {
            self.disc
                .law
                .as_ref()
                .is_none_or(|l| l.history_is_valid(h, np))
        };
        if !admissible(&core.history) || !admissible(&core.previous) {
            return Err(Error::BadState {
                reason: "an interface history value the interface law does not admit (for \
                         the cohesive law: a negative delta_max)"
                    .into(),
            });
        }
        Ok(())
    }
}

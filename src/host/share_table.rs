//! Answer sharing in the UMAT's `STATEV` mode (`[solver] share_tolerance`,
//! [`crate::model::share`], `docs/sharing.md`): a table per material and host increment,
//! shared by the host's threads, of the answers of the points solved so far in the
//! increment (anchors). A point whose committed `STATEV` core and strain match an anchor
//! takes its answer corrected to first order and writes the anchor's trial core with its
//! own strain and time, without rebuilding or solving its RVE.
//!
//! The increment is `(TIME(2), DTIME, KSTEP)` of the calls: a new one (or a cut-back's
//! smaller `DTIME`) starts an empty table. The answers then depend on which points of the
//! increment the host called first, which with several threads changes from run to run
//! (docs/sharing.md bounds the difference on the member).

use std::sync::{Arc, Mutex, PoisonError};

use crate::model::share::{self, Indicator};
use crate::model::{Model, Response};
use crate::state::statev::Core;

/// The increment a table belongs to: the bits of `TIME(2)` and `DTIME`, and `KSTEP`.
pub(super) type IncrementKey = (u64, u64, i32);

/// A point solved in the increment.
pub(super) struct Anchor {
    /// The committed core it solved from.
    pub committed: Core,
    pub strain: [f64; 3],
    pub response: Response,
    /// The trial core it wrote (its strain and time are the anchor's).
    pub trial: Core,
}

struct Increment {
    model: Arc<Model>,
    key: IncrementKey,
    anchors: Vec<Anchor>,
    solved: u64,
    shared: u64,
}

/// The tables of a UMAT, one per material, each of its current increment.
#[derive(Default)]
pub(super) struct ShareTable {
    increments: Mutex<Vec<Increment>>,
}

/// Prints each increment's counts on stderr when `MESORVE_SHARE_LOG` is set.
fn log(inc: &Increment) {
    static LOG: std::sync::LazyLock<bool> =
        std::sync::LazyLock::new(|| std::env::var_os("MESORVE_SHARE_LOG").is_some());
    if *LOG && inc.solved + inc.shared > 0 {
        eprintln!(
            "mesorve: sharing: increment at TIME(2) = {}, DTIME = {}: {} calls solved, {} shared",
            f64::from_bits(inc.key.0),
            f64::from_bits(inc.key.1),
            inc.solved,
            inc.shared
        );
    }
}

impl ShareTable {
    /// The table of `model` at `key`, emptied when the increment changed.
    fn with<R>(
        &self,
        model: &Arc<Model>,
        key: IncrementKey,
        f: impl FnOnce(&mut Increment) -> R,
    ) -> R {
        let mut all = self
            .increments
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        let i = match all.iter().position(|t| share::same_model(&t.model, model)) {
            Some(i) => i,
            None => {
                all.push(Increment {
                    model: model.clone(),
                    key,
                    anchors: Vec::new(),
                    solved: 0,
                    shared: 0,
                });
                all.len() - 1
            }
        };
        let inc = &mut all[i];
        if inc.key != key {
            log(inc);
            *inc = Increment {
                model: model.clone(),
                key,
                anchors: Vec::new(),
                solved: 0,
                shared: 0,
            };
        }
        f(inc)
    }

    /// The answer and the core to write for a point of committed core `core` at
    /// `strain`, from the first anchor that matches it and whose error indicator allows
    /// (`None`: the point solves). `time`: the host's time at the increment's end.
    pub fn follow(
        &self,
        model: &Arc<Model>,
        key: IncrementKey,
        tol: f64,
        (core, strain, time): (&Core, [f64; 3], Option<f64>),
    ) -> Option<(Response, Core)> {
        self.with(model, key, |inc| {
            let anchor = inc.anchors.iter().find(|a| {
                share::strains_close(tol, &strain, &a.strain)
                    && share::cores_close(tol, core, &a.committed)
            })?;
            let switched = anchor.trial.closed != anchor.committed.closed;
            let grew = !share::close(
                tol,
                &anchor.trial.history,
                &anchor.committed.history,
                share::H_FLOOR,
            );
            let indicator = Indicator::default();
            if !share::keeps_share(
                indicator,
                tol,
                &anchor.response,
                &anchor.strain,
                &strain,
                switched,
                grew,
            ) {
                return None;
            }
            let response = share::corrected(&anchor.response, &anchor.strain, &strain);
            let mut written = anchor.trial.clone();
            written.strain = strain;
            written.time = time;
            inc.shared += 1;
            Some((response, written))
        })
    }

    /// Records a point solved in the increment.
    pub fn insert(&self, model: &Arc<Model>, key: IncrementKey, anchor: Anchor) {
        self.with(model, key, |inc| {
            inc.solved += 1;
            inc.anchors.push(anchor);
        });
    }
}

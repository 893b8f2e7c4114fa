//! Per-thread workspaces, one per model a thread has used: `rve_update` and the UMAT
//! allocate a workspace the first time a thread updates an instance of a model, then
//! reuse it.

use std::cell::RefCell;
use std::sync::{Arc, Weak};

use crate::model::Model;
use mesorve_core::solver::Workspace;

thread_local! {
    /// Keyed by the model's address; the weak reference keeps that address from being
    /// reused by another model while the entry exists.
    static WORKSPACES: RefCell<Vec<(Weak<Model>, Workspace)>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f` with this thread's workspace for `model`. The workspace is taken out of the
/// cache while `f` runs, so a panic inside `f` drops it instead of leaving it half-used.
///
/// Models regularized for other element lengths share the workspaces of their scene's
/// model: a graded host mesh costs no workspace per length.
pub(crate) fn with_workspace<R>(model: &Arc<Model>, f: impl FnOnce(&mut Workspace) -> R) -> R {
    let model = model.unregularized();
    let taken = WORKSPACES.with(|w| {
        let mut w = w.borrow_mut();
        match w
            .iter()
            .position(|(m, _)| std::ptr::eq(m.as_ptr(), Arc::as_ptr(model)))
        {
            Some(i) => Some(w.swap_remove(i).1),
            None => {
                w.retain(|(m, _)| m.strong_count() > 0);
                None
            }
        }
    });
    let mut ws = taken.unwrap_or_else(|| model.workspace());
    let out = f(&mut ws);
    WORKSPACES.with(|w| w.borrow_mut().push((Arc::downgrade(model), ws)));
    out
}

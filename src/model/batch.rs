//! Batches: many instances trial-updated over one host time increment, in parallel on a
//! rayon pool. The one implementation behind the C entries `rve_update_batch` and
//! `rve_update_batch_timed`, the Python package and the tests.
//!
//! Point `k` is `points[k].update_timed(strains[k], dtime, ..)` on a workspace of the
//! thread that runs it; its stress and tangent are written only when it succeeds, its
//! [`PointReport`] always. The result does not depend on the number of threads, bit for
//! bit: each point is solved alone, from its own committed state, by the same code.
//!
//! **Sharing** (`[solver] share_tolerance` in the points' scene, a consistent tangent
//! asked for; see [`super::share`]): the points are split in index order, on the calling
//! thread, into anchors and followers (a point is an anchor unless an earlier anchor of
//! the same model matches it); the anchors are solved in parallel; then, in index order,
//! each follower takes its anchor's answer corrected to first order and a trial derived
//! from the anchor's, or, when the error indicator refuses, its own solve (in parallel).
//! Every choice depends only on the inputs and the anchors' answers, so the result is
//! still the same whatever the number of threads, bit for bit. Without the key every
//! point solves, as before.

use std::any::Any;
use std::collections::HashMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Arc, LazyLock, Mutex};

use rayon::iter::Either;
use rayon::prelude::*;

use super::share::{self, Indicator};
use super::workspaces::with_workspace;
use super::{Instance, Model, Response};
use crate::error::{Error, Result};
use crate::solver::TangentRequest;

/// How far to trust an update (MGIS-style).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Reliability {
    /// The update failed; only `suggested_step_ratio` is meaningful.
    #[default]
    Failed,
    /// Converged to the scene's tolerance in one step.
    Reliable,
    /// Converged, but after bisecting the increment or to an answer that depends on the
    /// increment's size (`solver.step_check`): the host's increments are large here.
    Substepped,
}

/// What one point of a batch reports besides its stress and tangent.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct PointReport {
    /// Newton corrections, summed over sub-steps.
    pub iterations: u32,
    /// Accepted sub-steps (1 when the increment converged in one go).
    pub substeps: u32,
    /// Numeric factorizations of the RVE stiffness, including the tangent's.
    pub factorizations: u32,
    pub reliability: Reliability,
    /// `Some(j)`: the answer was taken from point `j` of the batch, corrected to first
    /// order (answer sharing, [`super::share`]); `None`: the point solved its own RVE.
    pub shared_from: Option<usize>,
    /// The ratio of the next macro increment to this one that the update suggests
    /// (UMAT's `PNEWDT`): < 1 redo smaller, 1 otherwise. On a failure it is the solver's
    /// suggestion, or 1 for a failure that a smaller step does not mend (a bad argument).
    pub suggested_step_ratio: f64,
    /// The IMPL-EX step's integration error estimate relative to `solver.step_tolerance`
    /// (`eta / tol`, see `crate::solver::implex::error_estimate`; above 1 the step
    /// exceeds the tolerance); 0 when none is estimated (no `step_tolerance`, the implicit
    /// scheme, a failed update).
    pub error_estimate: f64,
    /// Out-of-plane stress `s_zz` (plane strain; 0 in plane stress).
    pub s_zz: f64,
    /// Answered without an equilibrium solve (fast path or repeated trial).
    pub fast: bool,
}

impl PointReport {
    /// The report of a successful update.
    pub fn from_response(r: &Response) -> Self {
        PointReport {
            iterations: r.report.iterations,
            substeps: r.report.substeps,
            factorizations: r.report.factorizations,
            reliability: if r.report.substepped() {
                Reliability::Substepped
            } else {
                Reliability::Reliable
            },
            shared_from: None,
            suggested_step_ratio: r.report.suggested_step_ratio(),
            error_estimate: r.report.error_estimate.unwrap_or(0.0),
            s_zz: r.s_zz,
            fast: r.report.answer.is_fast(),
        }
    }

    /// The report of a failed update.
    pub fn failed(suggested_step_ratio: f64) -> Self {
        PointReport {
            reliability: Reliability::Failed,
            suggested_step_ratio,
            ..PointReport::default()
        }
    }
}

/// The error of one point: the library's [`Error`] or a caller's own (the C interface's
/// failures also cover bad handles and busy instances).
pub trait PointError: Send + From<Error> {
    /// The solver's suggested step ratio, when the error is a failed solve.
    fn suggested_step_ratio(&self) -> Option<f64>;
}

impl PointError for Error {
    fn suggested_step_ratio(&self) -> Option<f64> {
        match self {
            Error::Solve {
                suggested_step_ratio,
                ..
            } => Some(*suggested_step_ratio),
            _ => None,
        }
    }
}

/// A point of a batch: an [`Instance`], or whatever names one (a C handle).
pub trait BatchPoint: Send {
    type Error: PointError;
    /// Runs `f` on the point's instance, for answer sharing; `None` (the default): the
    /// point does not take part in sharing and always solves.
    fn with_instance<R>(&mut self, f: impl FnOnce(&mut Instance) -> R) -> Option<R> {
        let _ = f;
        None
    }
    /// [`Instance::update_timed`] on a workspace of the calling thread.
    fn update_point(
        &mut self,
        strain: [f64; 3],
        dtime: f64,
        request: TangentRequest,
    ) -> std::result::Result<Response, Self::Error>;
}

impl BatchPoint for Instance {
    type Error = Error;
    fn with_instance<R>(&mut self, f: impl FnOnce(&mut Instance) -> R) -> Option<R> {
        Some(f(self))
    }
    fn update_point(
        &mut self,
        strain: [f64; 3],
        dtime: f64,
        request: TangentRequest,
    ) -> Result<Response> {
        let model = Arc::clone(self.model());
        with_workspace(&model, |ws| self.update_timed(strain, dtime, ws, request))
    }
}

/// The inputs shared by every point of a batch.
#[derive(Clone, Copy, Debug)]
pub struct BatchStep {
    /// The host time increment (`DTIME`; 0 or negative: none given); must be finite.
    pub dtime: f64,
    pub request: TangentRequest,
    /// 1: the calling thread; `k > 1`: a pool of `k` threads made on first use and kept
    /// for the process; 0: rayon's global pool (one thread per core, `RAYON_NUM_THREADS`).
    pub threads: usize,
}

/// Where a batch writes: `n` entries each (`tangents` may be `None`).
pub struct BatchOutputs<'a> {
    pub stresses: &'a mut [[f64; 3]],
    pub tangents: Option<&'a mut [[f64; 9]]>,
    pub reports: &'a mut [PointReport],
}

/// The failed points of a batch, `(index, error)` in index order (empty: all succeeded).
pub type Failures<E> = Vec<(usize, E)>;

/// Trial-updates every point to its strain over one host increment (see the module
/// documentation). Returns the failed points; `Err` only when nothing was run
/// (`dtime` not finite: [`Error::HostConvention`]; the pool could not be made:
/// [`Error::Threads`]). A panic in a point becomes its [`Error::Panic`].
///
/// # Panics
/// When the slices' lengths differ from `points.len()` (9 values a tangent).
pub fn update_batch<P: BatchPoint>(
    points: &mut [P],
    strains: &[[f64; 3]],
    step: BatchStep,
    out: BatchOutputs<'_>,
) -> Result<Failures<P::Error>> {
    update_batch_with(points, strains, step, Indicator::default(), out)
}

/// [`update_batch`] with the error indicator of answer sharing chosen (for measuring
/// the choices, `docs/sharing.md`); without `share_tolerance` in the points' scenes it
/// is `update_batch`.
///
/// # Panics
/// As [`update_batch`].
pub fn update_batch_with<P: BatchPoint>(
    points: &mut [P],
    strains: &[[f64; 3]],
    step: BatchStep,
    indicator: Indicator,
    out: BatchOutputs<'_>,
) -> Result<Failures<P::Error>> {
    let n = points.len();
    assert!(
        strains.len() == n
            && out.stresses.len() == n
            && out.reports.len() == n
            && out.tangents.as_ref().is_none_or(|t| t.len() == n),
        "update_batch: every slice needs one entry per point"
    );
    if !step.dtime.is_finite() {
        return Err(Error::HostConvention(format!(
            "dtime {} is not finite",
            step.dtime
        )));
    }
    let plan = if step.request == TangentRequest::Consistent {
        share_plan(points, strains)
    } else {
        None
    };
    if let Some(plan) = plan {
        let run = |pts: &mut [P]| shared(pts, strains, step, indicator, &plan, out);
        return Ok(match step.threads {
            1 | 0 => run(points),
            k => pool(k)?.install(|| run(points)),
        });
    }
    Ok(match step.threads {
        1 => sequential(points, strains, step, out),
        0 => parallel(points, strains, step, out),
        k => pool(k)?.install(|| parallel(points, strains, step, out)),
    })
}

/// One point's outputs: stress, tangent, report.
type PointOut<'a> = (
    &'a mut [f64; 3],
    Option<&'a mut [f64; 9]>,
    &'a mut PointReport,
);

/// Point `k`'s update; a panic becomes [`Error::Panic`].
fn solve_point<P: BatchPoint>(
    point: &mut P,
    strain: [f64; 3],
    step: BatchStep,
) -> std::result::Result<Response, P::Error> {
    catch_unwind(AssertUnwindSafe(|| {
        point.update_point(strain, step.dtime, step.request)
    }))
    .unwrap_or_else(|payload| Err(Error::Panic(panic_message(payload.as_ref())).into()))
}

/// Writes point `k`'s outcome; its failure, if any.
fn write_point<E: PointError>(
    k: usize,
    outcome: std::result::Result<Response, E>,
    shared_from: Option<usize>,
    (stress, tangent, report): PointOut<'_>,
) -> Option<(usize, E)> {
    match outcome {
        Ok(r) => {
            *stress = r.stress;
            if let Some(t) = tangent {
                *t = r.tangent;
            }
            *report = PointReport::from_response(&r);
            report.shared_from = shared_from;
            None
        }
        Err(e) => {
            *report = PointReport::failed(e.suggested_step_ratio().unwrap_or(1.0));
            Some((k, e))
        }
    }
}

/// Point `k`; its failure, if any. A panic becomes [`Error::Panic`].
fn run_point<P: BatchPoint>(
    k: usize,
    point: &mut P,
    strain: [f64; 3],
    step: BatchStep,
    out: PointOut<'_>,
) -> Option<(usize, P::Error)> {
    write_point(k, solve_point(point, strain, step), None, out)
}

/// A point's outcome in a sharing batch (`None`: not run in this pass).
type Outcome<E> = Option<std::result::Result<Response, E>>;

/// For answer sharing: each point's anchor (`Some(j)`, `j < k`) or `None` (it solves),
/// chosen in index order (a point is an anchor unless an earlier anchor of the same model
/// matches it, [`share::strains_close`] and [`share::states_close`]); `None` when no
/// point's scene asks for sharing.
fn share_plan<P: BatchPoint>(points: &mut [P], strains: &[[f64; 3]]) -> Option<Vec<Option<usize>>> {
    let models: Vec<Option<(Arc<Model>, f64)>> = points
        .iter_mut()
        .map(|p| {
            p.with_instance(|i| share::tolerance(i.model()).map(|t| (i.model().clone(), t)))
                .flatten()
        })
        .collect();
    if models.iter().all(Option::is_none) {
        return None;
    }
    let mut plan = vec![None; points.len()];
    let mut anchors: Vec<usize> = Vec::new();
    for k in 0..points.len() {
        let Some((model, tol)) = &models[k] else {
            continue;
        };
        let (left, right) = points.split_at_mut(k);
        let me = &mut right[0];
        let found = anchors.iter().copied().find(|&j| {
            let same = models[j]
                .as_ref()
                .is_some_and(|(m, _)| share::same_model(model, m));
            same && share::strains_close(*tol, &strains[k], &strains[j])
                && left[j]
                    .with_instance(|a| {
                        me.with_instance(|b| {
                            share::states_close(*tol, b.committed(), a.committed())
                        })
                    })
                    .flatten()
                    .unwrap_or(false)
        });
        match found {
            Some(j) => plan[k] = Some(j),
            None => anchors.push(k),
        }
    }
    Some(plan)
}

/// Solves the points of `mask`, in parallel or on the calling thread.
fn solve_set<P: BatchPoint>(
    points: &mut [P],
    strains: &[[f64; 3]],
    step: BatchStep,
    mask: &[bool],
) -> Vec<Outcome<P::Error>> {
    let solve = |(point, (strain, m)): (&mut P, (&[f64; 3], &bool))| {
        m.then(|| solve_point(point, *strain, step))
    };
    if step.threads == 1 {
        points
            .iter_mut()
            .zip(strains.iter().zip(mask))
            .map(solve)
            .collect()
    } else {
        let pairs = strains.par_iter().zip(mask.par_iter());
        points.par_iter_mut().zip(pairs).map(solve).collect()
    }
}

/// Follower `k` takes anchor `j`'s answer (`anchor`), corrected to first order, and a
/// trial derived from the anchor's, unless the error indicator refuses (`None`).
fn follow<P: BatchPoint>(
    points: &mut [P],
    (k, j): (usize, usize),
    strains: &[[f64; 3]],
    step: BatchStep,
    indicator: Indicator,
    anchor: &Response,
) -> Option<Response> {
    let (left, right) = points.split_at_mut(k);
    let (eps, eps_a) = (strains[k], strains[j]);
    left[j]
        .with_instance(|a| {
            let tol = share::tolerance(a.model())?;
            let (switched, grew) = (a.trial_switched(), share::grew(tol, a));
            if !share::keeps_share(indicator, tol, anchor, &eps_a, &eps, switched, grew) {
                return None;
            }
            let r = share::corrected(anchor, &eps_a, &eps);
            let adopt = |b: &mut Instance| b.adopt_trial(a, eps, step.dtime, step.request, r);
            right[0].with_instance(adopt)?.ok().map(|_| r)
        })
        .flatten()
}

/// The sharing batch (see the module documentation): anchors, then followers.
fn shared<P: BatchPoint>(
    points: &mut [P],
    strains: &[[f64; 3]],
    step: BatchStep,
    indicator: Indicator,
    plan: &[Option<usize>],
    out: BatchOutputs<'_>,
) -> Failures<P::Error> {
    let n = points.len();
    let anchors: Vec<bool> = plan.iter().map(Option::is_none).collect();
    let mut results = solve_set(points, strains, step, &anchors);
    let mut own = vec![false; n];
    let mut shared_from = vec![None; n];
    for k in 0..n {
        let Some(j) = plan[k] else {
            continue;
        };
        let anchor = match &results[j] {
            Some(Ok(r)) => Some(*r),
            _ => None,
        };
        match anchor.and_then(|a| follow(points, (k, j), strains, step, indicator, &a)) {
            Some(r) => {
                results[k] = Some(Ok(r));
                shared_from[k] = Some(j);
            }
            None => own[k] = true,
        }
    }
    let again = solve_set(points, strains, step, &own);
    let mut tangents = out.tangents.map(|t| t.iter_mut());
    let outs = out.stresses.iter_mut().zip(out.reports.iter_mut());
    let mut failures = Vec::new();
    for (k, ((first, second), (stress, report))) in
        results.into_iter().zip(again).zip(outs).enumerate()
    {
        let tangent = tangents.as_mut().and_then(Iterator::next);
        let outcome = second
            .or(first)
            .unwrap_or_else(|| Err(Error::NoTrial.into()));
        failures.extend(write_point(
            k,
            outcome,
            shared_from[k],
            (stress, tangent, report),
        ));
    }
    failures
}

fn sequential<P: BatchPoint>(
    points: &mut [P],
    strains: &[[f64; 3]],
    step: BatchStep,
    out: BatchOutputs<'_>,
) -> Failures<P::Error> {
    let mut tangents = out.tangents.map(|t| t.iter_mut());
    points
        .iter_mut()
        .zip(strains)
        .zip(out.stresses.iter_mut().zip(out.reports.iter_mut()))
        .enumerate()
        .filter_map(|(k, ((point, strain), (stress, report)))| {
            let tangent = tangents.as_mut().and_then(Iterator::next);
            run_point(k, point, *strain, step, (stress, tangent, report))
        })
        .collect()
}

fn parallel<P: BatchPoint>(
    points: &mut [P],
    strains: &[[f64; 3]],
    step: BatchStep,
    out: BatchOutputs<'_>,
) -> Failures<P::Error> {
    let n = points.len();
    let tangents = match out.tangents {
        Some(t) => Either::Left(t.par_iter_mut().map(Some)),
        None => Either::Right((0..n).into_par_iter().map(|_| None)),
    };
    points
        .par_iter_mut()
        .zip(strains)
        .zip(out.stresses.par_iter_mut().zip(out.reports.par_iter_mut()))
        .zip(tangents)
        .enumerate()
        .filter_map(|(k, (((point, strain), (stress, report)), tangent))| {
            run_point(k, point, *strain, step, (stress, tangent, report))
        })
        .collect()
}

static POOLS: LazyLock<Mutex<HashMap<usize, Arc<rayon::ThreadPool>>>> =
    LazyLock::new(|| Mutex::new(HashMap::new()));

/// A pool of `n` threads, built once per size and kept for the process.
fn pool(n: usize) -> Result<Arc<rayon::ThreadPool>> {
    let mut pools = POOLS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(p) = pools.get(&n) {
        return Ok(p.clone());
    }
    let p = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .thread_name(|i| format!("rve-batch-{i}"))
        .build()
        .map_err(|e| Error::Threads(e.to_string()))?;
    let p = Arc::new(p);
    pools.insert(n, p.clone());
    Ok(p)
}

/// The message a panic carried (a `&str` or `String` payload).
pub(crate) fn panic_message(payload: &(dyn Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "non-string panic payload".into())
}

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
//! each follower takes its anchor's answer corrected to first order (implicit
//! integration, when the error indicator allows) or its IMPL-EX step; the followers that
//! took a step answer on it, and those the indicator refused solve, in parallel.
//! Every choice depends only on the inputs and the anchors' answers, so the result is
//! still the same whatever the number of threads, bit for bit. Without the key every
//! point solves, as before.

use std::any::Any;
use std::collections::HashMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Arc, LazyLock, Mutex};

use rayon::iter::Either;
use rayon::prelude::*;

use super::share::{self, AdoptedStep, Follow, StepSignature};
use super::workspaces::with_workspace;
use super::{Instance, Model, Response};
use crate::error::{Error, Result};
use mesorve_core::solver::{implex, Integration, TangentRequest};
use mesorve_core::state::State;

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
    /// (`eta / tol`, see `mesorve_core::solver::implex::error_estimate`; above 1 the step
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
        share_plan(points, strains, step.dtime)
    } else {
        None
    };
    if let Some(plan) = plan {
        let run = |pts: &mut [P]| shared(pts, strains, step, &plan, out);
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

/// What a point of a sharing batch is compared by: its model and tolerance, and under
/// IMPL-EX the step ratio (bits) and signature of its next step.
struct Sharer {
    model: Arc<Model>,
    tol: f64,
    step: Option<(u64, Arc<StepSignature>)>,
}

impl Sharer {
    /// `None`: the point does not share (no instance, no `share_tolerance`).
    fn of(instance: &Instance, dtime: f64) -> Option<Self> {
        let model = instance.model();
        let tol = share::tolerance(model)?;
        let solver = &model.solver;
        let step = (solver.integration == Integration::Implex && solver.fast_path).then(|| {
            let ratio = implex::step_ratio(instance.committed().implex.step, dtime);
            let signature = StepSignature::of(model, &instance.committed_core_view(), ratio);
            (ratio.to_bits(), Arc::new(signature))
        });
        Some(Sharer {
            model: model.clone(),
            tol,
            step,
        })
    }
}

/// For sharing: each point's anchor (`Some(j)`, `j < k`) or `None` (it solves), chosen in
/// index order (a point is an anchor unless an earlier anchor of the same model matches
/// it: under IMPL-EX by [`share::steps_match`], else by [`share::strains_close`] and
/// [`share::states_close`]); `None` when no point's scene asks for sharing.
fn share_plan<P: BatchPoint>(points: &mut [P], strains: &[[f64; 3]], dtime: f64) -> Option<Plan> {
    let sharers: Vec<Option<Sharer>> = points
        .iter_mut()
        .map(|p| p.with_instance(|i| Sharer::of(i, dtime)).flatten())
        .collect();
    if sharers.iter().all(Option::is_none) {
        return None;
    }
    let mut plan = vec![None; points.len()];
    let mut anchors: Vec<usize> = Vec::new();
    for k in 0..points.len() {
        let Some(me) = &sharers[k] else {
            continue;
        };
        let (left, right) = points.split_at_mut(k);
        let point = &mut right[0];
        // `twin`: the committed states the same to round-off (IMPL-EX) or bit for bit and
        // the strains the same to round-off (implicit), which is tried first: a twin may
        // follow where another point may not (`share::follows`, `share::keeps_step`).
        let mut matches = |j: usize, a: &Sharer, twin: bool| {
            let mut both = |f: &dyn Fn(&State, &State) -> bool| {
                let pair = left[j]
                    .with_instance(|a| point.with_instance(|b| f(b.committed(), a.committed())));
                pair.flatten().unwrap_or(false)
            };
            match (&me.step, &a.step) {
                (Some((ratio, signature)), Some((ratio_a, signature_a))) => {
                    let scale = share::secant_scale(&me.model);
                    ratio == ratio_a
                        && signature.close(signature_a, me.tol, scale)
                        && both(&|b, a| {
                            share::steps_match(b, a)
                                && (!twin || share::states_close(share::ROUND_OFF, b, a))
                        })
                }
                (None, None) => {
                    let (tol, strain_tol) = if twin {
                        (0.0, share::ROUND_OFF)
                    } else {
                        (me.tol, me.tol)
                    };
                    share::strains_close(strain_tol, &strains[k], &strains[j])
                        && both(&|b, a| share::states_close(tol, b, a))
                }
                _ => false,
            }
        };
        let mut find = |twin: bool| {
            anchors.iter().copied().find(|&j| {
                sharers[j]
                    .as_ref()
                    .is_some_and(|a| share::same_model(&me.model, &a.model) && matches(j, a, twin))
            })
        };
        let found = find(true).or_else(|| find(false));
        match found {
            Some(j) => plan[k] = Some(j),
            None => anchors.push(k),
        }
    }
    Some(Plan {
        anchor: plan,
        sharers,
    })
}

/// Each point's anchor (`None`: it solves) and what it was compared by.
struct Plan {
    anchor: Vec<Option<usize>>,
    sharers: Vec<Option<Sharer>>,
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

/// What a follower whose anchor's answer it does not take does in the second pass.
enum Pass {
    /// It took the anchor's IMPL-EX step and answers on it.
    Step,
    /// It solves its own RVE.
    Solve,
}

/// Follower `k` after its anchor `j` answered `anchor`: under IMPL-EX it takes the
/// anchor's step ([`Instance::adopt_step`]); else the anchor's answer corrected to first
/// order with a trial of its own ([`share::follows`]), unless the error indicator refuses:
/// `Ok` the answer taken, `Err` what the second pass does.
fn follow<P: BatchPoint>(
    points: &mut [P],
    (k, j): (usize, usize),
    strains: &[[f64; 3]],
    (step, plan): (BatchStep, &Plan),
    anchor: &Response,
) -> std::result::Result<Response, Pass> {
    let (left, right) = points.split_at_mut(k);
    let (eps, eps_a) = (strains[k], strains[j]);
    let signature = |p: usize| plan.sharers[p].as_ref().and_then(|s| s.step.as_ref());
    let followed = left[j].with_instance(|a| {
        right[0].with_instance(|b| {
            let tol = share::tolerance(a.model())?;
            if let Some((implex_step, ratio)) = a.implex_step() {
                let ((_, own), (_, theirs)) = (signature(k)?, signature(j)?);
                let adopted = AdoptedStep {
                    own: own.clone(),
                    anchor: theirs.clone(),
                    anchor_strain: eps_a,
                    twin: share::states_close(share::ROUND_OFF, b.committed(), a.committed()),
                };
                let taken = b.adopt_step(implex_step, ratio, step.dtime, adopted);
                return taken.then_some(Err(Pass::Step));
            }
            let twin = share::states_close(0.0, b.committed(), a.committed());
            let r = share::corrected(anchor, &eps_a, &eps);
            match share::follows(tol, anchor, &eps_a, &eps, twin, a.trial_is_still())? {
                Follow::Twin => b.adopt_trial(a, eps, step.dtime, step.request, r).ok()?,
                Follow::Own => b.keep_own_trial(eps, step.dtime, step.request, r),
            }
            Some(Ok(r))
        })
    });
    followed.flatten().flatten().unwrap_or(Err(Pass::Solve))
}

/// The sharing batch (see the module documentation): anchors, then followers.
fn shared<P: BatchPoint>(
    points: &mut [P],
    strains: &[[f64; 3]],
    step: BatchStep,
    plan: &Plan,
    out: BatchOutputs<'_>,
) -> Failures<P::Error> {
    let n = points.len();
    let anchors: Vec<bool> = plan.anchor.iter().map(Option::is_none).collect();
    let mut results = solve_set(points, strains, step, &anchors);
    let mut again = vec![false; n];
    let mut shared_from = vec![None; n];
    for k in 0..n {
        let Some(j) = plan.anchor[k] else {
            continue;
        };
        let followed = match &results[j] {
            Some(Ok(r)) => {
                let r = *r;
                follow(points, (k, j), strains, (step, plan), &r)
            }
            _ => Err(Pass::Solve),
        };
        match followed {
            Ok(r) => {
                results[k] = Some(Ok(r));
                shared_from[k] = Some(j);
            }
            Err(Pass::Step) => {
                again[k] = true;
                shared_from[k] = Some(j);
            }
            Err(Pass::Solve) => again[k] = true,
        }
    }
    let second = solve_set(points, strains, step, &again);
    // A follower whose adopted step the indicator refused (`Instance::implex`) solved its
    // own.
    for (k, from) in shared_from.iter_mut().enumerate() {
        if second[k].is_some() && from.is_some() {
            let kept = points[k].with_instance(|b| b.on_adopted_step());
            if kept != Some(true) {
                *from = None;
            }
        }
    }
    let mut tangents = out.tangents.map(|t| t.iter_mut());
    let outs = out.stresses.iter_mut().zip(out.reports.iter_mut());
    let mut failures = Vec::new();
    for (k, ((first, second), (stress, report))) in
        results.into_iter().zip(second).zip(outs).enumerate()
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

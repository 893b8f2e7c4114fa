//! The shared model of one scene: mesh, materials, constraint map, sparsity pattern,
//! symbolic factorization, homogenization operators and the elastic tangent.

use std::borrow::Cow;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use super::fingerprint::{regularized_fingerprint, scene_fingerprint};
use super::from_scene::{interface_law, paste_law, with_friction};
use super::microstructure::build_microstructure;
use crate::error::{Error, Result};
use crate::scene::{Scene, MAX_STRAIN};
use mesorve_core::assembly::{Discretization, DiscretizationSpec};
use mesorve_core::constraint::BoundaryCondition;
use mesorve_core::homogenization::Homogenizer;
use mesorve_core::mesh::{Mesh, MeshStats, Microstructure};
use mesorve_core::solver::{
    fast_path, implex, solve_increment, step_check, Answer, IncrementReport, Integration,
    LinearSolver, Problem, Settings, TangentRequest, Workspace,
};
use mesorve_core::state::{statev, State};

static NEXT_MODEL_ID: AtomicU64 = AtomicU64::new(1);

/// Result of an update: homogenized stress, tangent and counters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Response {
    /// `[s_xx, s_yy, s_xy]`.
    pub stress: [f64; 3],
    /// Row-major `d stress_i / d strain_j` (zeros when not requested).
    pub tangent: [f64; 9],
    /// Out-of-plane stress (plane strain; 0 in plane stress).
    pub s_zz: f64,
    /// `d s_zz / d strain_j`, the out-of-plane row of the consistent tangent (zeros in
    /// plane stress and when no tangent was requested); see `Homogenizer::szz_tangent`.
    pub s_zz_tangent: [f64; 3],
    pub report: IncrementReport,
}

/// Everything that instances of one scene share. Immutable once built; read it through
/// its methods.
pub struct Model {
    pub(super) id: u64,
    pub(crate) scene: Scene,
    pub(crate) microstructure: Arc<Microstructure>,
    pub(crate) disc: Discretization,
    pub(crate) hom: Arc<Homogenizer>,
    /// Symbolic LL^T and LU analyses of the pattern.
    pub(crate) linear: Arc<LinearSolver>,
    pub(crate) solver: Settings,
    /// Homogenized tangent of the virgin RVE (row-major), and its `s_zz` row.
    pub(crate) elastic_tangent: [f64; 9],
    pub(crate) elastic_s_zz_tangent: [f64; 3],
    /// `-K_el^-1 G` of the virgin RVE (n x 3): the solver's predictor.
    pub(crate) elastic_sensitivity: Arc<[f64]>,
    /// What gives this model's states their meaning (`fingerprint`): states of another
    /// fingerprint are refused.
    pub(crate) fingerprint: u64,
    /// `STATEV` entries a host needs for this model's state (`Model::statev_len`).
    pub(crate) statev_len: usize,
    /// The unit of IMPL-EX step sharing's similarity (`share::secant_scale`).
    pub(crate) secant_scale: f64,
    /// For a model regularized by a host element's size ([`Model::regularized`]): the
    /// scene's own model, whose mesh, operators and per-thread workspaces it shares, and
    /// the element's length.
    pub(crate) regularizes: Option<(Arc<Model>, f64)>,
}

impl std::fmt::Debug for Model {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Model")
            .field("id", &self.id)
            .field("unknowns", &self.disc.n())
            .field("interfaces", &self.disc.interfaces.len())
            .finish()
    }
}

impl Model {
    /// Meshes the scene and builds everything instances share.
    pub fn from_scene(scene: &Scene) -> Result<Self> {
        let microstructure = build_microstructure(scene)?;
        Self::from_mesh(scene, microstructure)
    }

    /// Builds the model on an already built microstructure (tests, custom meshes).
    pub fn from_mesh(scene: &Scene, microstructure: Microstructure) -> Result<Self> {
        let spec = &scene.spec;
        let boundary = spec.boundary.kind;
        let mesh: &Mesh = &microstructure.mesh;
        if boundary == BoundaryCondition::Periodic && !mesh.boundary.sides_match {
            return Err(Error::scene(
                "boundary.kind",
                "periodic needs matching nodes on opposite sides, and this mesh has none",
            ));
        }
        let disc = Discretization::new(
            mesh,
            &DiscretizationSpec {
                analysis: spec.cell.analysis,
                matrix: spec.materials.matrix,
                aggregate: spec.materials.aggregate.unwrap_or(spec.materials.matrix),
                law: interface_law(spec)
                    .map(|law| with_friction(spec, law))
                    .transpose()?,
                paste_law: paste_law(spec)
                    .map(|law| with_friction(spec, law))
                    .transpose()?,
                quadrature: spec.mesh.interface_quadrature,
                boundary,
            },
        )?;
        let hom = Homogenizer::new(&disc);
        let spd_possible = boundary != BoundaryCondition::Minimal;
        let linear = if spec.effects.friction {
            LinearSolver::for_non_symmetric(&disc.pattern.symbolic, spd_possible)?
        } else {
            LinearSolver::new(&disc.pattern.symbolic, spd_possible)?
        };
        let mut model = Model {
            id: NEXT_MODEL_ID.fetch_add(1, Ordering::Relaxed),
            scene: scene.clone(),
            microstructure: Arc::new(microstructure),
            disc,
            hom: Arc::new(hom),
            linear: Arc::new(linear),
            solver: spec.solver,
            elastic_tangent: [0.0; 9],
            elastic_s_zz_tangent: [0.0; 3],
            elastic_sensitivity: Arc::new([]),
            fingerprint: scene_fingerprint(scene)?,
            statev_len: 0,
            secant_scale: 0.0,
            regularizes: None,
        };
        model.statev_len = statev::values_needed(
            model.state_sizes(),
            model.disc.interface_points(),
            model.solver.integration == Integration::Implex,
        );
        // The virgin tangent: one converged "update" at zero strain.
        let mut ws = model.workspace();
        let state = model.new_state();
        let mut trial = model.new_state();
        let response = model.update(
            &state,
            [0.0; 3],
            &mut ws,
            &mut trial,
            TangentRequest::Consistent,
        )?;
        model.elastic_tangent = response.tangent;
        model.elastic_s_zz_tangent = response.s_zz_tangent;
        model.elastic_sensitivity = ws.factorization().kg().iter().map(|v| -v).collect();
        model.secant_scale = super::share::virgin_secant_scale(&model);
        Ok(model)
    }

    /// A virgin state for a new instance.
    pub fn new_state(&self) -> State {
        State::virgin(self.disc.n(), self.disc.history_len())
    }

    /// A workspace for one thread (sized for the scene's own model, which a regularized
    /// one shares).
    pub fn workspace(&self) -> Workspace {
        Workspace::new(
            &self.disc,
            &self.linear,
            self.solver
                .max_iterations
                .max(self.solver.max_secant_iterations) as usize,
            self.workspace_id(),
        )
    }

    /// The id of the model whose workspaces this one uses: its own, or that of the
    /// scene's model it regularizes.
    pub(crate) fn workspace_id(&self) -> u64 {
        self.regularizes.as_ref().map_or(self.id, |(m, _)| m.id)
    }

    /// The scene's own model: this one, or the one it regularizes.
    pub(crate) fn unregularized(self: &Arc<Self>) -> &Arc<Model> {
        self.regularizes.as_ref().map_or(self, |(m, _)| m)
    }

    /// The host element's length this model is regularized for, if it is.
    pub fn element_length(&self) -> Option<f64> {
        self.regularizes.as_ref().map(|&(_, h)| h)
    }

    /// This scene's model regularized for a host element of characteristic length
    /// `element_length` (the scene's length unit), the crack band of Bažant & Oh (1983)
    /// applied to the cell: every interface law's softening is stretched by
    /// `s = L_cell / h` (`L_cell = sqrt(V)`, the cell's side), so that the cell dissipates
    /// `G_cell / h` per unit volume and a host element of size `h` crossed by one crack
    /// dissipates the cell's fracture energy per unit crack length, whatever `h`. The
    /// strength and the response before the peak are the scene's. Needs
    /// `effects.regularization`. It shares the mesh, operators, factorization analyses and
    /// workspaces of the scene's model; its laws are its own, and so is its fingerprint
    /// (a state of one element length is refused at another).
    pub fn regularized(self: &Arc<Self>, element_length: f64) -> Result<Model> {
        let base = self.unregularized();
        if !base.scene.spec.effects.regularization {
            return Err(Error::scene(
                "effects.regularization",
                format!(
                    "a host element length ({element_length}) was given and the scene does \
                     not regularize: set `[effects] regularization = true`, or pass no length"
                ),
            ));
        }
        if !(element_length.is_finite() && element_length > 0.0) {
            return Err(Error::scene(
                "element length",
                format!("{element_length}: the host element's length must be a positive number"),
            ));
        }
        let scale = base.disc.volume.sqrt() / element_length;
        let laws = base.disc.law.as_ref().map(|l| l.regularized(scale));
        Ok(Model {
            id: NEXT_MODEL_ID.fetch_add(1, Ordering::Relaxed),
            scene: base.scene.clone(),
            microstructure: base.microstructure.clone(),
            disc: match laws {
                Some(laws) => base.disc.with_laws(laws),
                None => base.disc.clone(),
            },
            hom: base.hom.clone(),
            linear: base.linear.clone(),
            solver: base.solver,
            elastic_tangent: base.elastic_tangent,
            elastic_s_zz_tangent: base.elastic_s_zz_tangent,
            elastic_sensitivity: base.elastic_sensitivity.clone(),
            fingerprint: regularized_fingerprint(base.fingerprint, element_length),
            statev_len: base.statev_len,
            secant_scale: base.secant_scale,
            regularizes: Some((base.clone(), element_length)),
        })
    }

    /// The mesh (for the writers of [`crate::io`]).
    pub fn mesh(&self) -> &Mesh {
        &self.microstructure.mesh
    }

    /// The scene the model was built from.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Homogenized tangent of the virgin RVE, row-major `d sigma_i / d eps_j`.
    pub fn elastic_tangent(&self) -> [f64; 9] {
        self.elastic_tangent
    }

    /// Number of unknowns of the RVE's linear systems (displacements and multipliers).
    pub fn unknowns(&self) -> usize {
        self.disc.n()
    }

    /// Number of interface (ITZ) elements.
    pub fn interface_elements(&self) -> usize {
        self.disc.interfaces.len()
    }

    /// Counts and quality figures of the mesh.
    pub fn mesh_stats(&self) -> MeshStats {
        MeshStats::of(&self.microstructure.mesh)
    }

    /// The fingerprint of what gives this model's states their meaning: the scene after a
    /// host's `PROPS`, a Gmsh file's content, the integration (see `fingerprint`), a
    /// number below 2^40 that `rve info` prints and the state refusals name.
    pub fn fingerprint(&self) -> u64 {
        self.fingerprint
    }

    /// How the interface history is integrated (`[solver] integration`).
    pub fn integration(&self) -> Integration {
        self.solver.integration
    }

    /// Trial update: solves the RVE at macro strain `strain` starting from `committed`,
    /// writes the converged trial state into `trial`, and returns the homogenized stress
    /// and (if asked) the consistent tangent. Never modifies `committed`; identical inputs
    /// give bit-identical outputs.
    ///
    /// The trial keeps the fast path's data (`mesorve_core::state::LinearBranch`) when every
    /// interface point ends on a linear branch and the tangent was requested; this
    /// function always solves ([`Model::fast_update`] is the fast path).
    pub fn update(
        &self,
        committed: &State,
        strain: [f64; 3],
        ws: &mut Workspace,
        trial: &mut State,
        request: TangentRequest,
    ) -> Result<Response> {
        if ws.model_id() != self.workspace_id() {
            return Err(Error::WorkspaceMismatch);
        }
        check_strain(strain)?;
        let problem = self.problem();
        let solved = solve_increment(&problem, committed, strain, request, ws, trial)?;
        let tangent = match request {
            TangentRequest::Consistent => self.hom.tangent_from_condensed(&solved.condensed),
            TangentRequest::None | TangentRequest::Elastic => [0.0; 9],
        };
        let (stress, s_zz) = self.hom.stress(&self.disc, &strain, &trial.unknowns);
        // A consistent update leaves X = K^-1 G of the converged state in the workspace.
        let s_zz_tangent = match request {
            TangentRequest::Consistent => self.hom.szz_tangent(ws.factorization().kg()),
            TangentRequest::None | TangentRequest::Elastic => [0.0; 3],
        };
        // A converged residual does not exclude overflow in the tangent or the stress
        // (material constants near the ends of the f64 range): never hand out NaN.
        let mut outputs = stress.iter().chain(&tangent).chain(&s_zz_tangent);
        if !(outputs.all(|v| v.is_finite()) && s_zz.is_finite()) {
            return Err(Error::Solve {
                reason: format!(
                    "the homogenized stress {stress:?} or tangent is not finite (NaN or \
                     infinite): the scene's material constants are out of floating-point \
                     range for this RVE"
                ),
                depth: 0,
                suggested_step_ratio: 0.5,
            });
        }
        if request == TangentRequest::Consistent {
            fast_path::build(&problem, trial, tangent, s_zz_tangent, ws);
        }
        let mut report = solved.report;
        if step_check::applies(
            &problem,
            committed,
            trial,
            report.substeps,
            report.limit_points,
        ) {
            (report.step_too_large, report.check_factorizations) =
                step_check::depends_on_step(&problem, committed, strain, trial, ws);
        }
        Ok(Response {
            stress,
            tangent,
            s_zz,
            s_zz_tangent,
            report,
        })
    }

    /// An IMPL-EX update at `strain` from `committed` for a host time increment `dt` (0:
    /// none, see `mesorve_core::solver::implex`). With `reuse`, `trial.linear` already holds the
    /// step of this `committed` state and this `dt` ratio, and the answer costs no
    /// factorization; otherwise the step is assembled and factorized once and kept there.
    /// Never modifies `committed`. The tangent is the step's `D_ex`, symmetric positive
    /// definite; it is returned whatever `request` (it costs nothing more).
    pub fn implex_update(
        &self,
        committed: &State,
        strain: [f64; 3],
        dt: f64,
        ws: &mut Workspace,
        trial: &mut State,
        reuse: bool,
    ) -> Result<Response> {
        if ws.model_id() != self.workspace_id() {
            return Err(Error::WorkspaceMismatch);
        }
        check_strain(strain)?;
        let problem = self.problem();
        let mut factorizations = 0;
        if !reuse {
            let ratio = implex::step_ratio(committed.implex.step, dt);
            let condensed = implex::factorize_step(&problem, committed, ratio, ws)?;
            // `D_ex` is symmetric (eq. 18 with `K_ex` symmetric): its symmetric part
            // removes the round-off of `G^T K_ex^-1 G`, and the stress `D_ex eps` is
            // formed with the same matrix, so the tangent stays its exact derivative.
            let mut tangent = self.hom.tangent_from_condensed(&condensed);
            for (i, j) in [(0, 1), (0, 2), (1, 2)] {
                let mean = 0.5 * (tangent[3 * i + j] + tangent[3 * j + i]);
                (tangent[3 * i + j], tangent[3 * j + i]) = (mean, mean);
            }
            let szz = self.hom.szz_tangent(ws.factorization().kg());
            if !tangent.iter().chain(&szz).all(|v| v.is_finite()) {
                return Err(Error::Solve {
                    reason: "the IMPL-EX step's homogenized tangent is not finite: the \
                             scene's material constants are out of floating-point range"
                        .into(),
                    depth: 0,
                    suggested_step_ratio: 0.5,
                });
            }
            implex::store_step(&problem, trial, &strain, tangent, szz, ws);
            factorizations = 1;
        }
        let mut report = implex::finish_step(&problem, committed, &strain, dt, trial);
        report.factorizations = factorizations;
        if reuse {
            report.answer = Answer::FastPath;
        }
        let (stress, s_zz) = fast_path::response(&trial.linear, &strain);
        if let Some(tolerance) = self.solver.step_tolerance {
            let ratio = implex::step_ratio(committed.implex.step, dt);
            let eta = implex::error_estimate(&problem, committed, trial, ratio, &strain);
            report.error_estimate = Some(eta / tolerance);
            if let Some(smallest) = self.solver.smallest_step {
                report.smallest_ratio = if dt > 0.0 {
                    smallest / dt
                } else {
                    f64::INFINITY
                };
            }
        }
        Ok(Response {
            stress,
            tangent: trial.linear.tangent,
            s_zz,
            s_zz_tangent: trial.linear.szz,
            report,
        })
    }

    /// The fast path's answer at `strain` from `committed` (see `mesorve_core::solver::fast_path`):
    /// `Some` when every interface point provably stays on the linear branch of the
    /// committed state's branch set, `None` when the update needs a solve. Exact to
    /// round-off against [`Model::update`]; the trial state is `committed` at `strain`
    /// with the same history (no buffers needed). Allocates nothing.
    pub fn fast_update(
        &self,
        committed: &State,
        strain: [f64; 3],
        request: TangentRequest,
    ) -> Result<Option<Response>> {
        check_strain(strain)?;
        let linear = &committed.linear;
        if !fast_path::answers(&self.problem(), &committed.history, linear, &strain) {
            return Ok(None);
        }
        let (stress, s_zz) = fast_path::response(linear, &strain);
        let (tangent, s_zz_tangent) = match request {
            TangentRequest::Consistent => (linear.tangent, linear.szz),
            TangentRequest::None | TangentRequest::Elastic => ([0.0; 9], [0.0; 3]),
        };
        let contact = linear.closed.iter().filter(|&&c| c).count();
        Ok(Some(Response {
            stress,
            tangent,
            s_zz,
            s_zz_tangent,
            report: IncrementReport {
                unloading: linear.closed.len() - contact,
                contact,
                answer: Answer::FastPath,
                ..Default::default()
            },
        }))
    }

    /// `state` with its unknowns at its own strain: itself, or (after fast updates, see
    /// `mesorve_core::state::LinearBranch`) a copy with `X_b eps` formed, which costs one
    /// factorization in a workspace made for it. For outputs, not for the hot path.
    pub fn current_state<'s>(&self, state: &'s State) -> Result<Cow<'s, State>> {
        if state.unknowns_are_current() {
            return Ok(Cow::Borrowed(state));
        }
        let mut ws = self.workspace();
        let mut out = self.new_state();
        if self.solver.integration == Integration::Implex {
            // The fluctuation of an IMPL-EX state is `X_ex eps` with its step's frozen
            // branches: rebuilt when the step extrapolated no growth.
            if implex::materialize(&self.problem(), state, &mut out, &mut ws)? {
                return Ok(Cow::Owned(out));
            }
            return Err(Error::Solve {
                reason: "the fluctuation of this IMPL-EX state was formed at another strain of \
                         a step that extrapolated the history's growth, which the state no \
                         longer holds; write outputs after an update that factorized its step"
                    .into(),
                depth: 0,
                suggested_step_ratio: 1.0,
            });
        }
        fast_path::materialize(&self.problem(), state, &mut out, &mut ws)?;
        Ok(Cow::Owned(out))
    }

    /// The problem the solver sees.
    pub(crate) fn problem(&self) -> Problem<'_> {
        Problem {
            disc: &self.disc,
            linear: &self.linear,
            settings: &self.solver,
            predictor: &self.elastic_sensitivity,
        }
    }
}

/// Refuses a strain that is not finite or beyond the small-strain range.
fn check_strain(strain: [f64; 3]) -> Result<()> {
    if strain.iter().any(|e| !e.is_finite()) {
        return Err(Error::BadStrain {
            strain,
            reason: "not finite".into(),
        });
    }
    if strain.iter().any(|e| e.abs() > MAX_STRAIN) {
        return Err(Error::BadStrain {
            strain,
            reason: format!("a component exceeds {MAX_STRAIN} (small-strain model)"),
        });
    }
    Ok(())
}

/// The model's parts in the core's types (the verification tests and benches check the
/// kernels and factorizations of a built model through them).
impl Model {
    pub fn microstructure(&self) -> &Microstructure {
        &self.microstructure
    }

    pub fn discretization(&self) -> &Discretization {
        &self.disc
    }

    pub fn homogenizer(&self) -> &Homogenizer {
        &self.hom
    }

    pub fn linear_solver(&self) -> &LinearSolver {
        &self.linear
    }

    pub fn settings(&self) -> &Settings {
        &self.solver
    }

    pub fn elastic_sensitivity(&self) -> &[f64] {
        &self.elastic_sensitivity
    }
}

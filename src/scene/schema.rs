//! The scene schema, key by key. Every table rejects unknown keys, so a typo is an error
//! that names the key instead of a silently ignored setting. README.md documents the
//! same keys for users; keep the two in step.

use serde::{Deserialize, Serialize};

use crate::element::InterfaceQuadrature;
use crate::geometry::{Explicit, RandomSpec};
use crate::material::{Analysis, IsotropicElastic};

/// The whole scene file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    pub cell: CellSpec,
    pub geometry: GeometrySpec,
    pub mesh: MeshSpec,
    pub materials: MaterialsSpec,
    #[serde(default)]
    pub effects: EffectsSpec,
    #[serde(default)]
    pub boundary: BoundarySpec,
    #[serde(default)]
    pub solver: SolverSpec,
    /// Macro strain path for the command-line runner: piecewise linear segments.
    #[serde(default)]
    pub path: Vec<PathSegment>,
}

/// `[cell]`: the rectangle `[0, w] x [0, h]` and the plane state.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CellSpec {
    /// `[width, height]` in length units (paper: mm).
    pub size: [f64; 2],
    pub analysis: Analysis,
}

/// `[geometry]`: where the inclusions come from, chosen by `kind`.
///
/// Deserialized by hand (see [`GeometrySpec::deserialize`]) so that an error inside the
/// table names the full key, e.g. `geometry.seed`; serde's internally tagged enums lose it.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum GeometrySpec {
    /// No inclusions: a homogeneous matrix cell (patch tests, calibration).
    Homogeneous,
    /// Random sequential placement up to a target area fraction.
    Random(RandomSpec),
    /// An explicit list of circles and ellipses.
    Explicit(Explicit),
    /// A Gmsh mesh file whose physical groups name the phases.
    Gmsh(GmshSpec),
    /// One straight vertical interface over the full height of the cell (closed-form
    /// verification): aggregate on the left of it, matrix on the right.
    StraightInterface(StraightInterfaceSpec),
}

impl<'de> Deserialize<'de> for GeometrySpec {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        use serde::de::Error as _;
        let mut table = toml::Table::deserialize(deserializer)?;
        let kind = match table.remove("kind") {
            Some(toml::Value::String(kind)) => kind,
            Some(other) => {
                return Err(D::Error::custom(format!(
                    "key `geometry.kind`: expected a string, got {other}"
                )))
            }
            None => return Err(D::Error::custom("missing field `kind` in [geometry]")),
        };
        fn variant<T: serde::de::DeserializeOwned, E: serde::de::Error>(
            table: toml::Table,
        ) -> Result<T, E> {
            serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
                let path = e.path().to_string();
                let inner = e.into_inner();
                if path == "." {
                    E::custom(format!("in [geometry]: {inner}"))
                } else {
                    E::custom(format!("key `geometry.{path}`: {inner}"))
                }
            })
        }
        match kind.as_str() {
            "homogeneous" => match table.keys().next() {
                None => Ok(GeometrySpec::Homogeneous),
                Some(key) => Err(D::Error::custom(format!(
                    "key `geometry.{key}`: unknown for kind = \"homogeneous\""
                ))),
            },
            "random" => variant(table).map(GeometrySpec::Random),
            "explicit" => variant(table).map(GeometrySpec::Explicit),
            "gmsh" => variant(table).map(GeometrySpec::Gmsh),
            "straight_interface" => variant(table).map(GeometrySpec::StraightInterface),
            other => Err(D::Error::custom(format!(
                "key `geometry.kind`: unknown kind `{other}`, expected one of \
                 `homogeneous`, `random`, `explicit`, `gmsh`, `straight_interface`"
            ))),
        }
    }
}

/// `kind = "gmsh"`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct GmshSpec {
    /// Path to an MSH 2.2 or 4.1 ASCII file, relative to the scene file.
    pub file: String,
    /// Physical group name of the matrix phase.
    pub matrix: String,
    /// Physical group names that are inclusions (aggregates).
    pub inclusions: Vec<String>,
}

/// `kind = "straight_interface"`: the cell cut by the vertical line `x = x` from the
/// bottom to the top side. The part `x' < x` is the aggregate phase, the part `x' > x` the
/// matrix; ITZ elements along the line have their normal along `+x`. Their nodes lie on
/// the bottom and top sides, where periodic pairing matches the copies on the same side
/// of the line.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct StraightInterfaceSpec {
    /// Position of the interface, `0 < x < width`.
    pub x: f64,
}

/// `[mesh]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    /// Target triangle edge length `h` (max triangle area `sqrt(3)/4 h^2`).
    pub size: f64,
    /// Edge length along inclusion boundaries (the ITZ elements). Default: `size`.
    #[serde(default)]
    pub interface_size: Option<f64>,
    /// Minimum angle asked of the refinement, degrees (at least 20, at most 30).
    #[serde(default = "default_min_angle")]
    pub min_angle: f64,
    /// Quadrature of the interface elements.
    #[serde(default)]
    pub interface_quadrature: InterfaceQuadratureSpec,
}

/// Interface quadrature: `"gauss3"` (the paper) or `"lobatto2"` (Newton-Cotes).
pub type InterfaceQuadratureSpec = InterfaceQuadrature;

/// `[materials]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialsSpec {
    pub matrix: ElasticSpec,
    /// Required when the geometry has inclusions.
    #[serde(default)]
    pub aggregate: Option<ElasticSpec>,
    /// The paper's cohesive-contact ITZ; with `effects.cohesive` on, this or
    /// `linear_itz` is required.
    #[serde(default)]
    pub itz: Option<ItzSpec>,
    /// A linear elastic ITZ instead (verification, compliant bonding).
    #[serde(default)]
    pub linear_itz: Option<LinearItzSpec>,
}

/// A linear elastic interface `t = diag(k_s, k_n) delta`, stiffnesses per unit area.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LinearItzSpec {
    pub shear_stiffness: f64,
    pub normal_stiffness: f64,
}

/// Isotropic linear elasticity: `{ young, poisson }` (the material type itself).
pub type ElasticSpec = IsotropicElastic;

/// The cohesive-contact law of the ITZ (paper eqs. 20-25, 36-37).
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ItzSpec {
    /// Maximum cohesive normal traction.
    pub sigma_c: f64,
    /// Characteristic opening.
    pub delta_c: f64,
    /// Shear-to-normal weight in the effective opening (eq. 20).
    pub beta: f64,
    pub penalty: PenaltySpec,
    /// What carries the shear of a closed point: `"penalty"` (the paper's eq. 47, default)
    /// or `"cohesive"` (Ortiz-Pandolfi: normal penalty only, continuous at closure). See
    /// `crate::interface::ContactShear`.
    #[serde(default)]
    pub contact_shear: crate::interface::ContactShear,
}

/// Contact penalty, exactly one of:
/// * `{ lambda_p = ... }`: the paper's `t = lambda_p l_e delta` (eqs. 36-37), the form the
///   shipped scenes use, so they reproduce the paper;
/// * `{ stiffness = ... }`: a mesh-independent stiffness per unit area, `t = k delta`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PenaltySpec {
    #[serde(default)]
    pub lambda_p: Option<f64>,
    #[serde(default)]
    pub stiffness: Option<f64>,
}

/// `[effects]`: what the RVE simulates. Effects that are off cost nothing.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct EffectsSpec {
    /// Insert cohesive ITZ elements. Off: perfect bonding, no interface elements.
    #[serde(default = "yes")]
    pub cohesive: bool,
    /// Penalty contact when a crack closes (needs `cohesive`).
    #[serde(default = "yes")]
    pub contact: bool,
}

impl Default for EffectsSpec {
    fn default() -> Self {
        EffectsSpec {
            cohesive: true,
            contact: true,
        }
    }
}

/// `[boundary]`: the space of admissible fluctuations.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    #[serde(default)]
    pub kind: BoundaryKind,
}

/// Taylor >= linear >= periodic >= minimal (stiffest first).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BoundaryKind {
    Taylor,
    Linear,
    #[default]
    Periodic,
    Minimal,
}

/// `[solver]`: the RVE Newton-Raphson settings.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// Relative residual tolerance.
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    #[serde(default = "default_iterations")]
    pub max_iterations: u32,
    /// Backtracking line search on the residual norm.
    #[serde(default = "yes")]
    pub line_search: bool,
    /// Maximum bisection depth of the macro strain increment (2^depth sub-steps).
    #[serde(default = "default_substep_depth")]
    pub max_substep_depth: u32,
    /// Trace the equilibrium path through limit points (arc length) when Newton fails on
    /// a step, before the secant iterations and bisection.
    #[serde(default = "yes")]
    pub path_following: bool,
    /// Iterations allowed to the secant-then-Newton loop that takes over when plain
    /// Newton fails on a step, before the step is bisected; 0 switches it off.
    #[serde(default = "default_secant_iterations")]
    pub max_secant_iterations: u32,
    /// Modified-Newton (chord) corrections: after a Newton correction that cut the
    /// residual at least a hundredfold, the next correction reuses its factorization
    /// instead of factorizing the new tangent (see `solver::newton`). `false` gives
    /// plain Newton with its quadratic rate.
    #[serde(default = "yes")]
    pub reuse_factorization: bool,
    /// Second-order predictor: an increment that keeps the direction of the previous one
    /// starts from `x_n + X_n Delta eps + s^2 e_n`, with the previous increment's
    /// prediction error `e_n` kept in the state (see `state::PathCurvature`); `false`
    /// predicts to first order only (`x_n + X_n Delta eps`) and keeps no curvature.
    #[serde(default = "yes")]
    pub second_order_predictor: bool,
    /// When the contact status of an ITZ point (closed iff its normal jump is negative,
    /// eqs. 36-37) is read: `"active_set"` (default) or `"per_iteration"`, see
    /// [`ContactStatusSpec`] and `docs/contact-algorithm.md`.
    #[serde(default)]
    pub contact_status: ContactStatusSpec,
    /// Answer an update without Newton when every ITZ point provably stays on the linear
    /// branch (unloading or contact) it had at the last full solve: `sigma = D_b eps`,
    /// exact (see `solver::fast_path`); `false` solves every update.
    #[serde(default = "yes")]
    pub fast_path: bool,
    /// How the ITZ history is integrated over a host increment: `"implicit"` (default)
    /// or `"implex"`, see [`IntegrationSpec`] and `docs/implex.md`.
    #[serde(default)]
    pub integration: IntegrationSpec,
    /// Check every implicit increment that Newton lands in one step while ITZ points pass
    /// the peak of their law against two half steps, and flag it when they reach another
    /// equilibrium (the answer depends on the host's step: `RveInfo` and the UMAT then
    /// ask for a smaller step, `PNEWDT` 0.5). `false` skips the check.
    #[serde(default = "yes")]
    pub step_check: bool,
}

/// `solver.integration`: how the ITZ law's history is integrated over a step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum IntegrationSpec {
    /// Backward Euler: the history of the step's end, found by Newton with path
    /// following through the RVE's snap-backs.
    #[default]
    Implicit,
    /// IMPL-EX (Oliver, Huespe & Cante 2008): the history extrapolated from the last two
    /// converged steps, the contact status of the last one. The RVE is linear within a
    /// step: one factorization per step, a symmetric positive definite tangent, no
    /// snap-back; the stress lags the implicit law by an error of first order in the step.
    Implex,
}

/// `solver.contact_status`: when the solver reads the contact status of the ITZ points
/// from their gaps. Matters only with the paper's contact law
/// (`materials.itz.contact_shear = "penalty"`), whose shear traction jumps at closure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactStatusSpec {
    /// Held within each Newton iteration and read again between iterations; a point may
    /// switch at most twice per Newton loop, then keeps its status (an active-set
    /// strategy).
    #[default]
    ActiveSet,
    /// Read from the gap at every evaluation of the law. The residual then jumps where a
    /// sliding point closes, and some paths have no equilibrium at all.
    PerIteration,
}

impl Default for SolverSpec {
    fn default() -> Self {
        SolverSpec {
            tolerance: default_tolerance(),
            max_iterations: default_iterations(),
            line_search: true,
            max_substep_depth: default_substep_depth(),
            path_following: true,
            max_secant_iterations: default_secant_iterations(),
            reuse_factorization: true,
            second_order_predictor: true,
            contact_status: ContactStatusSpec::ActiveSet,
            fast_path: true,
            integration: IntegrationSpec::Implicit,
            step_check: true,
        }
    }
}

/// `[[path]]`: go linearly from the previous strain (initially zero) to `to` in
/// `increments` equal steps. Strain in Voigt order with engineering shear.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PathSegment {
    pub to: [f64; 3],
    pub increments: u32,
}

fn yes() -> bool {
    true
}
fn default_min_angle() -> f64 {
    25.0
}
fn default_tolerance() -> f64 {
    1e-6
}
fn default_iterations() -> u32 {
    40
}
fn default_substep_depth() -> u32 {
    10
}
fn default_secant_iterations() -> u32 {
    100
}

//! The scene schema, key by key. Every table rejects unknown keys, so a typo is an error
//! that names the key instead of a silently ignored setting. README.md documents the
//! same keys for users; keep the two in step.

use serde::{Deserialize, Serialize};

use mesorve_core::constraint::BoundaryCondition;
use mesorve_core::element::InterfaceQuadrature;
use mesorve_core::geometry::{Explicit, RandomSpec};
use mesorve_core::interface::InterfaceLawSpec;
pub use mesorve_core::interface::{CrackSpec, ItzSpec, LinearItzSpec, PenaltySpec};
use mesorve_core::material::{Analysis, IsotropicElastic};
use mesorve_core::solver::{ContactStatus, Integration, Settings};

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
    #[serde(default)]
    pub statev: StatevSpec,
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
    /// The law of cracks through the paste (`effects.paste_cracking`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub paste_crack: Option<CrackSpec>,
    /// Coulomb friction on closed cracks (`effects.friction`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<FrictionSpec>,
}

/// `[materials.friction]`: Coulomb friction on the closed cracks of the ITZ and of the
/// paste, acting on their damaged part (`interface::Frictional`).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FrictionSpec {
    /// The friction coefficient `mu` (dimensionless, >= 0).
    pub coefficient: f64,
}

impl MaterialsSpec {
    /// Every interface law a scene can give, by its key under `[materials]`, with its
    /// table when given: the one place a law is registered (a new law adds its field
    /// above and a line here).
    pub fn interface_laws(&self) -> [(&'static str, Option<&dyn InterfaceLawSpec>); 2] {
        [
            ("itz", self.itz.as_ref().map(|s| s as &dyn InterfaceLawSpec)),
            (
                "linear_itz",
                self.linear_itz.as_ref().map(|s| s as &dyn InterfaceLawSpec),
            ),
        ]
    }
}

/// Isotropic linear elasticity: `{ young, poisson }` (the material type itself).
pub type ElasticSpec = IsotropicElastic;

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
    /// Cracks through the paste: interface elements on the paste's element edges with
    /// `materials.paste_crack`'s law (`docs/fracture.md`). Off (the default) is left out
    /// of the scene's fingerprint, so scenes without the key keep theirs.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub paste_cracking: bool,
    /// Coulomb friction on closed cracks, `materials.friction`'s coefficient: the tangent
    /// of a sliding point is not symmetric. Off (the default) is left out of the
    /// fingerprint.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub friction: bool,
    /// Regularization by the host element's size (the crack band applied to the cell,
    /// `docs/fracture.md`): a host's element length (`PROPS(7)`, `CELENT`) stretches the
    /// softening of the cell's laws. Off (the default) is left out of the fingerprint,
    /// and a length a host passes is then refused.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub regularization: bool,
}

impl Default for EffectsSpec {
    fn default() -> Self {
        EffectsSpec {
            cohesive: true,
            contact: true,
            paste_cracking: false,
            friction: false,
            regularization: false,
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

/// `boundary.kind`: the boundary condition itself, its snake_case name the scene's value
/// (`taylor`, `linear`, `periodic` (default), `minimal`).
pub type BoundaryKind = BoundaryCondition;

/// `[statev]`: what the UMAT accepts as the state a host hands over in `STATEV` (see
/// `host::umat` and docs/statev.md). A host protocol, not physics: it is not part of a
/// state's fingerprint.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct StatevSpec {
    /// Refuse a state whose committed strain differs from the host's `STRAN` (the total
    /// strain at the start of the increment) beyond round-off: `true` (default). `false`
    /// for a host that passes no `STRAN` or a strain of another meaning.
    #[serde(default = "yes")]
    pub check_strain: bool,
    /// Refuse a state committed at the end of another time than the increment's start
    /// (`TIME(2)`, the total time): `true` (default). `false` for a host whose `TIME(2)` is
    /// not the total time at the start of the increment.
    #[serde(default = "yes")]
    pub check_time: bool,
    /// An all-zero `STATEV` at a point whose `STRAN` is not zero.
    #[serde(default)]
    pub zero_at_strain: ZeroAtStrain,
}

impl Default for StatevSpec {
    fn default() -> Self {
        StatevSpec {
            check_strain: true,
            check_time: true,
            zero_at_strain: ZeroAtStrain::Refuse,
        }
    }
}

/// `statev.zero_at_strain`: what an all-zero `STATEV` at a strained point means.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ZeroAtStrain {
    /// The host lost the state (CalculiX 2.20 restarting a model without a contact pair):
    /// the call is refused.
    #[default]
    Refuse,
    /// The host zeroed the state to restart the point from a virgin RVE (an element
    /// re-added by a host that resets its state variables): answered as a virgin RVE at
    /// the host's strain.
    Virgin,
}

/// `[solver]`: the solver's own settings, by their names (see `solver::Settings`).
pub type SolverSpec = Settings;
/// `solver.integration`.
pub type IntegrationSpec = Integration;
/// `solver.contact_status`.
pub type ContactStatusSpec = ContactStatus;

/// `[[path]]`: go linearly from the previous strain (initially zero) to `to` in
/// `increments` equal steps. Strain in Voigt order with engineering shear.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PathSegment {
    pub to: [f64; 3],
    pub increments: u32,
    /// Components held at zero stress along the segment (`["yy"]`: uniaxial stress in x
    /// with `to = [eps, 0, 0]`); their strain is found (`model::mixed`), and their value in
    /// `to` must be 0.
    #[serde(default, skip_serializing_if = "ZeroStress::is_none")]
    pub zero_stress: ZeroStress,
}

/// Which of `[xx, yy, xy]` a path segment holds at zero stress; in a scene, a list of
/// their names (`["yy", "xy"]`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(try_from = "Vec<String>", into = "Vec<String>")]
pub struct ZeroStress(pub [bool; 3]);

impl ZeroStress {
    const NAMES: [&'static str; 3] = ["xx", "yy", "xy"];

    /// No component held.
    pub fn is_none(&self) -> bool {
        self.0 == [false; 3]
    }
}

impl TryFrom<Vec<String>> for ZeroStress {
    type Error = String;
    fn try_from(names: Vec<String>) -> std::result::Result<Self, String> {
        let mut held = [false; 3];
        for n in names {
            let i = Self::NAMES
                .iter()
                .position(|c| *c == n)
                .ok_or_else(|| format!("`{n}` is not a stress component (xx, yy, xy)"))?;
            held[i] = true;
        }
        if held == [true; 3] {
            return Err("every component at zero stress leaves nothing to prescribe".into());
        }
        Ok(ZeroStress(held))
    }
}

impl From<ZeroStress> for Vec<String> {
    fn from(z: ZeroStress) -> Self {
        (0..3)
            .filter(|&i| z.0[i])
            .map(|i| ZeroStress::NAMES[i].to_string())
            .collect()
    }
}

fn yes() -> bool {
    true
}
fn default_min_angle() -> f64 {
    25.0
}

//! What a microstructure is made of: the parameters of random placement and the explicit
//! inclusion lists. The scene schema embeds these types as its `[geometry]` tables (hence
//! the serde attributes); geometry itself reads nothing of the scene.

use serde::{Deserialize, Serialize};

/// Inclusion shape for random placement.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeKind {
    Circle,
    Ellipse,
}

/// Ellipse orientation: `"random"` (uniform in [0, 180) degrees) or a fixed angle in
/// degrees, counter-clockwise from the x axis to the major axis.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(untagged)]
pub enum Orientation {
    Fixed(f64),
    Named(RandomWord),
}

/// The single word accepted for a random orientation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RandomWord {
    Random,
}

impl Default for Orientation {
    fn default() -> Self {
        Orientation::Named(RandomWord::Random)
    }
}

/// `kind = "random"`: take-and-place, largest first.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RandomSpec {
    pub shape: ShapeKind,
    /// `[min, max]` diameter; uniform in between. For ellipses this is the major axis `2a`.
    pub diameter: [f64; 2],
    /// Ellipses only: major over minor semi-axis `a / b >= 1`.
    #[serde(default = "one")]
    pub aspect_ratio: f64,
    /// Ellipses only.
    #[serde(default)]
    pub orientation: Orientation,
    /// Target inclusion area over cell area.
    pub area_fraction: f64,
    /// Seed of the ChaCha8 generator: the same seed gives the same microstructure.
    #[serde(default)]
    pub seed: u64,
    /// Minimum distance between two inclusions.
    #[serde(default = "default_gap")]
    pub gap: f64,
    /// Minimum distance from an inclusion to the cell boundary.
    #[serde(default = "default_gap")]
    pub margin: f64,
    /// Random trials per inclusion before a placement round gives up.
    #[serde(default = "default_attempts")]
    pub max_attempts: u32,
    /// Placement rounds (each with fresh sizes from the same seeded stream) before failing.
    #[serde(default = "default_rounds")]
    pub max_rounds: u32,
}

/// `kind = "explicit"`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Explicit {
    pub inclusions: Vec<ExplicitInclusion>,
}

/// One explicit inclusion: a circle (`radius`) or an ellipse (`semi_axes`, `angle`).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ExplicitInclusion {
    pub center: [f64; 2],
    #[serde(default)]
    pub radius: Option<f64>,
    /// `[a, b]`, semi-axes along the rotated x and y axes.
    #[serde(default)]
    pub semi_axes: Option<[f64; 2]>,
    /// Degrees, counter-clockwise.
    #[serde(default)]
    pub angle: f64,
}

fn one() -> f64 {
    1.0
}
fn default_gap() -> f64 {
    0.1
}
fn default_attempts() -> u32 {
    20_000
}
fn default_rounds() -> u32 {
    50
}

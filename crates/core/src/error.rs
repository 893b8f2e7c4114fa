//! Typed errors. Every variant carries enough context to point the user at the cause.

use std::path::PathBuf;

/// A failure of the sparse linear algebra (faer), typed by the step that failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LinearAlgebraError {
    /// The symbolic analysis (ordering, elimination tree) of a pattern.
    #[error("symbolic {factorization} analysis failed: {reason}")]
    Analysis {
        factorization: &'static str,
        reason: String,
    },
    /// The numeric factorization of a matrix (singular, or no pivot found).
    #[error("numeric factorization failed: {reason}")]
    Numeric { reason: String },
}

/// Everything that can go wrong in mesorve, from reading a scene to solving an RVE.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene key has a bad value; `key` is the dotted path, e.g. `materials.itz.delta_c`.
    #[error("scene key `{key}`: {reason}")]
    Scene { key: String, reason: String },
    /// The TOML text could not be parsed or does not match the schema.
    #[error("scene parse error: {0}")]
    SceneParse(String),
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Random placement could not meet the request within its bounded attempts.
    #[error("geometry: {0}")]
    Placement(String),
    /// A Gmsh file is malformed or unsupported.
    #[error("gmsh file {path}, line {line}: {reason}")]
    Gmsh {
        path: PathBuf,
        line: usize,
        reason: String,
    },
    /// Meshing failed or produced an unusable mesh.
    #[error("mesh: {0}")]
    Mesh(String),
    /// The sparse linear algebra failed outside a solve (the symbolic analysis of a
    /// model's pattern); within a solve a failed factorization is [`Error::Solve`].
    #[error("linear algebra: {0}")]
    LinearAlgebra(#[from] LinearAlgebraError),
    /// The macro strain is NaN, infinite or absurdly large.
    #[error("strain {strain:?}: {reason}")]
    BadStrain { strain: [f64; 3], reason: String },
    /// The RVE solver failed even after sub-stepping; the committed state is unchanged.
    #[error(
        "RVE solver failed: {reason} (after {depth} bisections of the strain increment); \
         retry with a step ratio of {suggested_step_ratio}"
    )]
    Solve {
        reason: String,
        depth: u32,
        /// Suggested ratio of the next macro increment to the failed one (UMAT's PNEWDT).
        suggested_step_ratio: f64,
    },
    /// A workspace was used with a model it was not made for.
    #[error("workspace belongs to another model (make one with Model::workspace)")]
    WorkspaceMismatch,
    /// `commit` without a successful trial `update` since the last commit/revert.
    #[error("no trial to commit: call update first")]
    NoTrial,
    /// State bytes are not a mesorve state: another magic, truncated, undecodable, or
    /// values no state can have.
    #[error("state bytes: {reason}")]
    BadState { reason: String },
    /// State bytes in a format version this library does not read.
    #[error("state format version {found}; this library reads versions {older:?} and {current}")]
    StateVersion {
        found: u32,
        /// The older versions it reads.
        older: &'static [u32],
        /// The version it writes (and reads).
        current: u32,
    },
    /// State bytes of a model of other sizes (another scene).
    #[error(
        "state of a model with {saved_unknowns} unknowns and {saved_history} history points; \
         this instance's model has {unknowns} and {history} (another scene)"
    )]
    StateMismatch {
        saved_unknowns: u64,
        saved_history: u64,
        unknowns: u64,
        history: u64,
    },
    /// A state of another material: its fingerprint (the scene after `PROPS`, a Gmsh
    /// file's content, the integration; see `model::fingerprint`) is not this model's.
    #[error(
        "state written by a material of fingerprint {stored:010x}, and this material's is \
         {expected:010x}: another scene, other PROPS, another mesh file or another \
         integration wrote it"
    )]
    StateOwner { stored: u64, expected: u64 },
    /// A host's state whose committed strain is not the host's strain at the start of the
    /// increment (`STRAN`): another point's state, a stale one, or an element re-added
    /// with the state of its removal.
    #[error(
        "STATEV was committed at the strain {stored:?}, and STRAN (the strain at the start \
         of this increment) is {host:?}, which differs by {difference:.3e} (tolerance \
         {tolerance:.1e}): this is not the state of this point at this increment (another \
         point's, or an older increment's){remedy}"
    )]
    StateStrain {
        /// `[eps_xx, eps_yy, gamma_xy]` the state holds.
        stored: [f64; 3],
        /// The host's `STRAN`, in the same order.
        host: [f64; 3],
        difference: f64,
        tolerance: f64,
        /// What to check in the host, or "".
        remedy: String,
    },
    /// A host's state committed at the end of another time than the start of this
    /// increment (`TIME(2)`): a state of an earlier increment, such as an element re-added
    /// with the state of its removal.
    #[error(
        "STATEV was committed at the end of the time {stored}, and this increment starts at \
         TIME(2) = {host}: it is the state of another increment{remedy}"
    )]
    StateTime {
        stored: f64,
        host: f64,
        /// What to check in the host, or "".
        remedy: String,
    },
    /// An all-zero (virgin) state at a point whose strain is not zero: the host lost the
    /// state, or zeroed it to restart the point (which a scene switch allows).
    #[error(
        "STATEV is all zeros (no state) but STRAN is {host:?}: the host did not carry this \
         point's state{remedy}"
    )]
    StateLost { host: [f64; 3], remedy: String },
    /// A state could not be encoded (a bug).
    #[error("state encoding: {reason}")]
    StateEncoding { reason: String },
    /// A host code's call does not fit the RVE: its tensor layout (`NTENS`), an
    /// out-of-plane strain, or a scene in the other plane state (see `crate::host`).
    #[error("host convention: {0}")]
    HostConvention(String),
    /// No scene file of this name on the host's scene search path.
    #[error("scene `{name}` not found: searched {}", searched_list(.searched))]
    SceneNotFound {
        name: String,
        searched: Vec<PathBuf>,
    },
    /// A point of a batch panicked (a bug); the other points are unaffected.
    #[error("internal error (panic: {0}); please report it")]
    Panic(String),
    /// A batch's thread pool could not be started.
    #[error("thread pool: {0}")]
    Threads(String),
}

impl Error {
    /// Shorthand for a scene error on `key`.
    pub fn scene(key: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::Scene {
            key: key.into(),
            reason: reason.into(),
        }
    }
}

fn searched_list(paths: &[PathBuf]) -> String {
    let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    names.join(", ")
}

pub type Result<T> = std::result::Result<T, Error>;

/// `Ok` when `value` is a positive finite number, else [`Error::Scene`] naming `key`.
pub fn require_positive(key: &str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(Error::scene(
            key,
            format!("must be a positive finite number, got {value}"),
        ))
    }
}

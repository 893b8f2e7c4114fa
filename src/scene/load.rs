//! Reading a scene from a file or from text.

use std::path::{Path, PathBuf};

use super::schema::SceneSpec;
use crate::error::{Error, Result};

/// The paper's RVE (section 5.2: 10 x 10 mm, 45 % aggregates of 2.5-5.0 mm, ~520
/// triangles, ~95 ITZ elements), embedded so the tool runs with no input file.
pub const DEFAULT_SCENE_TOML: &str = include_str!("../../scenes/paper_rve.toml");
/// Name reported for the embedded scene.
pub const DEFAULT_SCENE_NAME: &str = "scenes/paper_rve.toml (embedded)";

/// A validated scene plus the directory that relative paths in it refer to.
#[derive(Clone, Debug)]
pub struct Scene {
    pub spec: SceneSpec,
    /// Directory of the scene file (for `geometry.file`); the working directory for text.
    pub base_dir: PathBuf,
}

impl Scene {
    /// Parses and validates TOML text; relative paths resolve against `base_dir`.
    pub fn from_toml_str(text: &str, base_dir: impl Into<PathBuf>) -> Result<Self> {
        // serde_path_to_error names the dotted key even where toml's own span is lost
        // (inside the internally tagged `[geometry]` table).
        let deserializer = toml::Deserializer::new(text);
        let spec: SceneSpec = serde_path_to_error::deserialize(deserializer).map_err(|e| {
            let path = e.path().to_string();
            let inner = e.into_inner();
            if path.is_empty() || path == "." {
                Error::SceneParse(inner.to_string())
            } else {
                Error::SceneParse(format!("key `{path}`: {inner}"))
            }
        })?;
        spec.validate()?;
        Ok(Scene {
            spec,
            base_dir: base_dir.into(),
        })
    }

    /// Reads, parses and validates a scene file.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Self::from_toml_str(&text, base).map_err(|e| match e {
            Error::SceneParse(msg) => Error::SceneParse(format!("{}: {msg}", path.display())),
            other => other,
        })
    }

    /// The embedded default scene (the paper's RVE).
    pub fn embedded_default() -> Result<Self> {
        Self::from_toml_str(DEFAULT_SCENE_TOML, ".")
    }
}

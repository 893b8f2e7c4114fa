//! The process-wide model cache: instances of one scene share one `Arc<Model>`, so
//! creating 10^4 instances meshes and analyses the scene once. The C interface
//! (`rve_init_*`) and the UMAT (`crate::host`) share it.
//!
//! Keys: a file scene by its canonical path and its text (an edited file is a new
//! scene); a text scene by its text and base directory. The cache holds weak references:
//! a model lives as long as one of its instances.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, LazyLock, Mutex, Weak};

use crate::error::{Error, Result};
use crate::model::Model;
use crate::scene::Scene;

#[derive(Clone, Debug, Hash, PartialEq, Eq)]
enum Key {
    File { path: PathBuf, text: String },
    Text { text: String, base: PathBuf },
}

static CACHE: LazyLock<Mutex<HashMap<Key, Weak<Model>>>> =
    LazyLock::new(|| Mutex::new(HashMap::new()));
/// A regularized model's key: its scene model's id and the element length's bits.
type RegularizedKey = (u64, u64);

static REGULARIZED: LazyLock<Mutex<HashMap<RegularizedKey, Weak<Model>>>> =
    LazyLock::new(|| Mutex::new(HashMap::new()));
static BUILDS: AtomicU64 = AtomicU64::new(0);

/// Models built through this cache by this process (each scene once while one of its
/// instances lives).
pub fn model_builds() -> u64 {
    BUILDS.load(Ordering::Relaxed)
}

fn cached(key: Key, build: impl FnOnce() -> Result<Scene>) -> Result<Arc<Model>> {
    // The lock is held while building so that concurrent inits of one scene build once.
    let mut cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(model) = cache.get(&key).and_then(Weak::upgrade) {
        return Ok(model);
    }
    let scene = build()?;
    let model = Arc::new(Model::from_scene(&scene)?);
    BUILDS.fetch_add(1, Ordering::Relaxed);
    cache.retain(|_, m| m.strong_count() > 0);
    cache.insert(key, Arc::downgrade(&model));
    Ok(model)
}

/// `model`'s scene model regularized for a host element of length `element_length`
/// ([`Model::regularized`]), one per scene model and length while one of its instances
/// lives: the points of one element, or of a graded mesh's elements of one size, share
/// it.
pub fn regularized(model: &Arc<Model>, element_length: f64) -> Result<Arc<Model>> {
    let base = model.unregularized();
    let key = (base.id, element_length.to_bits());
    let mut cache = REGULARIZED.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(model) = cache.get(&key).and_then(Weak::upgrade) {
        return Ok(model);
    }
    let model = Arc::new(base.regularized(element_length)?);
    if cache.len().is_power_of_two() {
        // Amortized: a graded mesh adds its lengths one by one.
        cache.retain(|_, m| m.strong_count() > 0);
    }
    cache.insert(key, Arc::downgrade(&model));
    Ok(model)
}

/// The model of the scene file at `path`.
pub fn model_for_file(path: &Path) -> Result<Arc<Model>> {
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let canonical = std::fs::canonicalize(path).map_err(io)?;
    let text = std::fs::read_to_string(&canonical).map_err(io)?;
    let base = canonical
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    let key = Key::File {
        path: canonical.clone(),
        text: text.clone(),
    };
    cached(key, || {
        Scene::from_toml_str(&text, base).map_err(|e| match e {
            Error::SceneParse(msg) => Error::SceneParse(format!("{}: {msg}", path.display())),
            other => other,
        })
    })
}

/// The model of scene text whose relative paths resolve against `base` (default: the
/// working directory).
pub fn model_for_text(text: &str, base: Option<&Path>) -> Result<Arc<Model>> {
    let base = base.map(Path::to_path_buf).unwrap_or_else(|| ".".into());
    let key = Key::Text {
        text: text.to_string(),
        base: base.clone(),
    };
    cached(key, || Scene::from_toml_str(text, base))
}

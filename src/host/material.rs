//! A host's material: the RVE scene that the material name (`CMNAME`) selects on a search
//! path, with documented scene keys overridden by the material constants (`PROPS`).
//!
//! **Scene name.** Trailing blanks and NULs of `CMNAME` (Fortran padding) are dropped.
//! A name that starts with `@` is CalculiX's external-behaviour selector
//! (`@ABAQUS_<LIB>_<FUNC>`): that first `@` field is dropped. The scene name is then the
//! text up to the next `@`; what follows it is a free tag that makes material names
//! distinct (two materials of one scene with different `PROPS`):
//!
//! | `CMNAME` | scene name |
//! |---|---|
//! | `CONCRETE` | `CONCRETE` |
//! | `CONCRETE@WEAK` | `CONCRETE` |
//! | `@ABAQUS_RVE_UMAT@CONCRETE` | `CONCRETE` |
//! | `@ABAQUS_RVE_UMAT@CONCRETE@WEAK` | `CONCRETE` |
//! | `@ABAQUS_RVE_UMAT` | none: the embedded paper RVE |
//!
//! A scene name has ASCII letters, digits, `_`, `-` and `.` only, and does not start
//! with `.`.
//!
//! **Search path.** The environment variable [`SCENE_PATH_VAR`] (`MESORVE_SCENE_PATH`)
//! lists directories separated by `:`; unset or empty, the working directory. In each
//! directory in turn, `<name>.toml` and then `<lowercase name>.toml` are tried (hosts
//! such as CalculiX and Abaqus upper-case material names). No match is
//! [`Error::SceneNotFound`], which lists every path tried.
//!
//! **`PROPS`.** `PROPS(k)` = 0 (or `NPROPS < k`) keeps the scene's value; any other value
//! overrides the key of [`PROPS_KEYS`]:
//!
//! | `PROPS` | meaning |
//! |---|---|
//! | 1 | `materials.itz.sigma_c` |
//! | 2 | `materials.itz.delta_c` |
//! | 3 | `geometry.seed` (a random geometry; an integer) |
//! | 4 | `materials.matrix.young` |
//! | 5 | `materials.aggregate.young` |
//! | 6 | the tangent returned in `DDSDDE`: 0 the consistent one, 1 the elastic tangent of the virgin RVE |
//! | 7 | the element's characteristic length (scene length unit) for a scene with `effects.regularization`; 0: `CELENT` where the host passes it |
//!
//! A non-zero `PROPS(k)` for `k > 7` is refused. `PROPS(7)` is not a scene key: the
//! elements of every length share the scene's model ([`Material::for_element`]). Overridden scenes are built from the
//! edited scene text (relative paths still resolve against the scene file's directory);
//! the same scene with the same overrides is meshed once per process.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::diagnostics::{note_once, Note};
use super::hypothesis::PlaneResponse;
use crate::error::{Error, Result};
use crate::model::{cache, Model};
use crate::scene::DEFAULT_SCENE_TOML;
use mesorve_core::solver::TangentRequest;

/// The environment variable that lists the directories searched for scene files.
pub const SCENE_PATH_VAR: &str = "MESORVE_SCENE_PATH";

/// The environment variable that names the scene of every UMAT call, in place of `CMNAME`
/// (which is then not read): a scene file's path (with a `/` or ending in `.toml`) or a
/// scene name searched like a `CMNAME`'s (see [`UmatScene::from_env`]).
pub const UMAT_SCENE_VAR: &str = "MESORVE_UMAT_SCENE";

/// The scene [`UMAT_SCENE_VAR`] names: the material name the calls get, and the directory
/// searched first when the variable is a path.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UmatScene {
    /// The scene name (the file's stem for a path), used as the material name.
    pub name: String,
    /// The file's directory for a path; `None` for a name.
    pub dir: Option<PathBuf>,
}

impl UmatScene {
    /// From [`UMAT_SCENE_VAR`]; `None` when it is unset or empty.
    pub fn from_env() -> Option<UmatScene> {
        let value = std::env::var_os(UMAT_SCENE_VAR)?;
        UmatScene::parse(Path::new(&value))
    }

    /// A path (it has a `/` or ends in `.toml`) gives its stem and directory; anything
    /// else is a scene name.
    pub fn parse(value: &Path) -> Option<UmatScene> {
        let text = value.to_string_lossy();
        if text.is_empty() {
            return None;
        }
        if !(text.contains('/') || text.ends_with(".toml")) {
            return Some(UmatScene {
                name: text.into_owned(),
                dir: None,
            });
        }
        let dir = match value.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let name = value.file_stem()?.to_string_lossy().into_owned();
        Some(UmatScene {
            name,
            dir: Some(dir),
        })
    }
}

/// The scene keys that `PROPS(1..=5)` override, in order.
pub const PROPS_KEYS: [&str; 5] = [
    "materials.itz.sigma_c",
    "materials.itz.delta_c",
    "geometry.seed",
    "materials.matrix.young",
    "materials.aggregate.young",
];

/// Position (1-based) of the tangent choice in `PROPS`.
pub const PROPS_TANGENT: usize = 6;

/// Position (1-based) of the element's characteristic length in `PROPS`.
pub const PROPS_LENGTH: usize = 7;

/// Directories searched for scene files, in order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SearchPath(Vec<PathBuf>);

impl SearchPath {
    pub fn new(dirs: impl IntoIterator<Item = PathBuf>) -> Self {
        let dirs: Vec<PathBuf> = dirs
            .into_iter()
            .filter(|d| !d.as_os_str().is_empty())
            .collect();
        if dirs.is_empty() {
            SearchPath(vec![PathBuf::from(".")])
        } else {
            SearchPath(dirs)
        }
    }

    /// From [`SCENE_PATH_VAR`] (`:`-separated); the working directory when unset.
    pub fn from_env() -> Self {
        match std::env::var_os(SCENE_PATH_VAR) {
            Some(v) => SearchPath::new(std::env::split_paths(&v)),
            None => SearchPath::new([]),
        }
    }

    /// This path with `dir` searched first.
    pub fn with_first(&self, dir: PathBuf) -> Self {
        SearchPath::new(std::iter::once(dir).chain(self.0.iter().cloned()))
    }

    pub fn dirs(&self) -> &[PathBuf] {
        &self.0
    }

    /// The first `<name>.toml` or `<lowercase name>.toml` in the directories.
    pub fn find(&self, name: &str) -> Result<PathBuf> {
        let lower = name.to_ascii_lowercase();
        let mut searched = Vec::new();
        for dir in &self.0 {
            for candidate in [name, lower.as_str()] {
                let path = dir.join(format!("{candidate}.toml"));
                if searched.contains(&path) {
                    continue;
                }
                if path.is_file() {
                    return Ok(path);
                }
                searched.push(path);
            }
        }
        Err(Error::SceneNotFound {
            name: name.to_string(),
            searched,
        })
    }
}

/// The scene name inside a material name (see the module documentation); `None` for the
/// embedded paper RVE.
pub fn scene_name(cmname: &str) -> Result<Option<&str>> {
    let name = cmname.trim_end_matches([' ', '\0']);
    let rest = match name.strip_prefix('@') {
        Some(selector) => selector.split_once('@').map_or("", |(_, r)| r),
        None => name,
    };
    let scene = rest.split('@').next().unwrap_or("");
    if scene.is_empty() {
        return Ok(None);
    }
    let allowed = |c: char| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.');
    if scene.starts_with('.') || !scene.chars().all(allowed) {
        return Err(Error::HostConvention(format!(
            "material name `{name}`: the scene name `{scene}` may hold ASCII letters, digits, \
             `_`, `-` and `.` only, and may not start with `.`"
        )));
    }
    Ok(Some(scene))
}

/// A resolved material: its model, the tangent it returns and its elastic response.
#[derive(Debug)]
pub struct Material {
    pub model: Arc<Model>,
    /// The tangent it returns in `DDSDDE`: `Consistent` or `Elastic` (`PROPS(6)`).
    pub tangent: TangentRequest,
    /// The virgin RVE's tangent and `d s_zz / d eps` (stress and `s_zz` zero).
    pub elastic: PlaneResponse,
    /// Where the scene came from and what `PROPS` overrode, for messages.
    pub source: String,
}

impl Material {
    /// Resolves a material name and its constants (see the module documentation).
    pub fn resolve(cmname: &str, props: &[f64], path: &SearchPath) -> Result<Material> {
        let overrides = overrides(props)?;
        let tangent = tangent_choice(props)?;
        let file = scene_name(cmname)?.map(|n| path.find(n)).transpose()?;
        let mut source = match &file {
            Some(f) => format!("scene {}", f.display()),
            None => "the embedded paper RVE".to_string(),
        };
        let model = if overrides.is_empty() {
            match &file {
                Some(f) => cache::model_for_file(f)?,
                None => cache::model_for_text(DEFAULT_SCENE_TOML, None)?,
            }
        } else {
            let (text, base) = match &file {
                Some(f) => {
                    let text = std::fs::read_to_string(f).map_err(|source| Error::Io {
                        path: f.clone(),
                        source,
                    })?;
                    (text, f.parent().map(Path::to_path_buf))
                }
                None => (DEFAULT_SCENE_TOML.to_string(), None),
            };
            for (k, key, value) in &overrides {
                source += &format!(", PROPS({k}) {key} = {value}");
            }
            let edited = apply_overrides(&text, &overrides)?;
            cache::model_for_text(&edited, base.as_deref())?
        };
        let elastic = PlaneResponse {
            stress: [0.0; 3],
            tangent: model.elastic_tangent,
            s_zz: 0.0,
            s_zz_tangent: model.elastic_s_zz_tangent,
        };
        Ok(Material {
            model,
            tangent,
            elastic,
            source,
        })
    }
}

impl Material {
    /// This material at an element of the host: regularized for the element's length
    /// (`PROPS(7)`, else `CELENT`) when the scene has `effects.regularization`; itself
    /// otherwise (a `CELENT` is then not read; a `PROPS(7)` is refused by
    /// [`Model::regularized`]). The regularized model shares the scene's mesh,
    /// operators and workspaces: a graded mesh costs a small model per distinct length.
    pub fn for_element(self: &Arc<Self>, props: &[f64], celent: Option<f64>) -> Result<Arc<Self>> {
        let regularizes = self.model.scene().spec.effects.regularization;
        let (length, from_celent) = match props.get(PROPS_LENGTH - 1).copied().unwrap_or(0.0) {
            // A CELENT that is not a positive number is one the host did not set (CalculiX
            // 2.20 passes its unset variable).
            0.0 => match celent.filter(|h| regularizes && h.is_finite() && *h > 0.0) {
                Some(h) => (h, true),
                None => {
                    if regularizes {
                        note_once(Note::NoElementLength, || {
                            format!(
                                "mesorve: {}: effects.regularization is on and the host gives \
                                 no element length (PROPS(7) = 0, no CELENT): the cell is not \
                                 regularized, and a member's dissipation follows its mesh \
                                 (printed once)",
                                self.source
                            )
                        });
                    }
                    return Ok(self.clone());
                }
            },
            h => (h, false),
        };
        let model = cache::regularized(&self.model, length)?;
        if from_celent {
            note_once(Note::Celent, || {
                format!(
                    "mesorve: {}: regularized by the host's CELENT ({length} at the first \
                     element); set PROPS(7) where the host does not set CELENT (CalculiX) \
                     (printed once)",
                    self.source
                )
            });
        }
        Ok(Arc::new(Material {
            model,
            tangent: self.tangent,
            elastic: self.elastic,
            source: format!(
                "{}, element length {length} ({})",
                self.source,
                if from_celent { "CELENT" } else { "PROPS(7)" }
            ),
        }))
    }
}

/// `(k, key, value)` for every non-zero `PROPS(k)`, `k` in `1..=5`.
fn overrides(props: &[f64]) -> Result<Vec<(usize, &'static str, f64)>> {
    let mut out = Vec::new();
    for (i, &v) in props.iter().enumerate() {
        let k = i + 1;
        if v == 0.0 {
            continue;
        }
        let prop = |reason: String| Error::scene(format!("PROPS({k})"), reason);
        if !v.is_finite() {
            return Err(prop(format!("{v} is not a finite number")));
        }
        match PROPS_KEYS.get(i) {
            Some(&key) => out.push((k, key, v)),
            None if k == PROPS_TANGENT => {}
            None if k == PROPS_LENGTH && v > 0.0 => {}
            None if k == PROPS_LENGTH => {
                return Err(prop(format!(
                    "{v}: the element's length is a positive number (0: CELENT or none)"
                )))
            }
            None => {
                return Err(prop(format!(
                    "{v}: only PROPS(1..={PROPS_LENGTH}) have a meaning ({}, tangent, \
                     element length)",
                    PROPS_KEYS.join(", ")
                )))
            }
        }
    }
    Ok(out)
}

fn tangent_choice(props: &[f64]) -> Result<TangentRequest> {
    match props.get(PROPS_TANGENT - 1).copied().unwrap_or(0.0) {
        0.0 => Ok(TangentRequest::Consistent),
        1.0 => Ok(TangentRequest::Elastic),
        v => Err(Error::scene(
            format!("PROPS({PROPS_TANGENT})"),
            format!("{v}: the tangent is 0 (consistent) or 1 (elastic)"),
        )),
    }
}

/// The scene text with `overrides` applied (TOML re-serialized; comments dropped).
fn apply_overrides(text: &str, overrides: &[(usize, &'static str, f64)]) -> Result<String> {
    let mut table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| Error::SceneParse(e.to_string()))?;
    for &(k, key, v) in overrides {
        let prop = |reason: &str| Error::scene(format!("PROPS({k}) ({key})"), reason);
        let value = if key == "geometry.seed" {
            let kind = table
                .get("geometry")
                .and_then(|g| g.get("kind"))
                .and_then(toml::Value::as_str);
            if kind != Some("random") {
                return Err(prop("the scene's geometry is not `kind = \"random\"`"));
            }
            if v < 0.0 || v.fract() != 0.0 || v >= 2f64.powi(53) {
                return Err(prop("a seed is a non-negative integer"));
            }
            toml::Value::Integer(v as i64)
        } else {
            toml::Value::Float(v)
        };
        let (parents, leaf) = key.rsplit_once('.').expect("keys are dotted");
        let mut node = &mut table;
        for part in parents.split('.') {
            node = node
                .get_mut(part)
                .and_then(toml::Value::as_table_mut)
                .ok_or_else(|| prop(&format!("the scene has no `{parents}` to override")))?;
        }
        node.insert(leaf.to_string(), value);
    }
    toml::to_string(&table).map_err(|e| Error::SceneParse(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A path gives its stem and directory, a bare name is a name, empty is unset.
    #[test]
    fn umat_scene_is_a_path_or_a_name() {
        let scene = |v: &str| UmatScene::parse(Path::new(v));
        assert_eq!(
            scene("/a/b/weak_itz.toml"),
            Some(UmatScene {
                name: "weak_itz".into(),
                dir: Some(PathBuf::from("/a/b"))
            })
        );
        assert_eq!(
            scene("paper_rve.toml").map(|s| s.dir),
            Some(Some(PathBuf::from(".")))
        );
        assert_eq!(
            scene("CONCRETE"),
            Some(UmatScene {
                name: "CONCRETE".into(),
                dir: None
            })
        );
        assert_eq!(scene(""), None);
    }

    #[test]
    fn scene_names_follow_the_documented_rule() {
        let cases = [
            ("CONCRETE", Some("CONCRETE")),
            ("CONCRETE@WEAK   ", Some("CONCRETE")),
            ("@ABAQUS_RVE_UMAT@CONCRETE", Some("CONCRETE")),
            ("@ABAQUS_RVE_UMAT@PAPER_RVE@2\0\0", Some("PAPER_RVE")),
            ("@ABAQUS_RVE_UMAT", None),
            ("@ABAQUS_RVE_UMAT@", None),
            ("", None),
            ("   ", None),
            ("a.b-c_1", Some("a.b-c_1")),
        ];
        for (cmname, want) in cases {
            assert_eq!(scene_name(cmname).unwrap(), want, "{cmname:?}");
        }
        for bad in [
            "../etc/passwd",
            "a/b",
            "@ABAQUS_RVE_UMAT@..",
            "x y",
            "sc\u{e9}ne",
        ] {
            let e = scene_name(bad).unwrap_err();
            assert!(matches!(e, Error::HostConvention(_)), "{bad}: {e}");
        }
    }

    #[test]
    fn props_are_checked() {
        assert!(overrides(&[0.0; 6]).unwrap().is_empty());
        let o = overrides(&[3.0, 0.0, 5.0]).unwrap();
        assert_eq!(
            o,
            vec![(1, "materials.itz.sigma_c", 3.0), (3, "geometry.seed", 5.0)]
        );
        assert!(overrides(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0])
            .unwrap()
            .is_empty());
        let e = overrides(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -2.0]).unwrap_err();
        assert!(e.to_string().contains("PROPS(7)"), "{e}");
        let e = overrides(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 1.0]).unwrap_err();
        assert!(e.to_string().contains("PROPS(8)"), "{e}");
        let e = overrides(&[f64::NAN]).unwrap_err();
        assert!(e.to_string().contains("PROPS(1)"), "{e}");
        assert_eq!(tangent_choice(&[]).unwrap(), TangentRequest::Consistent);
        assert_eq!(
            tangent_choice(&[0.0; 6]).unwrap(),
            TangentRequest::Consistent
        );
        let mut p = [0.0; 6];
        p[5] = 1.0;
        assert_eq!(tangent_choice(&p).unwrap(), TangentRequest::Elastic);
        p[5] = 0.5;
        assert!(tangent_choice(&p)
            .unwrap_err()
            .to_string()
            .contains("PROPS(6)"));
    }

    #[test]
    fn overrides_edit_the_named_keys() {
        let edited = apply_overrides(
            DEFAULT_SCENE_TOML,
            &[
                (1, PROPS_KEYS[0], 2.5),
                (3, PROPS_KEYS[2], 11.0),
                (5, PROPS_KEYS[4], 4e4),
            ],
        )
        .unwrap();
        let t: toml::Table = edited.parse().unwrap();
        assert_eq!(t["materials"]["itz"]["sigma_c"].as_float(), Some(2.5));
        assert_eq!(t["geometry"]["seed"].as_integer(), Some(11));
        assert_eq!(t["materials"]["aggregate"]["young"].as_float(), Some(4e4));
        assert_eq!(t["materials"]["matrix"]["young"].as_float(), Some(25000.0));
        let e = apply_overrides(DEFAULT_SCENE_TOML, &[(3, PROPS_KEYS[2], 1.5)]).unwrap_err();
        assert!(e.to_string().contains("non-negative integer"), "{e}");
        let homogeneous = "[cell]\nsize = [1.0, 1.0]\nanalysis = \"plane_strain\"\n\
                           [geometry]\nkind = \"homogeneous\"\n";
        let e = apply_overrides(homogeneous, &[(3, PROPS_KEYS[2], 2.0)]).unwrap_err();
        assert!(e.to_string().contains("kind = \"random\""), "{e}");
        let e = apply_overrides(homogeneous, &[(1, PROPS_KEYS[0], 2.0)]).unwrap_err();
        assert!(e.to_string().contains("no `materials.itz`"), "{e}");
    }
}

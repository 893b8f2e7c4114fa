//! The fingerprint of what gives a state's values their meaning: the parsed scene (after a
//! host's `PROPS` overrides), the content of a Gmsh mesh file, and the integration scheme.
//! A state written under one fingerprint is refused by a model of another
//! (`state::statev`, `state::persist`), so that a host handing over another material's
//! state, or a scene edited between the two parts of a restart, gets an error instead of
//! a number.
//!
//! **What enters.** The scene's `[cell]`, `[geometry]` (a Gmsh file by the FNV-1a digest of
//! its bytes instead of its path), `[mesh]`, `[materials]`, `[effects]`, `[boundary]` and
//! `solver.integration`. **What does not**, because it changes how an answer is found but
//! not what a state means: the rest of `[solver]` (tolerances, iteration limits, the
//! remedy ladder, the fast path, the step check and any later step or sharing control),
//! `[statev]` (how the UMAT checks what a host hands over), `[[path]]` (the command-line
//! runner's strain path), comments, key order and number spelling (the scene is compared
//! parsed). Changing one of those in the middle of an analysis is accepted; the answer is
//! then the new setting's, as for any solver setting.
//!
//! **Form.** The scene's tables as JSON with sorted keys, absent optional keys left out,
//! numbers as `serde_json` writes them (shortest round trip); its FNV-1a 64-bit hash folded
//! to [`FINGERPRINT_BITS`] bits. Leaving absent keys out keeps a fingerprint stable when a
//! later release adds an optional key: a new key that changes what a state means must be
//! optional (absent = the old meaning), or the state format must say so.

use serde_json::Value;

use crate::error::{Error, Result};
use crate::scene::{GeometrySpec, Scene};
pub use mesorve_core::state::statev::FINGERPRINT_BITS;

/// FNV-1a, 64 bits: a small stable hash (not a cryptographic one: it tells states of
/// different materials apart, it does not defend against forgery).
fn fnv1a64(bytes: &[u8]) -> u64 {
    const OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    bytes
        .iter()
        .fold(OFFSET, |h, &b| (h ^ u64::from(b)).wrapping_mul(PRIME))
}

/// The fingerprint of `scene` (see the module docs): reads a Gmsh file's bytes.
pub fn scene_fingerprint(scene: &Scene) -> Result<u64> {
    let mut value = serde_json::to_value(&scene.spec).map_err(|e| Error::StateEncoding {
        reason: format!("the scene as JSON for its fingerprint: {e}"),
    })?;
    let table = value
        .as_object_mut()
        .expect("a scene serializes as a table");
    table.remove("path");
    table.remove("statev");
    let integration = table
        .get("solver")
        .and_then(|s| s.get("integration"))
        .cloned()
        .unwrap_or(Value::Null);
    table.insert(
        "solver".into(),
        serde_json::json!({ "integration": integration }),
    );
    if let GeometrySpec::Gmsh(g) = &scene.spec.geometry {
        let path = scene.base_dir.join(&g.file);
        let bytes = std::fs::read(&path).map_err(|source| Error::Io { path, source })?;
        let digest = format!("{:016x}", fnv1a64(&bytes));
        table["geometry"]["file"] = Value::String(digest);
    }
    let mut canonical = String::new();
    write_canonical(&value, &mut canonical);
    Ok(fold(fnv1a64(canonical.as_bytes())))
}

/// The fingerprint of a model regularized for a host element of `element_length`: its
/// states mean other openings than the scene's own (`Model::regularized`).
pub fn regularized_fingerprint(scene_fingerprint: u64, element_length: f64) -> u64 {
    let text = format!(
        "{scene_fingerprint:016x} element_length {:016x}",
        element_length.to_bits()
    );
    fold(fnv1a64(text.as_bytes()))
}

/// `h` folded to [`FINGERPRINT_BITS`] bits (never 0, which old states stand for).
fn fold(h: u64) -> u64 {
    let mask = (1u64 << FINGERPRINT_BITS) - 1;
    let folded = (h ^ (h >> FINGERPRINT_BITS)) & mask;
    folded.max(1)
}

/// JSON with sorted keys and without nulls (absent optional keys).
fn write_canonical(value: &Value, out: &mut String) {
    match value {
        Value::Object(map) => {
            let mut keys: Vec<&String> = map.keys().filter(|k| !map[*k].is_null()).collect();
            keys.sort();
            out.push('{');
            for (i, k) in keys.into_iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                out.push_str(&Value::String(k.clone()).to_string());
                out.push(':');
                write_canonical(&map[k], out);
            }
            out.push('}');
        }
        Value::Array(items) => {
            out.push('[');
            for (i, item) in items.iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                write_canonical(item, out);
            }
            out.push(']');
        }
        other => out.push_str(&other.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::DEFAULT_SCENE_TOML;

    fn of(text: &str) -> u64 {
        scene_fingerprint(&Scene::from_toml_str(text, ".").unwrap()).unwrap()
    }

    #[test]
    fn comments_order_and_solver_settings_do_not_count() {
        let base = of(DEFAULT_SCENE_TOML);
        let commented = format!("# a comment\n{DEFAULT_SCENE_TOML}\n# another\n");
        assert_eq!(of(&commented), base);
        let tolerances = DEFAULT_SCENE_TOML
            .replace("tolerance = 1e-6", "tolerance = 1e-9")
            .replace(
                "max_iterations = 40",
                "max_iterations = 60\nstep_check = false",
            );
        assert_ne!(
            tolerances, DEFAULT_SCENE_TOML,
            "the scene has a [solver] table"
        );
        assert_eq!(of(&tolerances), base);
        assert!(base > 0 && base < 1 << FINGERPRINT_BITS);
    }

    #[test]
    fn what_a_state_means_counts() {
        let base = of(DEFAULT_SCENE_TOML);
        let implex = DEFAULT_SCENE_TOML.replace("[solver]", "[solver]\nintegration = \"implex\"");
        assert_ne!(of(&implex), base);
        let seed = DEFAULT_SCENE_TOML.replace("seed = ", "seed = 1");
        assert_ne!(seed, DEFAULT_SCENE_TOML, "the scene has a seed");
        assert_ne!(of(&seed), base);
    }
}

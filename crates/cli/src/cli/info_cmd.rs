//! `rve info [SCENE] [--json]`: what a host needs to know about a scene's RVE before it
//! calls it: its size, its state and `umat_nstatv`, the `STATEV` count (`*DEPVAR`) that
//! keeps the state in the host.

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use rve::error::Result;
use rve::Integration;
use rve::{Instance, Model, TangentRequest};
use serde::Serialize;

use super::load_scene_with;

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Scene file (TOML). Default: the embedded paper RVE (scenes/paper_rve.toml).
    scene: Option<PathBuf>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Set a scene key first, as `rve run --set` does (repeatable).
    #[arg(long, value_name = "KEY=VALUE")]
    set: Vec<String>,
}

#[derive(Serialize)]
struct Info {
    scene: String,
    analysis: rve::Analysis,
    integration: &'static str,
    nodes: usize,
    triangles: usize,
    interface_elements: usize,
    /// Reduced fluctuation dofs plus the minimal condition's multipliers.
    unknowns: usize,
    /// Interface quadrature points (ITZ points).
    itz_points: usize,
    /// Interface history values (the law's values per point, all points).
    history_values: usize,
    /// Bytes one instance owns after a loading update and its commit (committed and
    /// trial states, caches included): what a table of instances costs per point.
    instance_bytes: usize,
    /// Bytes of the checkpoint (`rve_state_save`) of that committed state.
    checkpoint_bytes: usize,
    /// `STATEV` entries that keep the committed core in the host (`*DEPVAR` at least
    /// this; + 5 for the UMAT's mirrors).
    umat_nstatv: usize,
    /// The fingerprint states of this scene carry (10 hex digits; the UMAT refuses a
    /// state of another): the scene as parsed, a Gmsh file's content, the integration.
    state_fingerprint: String,
    /// `effects.regularization`: whether the host's element length (`PROPS(7)`, else
    /// `CELENT`) stretches the cell's softening (the state fingerprint then also holds
    /// the length).
    regularization: bool,
}

pub fn run(args: &InfoArgs) -> Result<()> {
    let (scene, name) = load_scene_with(args.scene.as_ref(), &args.set)?;
    let model = Arc::new(Model::from_scene(&scene)?);
    let stats = model.mesh_stats();
    let (instance_bytes, checkpoint_bytes) = loaded_instance_bytes(&model)?;
    let info = Info {
        scene: name,
        analysis: scene.spec.cell.analysis,
        integration: match model.integration() {
            Integration::Implicit => "implicit",
            Integration::Implex => "implex",
        },
        nodes: stats.nodes,
        triangles: stats.triangles,
        interface_elements: stats.interface_elements,
        unknowns: model.state_sizes().unknowns,
        itz_points: model.interface_points(),
        history_values: model.state_sizes().history,
        instance_bytes,
        checkpoint_bytes,
        umat_nstatv: model.statev_len(),
        state_fingerprint: format!("{:010x}", model.fingerprint()),
        regularization: scene.spec.effects.regularization,
    };
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&info).expect("plain data")
        );
    } else {
        print_text(&info);
    }
    Ok(())
}

/// An instance's bytes and its checkpoint's after one small loading update with the
/// tangent (which fills the predictor's caches) and its commit.
fn loaded_instance_bytes(model: &Arc<Model>) -> Result<(usize, usize)> {
    let mut instance = Instance::new(model.clone());
    let mut ws = model.workspace();
    instance.update([1e-5, 0.0, 0.0], &mut ws, TangentRequest::Consistent)?;
    instance.commit()?;
    Ok((instance.state_bytes(), instance.state_size()?))
}

fn print_text(info: &Info) {
    let rows: [(&str, String); 14] = [
        ("scene", info.scene.clone()),
        (
            "analysis",
            serde_json::to_string(&info.analysis)
                .expect("plain data")
                .replace('"', ""),
        ),
        ("integration", info.integration.to_string()),
        ("nodes", info.nodes.to_string()),
        ("triangles", info.triangles.to_string()),
        ("interface elements", info.interface_elements.to_string()),
        ("unknowns", info.unknowns.to_string()),
        ("ITZ points", info.itz_points.to_string()),
        ("history values", info.history_values.to_string()),
        ("instance bytes", info.instance_bytes.to_string()),
        ("checkpoint bytes", info.checkpoint_bytes.to_string()),
        ("umat_nstatv", info.umat_nstatv.to_string()),
        ("state fingerprint", info.state_fingerprint.clone()),
        (
            "regularization",
            if info.regularization {
                "by the element length: PROPS(7), else CELENT".to_string()
            } else {
                "off".to_string()
            },
        ),
    ];
    for (label, value) in rows {
        println!("{label:<24} {value}");
    }
}

//! `rve mesh SCENE [--json] [--vtk FILE] [--svg FILE]`.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use rve::error::{Error, Result};
use rve::io::{write_svg, write_vtu};
use rve::model::build_microstructure;
use rve::MeshStats;
use serde::Serialize;

use super::load_scene_with;

#[derive(Args, Debug)]
pub struct MeshArgs {
    /// Scene file (TOML). Default: the embedded paper RVE (scenes/paper_rve.toml).
    scene: Option<PathBuf>,
    /// Print one JSON object with the statistics instead of text.
    #[arg(long)]
    json: bool,
    /// Write the mesh as a VTK unstructured grid (.vtu) for ParaView.
    #[arg(long, value_name = "FILE")]
    vtk: Option<PathBuf>,
    /// Write an SVG picture of the mesh (phases coloured, ITZ in red).
    #[arg(long, value_name = "FILE")]
    svg: Option<PathBuf>,
    /// Set a scene key first, as `rve run --set` does (repeatable).
    #[arg(long, value_name = "KEY=VALUE")]
    set: Vec<String>,
}

#[derive(Serialize)]
struct Report<'a> {
    scene: &'a str,
    #[serde(flatten)]
    stats: MeshStats,
    inclusions: usize,
    geometric_area_fraction: Option<f64>,
    placement_rounds: Option<u32>,
    mesh_seconds: f64,
}

fn create(path: &Path) -> Result<BufWriter<File>> {
    File::create(path)
        .map(BufWriter::new)
        .map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })
}

fn io_err(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

pub fn run(args: &MeshArgs) -> Result<()> {
    let (scene, name) = load_scene_with(args.scene.as_ref(), &args.set)?;
    let start = Instant::now();
    let micro = build_microstructure(&scene)?;
    let mesh_seconds = start.elapsed().as_secs_f64();
    let report = Report {
        scene: &name,
        stats: MeshStats::of(&micro.mesh),
        inclusions: micro.inclusions.len(),
        geometric_area_fraction: micro.geometric_area_fraction,
        placement_rounds: micro.placement_rounds,
        mesh_seconds,
    };
    if let Some(path) = &args.vtk {
        let mut w = create(path)?;
        write_vtu(&micro.mesh, &mut w)
            .and_then(|_| w.flush())
            .map_err(io_err(path))?;
    }
    if let Some(path) = &args.svg {
        let mut w = create(path)?;
        write_svg(&micro.mesh, 800.0, &mut w)
            .and_then(|_| w.flush())
            .map_err(io_err(path))?;
    }
    if args.json {
        let text = serde_json::to_string_pretty(&report).map_err(|e| Error::Mesh(e.to_string()))?;
        println!("{text}");
    } else {
        let s = &report.stats;
        println!("scene                    {}", report.scene);
        println!("cell                     {} x {}", s.cell[0], s.cell[1]);
        println!("inclusions               {}", report.inclusions);
        if let Some(f) = report.geometric_area_fraction {
            println!("area fraction (geometry) {f:.4}");
        }
        println!("area fraction (mesh)     {:.4}", s.inclusion_area_fraction);
        println!("nodes                    {}", s.nodes);
        println!(
            "triangles                {} ({} matrix, {} inclusion)",
            s.triangles, s.matrix_triangles, s.inclusion_triangles
        );
        println!("interface elements       {}", s.interface_elements);
        println!("min angle                {:.2} deg", s.min_angle_deg);
        println!("periodic sides match     {}", s.periodic_sides_match);
        println!(
            "meshing time             {:.2} ms",
            1e3 * report.mesh_seconds
        );
    }
    Ok(())
}

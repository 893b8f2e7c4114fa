//! `rve run [SCENE] --out DIR`: follow the scene's strain path, write `DIR/response.csv`.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use clap::Args;
use rve::error::{Error, Result};
use rve::scene::path_points;
use rve::{Instance, Model, TangentRequest};

use super::load_scene;

#[derive(Args, Debug)]
pub struct RunArgs {
    /// Scene file (TOML). Default: the embedded paper RVE (scenes/paper_rve.toml).
    scene: Option<PathBuf>,
    /// Output directory (created if missing).
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Do not print a line per increment.
    #[arg(long)]
    quiet: bool,
    /// Also write a ParaView time series of the micro fields to this directory: one
    /// `step_NNNN.vtu` per increment and the index `series.pvd` (time = step).
    #[arg(long, value_name = "DIR")]
    vtk: Option<PathBuf>,
}

/// Header of `response.csv`; the C driver writes the same columns.
pub const CSV_HEADER: &str = "step,eps_xx,eps_yy,gamma_xy,sig_xx,sig_yy,sig_xy,D11,D12,D13,D21,D22,D23,D31,D32,D33,iterations,substeps,s_zz,factorizations,loading_points,unloading_points,contact_points,seconds,limit_points";

pub fn run(args: &RunArgs) -> Result<()> {
    let (scene, name) = load_scene(args.scene.as_ref())?;
    if scene.spec.path.is_empty() {
        return Err(Error::scene(
            "path",
            "the scene has no [[path]] segments to follow",
        ));
    }
    let start = Instant::now();
    let model = Arc::new(Model::from_scene(&scene)?);
    let setup = start.elapsed().as_secs_f64();
    std::fs::create_dir_all(&args.out).map_err(|source| Error::Io {
        path: args.out.clone(),
        source,
    })?;
    let csv_path = args.out.join("response.csv");
    let io_err = |source| Error::Io {
        path: csv_path.clone(),
        source,
    };
    let mut csv = BufWriter::new(File::create(&csv_path).map_err(io_err)?);
    writeln!(csv, "{CSV_HEADER}").map_err(io_err)?;
    if !args.quiet {
        eprintln!(
            "{name}: {} unknowns, {} interface elements, model built in {:.1} ms",
            model.disc.n(),
            model.disc.interfaces.len(),
            1e3 * setup
        );
    }
    if let Some(dir) = &args.vtk {
        std::fs::create_dir_all(dir).map_err(|source| Error::Io {
            path: dir.clone(),
            source,
        })?;
    }
    let mut series = Vec::new();
    let mut instance = Instance::new(model.clone());
    let mut ws = model.workspace();
    for (step, eps) in path_points(&scene.spec.path).into_iter().enumerate() {
        let t0 = Instant::now();
        let r = instance.update(eps, &mut ws, TangentRequest::Consistent)?;
        let seconds = t0.elapsed().as_secs_f64();
        instance.commit()?;
        let d = r.tangent;
        writeln!(
            csv,
            "{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{:e},{},{},{},{},{:e},{}",
            step + 1, eps[0], eps[1], eps[2], r.stress[0], r.stress[1], r.stress[2],
            d[0], d[1], d[2], d[3], d[4], d[5], d[6], d[7], d[8],
            r.report.iterations, r.report.substeps, r.s_zz, r.report.factorizations,
            r.report.loading, r.report.unloading, r.report.contact, seconds,
            r.report.limit_points
        )
        .map_err(io_err)?;
        if let Some(dir) = &args.vtk {
            let file = format!("step_{:04}.vtu", step + 1);
            model.write_vtu(instance.committed(), &dir.join(&file))?;
            series.push(((step + 1) as f64, file));
        }
        if !args.quiet {
            eprintln!(
                "step {:4}  eps = [{:+.3e} {:+.3e} {:+.3e}]  sig = [{:+.4} {:+.4} {:+.4}]  it {} sub {}",
                step + 1, eps[0], eps[1], eps[2], r.stress[0], r.stress[1], r.stress[2],
                r.report.iterations, r.report.substeps
            );
        }
    }
    csv.flush().map_err(io_err)?;
    if let Some(dir) = &args.vtk {
        write_series_index(&dir.join("series.pvd"), &series)?;
    }
    if !args.quiet {
        eprintln!("wrote {}", csv_path.display());
    }
    Ok(())
}

/// Writes the `.pvd` index of the VTK series.
fn write_series_index(path: &std::path::Path, series: &[(f64, String)]) -> Result<()> {
    let io_err = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut w = BufWriter::new(File::create(path).map_err(io_err)?);
    rve::io::write_pvd(series, &mut w).map_err(io_err)?;
    w.flush().map_err(io_err)
}

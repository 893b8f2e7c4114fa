//! `rve run [SCENE] --out DIR`: follow the scene's strain path, write `DIR/response.csv`.

use std::fs::File;
use std::io::{BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rve::error::{Error, Result};
use rve::model::mixed::update_mixed;
use rve::scene::{path_points, path_zero_stress};
use rve::{Instance, Model, Response, TangentRequest};

use super::load_scene_with;

#[derive(Args, Debug)]
pub struct RunArgs {
    /// Scene file (TOML). Default: the embedded paper RVE (scenes/paper_rve.toml).
    scene: Option<PathBuf>,
    /// Output directory (created if missing).
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Print nothing but errors (no progress bar, no line per increment). Otherwise a
    /// progress bar when stderr is a terminal, a line per increment when it is not.
    #[arg(long)]
    quiet: bool,
    /// Also write a ParaView time series of the micro fields to this directory: one
    /// `step_NNNN.vtu` per increment and the index `series.pvd` (time = step).
    #[arg(long, value_name = "DIR")]
    vtk: Option<PathBuf>,
    /// Also write SVG pictures to this directory: the deformed RVE at the increments of
    /// `--frames` (`step_NNNN.svg`) and the stresses against the increment
    /// (`response.svg`).
    #[arg(long, value_name = "DIR")]
    svg: Option<PathBuf>,
    /// Increments pictured by `--svg`: `last`, `all`, `peak` (the peak of the first
    /// loading: the largest stress along the direction of the first increment's stress),
    /// or a list of increment numbers `N,M,...` (from 1).
    #[arg(long, default_value = "last", value_parser = parse_frames)]
    frames: Frames,
    /// Set a scene key before the run, as if the file said so (repeatable):
    /// `--set materials.itz.sigma_c=3.5 --set solver.tolerance=1e-8`. VALUE is a TOML
    /// value (a number, `true`, `"text"`, `[1, 2]`), else taken as a string; missing
    /// tables are created; `path.0.increments` is the first `[[path]]`'s. The scene is
    /// validated after.
    #[arg(long, value_name = "KEY=VALUE")]
    set: Vec<String>,
}

/// Which increments `--svg` pictures.
#[derive(Clone, Debug, PartialEq)]
pub enum Frames {
    Last,
    All,
    Peak,
    List(Vec<usize>),
}

fn parse_frames(s: &str) -> std::result::Result<Frames, String> {
    match s {
        "last" => Ok(Frames::Last),
        "all" => Ok(Frames::All),
        "peak" => Ok(Frames::Peak),
        _ => s
            .split(',')
            .map(|n| match n.trim().parse::<usize>() {
                Ok(k) if k >= 1 => Ok(k),
                _ => Err(format!(
                    "`{n}` is not an increment number (1, 2, ...); use last, all, peak or N,M,..."
                )),
            })
            .collect::<std::result::Result<Vec<_>, _>>()
            .map(Frames::List),
    }
}

/// Header of `response.csv`; the C driver writes the same columns.
pub const CSV_HEADER: &str = "step,eps_xx,eps_yy,gamma_xy,sig_xx,sig_yy,sig_xy,D11,D12,D13,D21,D22,D23,D31,D32,D33,iterations,substeps,s_zz,factorizations,loading_points,unloading_points,contact_points,seconds,limit_points,held_points,fast,check_factorizations,step_too_large,error_estimate,step_ratio";

/// Whether step control would have to follow a mixed-controlled segment.
fn controlled_with_zero_stress(solver: &rve::scene::SolverSpec, zero_stress: &[[bool; 3]]) -> bool {
    solver.step_tolerance.is_some() && zero_stress.iter().any(|z| *z != [false; 3])
}

pub fn run(args: &RunArgs) -> Result<()> {
    let (scene, name) = load_scene_with(args.scene.as_ref(), &args.set)?;
    if scene.spec.path.is_empty() {
        return Err(Error::scene(
            "path",
            "the scene has no [[path]] segments to follow",
        ));
    }
    let start = Instant::now();
    let model = Arc::new(Model::from_scene(&scene)?);
    let setup = start.elapsed().as_secs_f64();
    let points = path_points(&scene.spec.path);
    let mut outputs = Outputs::create(args, &model, points.len())?;
    if !args.quiet {
        eprintln!(
            "{name}: {} unknowns, {} interface elements, model built in {:.1} ms",
            model.unknowns(),
            model.interface_elements(),
            1e3 * setup
        );
    }
    outputs.create_dirs()?;
    let mut instance = Instance::new(model.clone());
    let mut ws = model.workspace();
    let progress = Progress::new(args.quiet, points.len());
    let zero_stress = path_zero_stress(&scene.spec.path);
    if controlled_with_zero_stress(&scene.spec.solver, &zero_stress) {
        return Err(Error::scene(
            "path",
            "zero_stress segments are followed with the path's own increments: leave out \
             solver.step_tolerance for them",
        ));
    }
    let times = step_times(&points);
    let controlled = scene.spec.solver.step_tolerance.is_some();
    let mut control = StepControl::default();
    for (step, eps) in points.into_iter().enumerate() {
        let r = if controlled {
            control.follow(&mut instance, &mut ws, &mut outputs, eps, times[step])?
        } else {
            let t0 = Instant::now();
            let (r, eps) = if zero_stress[step] == [false; 3] {
                let r =
                    instance.update_timed(eps, times[step], &mut ws, TangentRequest::Consistent)?;
                (r, eps)
            } else {
                let (r, eps) =
                    update_mixed(&mut instance, eps, zero_stress[step], times[step], &mut ws)?;
                if outputs.needs_fields() && !instance.trial_unknowns_are_current() {
                    // The mixed iterations reused the step at another strain: form it at
                    // this one for --vtk and --svg.
                    instance.refactor_step();
                    let request = TangentRequest::Consistent;
                    let again = instance.update_timed(eps, times[step], &mut ws, request)?;
                    (again, eps)
                } else {
                    (r, eps)
                }
            };
            let seconds = t0.elapsed().as_secs_f64();
            instance.commit()?;
            outputs.record(step + 1, eps, &r, seconds, instance.committed())?;
            r
        };
        progress.step(step, eps, &r);
    }
    progress.finish();
    if controlled && !args.quiet {
        eprintln!(
            "{name}: solver.step_tolerance: {} increments, {} redone smaller, {} kept above \
             the tolerance (the estimate did not fall with the step, or at the smallest \
             step, 1/{MIN_FRACTION_INV} of the path's)",
            control.rows, control.redos, control.kept_above
        );
    }
    outputs.finish()
}

/// `rve run`'s progress on stderr: a bar on a terminal, a line per increment otherwise,
/// nothing when quiet.
struct Progress {
    bar: Option<ProgressBar>,
    lines: bool,
}

impl Progress {
    fn new(quiet: bool, increments: usize) -> Self {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let style = ProgressStyle::with_template(
                "{bar:32} {pos}/{len} increments, {elapsed} (eta {eta})  {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar());
            ProgressBar::new(increments as u64).with_style(style)
        });
        let lines = !quiet && bar.is_none();
        Self { bar, lines }
    }

    fn step(&self, step: usize, eps: [f64; 3], r: &Response) {
        if let Some(bar) = &self.bar {
            bar.set_message(format!(
                "sig = [{:+.4} {:+.4} {:+.4}]",
                r.stress[0], r.stress[1], r.stress[2]
            ));
            bar.inc(1);
        } else if self.lines {
            eprintln!(
                "step {:4}  eps = [{:+.3e} {:+.3e} {:+.3e}]  sig = [{:+.4} {:+.4} {:+.4}]  it {} sub {}",
                step + 1, eps[0], eps[1], eps[2], r.stress[0], r.stress[1], r.stress[2],
                r.report.iterations, r.report.substeps
            );
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish();
        }
    }
}

/// Smallest step `rve run` takes under `solver.step_tolerance`, as a fraction of the
/// path's own increment: a step that still exceeds the tolerance there is kept.
const MIN_FRACTION_INV: u32 = 1024;

/// `rve run` as a host that follows the suggested step ratio (`solver.step_tolerance`):
/// each path increment is the largest step, a step whose ratio is below 1 is redone that
/// much smaller, and the next step is the ratio times the last (capped by the path's
/// increment, ending on each path point). Every accepted step is a row.
#[derive(Default)]
struct StepControl {
    /// The next step as a strain norm (0: the path's increment).
    step: f64,
    rows: usize,
    redos: usize,
    kept_above: usize,
}

impl StepControl {
    /// Steps from the committed strain to the path point `target`, `nominal` (its strain
    /// norm) away; returns the last accepted response.
    fn follow(
        &mut self,
        instance: &mut Instance,
        ws: &mut rve::Workspace,
        outputs: &mut Outputs,
        target: [f64; 3],
        nominal: f64,
    ) -> Result<Response> {
        let start = instance.committed().strain;
        let (mut done, mut seconds) = (0.0, 0.0);
        let smallest = nominal / f64::from(MIN_FRACTION_INV);
        loop {
            let mut step = if self.step > 0.0 {
                self.step.min(nominal)
            } else {
                nominal
            };
            if nominal - done <= step * (1.0 + 1e-9) || nominal <= 0.0 {
                step = nominal - done;
            }
            let last = nominal <= 0.0 || done + step >= nominal;
            let s = if last { 1.0 } else { (done + step) / nominal };
            let eps: [f64; 3] = std::array::from_fn(|c| start[c] + s * (target[c] - start[c]));
            let t0 = Instant::now();
            let r = instance.update_timed(eps, step, ws, TangentRequest::Consistent)?;
            seconds += t0.elapsed().as_secs_f64();
            let ratio = r.report.suggested_step_ratio();
            if ratio < 1.0 && step > smallest {
                instance.revert();
                self.redos += 1;
                self.step = (step * ratio).max(smallest);
                continue;
            }
            self.kept_above += usize::from(r.report.exceeds_tolerance());
            instance.commit()?;
            self.rows += 1;
            outputs.record(self.rows, eps, &r, seconds, instance.committed())?;
            seconds = 0.0;
            // A last piece cut short by the path point does not limit the next step.
            self.step = if last && step < self.step {
                self.step
            } else {
                step * ratio.max(1.0)
            };
            if last {
                return Ok(r);
            }
            done += step;
        }
    }
}

/// The files of one `rve run`: `response.csv`, and what `--vtk` and `--svg` ask for.
struct Outputs<'a> {
    args: &'a RunArgs,
    model: &'a Model,
    csv_path: PathBuf,
    csv: BufWriter<File>,
    /// Increments on the path.
    n_steps: usize,
    /// The points of `response.svg`.
    response: Vec<rve::io::ResponsePoint>,
    /// (increment, committed state, stress along the first one's) kept for --frames
    /// last/peak.
    kept: Option<(usize, rve::State, f64)>,
    /// (time, file) of the VTK series.
    series: Vec<(f64, String)>,
}

impl<'a> Outputs<'a> {
    /// Creates the output directory and `response.csv` with its header.
    fn create(args: &'a RunArgs, model: &'a Model, n_steps: usize) -> Result<Self> {
        std::fs::create_dir_all(&args.out).map_err(|source| Error::Io {
            path: args.out.clone(),
            source,
        })?;
        let csv_path = args.out.join("response.csv");
        let io_err = io_error(&csv_path);
        let mut csv = BufWriter::new(File::create(&csv_path).map_err(&io_err)?);
        writeln!(csv, "{CSV_HEADER}").map_err(io_err)?;
        Ok(Outputs {
            args,
            model,
            csv_path,
            csv,
            n_steps,
            response: Vec::new(),
            kept: None,
            series: Vec::new(),
        })
    }

    /// Whether `--vtk` or `--svg` write the RVE's fields.
    fn needs_fields(&self) -> bool {
        self.args.vtk.is_some() || self.args.svg.is_some()
    }

    /// Creates the `--vtk` and `--svg` directories, and checks that the increments of
    /// `--frames` are on the path.
    fn create_dirs(&self) -> Result<()> {
        let args = self.args;
        for dir in args.vtk.iter().chain(&args.svg) {
            std::fs::create_dir_all(dir).map_err(|source| Error::Io {
                path: dir.clone(),
                source,
            })?;
        }
        if let (Some(_), Frames::List(list)) = (&args.svg, &args.frames) {
            if let Some(bad) = list.iter().find(|&&k| k > self.n_steps) {
                return Err(Error::scene(
                    "path",
                    format!(
                        "--frames names increment {bad}, the path has {}",
                        self.n_steps
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Writes increment `step` (from 1) at strain `eps`, its response `r` solved in
    /// `seconds`, and its committed state `state`: a line of `response.csv`, a VTK file,
    /// a point of `response.svg` and a picture of `--frames`.
    fn record(
        &mut self,
        step: usize,
        eps: [f64; 3],
        r: &Response,
        seconds: f64,
        state: &rve::State,
    ) -> Result<()> {
        let d = r.tangent;
        writeln!(
            self.csv,
            "{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{:e},{},{},{},{},{:e},{},{},{},{},{},{:e},{:e}",
            step, eps[0], eps[1], eps[2], r.stress[0], r.stress[1], r.stress[2],
            d[0], d[1], d[2], d[3], d[4], d[5], d[6], d[7], d[8],
            r.report.iterations, r.report.substeps, r.s_zz, r.report.factorizations,
            r.report.loading, r.report.unloading, r.report.contact, seconds,
            r.report.limit_points, r.report.held_points, u8::from(r.report.answer.is_fast()),
            r.report.check_factorizations, u8::from(r.report.step_too_large),
            r.report.error_estimate.unwrap_or(0.0), r.report.suggested_step_ratio()
        )
        .map_err(io_error(&self.csv_path))?;
        if let Some(dir) = &self.args.vtk {
            let file = format!("step_{step:04}.vtu");
            self.model.write_vtu(state, &dir.join(&file))?;
            self.series.push((step as f64, file));
        }
        if let Some(dir) = &self.args.svg {
            self.picture(dir, step, r, state)?;
        }
        Ok(())
    }

    /// `--svg`: the point of `response.svg` of increment `step` (response `r`), and its
    /// picture if `--frames` names it, or the state kept for `last` and `peak`.
    fn picture(&mut self, dir: &Path, step: usize, r: &Response, state: &rve::State) -> Result<()> {
        self.response.push(rve::io::ResponsePoint {
            t: step as f64,
            stress: r.stress,
            loading_points: r.report.loading,
            contact_points: r.report.contact,
        });
        // The stress along the direction of the first increment's stress.
        let first = self.response[0].stress;
        let norm = first
            .iter()
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt()
            .max(f64::MIN_POSITIVE);
        let size = (0..3).map(|k| r.stress[k] * first[k]).sum::<f64>() / norm;
        let keep = match &self.args.frames {
            Frames::All => {
                write_frame(self.model, dir, step, state)?;
                false
            }
            Frames::List(list) => {
                if list.contains(&step) {
                    write_frame(self.model, dir, step, state)?;
                }
                false
            }
            Frames::Last => step == self.n_steps,
            Frames::Peak => self.kept.as_ref().is_none_or(|k| size > k.2),
        };
        if keep {
            self.kept = Some((step, state.clone(), size));
        }
        Ok(())
    }

    /// Flushes `response.csv`, writes the VTK index, the kept picture and
    /// `response.svg`.
    fn finish(mut self) -> Result<()> {
        self.csv.flush().map_err(io_error(&self.csv_path))?;
        let args = self.args;
        if let Some(dir) = &args.vtk {
            write_series_index(&dir.join("series.pvd"), &self.series)?;
        }
        if let Some(dir) = &args.svg {
            if let Some((step, state, _)) = &self.kept {
                write_frame(self.model, dir, *step, state)?;
            }
            let path = dir.join("response.svg");
            write_with(&path, |w| rve::io::write_response_svg(&self.response, w))?;
        }
        if !args.quiet {
            eprintln!("wrote {}", self.csv_path.display());
        }
        Ok(())
    }
}

/// Maps a failure to write `path` to [`Error::Io`].
fn io_error(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes the `.pvd` index of the VTK series.
fn write_series_index(path: &std::path::Path, series: &[(f64, String)]) -> Result<()> {
    write_with(path, |w| rve::io::write_pvd(series, w))
}

/// Writes `DIR/step_NNNN.svg`, the deformed RVE of the committed `state` of increment
/// `step`.
fn write_frame(
    model: &Model,
    dir: &std::path::Path,
    step: usize,
    state: &rve::State,
) -> Result<()> {
    let fields = model.fields(state)?;
    let e = state.strain;
    let caption = format!(
        "increment {step}, strain [{:.3e} {:.3e} {:.3e}]",
        e[0], e[1], e[2]
    );
    write_with(&dir.join(format!("step_{step:04}.svg")), |w| {
        rve::io::write_deformed_svg(model.mesh(), &fields, 900.0, &caption, w)
    })
}

/// Creates `path` and writes it with `f`, mapping failures to [`Error::Io`].
fn write_with(
    path: &std::path::Path,
    f: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<()> {
    let io_err = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut w = BufWriter::new(File::create(path).map_err(io_err)?);
    f(&mut w).map_err(io_err)?;
    w.flush().map_err(io_err)
}

/// The time increment of each path step: the norm of its strain increment (what IMPL-EX
/// scales its extrapolation by, see `solver::implex`).
fn step_times(points: &[[f64; 3]]) -> Vec<f64> {
    let mut previous = [0.0; 3];
    points
        .iter()
        .map(|eps| {
            let dt = (0..3)
                .map(|c| (eps[c] - previous[c]).powi(2))
                .sum::<f64>()
                .sqrt();
            previous = *eps;
            dt
        })
        .collect()
}

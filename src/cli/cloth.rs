//! `modelgap cloth`: run a cloth scene and write its trajectory (`run`), or time the solver
//! on a scene (`bench`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;
use clap::{Args, Subcommand, ValueEnum};
use modelgap::cloth::Method;
use modelgap::cloth::scenes::{self, Scene};
use modelgap::cloth::trajectory::{
    ClothRun, MarkerSelection, RunLimits, RunOptions, RunStats, run_scene, write_run_path,
};
use modelgap::io::Format;
use serde::Serialize;

use super::BadInput;
use super::format::num;

/// The built-in scene names, for messages.
const BUILT_IN: &str = "corner, two-corners, drape";

/// The `modelgap cloth` subcommands.
#[derive(Debug, Subcommand)]
pub enum ClothCommand {
    /// Run a scene and write the marker trajectory (.csv) or markers, mesh and transforms
    /// for Foxglove (.mcap)
    Run(RunArgs),
    /// Time the cloth solver on a scene: iterations, stretch, x real time
    Bench(BenchArgs),
}

/// Arguments of `modelgap cloth run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// A scene file (.toml) or a built-in scene: corner, two-corners, drape
    #[arg(long, value_name = "SCENE")]
    scene: String,

    /// Write the trajectory to this file: .csv (markers) or .mcap (markers, mesh, /tf)
    #[arg(long, value_name = "FILE")]
    out: PathBuf,

    /// Simulated time (s) [default: the scene's]
    #[arg(long, value_name = "T", value_parser = parse_positive, allow_negative_numbers = true)]
    duration: Option<f64>,

    /// Frames per second written (Hz) [default: one per step]
    #[arg(long, value_name = "HZ", value_parser = parse_positive, allow_negative_numbers = true)]
    rate: Option<f64>,

    /// The vertices written as markers: `all` or ids (vertex indices) separated by commas
    #[arg(long, value_name = "ID,ID,...|all", default_value = "all", value_parser = parse_markers)]
    markers: MarkerSelection,

    /// Constraint solver [default: the scene's, newton]
    #[arg(long, value_enum)]
    method: Option<MethodArg>,

    #[command(flatten)]
    limits: LimitArgs,

    /// The most memory the recorded frames may take (MiB): frames x (vertices + markers) x
    /// 24 bytes [default: 2048]
    #[arg(long, value_name = "MIB", value_parser = clap::value_parser!(u64).range(1..), allow_negative_numbers = true)]
    max_frame_mib: Option<u64>,
}

/// The size limits of `cloth run` and `cloth bench`, checked before the run starts.
#[derive(Debug, Args)]
struct LimitArgs {
    /// The most particles (nx x nz) the scene's grid may have [default: 1000000]
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..), allow_negative_numbers = true)]
    max_particles: Option<u64>,

    /// The most steps (duration / dt) the run may take [default: 10000000]
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..), allow_negative_numbers = true)]
    max_steps: Option<u64>,
}

impl LimitArgs {
    /// Puts the particle limit on the scene's grid and returns the run's limits.
    fn apply(&self, scene: &mut Scene) -> RunLimits {
        if let Some(n) = self.max_particles {
            scene.cloth.max_particles = usize::try_from(n).unwrap_or(usize::MAX);
        }
        let mut limits = RunLimits::default();
        if let Some(n) = self.max_steps {
            limits.max_steps = usize::try_from(n).unwrap_or(usize::MAX);
        }
        limits
    }
}

/// The constraint solver (`--method`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum MethodArg {
    /// The paper's iteration, one constraint at a time
    GaussSeidel,
    /// All constraints at once, sparse Cholesky (fast, exact)
    Newton,
    /// The paper's acceleration: acyclic strips solved in linear time
    Strips,
}

impl From<MethodArg> for Method {
    fn from(m: MethodArg) -> Method {
        match m {
            MethodArg::GaussSeidel => Method::GaussSeidel,
            MethodArg::Newton => Method::Newton,
            MethodArg::Strips => Method::Strips,
        }
    }
}

/// Arguments of `modelgap cloth bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// A scene file (.toml) or a built-in scene: corner, two-corners, drape
    #[arg(long, value_name = "SCENE")]
    scene: String,

    /// Vertices along x (the scene's grid is resized, pins kept at their places)
    #[arg(long, value_name = "N", requires = "nz", allow_negative_numbers = true)]
    nx: Option<usize>,

    /// Vertices along z
    #[arg(long, value_name = "N", requires = "nx", allow_negative_numbers = true)]
    nz: Option<usize>,

    /// Simulated time (s) [default: the scene's]
    #[arg(long, value_name = "T", value_parser = parse_positive, allow_negative_numbers = true)]
    duration: Option<f64>,

    /// Constraint solver [default: the scene's, newton]
    #[arg(long, value_enum)]
    method: Option<MethodArg>,

    /// Run the solver in a pool of N threads [default: 1]
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..), allow_negative_numbers = true)]
    threads: Option<u16>,

    /// Gauss-Seidel sweep order [default: coloured when --threads is given, else serial]
    #[arg(long, value_enum)]
    sweep: Option<SweepArg>,

    /// Allowed relative stretch per step [default: the scene's, 1e-4]
    #[arg(long, value_name = "REL", value_parser = parse_positive, allow_negative_numbers = true)]
    tolerance: Option<f64>,

    /// Iteration limit per step (sweeps or Newton solves) [default: 1000]
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..), allow_negative_numbers = true)]
    max_iterations: Option<u32>,

    #[command(flatten)]
    limits: LimitArgs,

    /// Print JSON instead of text
    #[arg(long)]
    json: bool,
}

/// The Gauss–Seidel sweep order (`--sweep`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum SweepArg {
    /// Constraint after constraint in index order (the paper's)
    Serial,
    /// Colour by colour, each large colour's constraints in parallel; the same result for
    /// any number of threads
    Coloured,
}

/// Runs a `modelgap cloth` subcommand.
///
/// # Errors
///
/// An unknown scene or unreadable scene file, a marker id past the mesh, an unwritable output
/// file, a solver error.
pub fn run(command: &ClothCommand) -> anyhow::Result<()> {
    match command {
        ClothCommand::Run(args) => run_cmd(args),
        ClothCommand::Bench(args) => bench(args),
    }
}

fn run_cmd(args: &RunArgs) -> anyhow::Result<()> {
    // Refuse an unknown extension before the simulation, not after it.
    Format::for_writing(&args.out)
        .with_context(|| format!("choosing the format of {}", args.out.display()))?;
    let mut scene = load_scene(&args.scene)?;
    if let Some(m) = args.method {
        scene.params.method = m.into();
    }
    let mut limits = args.limits.apply(&mut scene);
    if let (MarkerSelection::Ids(ids), Ok(n)) = (&args.markers, scene.cloth.n_vertices())
        && let Some(bad) = ids.iter().find(|&&id| id as usize >= n)
    {
        return Err(BadInput(format!(
            "--markers: expected vertex ids of scene {} ({} x {} grid, 0 to {}), found {bad}",
            scene.name,
            scene.cloth.nx,
            scene.cloth.nz,
            n - 1
        ))
        .into());
    }
    if let Some(mib) = args.max_frame_mib {
        limits.max_frame_bytes = mib.saturating_mul(1 << 20);
    }
    let options = RunOptions {
        duration: args.duration,
        rate: args.rate,
        markers: args.markers.clone(),
        limits,
        cancel: Some(super::interrupt::flag()),
    };
    let start = Instant::now();
    let run = run_scene(&scene, &options)
        .map_err(|e| run_error(e, &scene.name))
        .with_context(|| format!("running scene {}", scene.name))?;
    let wall = start.elapsed().as_secs_f64();
    super::interrupt::check(&format!("{} not written", args.out.display()))?;
    write_run_path(&run, &args.out).with_context(|| format!("writing {}", args.out.display()))?;
    super::print(&run_summary(&run, wall, &args.out))
}

fn run_summary(run: &ClothRun, wall_s: f64, out: &Path) -> String {
    let st = &run.stats;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "scene {}: {} particles, {} constraints, {} steps of {} s ({} s simulated)",
        run.scene,
        st.n_particles,
        st.n_constraints,
        st.steps,
        num(st.dt),
        num(st.simulated()),
    );
    let _ = writeln!(
        s,
        "worst stretch {:.3e} ({} of {} steps converged), iterations mean {:.1}, max {}{}",
        st.max_stretch,
        st.steps - st.unconverged_steps,
        st.steps,
        st.mean_iterations(),
        st.max_iterations,
        if st.fallback_steps > 0 {
            format!(
                "; {} steps fell back to Gauss-Seidel (Newton could not be built)",
                st.fallback_steps
            )
        } else {
            String::new()
        },
    );
    if st.first_order_steps > 0 {
        let _ = writeln!(
            s,
            "{} of {} steps did not converge as BDF2 and were taken as the paper's impulse step",
            st.first_order_steps, st.steps
        );
    }
    if let Some(stagnation) = &st.stagnation {
        let _ = writeln!(s, "warning: {stagnation}");
    }
    let _ = writeln!(
        s,
        "wall time {:.3} s, {} x real time",
        wall_s,
        real_time_factor(st, wall_s).map_or_else(|| "-".to_owned(), |x| format!("{x:.2}")),
    );
    if let Some(m) = &run.markers {
        let _ = writeln!(
            s,
            "wrote {} frames of {} markers to {}",
            m.n_frames(),
            m.n_markers(),
            out.display()
        );
    }
    s
}

/// Simulated time over wall time; `None` when the wall time is too short to measure.
fn real_time_factor(stats: &RunStats, wall_s: f64) -> Option<f64> {
    (wall_s > 0.0).then(|| stats.simulated() / wall_s)
}

/// Everything `bench --json` prints.
#[derive(Debug, Serialize)]
struct BenchReport {
    scene: String,
    particles: usize,
    constraints: usize,
    steps: usize,
    dt_s: f64,
    simulated_s: f64,
    max_stretch: f64,
    mean_iterations: f64,
    max_iterations: usize,
    unconverged_steps: usize,
    /// Steps that ran another method than the one asked for (Newton could not be built).
    fallback_steps: usize,
    /// Steps of a BDF2 scene taken again as the paper's impulse step.
    first_order_steps: usize,
    /// The stretch tolerance could not be reached: the warning, naming the level held.
    warning: Option<String>,
    /// Wall-clock time of the run (s): what a user waits, and what a shared machine slows.
    wall_s: f64,
    /// Simulated seconds per wall-clock second.
    x_real_time: Option<f64>,
    /// CPU time of the process over the run, every thread, user and system (s); `null`
    /// where the platform does not report it.
    cpu_s: Option<f64>,
    /// Simulated seconds per CPU second: the solver's own speed, which other load on the
    /// machine does not change (on one thread, the wall-clock factor of an idle machine).
    x_real_time_cpu: Option<f64>,
    /// Wall-clock time per step (ms).
    wall_ms_per_step: f64,
    /// CPU time per step (ms).
    cpu_ms_per_step: Option<f64>,
    threads: usize,
    method: &'static str,
    /// `serial` or `coloured`: the Gauss–Seidel sweep order (`none` for
    /// the other methods).
    sweep: &'static str,
    stretch_tolerance: f64,
}

fn bench(args: &BenchArgs) -> anyhow::Result<()> {
    let mut scene = load_scene(&args.scene)?;
    let limits = args.limits.apply(&mut scene);
    if let (Some(nx), Some(nz)) = (args.nx, args.nz) {
        scene = scene
            .resized(nx, nz)
            .map_err(|e| run_error(e, &scene.name))
            .with_context(|| format!("resizing the scene's grid to --nx {nx} --nz {nz}"))?;
    }
    if let Some(m) = args.method {
        scene.params.method = m.into();
    }
    if let Some(tol) = args.tolerance {
        scene.params.stretch_tolerance = tol;
    }
    if let Some(n) = args.max_iterations {
        scene.params.max_iterations = n as usize;
    }
    let threads = args.threads.map_or(1, usize::from);
    scene.params.coloured_sweep = match args.sweep {
        Some(sweep) => sweep == SweepArg::Coloured,
        None => args.threads.is_some() || scene.params.coloured_sweep,
    };
    let options = RunOptions {
        duration: args.duration,
        markers: MarkerSelection::None,
        limits,
        cancel: Some(super::interrupt::flag()),
        ..RunOptions::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .with_context(|| format!("starting a pool of {threads} threads"))?;
    let start = Instant::now();
    let cpu_start = modelgap::timing::cpu_seconds();
    let run = pool
        .install(|| run_scene(&scene, &options))
        .map_err(|e| run_error(e, &scene.name))
        .with_context(|| format!("running scene {}", scene.name))?;
    super::interrupt::check("the bench's report not printed")?;
    let wall_s = start.elapsed().as_secs_f64();
    let cpu_s = cpu_start
        .zip(modelgap::timing::cpu_seconds())
        .map(|(a, b)| b - a);
    let st = run.stats;
    let per_step = |t: f64| 1e3 * t / st.steps.max(1) as f64;
    let report = BenchReport {
        scene: run.scene,
        particles: st.n_particles,
        constraints: st.n_constraints,
        steps: st.steps,
        dt_s: st.dt,
        simulated_s: st.simulated(),
        max_stretch: st.max_stretch,
        mean_iterations: st.mean_iterations(),
        max_iterations: st.max_iterations,
        unconverged_steps: st.unconverged_steps,
        fallback_steps: st.fallback_steps,
        first_order_steps: st.first_order_steps,
        warning: st.stagnation.map(|s| s.to_string()),
        wall_s,
        x_real_time: real_time_factor(&st, wall_s),
        cpu_s,
        x_real_time_cpu: cpu_s.and_then(|c| real_time_factor(&st, c)),
        wall_ms_per_step: per_step(wall_s),
        cpu_ms_per_step: cpu_s.map(per_step),
        threads,
        method: match scene.params.method {
            Method::Newton => "newton",
            Method::Strips => "strips",
            _ => "gauss-seidel",
        },
        sweep: if scene.params.method != Method::GaussSeidel {
            "none"
        } else if scene.params.coloured_sweep {
            "coloured"
        } else {
            "serial"
        },
        stretch_tolerance: scene.params.stretch_tolerance,
    };
    if args.json {
        let mut text = serde_json::to_string_pretty(&report).context("writing the JSON")?;
        text.push('\n');
        return super::print(&text);
    }
    let mut s = String::new();
    let _ = writeln!(
        s,
        "scene {}: {} particles, {} constraints, {} steps of {} s",
        report.scene,
        report.particles,
        report.constraints,
        report.steps,
        num(report.dt_s)
    );
    let _ = writeln!(
        s,
        "{}{}, tolerance {:e}, {} thread{}",
        report.method,
        if scene.params.method != Method::GaussSeidel {
            String::new()
        } else {
            format!(" ({} sweep)", report.sweep)
        },
        report.stretch_tolerance,
        report.threads,
        if report.threads == 1 { "" } else { "s" }
    );
    let _ = writeln!(
        s,
        "max stretch {:.3e}, iterations mean {:.1}, max {}, {} steps unconverged, {} fell back \
         from Newton",
        report.max_stretch,
        report.mean_iterations,
        report.max_iterations,
        report.unconverged_steps,
        report.fallback_steps
    );
    if report.first_order_steps > 0 {
        let _ = writeln!(
            s,
            "{} of {} steps did not converge as BDF2 and were taken as the paper's impulse step",
            report.first_order_steps, report.steps
        );
    }
    if let Some(w) = &report.warning {
        let _ = writeln!(s, "warning: {w}");
    }
    let factor = |x: Option<f64>| x.map_or_else(|| "-".to_owned(), |x| format!("{x:.2}"));
    let _ = writeln!(
        s,
        "wall time {:.3} s for {} s simulated: {} x real time ({:.1} ms per step)",
        report.wall_s,
        num(report.simulated_s),
        factor(report.x_real_time),
        report.wall_ms_per_step,
    );
    if let Some(cpu_s) = report.cpu_s {
        let _ = writeln!(
            s,
            "CPU time {:.3} s (every thread): {} x real time ({:.1} ms per step)",
            cpu_s,
            factor(report.x_real_time_cpu),
            report.cpu_ms_per_step.unwrap_or(f64::NAN),
        );
    }
    super::print(&s)
}

/// A scene from a file (a path that exists, or ends in `.toml`) or a built-in name.
fn load_scene(name: &str) -> anyhow::Result<Scene> {
    let path = Path::new(name);
    if path.exists() || name.ends_with(".toml") {
        if !path.exists() {
            return Err(BadInput(format!("scene file {name} not found")).into());
        }
        return Scene::from_path(path)
            .map_err(|e| BadInput(e.to_string()))
            .with_context(|| format!("reading scene {name}"));
    }
    scenes::by_name(name).map_err(|_| {
        BadInput(format!(
            "unknown scene '{name}': expected a built-in scene ({BUILT_IN}) or a .toml file"
        ))
        .into()
    })
}

/// A run's error for the command line: Ctrl-C becomes [`Interrupted`](super::interrupt::Interrupted)
/// (exit code 130, nothing written); errors the user can fix (a bad option value, a marker
/// past the mesh, a limit, a marker file) become [`BadInput`], a limit with the option that
/// raises it; solver failures (a diverged run) stay as they are.
fn run_error(e: modelgap::cloth::ClothError, scene: &str) -> anyhow::Error {
    use modelgap::cloth::ClothError as E;
    let hint = match &e {
        E::Cancelled { step, steps } => {
            return super::interrupt::Interrupted(format!(
                "scene {scene} stopped after step {step} of {steps}; nothing written"
            ))
            .into();
        }
        E::NonFinite { .. } | E::BadTimeStep { .. } | E::Diverged { .. } => {
            return anyhow::Error::new(e);
        }
        E::TooManyParticles { .. } => "; raise the limit with --max-particles N",
        E::TooManySteps { .. } => "; raise the limit with --max-steps N, or shorten --duration",
        E::TooMuchFrameMemory { .. } => {
            " (--rate HZ, --markers ID,...), or raise the limit with --max-frame-mib MIB"
        }
        _ => "",
    };
    BadInput(format!("scene {scene}: {e}{hint}")).into()
}

/// Parses a finite number > 0.
fn parse_positive(text: &str) -> Result<f64, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("expected a number, found '{text}'"))?;
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(format!("must be positive and finite, found {v}"))
    }
}

/// Parses `all` or vertex ids separated by commas.
fn parse_markers(text: &str) -> Result<MarkerSelection, String> {
    if text.trim().eq_ignore_ascii_case("all") {
        return Ok(MarkerSelection::All);
    }
    let mut ids = Vec::new();
    for part in text.split(',') {
        let part = part.trim();
        let id: u32 = part.parse().map_err(|_| {
            format!(
                "expected `all` or vertex ids (whole numbers) separated by commas, found '{part}'"
            )
        })?;
        if ids.contains(&id) {
            return Err(format!("vertex id {id} is listed twice"));
        }
        ids.push(id);
    }
    Ok(MarkerSelection::Ids(ids))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markers_parse_all_or_ids() {
        assert_eq!(parse_markers("all").unwrap(), MarkerSelection::All);
        assert_eq!(
            parse_markers("0, 29,899").unwrap(),
            MarkerSelection::Ids(vec![0, 29, 899])
        );
        assert!(parse_markers("0,x").is_err());
        assert!(parse_markers("3,3").is_err());
        assert!(parse_markers("").is_err());
    }

    #[test]
    fn unknown_scene_names_the_built_ins() {
        let e = load_scene("nope").unwrap_err();
        assert!(e.to_string().contains(BUILT_IN), "{e}");
        assert_eq!(super::super::exit_code(&e), 2);
    }
}

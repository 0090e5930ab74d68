//! `modelgap bond simulate`: drive a model with constants, PWM or a recording's signals,
//! optionally with parameter faults and output noise, and write the run as CSV or MCAP.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use clap::{Args, ValueEnum};
use modelgap::bond::compiled::CompiledModel;
use modelgap::bond::simulate::{
    DEFAULT_MAX_EVENTS, DEFAULT_MAX_SAMPLES, Drive, Hold, Inputs, ParamChange, Run, SimOptions,
    Solver, checked_time_grid, simulate,
};
use modelgap::bond::{BondError, BondGraph};
use modelgap::io::{Format, write_recording_path};

use super::BadInput;
use super::format::{Align, aligned, num, unit};
use super::model::{
    ModelArgs, check_out_dir, load, parse_count, parse_hertz, parse_number, parse_seconds,
    read_recording_arg, steady_state,
};
use super::noise::{NoiseSpec, add_noise, parse_noise};

/// Arguments of `modelgap bond simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    #[command(flatten)]
    model: ModelArgs,

    /// Drive an input: NAME=VALUE (a constant) or NAME=pwm:DUTY@FREQ (a 0/1 PWM, FREQ in
    /// Hz); repeatable, overrides --inputs
    #[arg(long = "input", value_name = "NAME=DRIVE", value_parser = parse_input)]
    input: Vec<InputDrive>,

    /// Drive every model input found in this recording (.csv, .mcap or .parquet)
    #[arg(long, value_name = "FILE")]
    inputs: Option<PathBuf>,

    /// How the samples of --inputs are held between samples
    #[arg(long, value_enum, default_value_t = HoldArg::Linear)]
    hold: HoldArg,

    /// Simulated time (s) [default: up to the last sample of --inputs, else 1]
    #[arg(long, value_name = "T", value_parser = parse_seconds, allow_negative_numbers = true)]
    duration: Option<f64>,

    /// Output sample rate (Hz)
    #[arg(
        long,
        value_name = "HZ",
        default_value_t = 1000.0,
        value_parser = parse_hertz,
        allow_negative_numbers = true
    )]
    rate: f64,

    /// The most output samples (duration x rate + 1) a run may write; raise it for a long or
    /// fast run that is meant
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_SAMPLES, value_parser = parse_count, allow_negative_numbers = true)]
    max_samples: usize,

    /// The most discontinuities (PWM edges, two per period, and --fault changes) a run may
    /// have; raise it for a fast PWM over a long run that is meant
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_EVENTS, value_parser = parse_count, allow_negative_numbers = true)]
    max_events: usize,

    /// Integrator: exact (linear models), dopri5 (explicit), rosenbrock (stiff), auto
    #[arg(long, value_enum, default_value_t = SolverArg::Auto)]
    solver: SolverArg,

    /// A parameter jumps to a new value at time TIME (s), an abrupt fault: NAME=VALUE@TIME;
    /// repeatable
    #[arg(long = "fault", value_name = "NAME=VALUE@TIME", value_parser = parse_fault)]
    fault: Vec<ParamChange>,

    /// Start at the steady state under the inputs' values at t = 0 (a PWM counts as its
    /// average) instead of at rest
    #[arg(long)]
    steady_start: bool,

    /// Add white Gaussian noise to every output: SIGMA (in the output's unit) and an
    /// optional seed (default 0)
    #[arg(long, value_name = "SIGMA[,seed=N]", value_parser = parse_noise, allow_hyphen_values = true)]
    noise: Option<NoiseSpec>,

    /// Write time, inputs and outputs to this file (.csv or .mcap)
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,

    /// Also write the states (p3, p8, ...) to --out
    #[arg(long, requires = "out")]
    states: bool,
}

/// How sampled inputs are held (`--hold`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum HoldArg {
    /// Straight lines between samples
    Linear,
    /// Each sample's value until the next sample (zero-order hold)
    Zoh,
    /// A smooth cubic through the samples (Catmull–Rom)
    Cubic,
}

impl From<HoldArg> for Hold {
    fn from(h: HoldArg) -> Hold {
        match h {
            HoldArg::Linear => Hold::Linear,
            HoldArg::Zoh => Hold::Zero,
            HoldArg::Cubic => Hold::Cubic,
        }
    }
}

/// The integrator (`--solver`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum SolverArg {
    /// Exact for linear models without PWM, else dopri5 switching to rosenbrock when stiff
    Auto,
    /// Exact discretisation (matrix exponential); linear time-invariant models only
    Exact,
    /// Dormand-Prince 5(4), adaptive, explicit
    Dopri5,
    /// Rosenbrock, adaptive, L-stable, for stiff models
    Rosenbrock,
}

impl From<SolverArg> for Solver {
    fn from(s: SolverArg) -> Solver {
        match s {
            SolverArg::Auto => Solver::Auto,
            SolverArg::Exact => Solver::Exact,
            SolverArg::Dopri5 => Solver::Dopri5,
            SolverArg::Rosenbrock => Solver::Rosenbrock,
        }
    }
}

/// One `--input NAME=DRIVE`.
#[derive(Clone, Debug, PartialEq)]
pub struct InputDrive {
    /// The input.
    pub name: String,
    /// What drives it.
    pub drive: Drive,
}

/// Parses `NAME=VALUE` or `NAME=pwm:DUTY@FREQ`.
pub fn parse_input(text: &str) -> Result<InputDrive, String> {
    let (name, spec) = text
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=VALUE or NAME=pwm:DUTY@FREQ, found `{text}`"))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(format!("no input name in `{text}`"));
    }
    let spec = spec.trim();
    let drive = if let Some(pwm) = spec.strip_prefix("pwm:") {
        let (duty, freq) = pwm
            .split_once('@')
            .ok_or_else(|| format!("expected pwm:DUTY@FREQ for `{name}`, found `{spec}`"))?;
        let duty = parse_number(duty).map_err(|e| format!("{e} (PWM duty of `{name}`)"))?;
        let freq = parse_number(freq).map_err(|e| format!("{e} (PWM frequency of `{name}`)"))?;
        if !(0.0..=1.0).contains(&duty) {
            return Err(format!(
                "PWM duty of `{name}` must be in [0, 1], found {duty}"
            ));
        }
        if freq <= 0.0 {
            return Err(format!(
                "PWM frequency of `{name}` must be positive, found {freq} Hz"
            ));
        }
        Drive::pwm(duty, freq)
    } else {
        Drive::Constant(parse_number(spec).map_err(|e| format!("{e} for `{name}`"))?)
    };
    Ok(InputDrive {
        name: name.to_owned(),
        drive,
    })
}

/// Parses `NAME=VALUE@TIME`: the parameter `NAME` takes `VALUE` from time `TIME` (s) on.
pub fn parse_fault(text: &str) -> Result<ParamChange, String> {
    let (name, rest) = text
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=VALUE@TIME, found `{text}`"))?;
    let (value, at) = rest
        .split_once('@')
        .ok_or_else(|| format!("expected NAME=VALUE@TIME, found `{text}` (no @TIME)"))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(format!("no parameter name in `{text}`"));
    }
    let value = parse_number(value).map_err(|e| format!("{e} (new value of `{name}`)"))?;
    let at = parse_number(at).map_err(|e| format!("{e} (time of the change of `{name}`)"))?;
    if at < 0.0 {
        return Err(format!(
            "the change of `{name}` must be at t >= 0, found {at} s"
        ));
    }
    Ok(ParamChange {
        at,
        name: name.to_owned(),
        value,
    })
}

/// Simulates the model and prints a summary.
///
/// # Errors
///
/// Model errors, unreadable input files, drives of unknown inputs, faults of unknown
/// parameters, solver failures, unwritable output files.
pub fn run(args: &SimulateArgs) -> anyhow::Result<()> {
    let g = load(&args.model)?;
    if let Some(path) = &args.out {
        // Refuse a directory or an unknown extension before the simulation, not after it.
        if path.is_dir() {
            return Err(BadInput(format!(
                "--out {} is a directory: give the file to write (.csv or .mcap)",
                path.display()
            ))
            .into());
        }
        Format::for_writing(path)
            .with_context(|| format!("choosing the format of --out {}", path.display()))?;
        check_out_dir("--out", path)?;
    }
    let model = CompiledModel::new(&g).with_context(|| format!("compiling model {}", g.name))?;
    let (inputs, described, file_end) = drives(args, &g, &model)?;
    let duration = args.duration.or(file_end).unwrap_or(1.0);
    // Checked before anything is allocated: a typo in --rate must not exhaust memory.
    let t = checked_time_grid(duration, args.rate, args.max_samples).map_err(limit_hint)?;
    for change in &args.fault {
        if !g.params().contains_key(&change.name) && !g.inputs().contains_key(&change.name) {
            return Err(BadInput(format!(
                "--fault {}: model {} has no parameter `{}` (parameters: {})",
                change.name,
                g.name,
                change.name,
                g.params().keys().cloned().collect::<Vec<_>>().join(", ")
            ))
            .into());
        }
        // A value the element cannot have is refused before the run, naming the option.
        g.clone()
            .set_param(&change.name, change.value)
            .with_context(|| {
                format!(
                    "checking --fault {}={}@{}",
                    change.name,
                    num(change.value),
                    num(change.at)
                )
            })?;
    }
    let mut opts = SimOptions {
        solver: args.solver.into(),
        changes: args.fault.clone(),
        max_events: args.max_events,
        ..SimOptions::default()
    };
    if args.steady_start {
        let u0: Vec<f64> = model
            .input_names
            .iter()
            .zip(&model.input_defaults)
            .map(|(name, default)| inputs.get(name).map_or(*default, value_at_start))
            .collect();
        opts.initial_state = Some(
            steady_state(&g, &u0)
                .with_context(|| format!("finding the steady state of model {}", g.name))?,
        );
    }
    let mut run = simulate(&g, &inputs, &t, &opts)
        .map_err(limit_hint)
        .with_context(|| format!("simulating model {}", g.name))?;
    if let Some(noise) = args.noise {
        add_noise(&mut run.outputs, noise);
    }
    let has_pwm = model
        .input_names
        .iter()
        .any(|n| matches!(inputs.get(n), Some(Drive::Pwm { .. })));
    let exact = match args.solver {
        SolverArg::Exact => true,
        SolverArg::Auto => model.is_lti && !has_pwm,
        SolverArg::Dopri5 | SolverArg::Rosenbrock => false,
    };
    let mut s = summary(args, &g, &run, &described, duration, exact);
    if let Some(path) = &args.out {
        let rec = run
            .to_recording(args.states)
            .with_context(|| format!("collecting the run of model {}", g.name))?;
        write_recording_path(path, &rec).with_context(|| format!("writing {}", path.display()))?;
        let _ = writeln!(
            s,
            "wrote t, {} ({} samples) to {}",
            rec.names().join(", "),
            rec.len(),
            path.display()
        );
    }
    super::print(&s)
}

/// The drives of the run, a description of each model input's drive, and the last sample
/// time of `--inputs` (the default duration).
fn drives(
    args: &SimulateArgs,
    g: &BondGraph,
    model: &CompiledModel,
) -> anyhow::Result<(Inputs, Vec<String>, Option<f64>)> {
    let mut inputs = Inputs::new();
    let mut from_file: Vec<&str> = Vec::new();
    let mut file_end = None;
    if let Some(path) = &args.inputs {
        let rec = read_inputs_file(path)?;
        for name in &model.input_names {
            if let Some(signal) = rec.signal(name) {
                inputs.set(
                    name,
                    Drive::Sampled {
                        t: rec.t().to_vec(),
                        values: signal.values.clone(),
                        hold: args.hold.into(),
                    },
                );
                from_file.push(name);
            }
        }
        if from_file.is_empty() {
            return Err(BadInput(format!(
                "{} drives none of the inputs of model {} (model inputs: {}; signals in the file: {})",
                path.display(),
                g.name,
                model.input_names.join(", "),
                rec.names().join(", ")
            ))
            .into());
        }
        file_end = rec.t().last().copied().filter(|t| *t > 0.0);
    }
    for d in &args.input {
        inputs.set(&d.name, d.drive.clone());
    }
    let described = model
        .input_names
        .iter()
        .map(|name| {
            let unit = unit(g.inputs().get(name).map_or("", |i| i.unit.as_str()));
            match inputs.get(name) {
                Some(Drive::Constant(v)) => format!("{name} = {} {unit}", num(*v)),
                Some(Drive::Pwm {
                    frequency_hz, duty, ..
                }) => format!(
                    "{name} = PWM 0/1, duty {}, {} Hz",
                    num(*duty),
                    num(*frequency_hz)
                ),
                Some(Drive::Sampled { hold, .. }) => format!(
                    "{name} from {} ({} hold)",
                    args.inputs
                        .as_deref()
                        .map_or_else(String::new, |p| p.display().to_string()),
                    if *hold == Hold::Zero {
                        "zero-order"
                    } else {
                        "linear"
                    }
                ),
                None => {
                    let default = g.inputs().get(name).map_or(0.0, |i| i.default);
                    let value = format!("{name} = {} {unit}", num(default));
                    format!("{} (default)", value.trim_end())
                }
            }
        })
        .map(|text| text.trim_end().to_owned())
        .collect();
    Ok((inputs, described, file_end))
}

/// Reads `--inputs`, naming the option and the path when it is missing or a directory.
fn read_inputs_file(path: &Path) -> anyhow::Result<modelgap::Recording> {
    read_recording_arg("--inputs", "inputs", path)
}

/// A limit of the library ([`BondError::TooLarge`]) as the option that raises it here:
/// `--max-samples` or `--max-events`; other errors unchanged.
fn limit_hint(e: BondError) -> anyhow::Error {
    let BondError::TooLarge {
        what,
        count,
        limit,
        option,
    } = &e
    else {
        return e.into();
    };
    let (flag, lower) = match *option {
        "max_samples" => ("--max-samples", "lower --rate or --duration"),
        "max_events" => (
            "--max-events",
            "lower the PWM frequency or --duration, or use fewer --fault changes",
        ),
        _ => return e.into(),
    };
    BadInput(format!(
        "{what} would be {}, more than the limit {flag} {limit}: {lower}, or raise {flag} if the \
         run is meant",
        num(*count)
    ))
    .into()
}

/// The value a drive has at t = 0; a PWM counts as its average (the steady state of the
/// averaged model is the natural start of a switched one).
fn value_at_start(drive: &Drive) -> f64 {
    match drive {
        Drive::Constant(v) => *v,
        Drive::Sampled { values, .. } => values.first().copied().unwrap_or(0.0),
        Drive::Pwm {
            duty, high, low, ..
        } => low + duty * (high - low),
    }
}

/// The summary printed after a run.
fn summary(
    args: &SimulateArgs,
    g: &BondGraph,
    run: &Run,
    described: &[String],
    duration: f64,
    exact: bool,
) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "model {}: simulated {} s at {} Hz ({} samples) from {}",
        g.name,
        num(duration),
        num(args.rate),
        run.t.len(),
        if args.steady_start {
            "steady state"
        } else {
            "rest"
        }
    );
    let _ = writeln!(s, "inputs: {}", described.join(", "));
    if !args.fault.is_empty() {
        let faults: Vec<String> = args
            .fault
            .iter()
            .map(|c| format!("{} = {} from t = {} s", c.name, num(c.value), num(c.at)))
            .collect();
        let _ = writeln!(s, "faults: {}", faults.join(", "));
    }
    if let Some(noise) = args.noise {
        let _ = writeln!(
            s,
            "noise: Gaussian, sigma {} on every output, seed {}",
            num(noise.sigma),
            noise.seed
        );
    }
    let st = &run.stats;
    let solver = if exact {
        format!(
            "exact discretisation of the linear model ({} steps)",
            st.steps
        )
    } else {
        let mut text = format!(
            "{} steps ({} rejected), {} right-hand-side evaluations",
            st.steps, st.rejected, st.rhs_evals
        );
        if st.jacobian_evals > 0 || st.lu_decompositions > 0 {
            let _ = write!(
                text,
                ", {} Jacobians, {} LU decompositions",
                st.jacobian_evals, st.lu_decompositions
            );
        }
        if st.stiff_switches > 0 {
            text.push_str(", switched to rosenbrock (stiff)");
        }
        text
    };
    let solver_name = args
        .solver
        .to_possible_value()
        .map_or_else(String::new, |v| v.get_name().to_owned());
    let _ = writeln!(s, "solver: {solver_name}: {solver}");
    let t_end = run.t.last().copied().unwrap_or(0.0);
    let _ = writeln!(s, "final values at t = {} s:", num(t_end));
    let rows: Vec<Vec<String>> = run
        .output_names
        .iter()
        .zip(&run.outputs)
        .map(|(name, values)| {
            let unit = unit(
                g.outputs()
                    .iter()
                    .find(|o| &o.name == name)
                    .map_or("", |o| o.unit.as_str()),
            );
            vec![
                name.clone(),
                num(values.last().copied().unwrap_or(f64::NAN)),
                unit.to_owned(),
            ]
        })
        .collect();
    s.push_str(&aligned(
        &rows,
        2,
        &[Align::Left, Align::Right],
        Align::Left,
    ));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn input_drives_parse_constants_and_pwm() {
        assert_eq!(
            parse_input("V=24").map(|d| d.drive),
            Ok(Drive::Constant(24.0))
        );
        assert_eq!(
            parse_input("m=pwm:0.5@20000").map(|d| d.drive),
            Ok(Drive::pwm(0.5, 20000.0))
        );
        assert!(parse_input("V").is_err());
        assert!(parse_input("m=pwm:1.5@100").is_err());
        assert!(parse_input("m=pwm:0.5").is_err());
        assert!(parse_input("V=twelve").unwrap_err().contains("`twelve`"));
    }

    #[test]
    fn faults_parse_name_value_and_time() {
        assert_eq!(
            parse_fault("R=1.5@0.2"),
            Ok(ParamChange {
                at: 0.2,
                name: "R".into(),
                value: 1.5
            })
        );
        assert!(parse_fault("R=1.5").is_err());
        assert!(parse_fault("R=1.5@-1").is_err());
        assert!(parse_fault("R=x@1").unwrap_err().contains("`x`"));
    }

    #[test]
    fn pwm_starts_at_its_average() {
        assert_eq!(value_at_start(&Drive::pwm(0.25, 1000.0)), 0.25);
        assert_eq!(value_at_start(&Drive::Constant(3.0)), 3.0);
    }
}

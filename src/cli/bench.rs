//! `modelgap bond bench`: wall-clock timings of the bond-graph simulator on the reference
//! runs (the DC motor from rest over 0–4 s, the PWM-switched buck converter feeding the motor
//! over 0–1 s, both with 1 kHz output), with a check that their results are right.
//!
//! Criterion's `benches/bond_simulate.rs` times the same runs for development; this command
//! exists so that a release binary can be held against other tools side by side in one run
//! (`scripts/bench-vs-python` does that against scipy), hence its JSON output.

use std::fmt::Write as _;
use std::hint::black_box;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use clap::Args;
use modelgap::bond::BondGraph;
use modelgap::bond::library;
use modelgap::bond::simulate::{Drive, Inputs, Run, SimOptions, Solver, simulate, time_grid};
use serde::Serialize;

use super::format::{Align, aligned, num};
use super::model::parse_count;

/// Simulated time of the DC-motor runs (s).
const DC_MOTOR_DURATION: f64 = 4.0;
/// Simulated time of the PWM buck-motor run (s).
const BUCK_DURATION: f64 = 1.0;
/// Output rate of every run (Hz).
const OUTPUT_RATE_HZ: f64 = 1000.0;
/// Switching frequency of the buck converter's PWM (Hz).
const PWM_HZ: f64 = 1000.0;
/// Duty cycle of the PWM, and the switch modulus of the averaged model.
const PWM_DUTY: f64 = 0.5;

/// Without `--repeat`, a case runs until it has taken at least this long in total…
const MIN_TOTAL: Duration = Duration::from_millis(500);
/// …or at least this many times, whichever needs more runs.
const MIN_RUNS: usize = 20;
/// Without `--repeat`, no case runs more often than this (a sub-millisecond case would
/// otherwise run thousands of times for no better median).
const MAX_RUNS: usize = 10_000;

/// The DC motor's steady speed at 12 V from its parameters, k V / (R β + k²) (rad/s); after
/// 4 s (about 20 mechanical time constants) the run has reached it to well below 1e-6.
const DC_MOTOR_OMEGA_FINAL: f64 = 239.043_824_701_195_2;
/// Relative tolerance of the DC motor's final speed.
const DC_MOTOR_RTOL: f64 = 1e-4;
/// Length of the window at the end of the PWM run over which the mean speed is taken (s):
/// ten switching periods.
const PWM_WINDOW: f64 = 0.010;
/// Relative tolerance between the switched and the averaged model's mean speed: the ripple
/// a 1 kHz switch leaves on the shaft behind the converter's LC filter and the rotor's
/// inertia is far below this.
const PWM_RTOL: f64 = 0.01;

/// Arguments of `modelgap bond bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Print JSON instead of a table
    #[arg(long)]
    json: bool,

    /// Runs per case [default: enough for 0.5 s per case, and at least 20]
    #[arg(long, value_name = "N", value_parser = parse_count, allow_negative_numbers = true)]
    repeat: Option<usize>,
}

/// One reference run to time.
struct Case {
    /// Name printed and written to JSON (`dc_motor_4s_1khz/exact`).
    name: &'static str,
    /// The model.
    graph: BondGraph,
    /// The drives of its inputs.
    inputs: Inputs,
    /// Output times (s).
    t: Vec<f64>,
    /// Simulation options (the solver).
    opts: SimOptions,
}

impl Case {
    /// Runs the case once.
    fn run(&self) -> anyhow::Result<Run> {
        simulate(&self.graph, &self.inputs, &self.t, &self.opts)
            .with_context(|| format!("simulating bench case {}", self.name))
    }

    /// Simulated time (s).
    fn duration(&self) -> f64 {
        self.t.last().copied().unwrap_or(0.0) - self.t.first().copied().unwrap_or(0.0)
    }
}

/// The timings of one case, as printed and written to JSON.
#[derive(Debug, Serialize)]
struct CaseReport {
    /// Case name.
    name: String,
    /// Median wall time of one run (ms).
    median_ms: f64,
    /// Shortest wall time of one run (ms).
    min_ms: f64,
    /// Timed runs (a warm-up run comes before them).
    runs: usize,
    /// Accepted solver steps of one run (intervals for the exact solver).
    steps: usize,
    /// Simulated seconds per wall-clock second, at the median.
    x_real_time: f64,
    /// Simulated time (s).
    simulated_s: f64,
    /// Final value of every state and output, for cross-checks with other tools.
    #[serde(rename = "final")]
    final_values: serde_json::Map<String, serde_json::Value>,
}

/// A check that a run's result is right.
#[derive(Debug, Serialize)]
struct Check {
    /// What is checked.
    name: String,
    /// The value found.
    value: f64,
    /// The value expected.
    expected: f64,
    /// Relative difference |value − expected| / |expected|.
    rel_error: f64,
    /// Largest relative difference allowed.
    tolerance: f64,
    /// Whether the value is within tolerance.
    ok: bool,
}

impl Check {
    fn new(name: String, value: f64, expected: f64, tolerance: f64) -> Check {
        let rel_error = (value - expected).abs() / expected.abs();
        Check {
            name,
            value,
            expected,
            rel_error,
            tolerance,
            // A NaN fails, as it should.
            ok: rel_error <= tolerance,
        }
    }
}

/// The machine the timings come from.
#[derive(Debug, Serialize)]
struct Machine {
    /// Cores available to this process.
    cores: usize,
}

/// Everything `--json` prints.
#[derive(Debug, Serialize)]
struct Report {
    cases: Vec<CaseReport>,
    checks: Vec<Check>,
    machine: Machine,
}

/// Times the reference runs and prints a table, or JSON with `--json`.
///
/// # Errors
///
/// A simulation that fails, or standard output that cannot be written.
pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    let repeat = args.repeat;
    let mut cases = Vec::new();
    let mut checks = Vec::new();
    for case in cases_to_time() {
        let (report, run) = time_case(&case, repeat)?;
        checks.extend(check(&case, &run)?);
        cases.push(report);
    }
    let report = Report {
        cases,
        checks,
        machine: Machine {
            cores: std::thread::available_parallelism().map_or(1, usize::from),
        },
    };
    if args.json {
        let mut text = serde_json::to_string_pretty(&report).context("writing the JSON")?;
        text.push('\n');
        super::print(&text)
    } else {
        super::print(&text_report(&report))
    }
}

/// The cases: the DC motor with the solver `auto` picks (exact) and with the two others
/// a comparison with scipy needs, and the PWM buck-motor.
fn cases_to_time() -> Vec<Case> {
    let motor = library::dc_motor();
    let dc_t = time_grid(DC_MOTOR_DURATION, OUTPUT_RATE_HZ);
    let dc = |name, solver| Case {
        name,
        graph: motor.clone(),
        inputs: Inputs::new(),
        t: dc_t.clone(),
        opts: SimOptions {
            solver,
            ..SimOptions::default()
        },
    };
    vec![
        dc("dc_motor_4s_1khz/auto", Solver::Auto),
        dc("dc_motor_4s_1khz/exact", Solver::Exact),
        dc("dc_motor_4s_1khz/dopri5", Solver::Dopri5),
        Case {
            name: "buck_motor_pwm_1s/auto",
            graph: library::buck_motor(),
            inputs: Inputs::new().with("m", Drive::pwm(PWM_DUTY, PWM_HZ)),
            t: time_grid(BUCK_DURATION, OUTPUT_RATE_HZ),
            opts: SimOptions::default(),
        },
    ]
}

/// Runs a case once to warm up, then `repeat` times (or as often as [`MIN_TOTAL`] and
/// [`MIN_RUNS`] ask), timing each run; returns the report and the warm-up run.
fn time_case(case: &Case, repeat: Option<usize>) -> anyhow::Result<(CaseReport, Run)> {
    let start = Instant::now();
    let first = case.run()?;
    let once = start.elapsed();
    let runs = repeat.unwrap_or_else(|| {
        let needed = MIN_TOTAL.as_secs_f64() / once.as_secs_f64().max(1e-9);
        (needed.ceil() as usize).clamp(MIN_RUNS, MAX_RUNS)
    });
    let mut wall_ms = Vec::with_capacity(runs);
    for _ in 0..runs {
        let start = Instant::now();
        let run = case.run()?;
        let elapsed = start.elapsed();
        black_box(&run);
        wall_ms.push(elapsed.as_secs_f64() * 1e3);
    }
    wall_ms.sort_by(f64::total_cmp);
    let median_ms = median(&wall_ms);
    let final_values = first
        .state_names
        .iter()
        .zip(&first.states)
        .chain(first.output_names.iter().zip(&first.outputs))
        .map(|(name, values)| {
            let last = values.last().copied().unwrap_or(f64::NAN);
            (name.clone(), serde_json::Value::from(last))
        })
        .collect();
    let report = CaseReport {
        name: case.name.to_owned(),
        median_ms,
        min_ms: wall_ms.first().copied().unwrap_or(f64::NAN),
        runs,
        steps: first.stats.steps,
        x_real_time: case.duration() / (median_ms / 1e3),
        simulated_s: case.duration(),
        final_values,
    };
    Ok((report, first))
}

/// The median of sorted values (NaN for none).
fn median(sorted: &[f64]) -> f64 {
    let n = sorted.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => sorted[n / 2],
        _ => 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]),
    }
}

/// The checks of a case's run: the DC motor's final speed against its steady state, the
/// PWM run's mean speed at the end against the averaged model's.
fn check(case: &Case, run: &Run) -> anyhow::Result<Vec<Check>> {
    let omega = |r: &Run| -> anyhow::Result<Vec<f64>> {
        r.output("omega")
            .map(<[f64]>::to_vec)
            .with_context(|| format!("bench case {} has no output omega", case.name))
    };
    if case.name.starts_with("dc_motor") {
        let last = omega(run)?.last().copied().unwrap_or(f64::NAN);
        return Ok(vec![Check::new(
            format!("{}: final omega (rad/s)", case.name),
            last,
            DC_MOTOR_OMEGA_FINAL,
            DC_MOTOR_RTOL,
        )]);
    }
    // The averaged model: the same converter with the switch held at the duty cycle.
    let averaged = simulate(
        &case.graph,
        &Inputs::new().with("m", Drive::Constant(PWM_DUTY)),
        &case.t,
        &case.opts,
    )
    .with_context(|| format!("simulating the averaged model of {}", case.name))?;
    let t_end = case.t.last().copied().unwrap_or(0.0);
    // The last ten periods: samples after t_end − window, one per period at 1 kHz.
    let in_window = |t: f64| t > t_end - PWM_WINDOW * (1.0 - 1e-9);
    let mean_end = |values: &[f64]| {
        let (sum, n) = case
            .t
            .iter()
            .zip(values)
            .filter(|(t, _)| in_window(**t))
            .fold((0.0, 0usize), |(s, n), (_, v)| (s + v, n + 1));
        sum / n as f64
    };
    Ok(vec![Check::new(
        format!(
            "{}: mean omega over the last {} ms vs the averaged model (m = {PWM_DUTY})",
            case.name,
            num(PWM_WINDOW * 1e3)
        ),
        mean_end(&omega(run)?),
        mean_end(&omega(&averaged)?),
        PWM_RTOL,
    )])
}

/// The report as a table for people, with a warning line for each failed check.
fn text_report(report: &Report) -> String {
    let mut rows = vec![vec![
        "case".to_owned(),
        "runs".to_owned(),
        "median ms".to_owned(),
        "min ms".to_owned(),
        "steps".to_owned(),
        "x real time".to_owned(),
    ]];
    for c in &report.cases {
        rows.push(vec![
            c.name.clone(),
            c.runs.to_string(),
            format!("{:.4}", c.median_ms),
            format!("{:.4}", c.min_ms),
            c.steps.to_string(),
            format!("{:.0}", c.x_real_time),
        ]);
    }
    let mut s = format!(
        "modelgap bond bench: wall time per run on {} cores (release build to be meaningful)\n",
        report.machine.cores
    );
    s.push_str(&aligned(&rows, 2, &[Align::Left], Align::Right));
    for c in &report.checks {
        let _ = writeln!(
            s,
            "{} {}: {} (expected {}, relative error {:.1e}, tolerance {:.0e})",
            if c.ok {
                "check ok:"
            } else {
                "warning: check failed:"
            },
            c.name,
            num(c.value),
            num(c.expected),
            c.rel_error,
            c.tolerance
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&[1.0, 2.0, 7.0]), 2.0);
        assert_eq!(median(&[1.0, 2.0, 4.0, 7.0]), 3.0);
        assert!(median(&[]).is_nan());
    }

    #[test]
    fn dc_motor_steady_speed_matches_its_parameters() {
        // k V / (R beta + k^2) with R = 1, beta = 1e-5, k = 0.05, V = 12.
        let omega = 0.05 * 12.0 / (1.0 * 1e-5 + 0.05 * 0.05);
        assert!((omega - DC_MOTOR_OMEGA_FINAL).abs() < 1e-9);
    }

    #[test]
    fn reference_runs_pass_their_checks() {
        // One run of each case, no timing asserted: the results must be right.
        for case in cases_to_time() {
            let run = case.run().unwrap();
            for c in check(&case, &run).unwrap() {
                assert!(c.ok, "{}: {} vs {}", c.name, c.value, c.expected);
            }
        }
    }

    #[test]
    fn a_nan_fails_its_check() {
        assert!(!Check::new("x".into(), f64::NAN, 1.0, 0.1).ok);
        assert!(Check::new("x".into(), 1.05, 1.0, 0.1).ok);
    }
}

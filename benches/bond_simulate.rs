//! Benchmarks of the bond-graph simulator on the two reference runs: the DC motor
//! from rest over 0–4 s with 1 kHz output, and the buck converter feeding the motor with a
//! 1 kHz PWM switch over 0–1 s; plus compiling the DC motor on its own.
//!
//! `bond/simulate/…` times `simulate`, which compiles the graph on every call;
//! `bond/simulate_compiled/…` times the same runs of an already compiled model, so the two
//! together separate compiling from integrating. `modelgap bond bench` times the same runs
//! outside criterion, and `scripts/bench-vs-python` holds them against scipy.
#![allow(clippy::unwrap_used)] // benches: setup failures should abort

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};

/// The same allocator as the `modelgap` binary (see src/main.rs).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;
use modelgap::bond::compiled::CompiledModel;
use modelgap::bond::library;
use modelgap::bond::simulate::{
    Drive, Inputs, SimOptions, Solver, simulate, simulate_compiled, time_grid,
};

/// Simulated time of the DC-motor run (s).
const DC_MOTOR_DURATION: f64 = 4.0;
/// Simulated time of the PWM buck-motor run (s).
const BUCK_DURATION: f64 = 1.0;
/// Output rate of both runs (Hz).
const OUTPUT_RATE_HZ: f64 = 1000.0;
/// Switching frequency of the buck converter's PWM (Hz).
const PWM_HZ: f64 = 1000.0;
/// Duty cycle of the PWM.
const PWM_DUTY: f64 = 0.5;

/// Options with the default tolerances (rtol 1e-8, atol 1e-10) and the given solver.
fn options(solver: Solver) -> SimOptions {
    SimOptions {
        solver,
        ..SimOptions::default()
    }
}

/// The DC motor from rest at its default 12 V, through `simulate` (compiles each call) and
/// through `simulate_compiled`.
fn dc_motor(c: &mut Criterion) {
    let motor = library::dc_motor();
    let t = time_grid(DC_MOTOR_DURATION, OUTPUT_RATE_HZ);
    let inputs = Inputs::new();
    let solvers = [
        ("auto", Solver::Auto),
        ("exact", Solver::Exact),
        ("dopri5", Solver::Dopri5),
        ("rosenbrock", Solver::Rosenbrock),
    ];

    let mut group = c.benchmark_group("bond/simulate/dc_motor_4s_1khz");
    for (name, solver) in solvers {
        let opts = options(solver);
        group.bench_function(name, |b| {
            b.iter(|| {
                simulate(
                    black_box(&motor),
                    black_box(&inputs),
                    black_box(&t),
                    black_box(&opts),
                )
                .unwrap()
            });
        });
    }
    group.finish();

    let model = CompiledModel::new(&motor).unwrap();
    let mut group = c.benchmark_group("bond/simulate_compiled/dc_motor_4s_1khz");
    for (name, solver) in solvers {
        let opts = options(solver);
        group.bench_function(name, |b| {
            b.iter(|| {
                simulate_compiled(
                    black_box(&model),
                    black_box(&inputs),
                    black_box(&t),
                    black_box(&opts),
                )
                .unwrap()
            });
        });
    }
    group.finish();
}

/// The buck converter feeding the motor, its switch `m` driven by a 1 kHz PWM of duty 0.5.
fn buck_motor_pwm(c: &mut Criterion) {
    let buck = library::buck_motor();
    let t = time_grid(BUCK_DURATION, OUTPUT_RATE_HZ);
    let inputs = Inputs::new().with("m", Drive::pwm(PWM_DUTY, PWM_HZ));

    let mut group = c.benchmark_group("bond/simulate/buck_motor_pwm_1s");
    // 2000 switching instants per run: tens of milliseconds, so fewer samples than the default.
    group.sample_size(20);
    group.measurement_time(Duration::from_secs(5));
    for (name, solver) in [
        ("auto", Solver::Auto),
        ("dopri5", Solver::Dopri5),
        ("rosenbrock", Solver::Rosenbrock),
    ] {
        let opts = options(solver);
        group.bench_function(name, |b| {
            b.iter(|| {
                simulate(
                    black_box(&buck),
                    black_box(&inputs),
                    black_box(&t),
                    black_box(&opts),
                )
                .unwrap()
            });
        });
    }
    group.finish();
}

/// Causality, equations and the tape of the DC motor: what `simulate` adds to each run.
fn compile(c: &mut Criterion) {
    let motor = library::dc_motor();
    c.bench_function("bond/compile/dc_motor", |b| {
        b.iter(|| CompiledModel::new(black_box(&motor)).unwrap());
    });
}

criterion_group!(benches, dc_motor, buck_motor_pwm, compile);
criterion_main!(benches);

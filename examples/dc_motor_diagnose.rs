//! Diagnoses an armature-resistance fault of the DC motor with the bond-graph method of the
//! paper: simulate the motor at steady state, let R rise by 20 % at 0.1 s, then hand the
//! recording to the diagnosis and print its report (residuals, fault trees, signatures,
//! hypothesis sets).
//!
//! Run with `cargo run --example dc_motor_diagnose`.

use anyhow::Context as _;
use modelgap::prelude::*;

fn main() -> anyhow::Result<()> {
    let motor = library::builtin("dc-motor")?;

    // Start at the steady state under the default inputs (12 V, no load): for this linear
    // model the linearisation's steady state is exact.
    let defaults: Vec<f64> = motor.inputs().values().map(|i| i.default).collect();
    let ss = StateSpace::linearise(&motor, None, Some(&defaults))?;
    let x0 = ss
        .steady_state(&defaults)
        .context("the DC motor has a steady state")?;

    // The "process": the same motor whose resistance rises from 1.0 to 1.2 Ω at t = 0.1 s.
    let faulty = SimOptions {
        initial_state: Some(x0.clone()),
        changes: vec![ParamChange {
            at: 0.1,
            name: "R".to_owned(),
            value: 1.2,
        }],
        ..SimOptions::default()
    };
    let run = simulate(&motor, &Inputs::new(), &time_grid(1.0, 1000.0), &faulty)?;
    let recording = run.to_recording(false)?;
    println!(
        "recorded {} samples of {} over {} s (R: 1.0 -> 1.2 Ohm at 0.1 s)\n",
        recording.len(),
        recording.names().join(", "),
        recording.duration()
    );

    // Diagnose: the nominal model runs in parallel from the same steady state.
    let options = DiagnosisOptions {
        sim: SimOptions {
            initial_state: Some(x0),
            ..SimOptions::default()
        },
        ..DiagnosisOptions::default()
    };
    let diagnosis = diagnose(&motor, &recording, &options)?;
    print!("{}", diagnosis.report());
    println!(
        "\nthe resistance is {} the final hypothesis set",
        if diagnosis.parameters().iter().any(|p| p == "R") {
            "in"
        } else {
            "NOT in"
        }
    );
    Ok(())
}

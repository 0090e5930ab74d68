//! Recordings with a hidden effect: what the measurement loop is judged on.
//!
//! Each case takes a built-in model, builds a richer "true" system from it
//! — the hidden effect (or two, or none), plus what no candidate models: a
//! first-order sensor lag on every measurement and measurement noise that
//! is partly white and partly coloured (AR(1)) — drives it with a
//! reversing voltage profile and samples it. The nominal model, held
//! against the recording, must find the hidden effect (or nothing).

use modelgap_core::noise::Gaussian;
use modelgap_core::{Candidate, Recording, Signal};

use crate::effects;
use crate::error::{BondError, Result};
use crate::graph::BondGraph;
use crate::library;
use crate::simulate::{Drive, Hold, Inputs, SimOptions, simulate};

/// A hidden effect: a candidate id of the nominal model and its true values.
#[derive(Clone, Debug, PartialEq)]
pub struct Hidden {
    /// The candidate's id (`coulomb@1m`).
    pub id: String,
    /// Its true parameter values, in the candidate's order.
    pub values: Vec<f64>,
}

/// A hidden-effect case.
#[derive(Clone, Debug, PartialEq)]
pub struct HiddenCase {
    /// Short name (`coulomb`).
    pub name: String,
    /// The built-in model (`dc-motor`, `buck-motor`).
    pub model: String,
    /// The hidden effects (none for a control case).
    pub hidden: Vec<Hidden>,
    /// Scale of the input profile (1: the motor's full 12 V). Cogging is a
    /// low-speed effect: its case runs the motor slowly.
    pub drive_scale: f64,
}

/// How the recording is made.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordingOptions {
    /// Length (s). Default 4.
    pub duration: f64,
    /// Sample rate (Hz). Default 1000.
    pub rate_hz: f64,
    /// White noise standard deviation per output, as a fraction of the
    /// output's largest absolute value. Default 0.002.
    pub white: f64,
    /// Coloured (AR(1), coefficient `rho`) noise standard deviation, same units. Default 0.001.
    pub coloured: f64,
    /// AR(1) coefficient of the coloured noise. Default 0.9.
    pub rho: f64,
    /// Time constant of the sensors' first-order lag (s). Default 50 µs.
    pub sensor_lag: f64,
    /// Quantisation step of every measured output (an ADC's or encoder's
    /// resolution), as a fraction of the output's largest absolute value;
    /// 0 (the default) for none.
    pub quantisation: f64,
    /// Outputs whose sensor is dead: they read 0 throughout.
    pub dead: Vec<String>,
    /// The time column is written in these units per second (1000: ms, as a
    /// logger may write it); 1 (the default) for seconds.
    pub time_units_per_second: f64,
    /// Noise seed.
    pub seed: u64,
}

impl Default for RecordingOptions {
    fn default() -> RecordingOptions {
        RecordingOptions {
            duration: 4.0,
            rate_hz: 1000.0,
            white: 0.002,
            coloured: 0.001,
            rho: 0.9,
            sensor_lag: 50e-6,
            quantisation: 0.0,
            dead: Vec::new(),
            time_units_per_second: 1.0,
            seed: 1,
        }
    }
}

fn case(name: &str, model: &str, hidden: &[(&str, &[f64])]) -> HiddenCase {
    HiddenCase {
        name: name.to_string(),
        model: model.to_string(),
        hidden: hidden
            .iter()
            .map(|(id, v)| Hidden {
                id: id.to_string(),
                values: v.to_vec(),
            })
            .collect(),
        drive_scale: 1.0,
    }
}

/// The project's hidden-effect cases: eight single effects on the DC motor,
/// a buck–motor case, two effects at once, and two controls with nothing hidden.
pub fn cases() -> Vec<HiddenCase> {
    vec![
        case("coulomb", "dc-motor", &[("coulomb@1m", &[0.004])]),
        case("load", "dc-motor", &[("load@1m", &[0.01])]),
        case("brush", "dc-motor", &[("brush@1e", &[0.6])]),
        case("resistance", "dc-motor", &[("deviation:R", &[1.3])]),
        case("inertia", "dc-motor", &[("inertia@1m", &[5e-5])]),
        case(
            "coupling",
            "dc-motor",
            &[("coupling@1m", &[2.0, 2e-4, 1e-4])],
        ),
        HiddenCase {
            drive_scale: 0.15,
            ..case("cogging", "dc-motor", &[("cogging@1m", &[0.01, 8.0])])
        },
        case("fault", "dc-motor", &[("fault:R", &[1.6, 2.25])]),
        case("saturation", "dc-motor", &[("saturation@L", &[150.0, 1.0])]),
        case("nothing", "dc-motor", &[]),
        case("buck-load", "buck-motor", &[("load@1m", &[0.05])]),
        case("buck-nothing", "buck-motor", &[]),
        case(
            "coulomb+brush",
            "dc-motor",
            &[("coulomb@1m", &[0.004]), ("brush@1e", &[0.6])],
        ),
    ]
}

/// The input profile: the motor's voltage (or the converter's duty cycle)
/// steps up, reverses and steps down, so friction, loads and drops that
/// depend on the direction of motion show their sign.
pub fn excitation(model: &str, scale: f64, t: &[f64]) -> Vec<(String, Vec<f64>)> {
    let level = |t: f64| -> f64 {
        if t < 0.1 {
            0.0
        } else if t < 1.5 {
            1.0
        } else if t < 3.0 {
            -1.0
        } else {
            0.5
        }
    };
    match model {
        // The buck converter cannot reverse: its duty cycle steps instead.
        "buck-motor" => vec![(
            "m".to_string(),
            t.iter()
                .map(|&t| {
                    if t < 0.1 {
                        0.1
                    } else if t < 1.5 {
                        0.5
                    } else if t < 3.0 {
                        0.25
                    } else {
                        0.4
                    }
                })
                .collect(),
        )],
        _ => vec![(
            "V".to_string(),
            t.iter().map(|&t| 12.0 * scale * level(t)).collect(),
        )],
    }
}

/// The true system of a case: the nominal built-in with the hidden effects.
///
/// # Errors
/// [`BondError::UnknownModel`], or [`BondError::BadEffect`] for a hidden
/// effect the model does not offer.
pub fn true_system(case: &HiddenCase) -> Result<(BondGraph, Vec<crate::simulate::ParamChange>)> {
    let mut g = library::builtin(&case.model)?;
    let mut changes = Vec::new();
    for h in &case.hidden {
        let menu: Vec<Candidate> = effects::candidates(&g);
        let c = menu
            .iter()
            .find(|c| c.id == h.id)
            .ok_or_else(|| BondError::BadEffect {
                candidate: h.id.clone(),
                param: String::new(),
                detail: format!("model {} offers no such candidate", case.model),
            })?;
        let (g2, ch) = effects::apply(&g, c, &h.values)?;
        g = g2;
        changes.extend(ch);
    }
    Ok((g, changes))
}

/// Makes the recording of a case: inputs as commanded, measurements through
/// a sensor lag and with noise.
///
/// # Errors
/// As [`true_system`]; simulation errors.
pub fn record(case: &HiddenCase, opts: &RecordingOptions) -> Result<Recording> {
    let (g, changes) = true_system(case)?;
    let n = (opts.duration * opts.rate_hz).round() as usize;
    let t: Vec<f64> = (0..=n).map(|k| k as f64 / opts.rate_hz).collect();
    let profile = excitation(&case.model, case.drive_scale, &t);
    let mut inputs = Inputs::new();
    for (name, values) in &profile {
        inputs.set(
            name,
            Drive::Sampled {
                t: t.clone(),
                values: values.clone(),
                hold: Hold::Zero,
            },
        );
    }
    let sim = SimOptions {
        rtol: 1e-9,
        atol: 1e-12,
        changes,
        ..SimOptions::default()
    };
    let run = simulate(&g, &inputs, &t, &sim)?;
    let mut gauss = Gaussian::new(
        opts.seed
            .wrapping_mul(0x2545_F491_4F6C_DD1D)
            .wrapping_add(17),
    );
    let mut signals: Vec<Signal> = profile
        .into_iter()
        .map(|(name, values)| Signal { name, values })
        .collect();
    let dt = 1.0 / opts.rate_hz;
    let a = (-dt / opts.sensor_lag.max(1e-12)).exp();
    for (name, y) in run.output_names.iter().zip(&run.outputs) {
        if name == "v_c" {
            continue; // the buck case measures i and omega, as the paper does
        }
        let size = y.iter().fold(0.0_f64, |m, v| m.max(v.abs())).max(1e-12);
        let step = opts.quantisation * size;
        let dead = opts.dead.contains(name);
        let mut lagged = y[0];
        let mut coloured = 0.0;
        let values = y
            .iter()
            .map(|&v| {
                lagged = a * lagged + (1.0 - a) * v;
                coloured =
                    opts.rho * coloured + (1.0 - opts.rho * opts.rho).sqrt() * gauss.sample();
                let read = lagged + size * (opts.white * gauss.sample() + opts.coloured * coloured);
                if dead {
                    0.0
                } else if step > 0.0 {
                    (read / step).round() * step
                } else {
                    read
                }
            })
            .collect();
        signals.push(Signal {
            name: name.clone(),
            values,
        });
    }
    let t = t.iter().map(|t| t * opts.time_units_per_second).collect();
    Ok(Recording::new(t, signals)?)
}

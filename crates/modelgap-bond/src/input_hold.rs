//! How a recorded input is held between its samples, read from the recording.
//!
//! A simulation needs each input between its samples. A command (a controller's
//! output through its converter, a PWM duty, a set point) keeps its value until the
//! next sample: zero-order hold. A sampled analog signal (a force from a load cell, a
//! shaker's multisine, a voltage behind a reconstruction filter) moves between its
//! samples, and a smooth curve through them follows it: a cubic hold (straight lines,
//! the linear hold, miss its curvature, [`Hold::Cubic`]). Held the wrong way, the input
//! is shifted by half a sample interval. On a mass on a spring pushed by a multisine
//! up to 20 Hz, recorded 10 s at 1 kHz with noise at 0.3 % of the motion, that shift
//! alone left 3.5 times the noise, and explain named a mass 0.2 % off on a recording
//! that hid nothing (and took 20 times as long: a zero-order hold that changes at
//! every sample stops the adaptive solver at every sample).
//!
//! [`BondModel::settle_holds`] decides per input, from the recording. An input that
//! steps (it repeats its value at half its samples or more, or takes two values) is
//! held at each sample's value. For any other one the samples alone cannot decide (a
//! smooth multisine sent through a converter that holds it looks like a sampled analog
//! signal), so the model is run with the input held at each sample's value and held
//! between samples — by a cubic when the input is smooth between its samples
//! ([`SMOOTH`]), by straight lines when it is rough (a cubic through samples of a signal
//! near half the sampling rate overshoots) — and the way that predicts the measured
//! outputs clearly better ([`CLEARLY`]) is kept. When neither is clearly better (the
//! model's own error is larger than what the hold changes: a missing damping and a
//! half-sample lag look alike) the samples' shape decides: a smooth input is held between
//! samples, a rough one (it changes at every sample like a command updated at every
//! sample) at each sample's value. The note says which reason decided.

use std::fmt;

use modelgap_core::{Model as _, Recording};

use crate::model::BondModel;
use crate::simulate::Hold;

/// Share of samples equal to the one before above which an input steps (a command
/// held between its changes): held at each sample's value.
pub const STEPPING_SHARE: f64 = 0.5;

/// One hold predicts the outputs clearly better than the other when its squared error is
/// below this share of the other's.
pub const CLEARLY: f64 = 0.8;

/// An input is smooth between its samples when the RMS of its second differences is
/// below this share of the RMS of its first differences (a sine at a tenth of the
/// sampling rate gives 0.62, one at a quarter 1.4, white noise 1.7).
pub const SMOOTH: f64 = 0.5;

/// Why an input is held as it is.
#[derive(Clone, Debug, PartialEq)]
pub enum HoldReason {
    /// The input steps: it repeats its value at this share of its samples (a two-level
    /// signal counts as stepping whatever the share).
    Steps {
        /// Share of samples equal to the one before.
        repeats: f64,
    },
    /// The model was run both ways: the outputs' squared error, each relative to that
    /// output's variance and summed over the measured outputs. When neither is clearly
    /// better ([`CLEARLY`]), the input's shape decided.
    Fits {
        /// Held at each sample's value.
        zero: f64,
        /// Held between samples (by a cubic or straight lines: see the chosen hold).
        between: f64,
        /// RMS of the second differences over RMS of the first ([`SMOOTH`]).
        roughness: f64,
    },
    /// Could not be judged (a run failed, or no measured output moves): held as before.
    Undecided(String),
}

/// One input's hold, as [`BondModel::settle_holds`] chose it.
#[derive(Clone, Debug, PartialEq)]
pub struct HeldInput {
    /// The input's name.
    pub input: String,
    /// How it is now held.
    pub hold: Hold,
    /// Why.
    pub reason: HoldReason,
}

fn hold_words(hold: Hold) -> &'static str {
    match hold {
        Hold::Zero => "held at each sample's value until the next (zero-order hold)",
        Hold::Linear => "held linearly between samples",
        Hold::Cubic => "held by a smooth cubic through its samples",
    }
}

impl fmt::Display for HeldInput {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (name, how) = (&self.input, hold_words(self.hold));
        match &self.reason {
            HoldReason::Steps { repeats } => write!(
                f,
                "input `{name}` steps (it repeats its value at {:.0} % of its samples): {how}",
                100.0 * repeats
            ),
            HoldReason::Fits {
                zero,
                between,
                roughness,
            } => {
                let (chosen, other) = match self.hold {
                    Hold::Zero => (*zero, *between),
                    Hold::Linear | Hold::Cubic => (*between, *zero),
                };
                let way = if *roughness < SMOOTH {
                    "by a cubic"
                } else {
                    "linearly"
                };
                let errors = format!(
                    "squared error {} of the outputs' variance held at each sample, {} {way}",
                    sig(*zero),
                    sig(*between)
                );
                if chosen < CLEARLY * other {
                    write!(
                        f,
                        "input `{name}` is {how}: the model predicts the outputs clearly better \
                         so ({errors}); choosing the hold overrides this"
                    )
                } else {
                    let shape = if *roughness < SMOOTH {
                        "it is smooth between its samples, as a sampled analog signal is"
                    } else {
                        "it changes at every sample, as a command updated at every sample does"
                    };
                    write!(
                        f,
                        "input `{name}` is {how}: neither hold predicts the outputs clearly \
                         better ({errors}: the model's own error is larger than what the hold \
                         changes), and {shape} (second differences {} of the first); choosing \
                         the hold overrides this",
                        sig(*roughness)
                    )
                }
            }
            HoldReason::Undecided(why) => write!(f, "input `{name}` is {how} ({why})"),
        }
    }
}

/// A number to three significant digits.
fn sig(v: f64) -> String {
    if v == 0.0 || !(1e-3..1e4).contains(&v.abs()) {
        format!("{v:.2e}")
    } else {
        let decimals = (2 - v.abs().log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    }
}

/// RMS of the second differences over RMS of the first: small for a signal that is
/// smooth between its samples.
fn roughness(values: &[f64]) -> f64 {
    let (mut d1, mut d2) = (0.0, 0.0);
    for w in values.windows(3) {
        d1 += (w[1] - w[0]).powi(2);
        d2 += (w[2] - 2.0 * w[1] + w[0]).powi(2);
    }
    if d1 > 0.0 { (d2 / d1).sqrt() } else { 0.0 }
}

/// The share of samples equal to the one before, and whether the signal takes at most
/// two values.
fn stepping(values: &[f64]) -> (f64, bool) {
    let repeats = values.windows(2).filter(|w| w[1] == w[0]).count();
    let share = repeats as f64 / (values.len() - 1).max(1) as f64;
    let first = values[0];
    let other = values.iter().find(|&&v| v != first);
    let two_levels = other.is_none_or(|&o| values.iter().all(|&v| v == first || v == o));
    (share, two_levels)
}

impl BondModel {
    /// Chooses, input by input, how the inputs `rec` records are held between samples
    /// (see the [module](crate::input_hold)) and keeps the choice in the model; returns
    /// what was chosen and why, one entry per recorded input that is not constant.
    pub fn settle_holds(&mut self, rec: &Recording) -> Vec<HeldInput> {
        let names: Vec<String> = self.graph().inputs().keys().cloned().collect();
        let mut out = Vec::new();
        for name in names {
            let Some(signal) = rec.signal(&name) else {
                continue;
            };
            let values = &signal.values;
            if values.len() < 3 || values.iter().all(|&v| v == values[0]) {
                continue;
            }
            let (repeats, two_levels) = stepping(values);
            if repeats >= STEPPING_SHARE || two_levels {
                self.set_input_hold(&name, Hold::Zero);
                out.push(HeldInput {
                    input: name,
                    hold: Hold::Zero,
                    reason: HoldReason::Steps { repeats },
                });
                continue;
            }
            let roughness = roughness(values);
            let smooth_hold = if roughness < SMOOTH {
                Hold::Cubic
            } else {
                Hold::Linear
            };
            let mut error = [0.0; 2];
            let mut failed = None;
            for (k, hold) in [Hold::Zero, smooth_hold].into_iter().enumerate() {
                self.set_input_hold(&name, hold);
                match self.relative_error(rec) {
                    Ok(Some(e)) => error[k] = e,
                    Ok(None) => failed = Some("no measured output moves".to_owned()),
                    Err(e) => failed = Some(format!("the model could not run: {e}")),
                }
            }
            let [zero, between] = error;
            let (hold, reason) = match failed {
                Some(why) => (self.hold(), HoldReason::Undecided(why)),
                None => {
                    let hold = if between < CLEARLY * zero {
                        smooth_hold
                    } else if zero < CLEARLY * between {
                        Hold::Zero
                    } else if roughness < SMOOTH {
                        smooth_hold
                    } else {
                        Hold::Zero
                    };
                    let reason = HoldReason::Fits {
                        zero,
                        between,
                        roughness,
                    };
                    (hold, reason)
                }
            };
            self.set_input_hold(&name, hold);
            out.push(HeldInput {
                input: name,
                hold,
                reason,
            });
        }
        out
    }

    /// The measured outputs' squared error, each relative to its variance, summed;
    /// `None` when no measured output moves.
    fn relative_error(&self, rec: &Recording) -> modelgap_core::Result<Option<f64>> {
        let prediction = self.predict(rec)?;
        let mut total = None;
        for name in self.outputs() {
            let (Some(measured), Some(predicted)) = (rec.signal(&name), prediction.get(&name))
            else {
                continue;
            };
            let y = &measured.values;
            let mean = y.iter().sum::<f64>() / y.len() as f64;
            let spread: f64 = y.iter().map(|v| (v - mean).powi(2)).sum();
            if spread > 0.0 {
                let e: f64 = y.iter().zip(predicted).map(|(a, b)| (a - b).powi(2)).sum();
                *total.get_or_insert(0.0) += e / spread;
            }
        }
        Ok(total.filter(|t: &f64| t.is_finite()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_and_two_levels_are_recognised() {
        assert_eq!(stepping(&[0.0, 0.0, 1.0, 1.0, 1.0]), (0.75, true));
        let pwm = [0.0, 5.0, 0.0, 5.0, 5.0, 0.0];
        assert!(stepping(&pwm).1);
        let smooth: Vec<f64> = (0..100).map(|k| (0.1 * k as f64).sin()).collect();
        let (share, two) = stepping(&smooth);
        assert!(share < STEPPING_SHARE && !two);
    }

    #[test]
    fn roughness_tells_a_smooth_signal_from_a_rough_one() {
        let sine = |f: f64| -> Vec<f64> {
            (0..2000)
                .map(|k| (std::f64::consts::TAU * f * k as f64).sin())
                .collect()
        };
        assert!((roughness(&sine(0.1)) - 0.618).abs() < 0.01);
        assert!(roughness(&sine(0.02)) < 0.2);
        assert!(roughness(&sine(0.25)) > 1.3);
        let mut noise = modelgap_core::noise::Gaussian::new(1);
        let white: Vec<f64> = (0..20000).map(|_| noise.sample()).collect();
        assert!((roughness(&white) - 3f64.sqrt()).abs() < 0.05);
    }

    #[test]
    fn numbers_keep_three_digits() {
        assert_eq!(sig(0.5412), "0.541");
        assert_eq!(sig(12.345), "12.3");
        assert_eq!(sig(3.2e-5), "3.20e-5");
        assert_eq!(sig(0.0), "0.00e0");
    }
}

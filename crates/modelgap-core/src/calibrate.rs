//! Calibration: fit a model's own unknowns — the parameters marked free and
//! the initial states not known — to a recording by simulation error, before
//! asking what physics it misses.
//!
//! The unknowns come from [`Model::free_parameters`] as one candidate; the
//! fit is the bounded Levenberg–Marquardt of [`crate::fit`] on the residual
//! measured − predicted of every output the recording holds, each output
//! divided by the standard deviation of its measurement so that outputs in
//! different units weigh alike. Standard errors are widened for the
//! residual's correlation in time (effective sample size, AR(1)): a smooth
//! misfit leaves few independent samples, and the ± says so. A value that
//! ends on one of its bounds is marked, with no ± (the data did not place
//! it).
//!
//! An unknown may carry a Gaussian [`Prior`] (a datasheet's tolerance, an
//! earlier calibration): the fit is then run twice — first on the data
//! alone, to learn how large and how correlated the residual is, then with
//! one more residual `(value − mean) / std` per prior, weighed so that the
//! minimum is the posterior's mode and the ± the posterior's (the data's
//! effective samples, not their count, set how much they outweigh the
//! prior).
//!
//! ```
//! use modelgap_core::{calibrate, CalibrationOptions, Candidate, EffectKind, EffectParam};
//! use modelgap_core::{Effect, Model, Prediction, Recording, Signal};
//!
//! /// y = a·(1 − e^(−t/τ)) with `a` and `τ` unknown.
//! struct Step { a: f64, tau: f64 }
//! impl Model for Step {
//!     fn name(&self) -> String { "step".into() }
//!     fn outputs(&self) -> Vec<String> { vec!["y".into()] }
//!     fn predict_with(&self, rec: &Recording, fx: &[(&Candidate, &[f64])]) -> modelgap_core::Result<Prediction> {
//!         let (a, tau) = fx.first().map_or((self.a, self.tau), |(_, v)| (v[0], v[1]));
//!         let y = rec.t().iter().map(|t| a * (1.0 - (-t / tau).exp())).collect();
//!         Ok(Prediction { names: vec!["y".into()], values: vec![y] })
//!     }
//!     fn candidates(&self) -> Vec<Candidate> { Vec::new() }
//!     fn free_parameters(&self) -> Option<Candidate> {
//!         Some(Candidate {
//!             id: "calibration".into(), name: "calibration".into(),
//!             kind: EffectKind::Calibration, acts_on: "step".into(),
//!             params: vec![
//!                 EffectParam::new("a", "V", self.a, (0.0, 10.0), 1.0),
//!                 EffectParam::new("tau", "s", self.tau, (0.01, 10.0), 0.1),
//!             ],
//!         })
//!     }
//!     fn with_effects(&self, fx: &[Effect]) -> modelgap_core::Result<Box<dyn Model>> {
//!         let v = &fx[0].values;
//!         Ok(Box::new(Step { a: v[0], tau: v[1] }))
//!     }
//! }
//!
//! let t: Vec<f64> = (0..200).map(|k| k as f64 * 0.01).collect();
//! let y: Vec<f64> = t.iter().map(|t| 2.0 * (1.0 - (-t / 0.3_f64).exp())).collect();
//! let rec = Recording::new(t, vec![Signal::new("y", y)])?;
//! let cal = calibrate(&Step { a: 1.0, tau: 1.0 }, &rec, &CalibrationOptions::default())?;
//! assert!((cal.values[0].value - 2.0).abs() < 1e-6 && (cal.values[1].value - 0.3).abs() < 1e-6);
//! assert!(cal.rms_after[0].1 < 1e-6 * cal.rms_before[0].1);
//! # Ok::<(), modelgap_core::CoreError>(())
//! ```

use crate::effect::{Candidate, Effect, Prior};
use crate::error::{CoreError, Result};
use crate::fit::{Cancel, FitOptions, ResidualProblem, Termination, fit};
use crate::model::Model;
use crate::recording::Recording;
use crate::residual::effective_sample_size;

/// Options of [`calibrate`].
#[derive(Clone, Debug, Default)]
pub struct CalibrationOptions {
    /// The fit's tolerances and limits; its `name` is set to the model's.
    pub fit: FitOptions,
    /// Checked before every simulation (Ctrl-C); a cancelled calibration
    /// returns the best point so far with [`Termination::Cancelled`].
    pub cancel: Option<std::sync::Arc<Cancel>>,
}

/// One fitted unknown.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FittedValue {
    /// The parameter (`k1`) or initial state (`Tank1(0)`).
    pub name: String,
    /// Its unit.
    pub unit: String,
    /// Where the fit started (the model's value).
    pub start: f64,
    /// The fitted value.
    pub value: f64,
    /// Standard error, widened for the residual's correlation in time;
    /// `None` when the data do not determine it (on a bound, or moving with
    /// another unknown in a way the outputs cannot see).
    pub std_error: Option<f64>,
    /// `Some("lower")` or `Some("upper")` when the fit ended on that bound.
    pub at_bound: Option<&'static str>,
    /// The bounds it was fitted within.
    pub bounds: (f64, f64),
    /// The prior it was weighed against, if it had one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prior: Option<Prior>,
}

/// What [`calibrate`] found.
pub struct Calibration {
    /// The unknowns as fitted, in the candidate's order.
    pub values: Vec<FittedValue>,
    /// Correlation matrix of the unknowns (rows and columns in the order of
    /// [`Calibration::values`]).
    pub correlation: Vec<Vec<f64>>,
    /// RMS of measured − predicted per output, with the model's values.
    pub rms_before: Vec<(String, f64)>,
    /// The same with the fitted values.
    pub rms_after: Vec<(String, f64)>,
    /// Why the fit stopped.
    pub termination: Termination,
    /// Effective number of independent samples in the final residual.
    pub effective_samples: f64,
    /// The calibrated model (the fitted values built in).
    pub model: Box<dyn Model>,
    /// The candidate fitted, with the fitted values: what
    /// [`Model::with_effects`] built into [`Calibration::model`].
    pub effect: Effect,
}

impl std::fmt::Debug for Calibration {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Calibration")
            .field("values", &self.values)
            .field("rms_before", &self.rms_before)
            .field("rms_after", &self.rms_after)
            .field("termination", &self.termination)
            .finish_non_exhaustive()
    }
}

struct Problem<'a> {
    model: &'a dyn Model,
    rec: &'a Recording,
    candidate: &'a Candidate,
    names: Vec<String>,
    measured: Vec<&'a [f64]>,
    /// Each output's measured standard deviation: what its residual is divided by.
    sd: Vec<f64>,
    /// The unknowns with a prior (index into the candidate's parameters).
    priors: Vec<(usize, Prior)>,
    /// What a prior's residual `(value − mean) / std` is multiplied by (0:
    /// priors ignored); see [`prior_weight`].
    prior_weight: f64,
}

impl Problem<'_> {
    /// `(measured − predicted) / scale` per output, output after output.
    fn scaled(&self, values: &[f64], scale: &[f64], out: &mut [f64]) -> Result<()> {
        self.model
            .predict_with(self.rec, &[(self.candidate, values)])?
            .residuals_into(&self.names, &self.measured, scale, out)
    }

    /// Unweighted residuals measured − predicted (the data's rows only).
    fn raw(&self, values: &[f64], out: &mut [f64]) -> Result<()> {
        self.scaled(values, &vec![1.0; self.names.len()], out)
    }

    /// The number of data rows (outputs × samples).
    fn n_data(&self) -> usize {
        self.names.len() * self.rec.len()
    }

    fn rms(&self, raw: &[f64]) -> Vec<(String, f64)> {
        let n = self.rec.len();
        (self.names.iter().enumerate())
            .map(|(j, name)| {
                let r = &raw[j * n..(j + 1) * n];
                let rms = (r.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
                (name.clone(), rms)
            })
            .collect()
    }
}

impl ResidualProblem for Problem<'_> {
    fn n_params(&self) -> usize {
        self.candidate.params.len()
    }

    fn n_residuals(&self) -> usize {
        self.n_data() + self.priors.len()
    }

    /// One series per output, then the priors.
    fn series_length(&self) -> Option<usize> {
        Some(self.rec.len())
    }

    fn residuals(&self, values: &[f64], out: &mut [f64]) -> Result<()> {
        let (data, priors) = out.split_at_mut(self.n_data());
        self.scaled(values, &self.sd, data)?;
        for (o, (i, prior)) in priors.iter_mut().zip(&self.priors) {
            *o = self.prior_weight * (values[*i] - prior.mean) / prior.std;
        }
        Ok(())
    }
}

/// The weight of the priors' rows against the data's: the log-posterior is
/// `−Σ r²/(2 s²) · n_eff/n − Σ (θ − μ)²/(2 σ²)` for `n` residuals `r` of
/// variance `s²` carrying `n_eff` independent samples; multiplied through by
/// `s² n / n_eff` it is a least-squares cost whose prior rows are
/// `s √(n / n_eff) (θ − μ) / σ`. `s²` and `n_eff` come from a fit without the
/// priors. The fit's uncertainties (scaled by `√(n / n_eff)` as without
/// priors) are then the posterior's.
fn prior_weight(scaled: &[f64], n_eff: f64) -> f64 {
    let n = scaled.len() as f64;
    let s2 = scaled.iter().map(|r| r * r).sum::<f64>() / n.max(1.0);
    if n_eff > 0.0 && n_eff.is_finite() && s2.is_finite() {
        (s2 * n / n_eff).sqrt()
    } else {
        0.0
    }
}

/// Fits the model's unknowns ([`Model::free_parameters`]) to `rec` by
/// simulation error (see the [module docs](self)).
///
/// # Errors
/// [`CoreError::Fit`] when the model has no unknowns or the recording holds
/// none of its outputs, or an output is constant (nothing to fit to); the
/// model's error when it cannot simulate at its own values.
pub fn calibrate(
    model: &dyn Model,
    rec: &Recording,
    opts: &CalibrationOptions,
) -> Result<Calibration> {
    let fit_error = |reason: String| CoreError::Fit {
        what: format!("calibration of {}", model.name()),
        reason,
    };
    let candidate = model.free_parameters().ok_or_else(|| {
        fit_error(
            "the model has nothing to calibrate: mark parameters `free = true` (or give --free NAME) or initial states free"
                .to_string(),
        )
    })?;
    let names: Vec<String> = (model.outputs().into_iter())
        .filter(|o| rec.signal(o).is_some())
        .collect();
    if names.is_empty() {
        return Err(fit_error(format!(
            "the recording holds none of the model's outputs ({})",
            model.outputs().join(", ")
        )));
    }
    let measured: Vec<&[f64]> = (names.iter())
        .filter_map(|o| rec.signal(o).map(|s| s.values.as_slice()))
        .collect();
    let mut sd = Vec::new();
    for (name, m) in names.iter().zip(&measured) {
        let mean = m.iter().sum::<f64>() / m.len() as f64;
        let spread =
            (m.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / m.len() as f64).sqrt();
        if !(spread > 0.0 && spread.is_finite()) {
            return Err(fit_error(format!(
                "output '{name}' is constant in the recording: nothing to calibrate against"
            )));
        }
        sd.push(spread);
    }
    let priors: Vec<(usize, Prior)> = (candidate.params.iter().enumerate())
        .filter_map(|(i, p)| p.prior.map(|pr| (i, pr)))
        .collect();
    let mut problem = Problem {
        model,
        rec,
        candidate: &candidate,
        names,
        measured,
        sd,
        priors: Vec::new(),
        prior_weight: 0.0,
    };
    let start = candidate.initial();
    let mut raw = vec![0.0; problem.n_data()];
    problem.raw(&start, &mut raw)?;
    let rms_before = problem.rms(&raw);
    let bounds: Vec<(f64, f64)> = candidate
        .params
        .iter()
        .map(|p| (p.lower, p.upper))
        .collect();
    let scales: Vec<f64> = candidate.params.iter().map(|p| p.scale).collect();
    let mut fit_opts = opts.fit.clone();
    fit_opts.name = format!("calibration of {}", model.name());
    let mut report = fit(
        &problem,
        &start,
        &bounds,
        &scales,
        &fit_opts,
        opts.cancel.as_deref(),
    )?;
    let n = problem.rec.len();
    let effective = |raw: &[f64]| -> f64 {
        (0..problem.names.len())
            .map(|j| effective_sample_size(&raw[j * n..(j + 1) * n]))
            .sum()
    };
    if !priors.is_empty() && report.termination != Termination::Cancelled {
        // Again with the priors, weighed against the data as the first fit
        // left them (see `prior_weight`), from where it ended.
        problem.raw(&report.params, &mut raw)?;
        let mut scaled = vec![0.0; problem.n_data()];
        problem.scaled(&report.params, &problem.sd, &mut scaled)?;
        problem.prior_weight = prior_weight(&scaled, effective(&raw));
        problem.priors = priors;
        report = fit(
            &problem,
            &report.params,
            &bounds,
            &scales,
            &fit_opts,
            opts.cancel.as_deref(),
        )?;
    }
    problem.raw(&report.params, &mut raw)?;
    let rms_after = problem.rms(&raw);
    let effective_samples = effective(&raw);
    // The sandwich over the fit's residual: it holds for coloured noise and for the model
    // error a calibration leaves (the white formula scaled by the residual's effective
    // samples was tens of times too wide on a smooth residual).
    let std_errors = report.robust_std_errors.clone();
    let values = (candidate.params.iter().enumerate())
        .map(|(i, p)| {
            let v = report.params[i];
            let slack = 1e-9 * p.scale.abs().max(v.abs());
            let at_bound = if v <= p.lower + slack {
                Some("lower")
            } else if v >= p.upper - slack {
                Some("upper")
            } else {
                None
            };
            FittedValue {
                name: p.name.clone(),
                unit: p.unit.clone(),
                start: p.initial,
                value: v,
                std_error: (at_bound.is_none() && std_errors[i].is_finite())
                    .then_some(std_errors[i]),
                at_bound,
                bounds: (p.lower, p.upper),
                prior: p.prior,
            }
        })
        .collect();
    let effect = Effect {
        candidate: candidate.clone(),
        values: report.params.clone(),
    };
    let calibrated = model.with_effects(std::slice::from_ref(&effect))?;
    Ok(Calibration {
        values,
        correlation: report.correlation.clone(),
        rms_before,
        rms_after,
        termination: report.termination,
        effective_samples,
        model: calibrated,
        effect,
    })
}

//! Candidate effects: what a model may be missing, with parameters to fit.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::error::CoreError;

/// Slack within which a value still counts as inside its bounds, relative to
/// the bound (or to the parameter's scale, for a bound at 0): rounding in a
/// fit's projection onto the bounds.
pub const BOUND_SLACK: f64 = 1e-12;

/// What kind of change a candidate is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EffectKind {
    /// An existing parameter is off (R is not 1.0 Ω but 1.2 Ω).
    ParameterDeviation,
    /// An existing parameter changes abruptly at an unknown time (a fault).
    AbruptChange,
    /// A physical element the model does not have (friction, a load, a coupling).
    MissingElement,
    /// The model's own unknowns: parameters marked free and unknown
    /// initial states, fitted by calibration (see [`crate::calibrate()`]).
    Calibration,
}

impl fmt::Display for EffectKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            EffectKind::ParameterDeviation => "parameter-deviation",
            EffectKind::AbruptChange => "abrupt-change",
            EffectKind::MissingElement => "missing-element",
            EffectKind::Calibration => "calibration",
        })
    }
}

/// A parameter of a candidate effect, in SI units.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EffectParam {
    /// Name (`tau_c`, `R`, `t_fault`).
    pub name: String,
    /// Unit (`N m`, `Ohm`, `s`).
    pub unit: String,
    /// Where the fit starts.
    pub initial: f64,
    /// Lower bound.
    pub lower: f64,
    /// Upper bound.
    pub upper: f64,
    /// A typical size of the parameter: sets absolute finite-difference steps
    /// and scales the fit (a start value of 0 needs it).
    pub scale: f64,
    /// Number of evenly spaced start values across `[lower, upper]` the fit
    /// tries for this parameter before refining (0: start at `initial`
    /// only). For parameters a local fit cannot find: a fault time
    /// (`t_fault`, whose bounds the loop narrows to the recording), a period
    /// count.
    #[serde(default)]
    pub grid: usize,
    /// The grid's start values are spaced evenly in the logarithm instead
    /// (a time constant from a tenth of a sample to a fifth of the record:
    /// evenly spaced starts would all lie far above a lag of tens of
    /// samples). Only for a positive lower bound.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub log_grid: bool,
    /// The lattice a discrete parameter lives on (a vertex's column, a
    /// harmonic's order): its values are `lower + k · step`. 0 (the default)
    /// for a continuous parameter. A fit holds a discrete parameter while it
    /// fits the others, then moves it by whole steps while that lowers the
    /// error (a compass search from half its grid's spacing down to one
    /// step); it is given no ± (the lattice point is the answer).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub step: f64,
    /// What is known of the value before the data: a Gaussian prior that a
    /// calibration weighs against the recording (see [`crate::calibrate()`]);
    /// `None` (the default): only the bounds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prior: Option<Prior>,
}

/// A Gaussian prior on a parameter: the value is believed to be `mean`
/// within a standard deviation `std` (same unit) before the data are seen —
/// a datasheet's tolerance, a previous calibration.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Prior {
    /// The value believed most likely.
    pub mean: f64,
    /// Its standard deviation (positive, finite).
    pub std: f64,
}

impl Prior {
    /// A prior `mean ± std`, or `None` unless both are finite and `std` is
    /// positive.
    pub fn new(mean: f64, std: f64) -> Option<Prior> {
        (mean.is_finite() && std.is_finite() && std > 0.0).then_some(Prior { mean, std })
    }
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

impl EffectParam {
    /// A parameter starting at `initial` within `bounds` (lower, upper), of
    /// typical size `scale`, with no grid of start values.
    ///
    /// # Example
    /// ```
    /// # use modelgap_core::EffectParam;
    /// let tau_c = EffectParam::new("tau_c", "N m", 0.0, (0.0, 0.5), 0.01);
    /// assert_eq!((tau_c.lower, tau_c.upper, tau_c.grid), (0.0, 0.5, 0));
    /// ```
    pub fn new(
        name: impl Into<String>,
        unit: impl Into<String>,
        initial: f64,
        bounds: (f64, f64),
        scale: f64,
    ) -> EffectParam {
        EffectParam {
            name: name.into(),
            unit: unit.into(),
            initial,
            lower: bounds.0,
            upper: bounds.1,
            scale,
            grid: 0,
            log_grid: false,
            step: 0.0,
            prior: None,
        }
    }

    /// The same parameter with `grid` evenly spaced start values across its
    /// bounds (see [`EffectParam::grid`]).
    #[must_use]
    pub fn with_grid(mut self, grid: usize) -> EffectParam {
        self.grid = grid;
        self
    }

    /// The same parameter with `grid` start values spaced evenly in the
    /// logarithm across its bounds (see [`EffectParam::log_grid`]); evenly
    /// spaced when the lower bound is not positive.
    ///
    /// # Example
    /// ```
    /// # use modelgap_core::EffectParam;
    /// let tau = EffectParam::new("tau", "s", 1e-3, (1e-4, 1.0), 1e-3).with_log_grid(5);
    /// let starts = tau.grid_points();
    /// assert_eq!(starts.len(), 5);
    /// assert!((starts[1] / 1e-3 - 1.0).abs() < 1e-12 && (starts[4] - 1.0).abs() < 1e-12);
    /// // Across a bound of 0 the starts are evenly spaced.
    /// let b = EffectParam::new("b", "N m s/rad", 0.0, (0.0, 1.0), 0.1).with_log_grid(3);
    /// assert_eq!(b.grid_points(), vec![0.0, 0.5, 1.0]);
    /// ```
    #[must_use]
    pub fn with_log_grid(mut self, grid: usize) -> EffectParam {
        self.grid = grid;
        self.log_grid = self.lower > 0.0;
        self
    }

    /// The start values of the grid (see [`EffectParam::grid`]): `initial`
    /// alone for a grid of one, none for no grid.
    pub fn grid_points(&self) -> Vec<f64> {
        let n = self.grid;
        (0..n)
            .map(|k| {
                if n == 1 {
                    self.initial
                } else if self.log_grid && self.lower > 0.0 && self.upper > self.lower {
                    self.lower * (self.upper / self.lower).powf(k as f64 / (n - 1) as f64)
                } else {
                    self.lower + (self.upper - self.lower) * k as f64 / (n - 1) as f64
                }
            })
            .collect()
    }

    /// The same parameter on a lattice of `step` (see [`EffectParam::step`]).
    #[must_use]
    pub fn with_step(mut self, step: f64) -> EffectParam {
        self.step = step;
        self
    }

    /// Whether the parameter lives on a lattice (see [`EffectParam::step`]).
    pub fn is_discrete(&self) -> bool {
        self.step > 0.0
    }

    /// The same parameter with a Gaussian prior (see [`EffectParam::prior`]).
    #[must_use]
    pub fn with_prior(mut self, prior: Option<Prior>) -> EffectParam {
        self.prior = prior;
        self
    }

    /// True when `value` lies within the bounds, up to [`BOUND_SLACK`].
    pub fn admits(&self, value: f64) -> bool {
        let slack = |bound: f64| BOUND_SLACK * bound.abs().max(self.scale.abs());
        value >= self.lower - slack(self.lower) && value <= self.upper + slack(self.upper)
    }
}

/// An effect a model may be missing, before it is fitted.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// A stable identifier (`coulomb@1m`, `deviation:R`).
    pub id: String,
    /// A plain name (`Coulomb friction on the shaft`).
    pub name: String,
    /// What kind of change it is.
    pub kind: EffectKind,
    /// Where it acts (an element, a junction, a region).
    pub acts_on: String,
    /// Its parameters.
    pub params: Vec<EffectParam>,
}

impl Candidate {
    /// Initial values of the parameters.
    pub fn initial(&self) -> Vec<f64> {
        self.params.iter().map(|p| p.initial).collect()
    }

    /// Checks values for this candidate: one per parameter, each finite and
    /// within its bounds (up to [`BOUND_SLACK`]).
    ///
    /// # Errors
    /// [`BadValues`] naming the candidate and the parameter (none for a
    /// wrong count); `?` turns it into [`CoreError::Model`].
    ///
    /// # Example
    /// ```
    /// # use modelgap_core::{Candidate, EffectKind, EffectParam};
    /// let c = Candidate {
    ///     id: "coulomb@1m".into(),
    ///     name: "Coulomb friction on the shaft".into(),
    ///     kind: EffectKind::MissingElement,
    ///     acts_on: "1m".into(),
    ///     params: vec![EffectParam::new("tau_c", "N m", 0.0, (0.0, 0.5), 0.01)],
    /// };
    /// assert!(c.check_values(&[0.01]).is_ok());
    /// let err = c.check_values(&[-1.0]).unwrap_err();
    /// assert_eq!(err.param, "tau_c");
    /// ```
    pub fn check_values(&self, values: &[f64]) -> Result<(), BadValues> {
        let bad = |param: &str, detail: String| BadValues {
            candidate: self.id.clone(),
            param: param.to_string(),
            detail,
        };
        if values.len() != self.params.len() {
            return Err(bad(
                "",
                format!(
                    "expected {} value{} ({}), found {}",
                    self.params.len(),
                    if self.params.len() == 1 { "" } else { "s" },
                    self.params
                        .iter()
                        .map(|p| p.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", "),
                    values.len()
                ),
            ));
        }
        for (p, &v) in self.params.iter().zip(values) {
            if !v.is_finite() {
                return Err(bad(
                    &p.name,
                    format!("parameter '{}' must be finite, found {v}", p.name),
                ));
            }
            if !p.admits(v) {
                return Err(bad(
                    &p.name,
                    format!(
                        "parameter '{}' = {v} {} is outside its bounds [{}, {}]",
                        p.name, p.unit, p.lower, p.upper
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Values a candidate cannot take: a wrong count, a value that is not
/// finite or one outside its bounds (see [`Candidate::check_values`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("effect '{candidate}': {detail}")]
pub struct BadValues {
    /// The candidate's id (`coulomb@1m`).
    pub candidate: String,
    /// The parameter concerned; empty for a wrong number of values.
    pub param: String,
    /// What is wrong, naming the parameter.
    pub detail: String,
}

impl From<BadValues> for CoreError {
    /// A model cannot be edited with these values: [`CoreError::Model`] with
    /// the same message.
    fn from(e: BadValues) -> CoreError {
        CoreError::from_model(None, e)
    }
}

/// A candidate with fitted parameter values: what `fix` adds to a model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Effect {
    /// The candidate.
    pub candidate: Candidate,
    /// Its parameter values, in the candidate's order.
    pub values: Vec<f64>,
}

impl fmt::Display for Effect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.candidate.name)?;
        for (p, v) in self.candidate.params.iter().zip(&self.values) {
            write!(f, " {}={:.4e} {}", p.name, v, p.unit)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn coulomb() -> Candidate {
        Candidate {
            id: "coulomb@1m".into(),
            name: "Coulomb friction".into(),
            kind: EffectKind::MissingElement,
            acts_on: "1m".into(),
            params: vec![EffectParam::new("tau_c", "N m", 0.0, (0.0, 0.5), 0.01)],
        }
    }

    #[test]
    fn values_within_bounds_pass_up_to_the_slack() {
        let c = coulomb();
        for v in [0.0, 0.25, 0.5, -1e-15, 0.5 + 1e-13] {
            assert!(c.check_values(&[v]).is_ok(), "{v}");
        }
    }

    #[test]
    fn bad_values_name_the_candidate_the_parameter_and_the_fault() {
        let c = coulomb();
        for (values, param, says) in [
            (
                vec![f64::NAN],
                "tau_c",
                "parameter 'tau_c' must be finite, found NaN",
            ),
            (vec![f64::INFINITY], "tau_c", "must be finite, found inf"),
            (
                vec![-0.1],
                "tau_c",
                "parameter 'tau_c' = -0.1 N m is outside its bounds [0, 0.5]",
            ),
            (vec![], "", "expected 1 value (tau_c), found 0"),
            (vec![0.1, 0.2], "", "expected 1 value (tau_c), found 2"),
        ] {
            let err = c.check_values(&values).unwrap_err();
            assert_eq!(
                (err.candidate.as_str(), err.param.as_str()),
                ("coulomb@1m", param)
            );
            let text = err.to_string();
            assert!(text.starts_with("effect 'coulomb@1m': "), "{text}");
            assert!(text.contains(says), "{text}");
            let core = CoreError::from(err);
            assert!(matches!(core, CoreError::Model { .. }));
            assert_eq!(core.to_string(), text);
        }
    }

    #[test]
    fn a_grid_is_set_by_with_grid() {
        let p = EffectParam::new("N_cog", "1", 6.0, (2.0, 24.0), 6.0).with_grid(12);
        assert_eq!(
            (p.name.as_str(), p.unit.as_str(), p.grid),
            ("N_cog", "1", 12)
        );
        assert_eq!(
            (p.initial, p.lower, p.upper, p.scale),
            (6.0, 2.0, 24.0, 6.0)
        );
    }
}

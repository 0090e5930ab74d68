//! Candidate effects: what a model may be missing, with parameters to fit.

use std::fmt;

use serde::{Deserialize, Serialize};

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
}

impl fmt::Display for EffectKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            EffectKind::ParameterDeviation => "parameter-deviation",
            EffectKind::AbruptChange => "abrupt-change",
            EffectKind::MissingElement => "missing-element",
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

//! Stage 1 of discovery, **estimate**: where the model fails and by how much,
//! as a physical signal. A model that can ([`Model::missing_signals`]) gives,
//! for each place an unknown effort or flow could act (a 1-junction's common
//! flow, a 0-junction's common effort), the missing effort (or flow) that the
//! measurements call for there: a time series with a one-sigma band, beside
//! the signals acting at that place (its flow, the position that flow
//! integrates to, the displacements of springs bonded there, the inputs) as
//! the model and the measurements together estimate them. The screen
//! ([`super::screen`]) then regresses a typed library of laws on it.
//!
//! [`Model::missing_signals`]: crate::Model::missing_signals

use serde::Serialize;

/// What is missing at a place: an effort on a common-flow junction (a
/// torque, a force, a voltage drop) or a flow at a common-effort junction (a
/// leak, a heat flow, a current).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Quantity {
    /// An effort acting on a 1-junction: positive opposes its flow.
    Effort,
    /// A flow drawn from a 0-junction: positive lowers its effort.
    Flow,
}

impl Quantity {
    /// `effort` or `flow`.
    pub fn word(self) -> &'static str {
        match self {
            Quantity::Effort => "effort",
            Quantity::Flow => "flow",
        }
    }
}

/// What an acting signal is, physically: the screen picks the laws that make
/// sense of it (a sign of a velocity, harmonics of an angle, a square root of
/// a level).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SignalRole {
    /// The flow of the place (a speed, a velocity, a current).
    Flow,
    /// The integral of a rotational flow from the start: an angle (rad),
    /// whose harmonics a ripple follows.
    Angle,
    /// A translational position from the start (the place's velocity
    /// integrated): a ripple locked to it (a linear motor's magnets, a
    /// screw's or a rack's pitch) repeats every wavelength.
    Position,
    /// A displacement: the state of a spring or capacitor bonded at the
    /// place (or a position of a place of no known domain).
    Displacement,
    /// The effort of a storage node (a level, a pressure, a temperature).
    Effort,
    /// An input of the model, as recorded.
    Input,
    /// The flow of a place one transducer (a gyrator or transformer) away,
    /// read where the effort is missing: the winding's current at a motor's
    /// shaft. It scales a law there (a torque ripple in proportion to the
    /// current, `i·sin nθ`), so it enters the products only: alone it is the
    /// transducer's own modulus, which the menu offers.
    Coupled,
}

impl SignalRole {
    /// A flow, position, displacement or effort: a signal a law reads by its
    /// value (not an angle, read by its harmonics, nor an input).
    pub fn is_plain(self) -> bool {
        matches!(
            self,
            SignalRole::Flow | SignalRole::Position | SignalRole::Displacement | SignalRole::Effort
        )
    }
}

/// A signal acting where an effort or flow is missing, as estimated.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct ActingSignal {
    /// The name the model's laws read it by (`1m.f`, `theta_1m.q`, `V`).
    pub name: String,
    /// What it is, in words (`speed of the shaft (1m)`).
    pub label: String,
    /// Its unit (`rad/s`), possibly empty.
    pub unit: String,
    /// Its physical role.
    pub role: SignalRole,
    /// Its value at each sample.
    pub values: Vec<f64>,
}

/// The missing effort (or flow) at one place, estimated from the recording.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct MissingSignal {
    /// The element the place is (`1m`).
    pub location: String,
    /// The place in words (`the shaft (1m)`).
    pub place: String,
    /// Effort or flow.
    pub quantity: Quantity,
    /// The unit of the missing effort or flow (`N m`).
    pub unit: String,
    /// Sample times (s).
    pub t: Vec<f64>,
    /// The estimate at each sample.
    pub value: Vec<f64>,
    /// Its one-sigma band at each sample (how far the measurements pin it).
    pub band: Vec<f64>,
    /// The signals acting there, estimated with it.
    pub acting: Vec<ActingSignal>,
    /// The share of the outputs' squared residual (about the model's own
    /// prediction) that an effort here can remove, in [0, 1]: where the
    /// model fails, a place that cannot explain the outputs scores low.
    pub explained: f64,
}

/// What discovery found at one place, without the series: for the text, the
/// JSON and the report's table.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct PlaceFinding {
    /// The element the place is (`1m`).
    pub location: String,
    /// The place in words.
    pub place: String,
    /// Effort or flow.
    pub quantity: Quantity,
    /// The unit of the missing effort or flow.
    pub unit: String,
    /// The share of the outputs' squared residual an effort here can remove.
    pub explained: f64,
    /// The RMS of the estimated missing effort.
    pub rms: f64,
    /// Its typical one-sigma band.
    pub band: f64,
    /// The law the screen found for it, if any term earned its place.
    pub law: Option<super::screen::Law>,
}

impl MissingSignal {
    /// The RMS of the estimate.
    pub fn rms(&self) -> f64 {
        crate::residual::rms(&self.value)
    }

    /// The median of the band: how well the estimate is pinned.
    pub fn typical_band(&self) -> f64 {
        let mut b: Vec<f64> = self
            .band
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .collect();
        if b.is_empty() {
            return f64::INFINITY;
        }
        b.sort_by(f64::total_cmp);
        b[b.len() / 2]
    }

    /// An acting signal by role (the first).
    pub fn acting(&self, role: SignalRole) -> Option<&ActingSignal> {
        self.acting.iter().find(|a| a.role == role)
    }
}

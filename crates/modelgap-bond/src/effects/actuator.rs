//! An actuator that follows its command late, in any domain: what a source
//! driven by an input imposes is not the command `v` the recording holds but
//!
//! - `actuator-lag@<source>`: `v` through a first-order lag `τ u̇ = v − u` (a
//!   motor driver's current loop, a valve's stroke, a heater's element warming
//!   up, a pump spinning up), or
//! - `actuator-delay@<source>`: `v` a time `d` ago, any fraction of a sample
//!   (a fieldbus cycle, a transport line, a controller's computation), the
//!   first-order Padé all-pass `2 / (1 + s d/2) − 1` as for a sensor's delay.
//!
//! Built from the signal elements of a sensor's [`lag`](super::SensorLag) (a
//! modulated flow source reading the command, a 0-junction, a C of capacity
//! `τ` and an R with `f = e`) behind the source, whose value then reads the
//! 0-junction's effort. One new state, starting at 0 (an actuator at rest) or
//! at the steady state with `--steady-start`. For a linear model with one
//! input and one output a lag (or delay) in front of the plant predicts what
//! one behind it does, and the ranking says they are the same explanation;
//! through a nonlinear plant, or with several outputs, they differ.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::deadzone::{DeadZone, source_value};
use super::def::EffectDef;
use super::edit::{added, ident, new_param};
use super::lag::{Stage, lag_stage_at};
use super::menu::element_place;
use super::scales::Scales;
use super::tag::Tag;
use crate::element::Law;
use crate::error::Result;
use crate::expr::Expr;
use crate::graph::{BondGraph, ElementId};
use crate::simulate::ParamChange;

/// Start values of an actuator's lag or delay, spaced evenly in the logarithm across its
/// bounds: the screen's linearised step from one sample's lag undersized a heater's 40 s
/// lag (1 s samples) to 26 s, and a sensor's lag, fitted exactly, took its place.
const LAG_GRID: usize = 6;

/// A first-order lag between a driven source's command and what it imposes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ActuatorLag {
    /// The source (Se or Sf) whose value an input drives.
    pub source: ElementId,
}

/// A pure delay between a driven source's command and what it imposes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ActuatorDelay {
    /// The source (Se or Sf) whose value an input drives.
    pub source: ElementId,
}

impl ActuatorLag {
    /// The lag on element `id` of `g`, if it is a source an input drives.
    pub fn at(g: &BondGraph, id: ElementId) -> Option<ActuatorLag> {
        DeadZone::at(g, id).map(|_| ActuatorLag { source: id })
    }
}

impl ActuatorDelay {
    /// The delay on element `id` of `g`, if it is a source an input drives.
    pub fn at(g: &BondGraph, id: ElementId) -> Option<ActuatorDelay> {
        DeadZone::at(g, id).map(|_| ActuatorDelay { source: id })
    }
}

/// The sample interval and length the time constants are bounded by (those of
/// the model's own start-up without a recording).
fn interval_and_length(scales: &Scales) -> (f64, f64) {
    let dt = scales.sample_time.filter(|d| *d > 0.0).unwrap_or(1e-3);
    let length = scales.duration.filter(|d| *d > dt).unwrap_or(1000.0 * dt);
    (dt, length)
}

impl EffectDef for ActuatorLag {
    fn offers(g: &BondGraph) -> Vec<ActuatorLag> {
        g.element_ids()
            .filter_map(|id| ActuatorLag::at(g, id))
            .collect()
    }

    /// `τ` from a tenth of the sample interval to a fifth of the recording,
    /// starting at one sample interval (scale the same), as a sensor's lag.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let el = g.element(self.source);
        let (dt, length) = interval_and_length(scales);
        Candidate {
            id: Tag::ActuatorLag.id(&el.name),
            name: format!(
                "{} follows its command with a lag (first order)",
                element_place(g, self.source)
            ),
            kind: EffectKind::MissingElement,
            acts_on: el.name.clone(),
            params: vec![
                EffectParam::new("tau", "s", dt, (0.1 * dt, (0.2 * length).max(dt)), dt)
                    .with_log_grid(LAG_GRID),
            ],
        }
    }

    /// The source's value becomes the lag stage's output, the stage following `v`.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (name, v) = source_value(g, self.source, c, "to follow late")?;
        let tau = new_param(
            g,
            &format!("tau_act_{}", ident(&name)),
            values[0],
            "s",
            &format!("time constant of the actuator of {name} {}", added(c)),
        )?;
        let node = lag_stage_at(g, c, Stage::Actuator, &name, v, Expr::Param(tau))?;
        g.element_mut(self.source).law = Law::Source(Expr::signal(&node, "e"));
        Ok(Vec::new())
    }
}

impl EffectDef for ActuatorDelay {
    fn offers(g: &BondGraph) -> Vec<ActuatorDelay> {
        g.element_ids()
            .filter_map(|id| ActuatorDelay::at(g, id))
            .collect()
    }

    /// `d` from a tenth of the sample interval to fifty intervals, starting at
    /// one interval, as a sensor's delay.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let el = g.element(self.source);
        let (dt, _) = interval_and_length(scales);
        Candidate {
            id: Tag::ActuatorDelay.id(&el.name),
            name: format!(
                "{} acts late: it follows its command a delay behind",
                element_place(g, self.source)
            ),
            kind: EffectKind::MissingElement,
            acts_on: el.name.clone(),
            params: vec![
                EffectParam::new("delay", "s", dt, (0.1 * dt, 50.0 * dt), dt)
                    .with_log_grid(LAG_GRID),
            ],
        }
    }

    /// The source's value becomes `2 u − v`, `u` a lag of `d/2` following `v`.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (name, v) = source_value(g, self.source, c, "to follow late")?;
        let d = new_param(
            g,
            &format!("delay_act_{}", ident(&name)),
            values[0],
            "s",
            &format!("delay of the actuator of {name} {}", added(c)),
        )?;
        let half = Expr::Mul(vec![Expr::Num(0.5), Expr::Param(d)]);
        let node = lag_stage_at(g, c, Stage::Actuator, &name, v.clone(), half)?;
        let delivered = Expr::Add(vec![
            Expr::Mul(vec![Expr::Num(2.0), Expr::signal(&node, "e")]),
            Expr::Neg(Box::new(v)),
        ]);
        g.element_mut(self.source).law = Law::Source(delivered);
        Ok(Vec::new())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::library;
    use crate::simulate::{Inputs, SimOptions, simulate, time_grid};

    #[test]
    fn a_late_driver_turns_the_shaft_as_the_voltage_of_a_moment_ago_would() {
        let mut g = library::dc_motor();
        g.add_input("V", 12.0, "V", "armature voltage").unwrap();
        let source = g.find("V").unwrap();
        let d = ActuatorDelay::at(&g, source).unwrap();
        let c = d.candidate(&g, &Scales::of(&g));
        assert_eq!(c.id, "actuator-delay@V");
        let t = time_grid(0.2, 10_000.0);
        let plain = simulate(&g, &Inputs::new(), &t, &SimOptions::default()).unwrap();
        let (late, _) = d.apply(&g, &c, &[2e-3]).unwrap();
        let run = simulate(&late, &Inputs::new(), &t, &SimOptions::default()).unwrap();
        let (w, wd) = (plain.output("omega").unwrap(), run.output("omega").unwrap());
        // A step of the supply delayed by 2 ms (20 samples): the shaft follows 20 samples
        // behind once the Padé stage has settled.
        let peak = w.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let worst = (500..w.len())
            .map(|k| (wd[k] - w[k - 20]).abs())
            .fold(0.0_f64, f64::max);
        assert!(worst < 0.01 * peak, "{worst} of {peak}");
    }

    #[test]
    fn a_slow_driver_delivers_its_command_through_a_lag() {
        let mut g = library::dc_motor();
        g.add_input("V", 12.0, "V", "armature voltage").unwrap();
        let source = g.find("V").unwrap();
        let l = ActuatorLag::at(&g, source).unwrap();
        let c = l.candidate(&g, &Scales::of(&g));
        assert_eq!(c.id, "actuator-lag@V");
        let t = time_grid(0.5, 10_000.0);
        let plain = simulate(&g, &Inputs::new(), &t, &SimOptions::default()).unwrap();
        let (slow, _) = l.apply(&g, &c, &[0.02]).unwrap();
        let run = simulate(&slow, &Inputs::new(), &t, &SimOptions::default()).unwrap();
        let (w, ws) = (plain.output("omega").unwrap(), run.output("omega").unwrap());
        // The same end (the lag has no gain), reached later.
        let end = w.len() - 1;
        assert!(
            (ws[end] - w[end]).abs() < 1e-3 * w[end].abs(),
            "{} {}",
            ws[end],
            w[end]
        );
        let k = t.iter().position(|&t| t >= 0.02).unwrap();
        assert!(ws[k] < 0.7 * w[k], "{} {}", ws[k], w[k]);
        // Only a source an input drives has an actuator.
        let shaft = g.find("1m").unwrap();
        assert!(ActuatorLag::at(&g, shaft).is_none());
    }
}

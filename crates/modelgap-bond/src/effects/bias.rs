//! `actuator-offset@<source>`: an actuator that delivers its command plus a
//! constant, in any domain — a motor driver's zero that drifted, a valve that
//! leaks a little when shut, a heater's standing power, a pump's bias: the
//! value `v` a source driven by an input imposes becomes `v + b`. (A sensor's
//! offset, [`offset`](super::SensorOffset), is on what is measured; this one
//! passes through the plant. It is not offered where it would be the menu's
//! constant load on the mechanical junction an effort source is bonded to, or
//! its inflow into the node a flow source is bonded to: the same physics.)

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::deadzone::{DeadZone, source_value};
use super::def::{EffectDef, all_zero};
use super::edit::{added, ident, law, new_param};
use super::junction::Junction;
use super::load::Load;
use super::menu::element_place;
use super::node::Node;
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{ElementKind, Law};
use crate::error::Result;
use crate::graph::{BondGraph, ElementId};
use crate::simulate::ParamChange;

/// A constant `b` added to what a driven source imposes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ActuatorOffset {
    /// The source (Se or Sf) whose value an input drives.
    pub source: ElementId,
}

impl ActuatorOffset {
    /// The offset on element `id` of `g`, if it is a source an input drives and not
    /// bonded to a junction where a load or an inflow is on the menu.
    pub fn at(g: &BondGraph, id: ElementId) -> Option<ActuatorOffset> {
        DeadZone::at(g, id)?;
        let said_otherwise = (g.ports(id).into_iter())
            .map(|(b, _)| g.other_end(b, id))
            .any(|j| match g.element(id).kind {
                ElementKind::Se => Junction::of(g, j).and_then(Load::at).is_some(),
                _ => Node::of(g, j).is_some(),
            });
        (!said_otherwise).then_some(ActuatorOffset { source: id })
    }
}

impl EffectDef for ActuatorOffset {
    fn offers(g: &BondGraph) -> Vec<ActuatorOffset> {
        g.element_ids()
            .filter_map(|id| ActuatorOffset::at(g, id))
            .collect()
    }

    /// `b` within ± the largest value the source imposed over the run the scales
    /// come from (a recording's inputs, never an input's default when a recording
    /// is given), starting at 0, scale a tenth of that.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let el = g.element(self.source);
        let driven = DeadZone {
            source: self.source,
        };
        let peak = driven.peak(g, scales);
        Candidate {
            id: Tag::ActuatorOffset.id(&el.name),
            name: format!(
                "{} delivers its command plus a constant (an actuator's offset)",
                element_place(g, self.source)
            ),
            kind: EffectKind::MissingElement,
            acts_on: el.name.clone(),
            params: vec![EffectParam::new(
                "b",
                driven.unit(g),
                0.0,
                (-peak, peak),
                0.1 * peak,
            )],
        }
    }

    /// The source's law `v` becomes `(v) + b`.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (target, v) = source_value(g, self.source, c, "to offset")?;
        let unit = DeadZone {
            source: self.source,
        }
        .unit(g);
        let b = new_param(
            g,
            &format!("b_act_{}", ident(&target)),
            values[0],
            &unit,
            &format!("offset of the actuator of {target} {}", added(c)),
        )?;
        let value = law(c, &format!("({v}) + {b}"))?;
        g.element_mut(self.source).law = Law::Source(value);
        Ok(Vec::new())
    }

    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        all_zero(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::library;
    use crate::simulate::{Inputs, SimOptions, simulate, time_grid};

    /// The motor with its supply an input defaulting to `volts`.
    fn motor(volts: f64) -> BondGraph {
        let mut g = library::dc_motor();
        g.add_input("V", volts, "V", "armature voltage").unwrap();
        g
    }

    #[test]
    fn a_driver_half_a_volt_high_turns_the_motor_as_half_a_volt_more_would() {
        let g = motor(12.0);
        let source = g.find("V").unwrap();
        let k = ActuatorOffset::at(&g, source).unwrap();
        let c = k.candidate(&g, &Scales::of(&g));
        assert_eq!(c.id, "actuator-offset@V");
        assert_eq!(c.params[0].unit, "V");
        assert_eq!(ActuatorOffset::vanishing_values(&c), Some(vec![0.0]));
        let t = time_grid(0.2, 10_000.0);
        let (high, _) = k.apply(&g, &c, &[0.5]).unwrap();
        let run = simulate(&high, &Inputs::new(), &t, &SimOptions::default()).unwrap();
        let more = simulate(&motor(12.5), &Inputs::new(), &t, &SimOptions::default()).unwrap();
        let (w, wm) = (run.output("omega").unwrap(), more.output("omega").unwrap());
        let peak = wm.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let worst = (w.iter().zip(wm)).fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(worst < 1e-6 * peak, "{worst} of {peak}");
    }

    #[test]
    fn a_driven_load_torque_is_left_to_the_constant_load() {
        let mut g = motor(12.0);
        g.add_input("tau_L", 0.0, "N m", "load torque").unwrap();
        let load = g.find("tau_L").unwrap();
        assert!(DeadZone::at(&g, load).is_some());
        assert_eq!(ActuatorOffset::at(&g, load), None);
        assert!(ActuatorOffset::at(&g, g.find("V").unwrap()).is_some());
    }
}

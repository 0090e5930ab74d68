//! `limit@<source>`: an actuator that saturates, in any domain — a motor
//! driver at its supply rail, a valve fully open, a pump at its largest
//! flow, a heater at full power: the value `v` a source driven by an input
//! imposes becomes `sign(v) · min(|v|, v_max)`.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::DeadZone;
use super::deadzone::source_value;
use super::def::EffectDef;
use super::edit::{ident, law, new_param};
use super::menu::element_place;
use super::scales::Scales;
use super::tag::Tag;
use crate::element::Law;
use crate::error::Result;
use crate::graph::{BondGraph, ElementId};
use crate::simulate::ParamChange;

/// Grid starts of the limit: a limit above everything the source imposed
/// changes nothing, so a local fit cannot find one from there.
const LIMIT_GRID: usize = 8;

/// A symmetric limit `±v_max` on what a source imposes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ActuatorLimit {
    /// The source (Se or Sf) whose value an input drives.
    pub source: ElementId,
}

impl ActuatorLimit {
    /// The limit on element `id` of `g`, if it is a source whose value names
    /// an input (an actuator the recording drives).
    pub fn at(g: &BondGraph, id: ElementId) -> Option<ActuatorLimit> {
        DeadZone::at(g, id).map(|_| ActuatorLimit { source: id })
    }
}

impl EffectDef for ActuatorLimit {
    fn offers(g: &BondGraph) -> Vec<ActuatorLimit> {
        g.element_ids()
            .filter_map(|id| ActuatorLimit::at(g, id))
            .collect()
    }

    /// `v_max` from a twentieth of the largest value the source imposed over
    /// the run the scales come from (a recording's inputs, never an input's
    /// default when a recording is given) to that largest value, where it
    /// does nothing; eight grid starts across.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let el = g.element(self.source);
        let peak = DeadZone {
            source: self.source,
        }
        .peak(g, scales);
        Candidate {
            id: Tag::Limit.id(&el.name),
            name: format!(
                "{} saturates: it delivers no more than a limit",
                element_place(g, self.source)
            ),
            kind: EffectKind::MissingElement,
            acts_on: el.name.clone(),
            params: vec![
                EffectParam::new(
                    "v_max",
                    DeadZone {
                        source: self.source,
                    }
                    .unit(g),
                    peak,
                    (0.05 * peak, peak),
                    0.1 * peak,
                )
                .with_grid(LIMIT_GRID),
            ],
        }
    }

    /// The source's law `v` becomes `sign(v) * min(abs(v), v_max)`.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (target, v) = source_value(g, self.source, c, "to limit")?;
        let unit = DeadZone {
            source: self.source,
        }
        .unit(g);
        let limit = new_param(
            g,
            &format!("v_max_{}", ident(&target)),
            values[0],
            &unit,
            &format!(
                "saturation: the source delivers no more than v_max either way (added effect {})",
                c.id
            ),
        )?;
        let value = law(c, &format!("sign({v}) * min(abs({v}), {limit})"))?;
        g.element_mut(self.source).law = Law::Source(value);
        Ok(Vec::new())
    }

    /// At its upper bound, the largest value the source imposed: no limit.
    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        Some(c.params.iter().map(|p| p.upper).collect())
    }
}

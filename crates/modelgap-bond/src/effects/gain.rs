//! `gain@<source>`: an actuator whose gain is not one — a motor driver that
//! delivers 90 % of its command, a pump below its rating, a heater whose
//! element has aged: the value `v` a source driven by an input imposes becomes
//! `k · v`. In any domain. (A parameter's deviation cannot say this when the
//! input is a recorded signal, not a parameter.)

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::deadzone::{DeadZone, source_value};
use super::def::EffectDef;
use super::edit::{ident, law, new_param};
use super::menu::element_place;
use super::scales::Scales;
use super::tag::Tag;
use crate::element::Law;
use crate::error::Result;
use crate::graph::{BondGraph, ElementId};
use crate::simulate::ParamChange;

/// A gain `k` on what a driven source imposes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ActuatorGain {
    /// The source (Se or Sf) whose value an input drives.
    pub source: ElementId,
}

impl ActuatorGain {
    /// The gain on element `id` of `g`, if it is a source an input drives.
    pub fn at(g: &BondGraph, id: ElementId) -> Option<ActuatorGain> {
        DeadZone::at(g, id).map(|_| ActuatorGain { source: id })
    }
}

impl EffectDef for ActuatorGain {
    fn offers(g: &BondGraph) -> Vec<ActuatorGain> {
        g.element_ids()
            .filter_map(|id| ActuatorGain::at(g, id))
            .collect()
    }

    /// `k` from 0.2 to 2, starting at 1 (scale 0.1).
    fn candidate(&self, g: &BondGraph, _scales: &Scales) -> Candidate {
        let el = g.element(self.source);
        Candidate {
            id: Tag::Gain.id(&el.name),
            name: format!(
                "the gain of {} is not one (the actuator delivers k times its command)",
                element_place(g, self.source)
            ),
            kind: EffectKind::MissingElement,
            acts_on: el.name.clone(),
            params: vec![EffectParam::new("k", "1", 1.0, (0.2, 2.0), 0.1)],
        }
    }

    /// The source's law `v` becomes `k * (v)`.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (target, v) = source_value(g, self.source, c, "to scale")?;
        let k = new_param(
            g,
            &format!("k_{}", ident(&target)),
            values[0],
            "1",
            &format!(
                "actuator gain: the source delivers k times its command (added effect {})",
                c.id
            ),
        )?;
        let value = law(c, &format!("{k} * ({v})"))?;
        g.element_mut(self.source).law = Law::Source(value);
        Ok(Vec::new())
    }

    fn vanishing_values(_c: &Candidate) -> Option<Vec<f64>> {
        Some(vec![1.0])
    }
}

//! `load@<j>`: a constant load on a shaft or a moving body.

use modelgap_core::{Candidate, EffectParam};

use super::Junction;
use super::def::{EffectDef, QualTarget, all_zero};
use super::edit::{added, attach, new_param};
use super::junction::non_empty;
use super::scales::Scales;
use super::tag::Tag;
use crate::element::Element;
use crate::error::Result;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// A constant load torque (force) on a mechanical junction: an Se whose
/// bond points into it, so a positive `tau_0` (`F_0`) opposes forward motion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Load {
    /// The shaft or body.
    pub junction: Junction,
}

impl Load {
    /// A load on `junction`, if it is mechanical.
    pub fn at(junction: Junction) -> Option<Load> {
        junction.domain.is_mechanical().then_some(Load { junction })
    }
}

impl EffectDef for Load {
    fn offers(g: &BondGraph) -> Vec<Load> {
        Junction::all(g).into_iter().filter_map(Load::at).collect()
    }

    /// Either sign, up to the junction's peak effort.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let j = self.junction;
        let (stem, _, _) = j.domain.stems();
        let peak = j.effort_peak(scales);
        j.candidate(
            g,
            Tag::Load,
            format!("constant load {} on {}", j.domain.effort_word(), j.place(g)),
            vec![EffectParam::new(
                format!("{stem}_0"),
                j.domain.effort_unit(),
                0.0,
                (-peak, peak),
                j.effort_scale(scales),
            )],
        )
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (j, suffix) = (self.junction, self.junction.suffix(g));
        let (stem, _, _) = j.domain.stems();
        let word = j.domain.effort_word();
        let load = new_param(
            g,
            &format!("{stem}_0_{suffix}"),
            values[0],
            j.domain.effort_unit(),
            &format!(
                "constant load {word} (positive opposes forward motion) {}",
                added(c)
            ),
        )?;
        attach(
            g,
            j.id,
            Element::se(&format!("load_{suffix}"), &load).described(&format!(
                "constant load {word}; its bond points into it, so a positive load opposes motion"
            )),
        )?;
        Ok(Vec::new())
    }

    /// The junction's load inputs (opposing motion) or R increasing.
    fn qualitative_signature(&self, g: &BondGraph) -> Option<Vec<QualTarget>> {
        let mut v = self.junction.loads(g);
        v.extend(self.junction.resistances_up(g));
        non_empty(v)
    }

    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        all_zero(c)
    }
}

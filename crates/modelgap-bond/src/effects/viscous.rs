//! `viscous@<j>`: viscous friction on a shaft or a moving body.

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

/// Viscous friction on a mechanical junction: an R of coefficient `b` ≥ 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Viscous {
    /// The shaft or body.
    pub junction: Junction,
}

impl Viscous {
    /// Viscous friction on `junction`, if it is mechanical.
    pub fn at(junction: Junction) -> Option<Viscous> {
        junction
            .domain
            .is_mechanical()
            .then_some(Viscous { junction })
    }
}

impl EffectDef for Viscous {
    fn offers(g: &BondGraph) -> Vec<Viscous> {
        Junction::all(g)
            .into_iter()
            .filter_map(Viscous::at)
            .collect()
    }

    /// `b` from 0 up to the peak effort at the typical flow (at least ten
    /// times its scale, the typical effort over the typical flow); a
    /// negative correction of an existing friction is the deviation's job.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let j = self.junction;
        let f_scale = j.flow_scale(scales);
        let b_scale = j.effort_scale(scales) / f_scale;
        let b_upper = (j.effort_peak(scales) / f_scale).max(10.0 * b_scale);
        j.candidate(
            g,
            Tag::Viscous,
            format!("viscous friction on {}", j.place(g)),
            vec![EffectParam::new(
                "b",
                j.domain.damping_unit(),
                0.0,
                (0.0, b_upper),
                b_scale,
            )],
        )
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (j, suffix) = (self.junction, self.junction.suffix(g));
        let b = new_param(
            g,
            &format!("b_{suffix}"),
            values[0],
            j.domain.damping_unit(),
            &format!("viscous friction coefficient {}", added(c)),
        )?;
        attach(
            g,
            j.id,
            Element::r(&format!("viscous_{suffix}"), &b).described("viscous friction"),
        )?;
        Ok(Vec::new())
    }

    /// The junction's R increasing.
    fn qualitative_signature(&self, g: &BondGraph) -> Option<Vec<QualTarget>> {
        non_empty(self.junction.resistances_up(g))
    }

    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        all_zero(c)
    }
}

//! `inertia@<j>`: extra inertia (mass) on a shaft or a moving body.

use modelgap_core::{Candidate, EffectParam};

use super::Junction;
use super::def::{EffectDef, QualTarget, all_zero};
use super::edit::{added, bad, law, new_param};
use super::junction::non_empty;
use super::scales::Scales;
use super::tag::Tag;
use crate::element::Law;
use crate::error::Result;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// Extra inertia on a mechanical junction: `dJ` (`dm`) added to the law of
/// the junction's I.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Inertia {
    /// The shaft or body.
    pub junction: Junction,
}

impl Inertia {
    /// Extra inertia on `junction`, if it is mechanical.
    pub fn at(junction: Junction) -> Option<Inertia> {
        junction
            .domain
            .is_mechanical()
            .then_some(Inertia { junction })
    }
}

impl EffectDef for Inertia {
    /// Mechanical junctions whose inertia has a positive nominal value.
    fn offers(g: &BondGraph) -> Vec<Inertia> {
        Junction::all(g)
            .into_iter()
            .filter(|j| j.inertia_value(g).is_some())
            .filter_map(Inertia::at)
            .collect()
    }

    /// `dJ` from −0.9 J to 100 J, scale J.
    fn candidate(&self, g: &BondGraph, _scales: &Scales) -> Candidate {
        let j = self.junction;
        let m = j.inertia_value(g).unwrap_or(1.0);
        let (_, d_stem, _) = j.domain.stems();
        j.candidate(
            g,
            Tag::Inertia,
            format!("extra {} on {}", j.domain.inertia_word(), j.place(g)),
            vec![EffectParam::new(
                d_stem,
                j.domain.inertia_unit(),
                0.0,
                (-0.9 * m, 100.0 * m),
                m,
            )],
        )
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (j, suffix) = (self.junction, self.junction.suffix(g));
        let Law::Linear(old) = g.element(j.inertia).law.clone() else {
            return Err(bad(c, "", "the junction's I has no linear law".to_string()));
        };
        let (_, d_stem, _) = j.domain.stems();
        let extra = new_param(
            g,
            &format!("{d_stem}_{suffix}"),
            values[0],
            j.domain.inertia_unit(),
            &format!("extra {} {}", j.domain.inertia_word(), added(c)),
        )?;
        let new_law = law(c, &format!("({old}) + {extra}"))?;
        g.element_mut(j.inertia).law = Law::Linear(new_law);
        Ok(Vec::new())
    }

    /// The junction's inertia, either sign.
    fn qualitative_signature(&self, g: &BondGraph) -> Option<Vec<QualTarget>> {
        non_empty(self.junction.inertias(g))
    }

    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        all_zero(c)
    }
}

//! `brush@<j>`: a brush/contact voltage drop in an electrical loop.

use modelgap_core::{Candidate, EffectParam};

use super::def::{EffectDef, QualTarget, all_zero};
use super::edit::{added, smoothed_sign};
use super::junction::non_empty;
use super::scales::Scales;
use super::tag::Tag;
use super::{Domain, Junction};
use crate::error::Result;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// A brush/contact voltage drop on an electrical junction: an R of effort
/// `v_b · tanh(i / i_s)`, `v_b` ≥ 0, with the fixed smoothing
/// [`CONTACT_SMOOTHING_A`](super::CONTACT_SMOOTHING_A).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Brush {
    /// The electrical loop.
    pub junction: Junction,
}

impl Brush {
    /// A brush drop on `junction`, if it is electrical.
    pub fn at(junction: Junction) -> Option<Brush> {
        (junction.domain == Domain::Electrical).then_some(Brush { junction })
    }
}

impl EffectDef for Brush {
    fn offers(g: &BondGraph) -> Vec<Brush> {
        Junction::all(g).into_iter().filter_map(Brush::at).collect()
    }

    /// The drop from 0 up to the loop's peak voltage.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let j = self.junction;
        j.candidate(
            g,
            Tag::Brush,
            format!("brush/contact voltage drop in {}", j.place(g)),
            vec![EffectParam::new(
                "v_b",
                "V",
                0.0,
                (0.0, j.effort_peak(scales)),
                j.effort_scale(scales),
            )],
        )
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (j, suffix) = (self.junction, self.junction.suffix(g));
        smoothed_sign(
            g,
            c,
            j.id,
            j.domain,
            [
                &format!("v_b_{suffix}"),
                &format!("i_s_{suffix}"),
                &format!("brush_{suffix}"),
            ],
            values[0],
            [
                &format!("brush/contact voltage drop {}", added(c)),
                "current below which the contact drop fades (fixed smoothing)",
                "brush/contact voltage drop: level times a smoothed sign of the current",
            ],
        )?;
        Ok(Vec::new())
    }

    /// The loop's R increasing.
    fn qualitative_signature(&self, g: &BondGraph) -> Option<Vec<QualTarget>> {
        non_empty(self.junction.resistances_up(g))
    }

    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        all_zero(c)
    }
}

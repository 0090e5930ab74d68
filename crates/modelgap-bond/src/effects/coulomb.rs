//! `coulomb@<j>`: (smoothed) Coulomb friction on a shaft or a moving body.

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

/// Coulomb friction on a mechanical junction: an R of effort
/// `tau_c · tanh(ω / ω_s)` (`F_c`, `v_s` on a body), `tau_c` ≥ 0, with the
/// fixed smoothing [`COULOMB_SMOOTHING_RAD_S`](super::COULOMB_SMOOTHING_RAD_S)
/// ([`COULOMB_SMOOTHING_M_S`](super::COULOMB_SMOOTHING_M_S)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Coulomb {
    /// The shaft or body.
    pub junction: Junction,
}

impl Coulomb {
    /// Coulomb friction on `junction`, if it is mechanical.
    pub fn at(junction: Junction) -> Option<Coulomb> {
        junction
            .domain
            .is_mechanical()
            .then_some(Coulomb { junction })
    }
}

impl EffectDef for Coulomb {
    fn offers(g: &BondGraph) -> Vec<Coulomb> {
        Junction::all(g)
            .into_iter()
            .filter_map(Coulomb::at)
            .collect()
    }

    /// The level from 0 up to the junction's peak effort.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let j = self.junction;
        let (stem, _, _) = j.domain.stems();
        j.candidate(
            g,
            Tag::Coulomb,
            format!("Coulomb friction on {}", j.place(g)),
            vec![EffectParam::new(
                format!("{stem}_c"),
                j.domain.effort_unit(),
                0.0,
                (0.0, j.effort_peak(scales)),
                j.effort_scale(scales),
            )],
        )
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (j, suffix) = (self.junction, self.junction.suffix(g));
        let (stem, _, _) = j.domain.stems();
        let smooth = if j.domain == Domain::Rotational {
            "omega_s"
        } else {
            "v_s"
        };
        smoothed_sign(
            g,
            c,
            j.id,
            j.domain,
            [
                &format!("{stem}_c_{suffix}"),
                &format!("{smooth}_{suffix}"),
                &format!("coulomb_{suffix}"),
            ],
            values[0],
            [
                &format!("Coulomb friction level {}", added(c)),
                "speed below which Coulomb friction fades (fixed smoothing)",
                "Coulomb friction: level times a smoothed sign of the speed",
            ],
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

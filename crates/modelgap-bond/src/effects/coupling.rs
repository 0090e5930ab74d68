//! `coupling@<j>`: a flexible coupling of a shaft (body) to a second inertia.

use modelgap_core::{Candidate, EffectParam};

use super::Junction;
use super::def::EffectDef;
use super::edit::{added, attach, law, new_param};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{Element, Law};
use crate::error::Result;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// Damping ratio of the initial flexible coupling.
const COUPLING_DAMPING_RATIO: f64 = 0.1;

/// The coupling's initial resonance, as a multiple of the slowest mode's rate.
const COUPLING_FREQUENCY_FACTOR: f64 = 10.0;

/// A second inertia `J2` (`m2`) behind a spring `k_s` and a damper `c` on a
/// mechanical junction: `j → 0 → {1_twist: C (1/k_s), R (c)} and {1_load:
/// I (J2)}`; adds two states. It has no vanishing values (`J2 → 0` is singular).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Coupling {
    /// The shaft or body.
    pub junction: Junction,
}

impl Coupling {
    /// A coupling on `junction`, if it is mechanical.
    pub fn at(junction: Junction) -> Option<Coupling> {
        junction
            .domain
            .is_mechanical()
            .then_some(Coupling { junction })
    }
}

impl EffectDef for Coupling {
    /// Mechanical junctions whose inertia has a positive nominal value.
    fn offers(g: &BondGraph) -> Vec<Coupling> {
        Junction::all(g)
            .into_iter()
            .filter(|j| j.inertia_value(g).is_some())
            .filter_map(Coupling::at)
            .collect()
    }

    /// Starts at `J2 = J`, a resonance `sqrt(k (1/J + 1/J2))` ten times the
    /// slowest mode's rate and damping ratio 0.1 on the reduced inertia;
    /// `k_s`, `J2` and `c` span a factor of 100 around their start (`c` down to 0).
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let j = self.junction;
        let d = j.domain;
        let m = j.inertia_value(g).unwrap_or(1.0);
        let (_, _, two_stem) = d.stems();
        let rate = scales.slowest_rate.unwrap_or(1.0);
        let w = COUPLING_FREQUENCY_FACTOR * rate;
        let reduced = m * m / (m + m);
        let k0 = w * w * reduced;
        let c0 = 2.0 * COUPLING_DAMPING_RATIO * (k0 * reduced).sqrt();
        j.candidate(
            g,
            Tag::Coupling,
            format!(
                "flexible coupling of {} to a second {}",
                j.place(g),
                d.inertia_word()
            ),
            vec![
                EffectParam::new("k_s", d.stiffness_unit(), k0, (k0 / 100.0, k0 * 100.0), k0),
                EffectParam::new("c", d.damping_unit(), c0, (0.0, c0 * 100.0), c0),
                EffectParam::new(two_stem, d.inertia_unit(), m, (m / 100.0, m * 100.0), m),
            ],
        )
    }

    /// The 0-junction carries the coupling torque, the twist junction the
    /// relative speed.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (j, suffix) = (self.junction, self.junction.suffix(g));
        let domain = j.domain;
        let (_, _, two_stem) = domain.stems();
        let tag = added(c);
        let k = new_param(
            g,
            &format!("k_s_{suffix}"),
            values[0],
            domain.stiffness_unit(),
            &format!("coupling stiffness {tag}"),
        )?;
        let damping = new_param(
            g,
            &format!("c_{suffix}"),
            values[1],
            domain.damping_unit(),
            &format!("coupling damping {tag}"),
        )?;
        let inertia = new_param(
            g,
            &format!("{two_stem}_{suffix}"),
            values[2],
            domain.inertia_unit(),
            &format!("second {} behind the coupling {tag}", domain.inertia_word()),
        )?;
        let zero = attach(
            g,
            j.id,
            Element::zero(&format!("coupling_{suffix}"))
                .described(&format!("coupling: common {}", domain.effort_word())),
        )?;
        let twist = attach(
            g,
            zero,
            Element::one(&format!("twist_{suffix}")).described("coupling twist: relative speed"),
        )?;
        let compliance = law(c, &format!("1 / {k}"))?;
        let mut spring = Element::c(&format!("spring_{suffix}"), &k).described("coupling spring");
        spring.law = Law::Linear(compliance);
        attach(g, twist, spring)?;
        attach(
            g,
            twist,
            Element::r(&format!("damper_{suffix}"), &damping).described("coupling damper"),
        )?;
        let far = attach(
            g,
            zero,
            Element::one(&format!("far_{suffix}"))
                .described("far side of the coupling: its own speed"),
        )?;
        attach(
            g,
            far,
            Element::i(&format!("{two_stem}_{suffix}"), &inertia).described(&format!(
                "second {} behind the coupling",
                domain.inertia_word()
            )),
        )?;
        Ok(Vec::new())
    }
}

//! `backlash@<j>`: play in a gear or a coupling — part of a shaft's (body's)
//! inertia sits behind a gap, and is driven only once the gap has closed.
//!
//! The junction's inertia `J` is the whole drive as the model without play
//! sees it; the candidate moves a share `J2` of it behind a gap of half-width
//! `b`: `j → 0 → {1_gap: C (contact), R (contact damping)} and {1_load: I
//! (J2)}`, the shaft keeping `J − J2`. The contact is a spring that pushes
//! only beyond the gap, `e = k_c · sign(q) · max(|q| − b, 0)`, damped while in
//! contact at a fixed ratio, `c = 2 · 0.3 · √(k_c J_r)` with `J_r` the reduced
//! inertia, `· [|q| > b]`. Its hidden state is the twist `q` across the gap
//! (where in the gap the load is) and the load's momentum: two states.

use modelgap_core::{Candidate, EffectParam};

use super::Junction;
use super::def::EffectDef;
use super::edit::{added, attach, bad, law, new_param};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{Element, ElementKind, Law};
use crate::error::Result;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// The contact's damping ratio on the reduced inertia.
const CONTACT_DAMPING_RATIO: f64 = 0.3;

/// The contact's initial resonance, as a multiple of the slowest mode's rate,
/// when the scales know no sampling rate.
const CONTACT_FREQUENCY_FACTOR: f64 = 30.0;

/// A share `J2` of a junction's inertia behind a gap of half-width `b`.
/// It has no vanishing values (`J2 → 0` is singular).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Backlash {
    /// The shaft or body.
    pub junction: Junction,
}

impl Backlash {
    /// Backlash on `junction`, if it is mechanical.
    pub fn at(junction: Junction) -> Option<Backlash> {
        junction
            .domain
            .is_mechanical()
            .then_some(Backlash { junction })
    }
}

impl EffectDef for Backlash {
    /// Mechanical junctions whose inertia has a positive nominal value and a
    /// linear law.
    fn offers(g: &BondGraph) -> Vec<Backlash> {
        Junction::all(g)
            .into_iter()
            .filter(|j| j.inertia_value(g).is_some())
            .filter_map(Backlash::at)
            .collect()
    }

    /// `b` from 0 to the travel of a fiftieth of the slowest time constant at
    /// the junction's peak speed over the run (a few degrees on a motor's
    /// shaft), five grid starts; `J2` from a
    /// twentieth of `J` to 0.95 `J`, three grid starts; `k_c` a factor of 100
    /// either side of a contact resonance at a quarter of the sampling rate.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let j = self.junction;
        let d = j.domain;
        let m = j.inertia_value(g).unwrap_or(1.0);
        let rate = scales.slowest_rate.unwrap_or(1.0);
        // A contact is stiff: its resonance starts at a quarter of the sampling rate (what
        // lies beyond cannot be told apart in the record), or thirty times the slowest
        // mode's rate without a record.
        let w = scales
            .sample_time
            .map_or(CONTACT_FREQUENCY_FACTOR * rate, |dt| {
                0.25 * std::f64::consts::TAU / dt
            });
        let reduced = 0.25 * m;
        let k0 = w * w * reduced;
        let speed = j.flow_scale(scales);
        let speed = scales.flow(j.id).peak_or(speed);
        let b_max = (0.02 * speed / rate).max(f64::MIN_POSITIVE);
        let travel = if d.stiffness_unit().contains("rad") {
            "rad"
        } else {
            "m"
        };
        let (_, _, two_stem) = d.stems();
        j.candidate(
            g,
            Tag::Backlash,
            format!(
                "backlash at {}: part of its {} behind a gap",
                j.place(g),
                d.inertia_word()
            ),
            vec![
                EffectParam::new("b", travel, 0.25 * b_max, (0.0, b_max), 0.1 * b_max).with_grid(5),
                EffectParam::new(two_stem, d.inertia_unit(), 0.5 * m, (0.05 * m, 0.95 * m), m)
                    .with_grid(3),
                EffectParam::new("k_c", d.stiffness_unit(), k0, (k0 / 100.0, k0 * 100.0), k0),
                EffectParam::new("p_c", "1", 1.0, (1.0, 2.0), 0.25),
            ],
        )
    }

    /// The shaft's inertia becomes `J − J2`; the gap's junction carries the
    /// relative speed, the load's its own.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (j, suffix) = (self.junction, self.junction.suffix(g));
        let domain = j.domain;
        let (_, _, two_stem) = domain.stems();
        let tag = added(c);
        let Law::Linear(whole) = g.element(j.inertia).law.clone() else {
            return Err(bad(
                c,
                "",
                format!(
                    "the inertia of '{}' has no linear law to take a share of",
                    j.name(g)
                ),
            ));
        };
        let gap = new_param(
            g,
            &format!("b_{suffix}"),
            values[0],
            if domain.stiffness_unit().contains("rad") {
                "rad"
            } else {
                "m"
            },
            &format!("backlash: half-width of the gap {tag}"),
        )?;
        let share = new_param(
            g,
            &format!("{two_stem}_{suffix}"),
            values[1],
            domain.inertia_unit(),
            &format!("backlash: {} behind the gap {tag}", domain.inertia_word()),
        )?;
        let k = new_param(
            g,
            &format!("k_c_{suffix}"),
            values[2],
            domain.stiffness_unit(),
            &format!("backlash: contact stiffness {tag}"),
        )?;
        let exponent = new_param(
            g,
            &format!("p_c_{suffix}"),
            values[3],
            "1",
            &format!("backlash: exponent of the contact law (1 linear, 1.5 Hertz) {tag}"),
        )?;
        let whole = whole.to_string();
        g.element_mut(j.inertia).law = Law::Linear(law(c, &format!("({whole}) - {share}"))?);
        let zero = attach(
            g,
            j.id,
            Element::zero(&format!("backlash_{suffix}"))
                .described(&format!("backlash: common {}", domain.effort_word())),
        )?;
        let across = attach(
            g,
            zero,
            Element::one(&format!("gap_{suffix}")).described("backlash: speed across the gap"),
        )?;
        let contact = g.element(across).name.clone();
        let spring_name = format!("contact_{suffix}");
        let spring = attach(
            g,
            across,
            Element::nonlinear(
                &spring_name,
                ElementKind::C,
                Some(law(
                    c,
                    &format!("{k} * sign(q) * max(abs(q) - {gap}, 0)^{exponent}"),
                )?),
                None,
            )
            .described("backlash: the contact, pushing only beyond the gap"),
        )?;
        let spring_name = g.element(spring).name.clone();
        let damping = format!(
            "2 * {CONTACT_DAMPING_RATIO} * sqrt({k} * {share} * (({whole}) - {share}) / ({whole}))"
        );
        attach(
            g,
            across,
            Element::nonlinear(
                &format!("contact_damper_{suffix}"),
                ElementKind::R,
                Some(law(
                    c,
                    &format!("{damping} * f * max(sign(abs({spring_name}.q) - {gap}), 0)"),
                )?),
                None,
            )
            .described(&format!("backlash: damping while in contact ({contact})")),
        )?;
        let far = attach(
            g,
            zero,
            Element::one(&format!("behind_{suffix}")).described("behind the gap: its own speed"),
        )?;
        attach(
            g,
            far,
            Element::i(&format!("{two_stem}_{suffix}"), &share)
                .described(&format!("{} behind the gap", domain.inertia_word())),
        )?;
        Ok(Vec::new())
    }
}

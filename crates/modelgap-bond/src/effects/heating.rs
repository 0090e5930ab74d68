//! `heating@<R>`: a resistance that rises with the heat it has dissipated
//! (Joule heating of an armature or a winding, no cooling within the record).

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::def::{EffectDef, all_zero};
use super::edit::{added, bad, ident, law, new_param};
use super::menu::{law_value, linear_element_words};
use super::scales::Scales;
use super::tag::Tag;
use super::{Domain, Junction};
use crate::element::{Element, ElementKind, Law};
use crate::error::Result;
use crate::expr::Expr;
use crate::graph::{BondGraph, ElementId};
use crate::qual::Qual;
use crate::simulate::ParamChange;

use super::def::QualTarget;

/// Joule heating of an R with a positive linear law on an electrical
/// 1-junction: its law becomes `e = R (1 + a_heat E) f`, with `E = ∫ e f dt`
/// the energy it has dissipated since the start (J, a new state) and
/// `a_heat` ≥ 0 the relative rise of the resistance per joule (1/J). Over a
/// record much shorter than the winding's thermal time constant the heat
/// stays in: the copper's temperature, and with it the resistance, follows
/// the integral of the loss.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Heating {
    /// The R element.
    pub element: ElementId,
    /// The electrical 1-junction it sits on.
    pub junction: ElementId,
}

impl Heating {
    /// Heating of the R element `id` of `g`: an R with a linear law bonded to
    /// an electrical 1-junction (one whose inertance is in H).
    pub fn at(g: &BondGraph, id: ElementId) -> Option<Heating> {
        let el = g.element(id);
        if el.kind != ElementKind::R {
            return None;
        }
        if !matches!(el.law, Law::Linear(_)) {
            return None;
        }
        let [(bond, _)] = g.ports(id)[..] else {
            return None;
        };
        let j = g.other_end(bond, id);
        Junction::of(g, j)
            .filter(|j| j.domain == Domain::Electrical)
            .map(|j| Heating {
                element: id,
                junction: j.id,
            })
    }

    /// The law's coefficient (`R`), its value.
    fn resistance(self, g: &BondGraph) -> Option<(Expr, f64)> {
        let Law::Linear(x) = &g.element(self.element).law else {
            return None;
        };
        Some((x.clone(), law_value(g, x)?))
    }
}

impl EffectDef for Heating {
    /// Every such R whose resistance is positive in the model as given (a
    /// calibration may later take it to 0, where heating does nothing).
    fn offers(g: &BondGraph) -> Vec<Heating> {
        g.element_ids()
            .filter_map(|id| Heating::at(g, id))
            .filter(|h| h.resistance(g).is_some_and(|(_, v)| v > 0.0))
            .collect()
    }

    /// `a_heat` from 0 to `4 / E`, scale `0.1 / E`, with `E = R I² T` the
    /// energy the R dissipates over the run (`I` the junction's typical
    /// current, `T` the run's length): at the upper bound the resistance
    /// has risen fivefold by the end.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let el = g.element(self.element);
        let r = self.resistance(g).map_or(1.0, |(_, v)| v);
        let current = scales.flow(self.junction).flow();
        let duration = scales.duration.filter(|d| *d > 0.0).unwrap_or(1.0);
        let mut energy = r * current * current * duration;
        if !(energy.is_finite() && energy > 0.0) {
            energy = 1.0;
        }
        let what = linear_element_words(g, self.element);
        Candidate {
            id: Tag::Heating.id(&el.name),
            name: format!("heating of {what}: it rises with the energy it dissipates"),
            kind: EffectKind::MissingElement,
            acts_on: el.name.clone(),
            params: vec![EffectParam::new(
                "a_heat",
                "1/J",
                0.0,
                (0.0, 4.0 / energy),
                0.1 / energy,
            )],
        }
    }

    /// Adds the dissipated energy as a storage (`heat_<R>`, zero effort) fed
    /// by a flow source equal to the R's power, and makes the R's law read it.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let target = g.element(self.element).name.clone();
        let Some((old, _)) = self.resistance(g) else {
            return Err(bad(
                c,
                "",
                format!("the R element '{target}' has no linear law to heat"),
            ));
        };
        let suffix = ident(&target);
        let a = new_param(
            g,
            &format!("a_heat_{suffix}"),
            values[0],
            "1/J",
            &format!(
                "heating: relative rise of the resistance per joule dissipated {}",
                added(c)
            ),
        )?;
        let junction = g.element(self.junction).name.clone();
        let store_name = format!("heat_{suffix}");
        if g.find(&store_name).is_some() {
            return Err(bad(
                c,
                "",
                format!("an element '{store_name}' already exists: '{target}' is heated once"),
            ));
        }
        let factor = format!("(1 + {a} * {store_name}.q)");
        let power = law(c, &format!("({old}) * {factor} * '{junction}'.f^2"))?;
        let store = g.add(
            Element::nonlinear(&store_name, ElementKind::C, Some(law(c, "0 * q")?), None)
                .described(&format!(
                    "energy dissipated in {target} since the start (J) {}",
                    added(c)
                )),
        )?;
        let mut source = Element::sf(&format!("heat_in_{suffix}"), "0");
        source.law = Law::Source(power);
        let source = g.add(source.described(&format!(
            "the power dissipated in {target}, filling its heat store {}",
            added(c)
        )))?;
        g.bond(source, store)?;
        g.element_mut(self.element).law = Law::Nonlinear {
            effort: Some(law(c, &format!("({old}) * {factor} * f"))?),
            flow: None,
        };
        Ok(Vec::new())
    }

    /// To the fault trees a heated resistance is a resistance that rose.
    fn qualitative_signature(&self, g: &BondGraph) -> Option<Vec<QualTarget>> {
        let (x, _) = self.resistance(g)?;
        let names: Vec<QualTarget> = (x.params().into_iter())
            .map(|n| (n, Some(Qual::Plus)))
            .collect();
        (!names.is_empty()).then_some(names)
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

    #[test]
    fn the_armature_resistance_is_offered_and_heats_as_it_dissipates() {
        let g = library::dc_motor();
        let offers = Heating::offers(&g);
        assert_eq!(offers.len(), 1, "{offers:?}");
        let h = offers[0];
        assert_eq!(g.element(h.element).name, "R");
        let c = h.candidate(&g, &Scales::of(&g));
        assert_eq!(c.id, "heating@R");
        let t = time_grid(1.0, 1000.0);
        let plain = simulate(&g, &Inputs::new(), &t, &SimOptions::default()).unwrap();
        // 0.5 per joule: a start-up dissipates a few joules.
        let a = 0.5;
        assert!(c.params[0].upper > a);
        let (hot, _) = h.apply(&g, &c, &[a]).unwrap();
        let heated = simulate(&hot, &Inputs::new(), &t, &SimOptions::default()).unwrap();
        let (i0, i1) = (plain.output("i").unwrap(), heated.output("i").unwrap());
        // The same start (no heat yet), a lower current once heat has built up.
        assert!((i0[1] - i1[1]).abs() < 1e-3 * i0[1].abs().max(1e-9));
        assert!(i1[999] < i0[999], "{} vs {}", i1[999], i0[999]);
        // At a = 0 nothing changes.
        let (cold, _) = h.apply(&g, &c, &[0.0]).unwrap();
        let same = simulate(&cold, &Inputs::new(), &t, &SimOptions::default()).unwrap();
        let i2 = same.output("i").unwrap();
        assert!((i2[999] - i0[999]).abs() < 1e-9 * i0[999].abs().max(1.0));
    }
}

//! `saturation@<I>`: magnetic saturation of an inductance.

/// Bounds of the saturation's exponent `m` (dimensionless).
const EXPONENTS: (f64, f64) = (1.0, 6.0);
/// Grid starts of the exponent.
const EXPONENT_GRID: usize = 3;

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::Domain;
use super::def::EffectDef;
use super::edit::{bad, ident, law, new_param};
use super::menu::{law_value, linear_element_words};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{ElementKind, Law};
use crate::error::Result;
use crate::expr::Expr;
use crate::graph::{BondGraph, ElementId};
use crate::simulate::ParamChange;

/// Magnetic saturation of an electrical I with a linear law: its law
/// becomes `f = p / L · (1 + a_sat p²)^m`, `a_sat` ≥ 0 in 1/Wb² and `m` in
/// [1, 6]: with `m = 1` the current grows by a cube of the flux, with larger
/// `m` it turns up more sharply as the core saturates. A flux that reaches a
/// limit (`L i_s tanh(i/i_s)`, `L i_s atan(i/i_s)`) is [`FluxLimit`](super::FluxLimit)'s.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Saturation {
    /// The I element.
    pub element: ElementId,
}

impl Saturation {
    /// Saturation of the I element `id` of `g`, if it is an I.
    pub fn at(g: &BondGraph, id: ElementId) -> Option<Saturation> {
        (g.element(id).kind == ElementKind::I).then_some(Saturation { element: id })
    }

    /// The nominal inductance, when the law is linear in a parameter in H
    /// (or Wb/A) and positive: what the menu offers saturation for.
    fn inductance(self, g: &BondGraph) -> Option<f64> {
        let Law::Linear(x) = &g.element(self.element).law else {
            return None;
        };
        let electrical = x.params().iter().any(|n| {
            g.params()
                .get(n)
                .is_some_and(|p| Domain::of_unit(&p.unit) == Some(Domain::Electrical))
        });
        if !electrical {
            return None;
        }
        law_value(g, x).filter(|v| *v > 0.0)
    }

    /// The I's name and its linear law (`L`), or a typed error naming it.
    pub(super) fn linear_law(self, g: &BondGraph, c: &Candidate) -> Result<(String, Expr)> {
        let target = g.element(self.element).name.clone();
        let Law::Linear(old) = g.element(self.element).law.clone() else {
            return Err(bad(
                c,
                "",
                format!("the I element '{target}' has no linear law to saturate"),
            ));
        };
        Ok((target, old))
    }

    /// Makes the I's law its current as `formula` of its flux `p`.
    pub(super) fn set_current(self, g: &mut BondGraph, c: &Candidate, formula: &str) -> Result<()> {
        let flow = law(c, formula)?;
        g.element_mut(self.element).law = Law::Nonlinear {
            effort: None,
            flow: Some(flow),
        };
        Ok(())
    }

    /// The peak flux of the model's run (a start-up's, or the recording's),
    /// else `L` times the junction's flow scale.
    pub(super) fn peak_flux(self, g: &BondGraph, scales: &Scales) -> f64 {
        let id = self.element;
        let l = self.inductance(g).unwrap_or(1.0);
        (scales.state_peak.get(&id).copied())
            .filter(|p| *p > 0.0)
            .or_else(|| {
                let (bond, _) = *g.ports(id).first()?;
                Some(l * scales.flow(g.other_end(bond, id)).flow())
            })
            .unwrap_or(1.0)
    }
}

impl EffectDef for Saturation {
    fn offers(g: &BondGraph) -> Vec<Saturation> {
        g.element_ids()
            .filter_map(|id| Saturation::at(g, id))
            .filter(|s| s.inductance(g).is_some())
            .collect()
    }

    /// `a_sat` from 0 to `10 / p_peak²`, scale `0.1 / p_peak²`, with
    /// `p_peak` the peak flux of a start-up (else `L` times the junction's
    /// flow scale).
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let id = self.element;
        let el = g.element(id);
        let p_peak = self.peak_flux(g, scales);
        let a = 1.0 / (p_peak * p_peak);
        let what = linear_element_words(g, self.element);
        Candidate {
            id: Tag::Saturation.id(&el.name),
            name: format!("magnetic saturation of {what}"),
            kind: EffectKind::MissingElement,
            acts_on: el.name.clone(),
            params: vec![
                EffectParam::new("a_sat", "1/Wb^2", 0.0, (0.0, 10.0 * a), 0.1 * a),
                EffectParam::new("m_sat", "1", 1.0, EXPONENTS, 0.5).with_grid(EXPONENT_GRID),
            ],
        }
    }

    /// Changes the law of the I to `f = p / L · (1 + a p²)^m`.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (target, old) = self.linear_law(g, c)?;
        let a_name = new_param(
            g,
            &format!("a_sat_{}", ident(&target)),
            values[0],
            "1/Wb^2",
            &format!(
                "saturation: current grows by a_sat p^2 at flux p (added effect {})",
                c.id
            ),
        )?;
        let m_name = new_param(
            g,
            &format!("m_sat_{}", ident(&target)),
            values[1],
            "1",
            &format!(
                "saturation: the exponent of its growth (added effect {})",
                c.id
            ),
        )?;
        self.set_current(
            g,
            c,
            &format!("p / ({old}) * (1 + {a_name} * p^2)^{m_name}"),
        )?;
        Ok(Vec::new())
    }

    /// With `a_sat = 0` the law is linear, whatever the exponent.
    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        let m = c.params.get(1).map_or(1.0, |p| p.initial);
        Some(vec![0.0, m])
    }
}

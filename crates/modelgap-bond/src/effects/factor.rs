//! `deviation:<u>`: the input modulating an MTF or MGY is off by a factor.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::def::{EffectDef, QualTarget};
use super::edit::{bad, ident, law, new_param};
use super::menu::element_place;
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{ElementKind, Law};
use crate::error::Result;
use crate::graph::{BondGraph, ElementId};
use crate::simulate::ParamChange;

/// The effective modulus of a modulated element (a switch's duty cycle `m`)
/// is off by a factor: its one parameter `<u>_factor` multiplies the
/// modulus of every MTF/MGY that uses input `u`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Factor {
    /// The input used as a modulus.
    pub input: String,
    /// The first MTF or MGY whose modulus uses it (named in the candidate).
    pub element: ElementId,
}

impl Factor {
    /// The factor on input `input` of `g`, if an MTF or MGY modulus uses it.
    pub fn at(g: &BondGraph, input: &str) -> Option<Factor> {
        Factor::offers(g).into_iter().find(|f| f.input == input)
    }

    /// "the effective modulus of switch and diode [switch] (m)".
    pub(super) fn subject(&self, g: &BondGraph) -> String {
        format!(
            "the effective modulus of {} ({})",
            element_place(g, self.element),
            self.input
        )
    }

    /// The factor: initial 1, bounds [0.5, 1.5].
    pub(super) fn factor_param(&self) -> EffectParam {
        EffectParam::new(format!("{}_factor", self.input), "1", 1.0, (0.5, 1.5), 1.0)
    }

    /// Puts a factor parameter (value `value`) on every MTF/MGY law that
    /// uses the input; returns the factor's name.
    pub(super) fn add_factor(
        &self,
        g: &mut BondGraph,
        c: &Candidate,
        value: f64,
    ) -> Result<String> {
        let input = self.input.as_str();
        let users: Vec<ElementId> = g
            .element_ids()
            .filter(|&id| {
                let el = g.element(id);
                matches!(el.kind, ElementKind::Mtf | ElementKind::Mgy)
                    && matches!(&el.law, Law::Linear(e) if g.resolved(e).inputs().contains(input))
            })
            .collect();
        if users.is_empty() {
            return Err(bad(
                c,
                "",
                format!("the model has no parameter or modulus input '{input}'"),
            ));
        }
        let factor = new_param(
            g,
            &format!("{}_factor", ident(input)),
            value,
            "1",
            &format!(
                "factor on the modulus input {input} (added effect {})",
                c.id
            ),
        )?;
        for id in users {
            if let Law::Linear(old) = g.element(id).law.clone() {
                let new_law = law(c, &format!("{factor} * ({old})"))?;
                g.element_mut(id).law = Law::Linear(new_law);
            }
        }
        Ok(factor)
    }
}

impl EffectDef for Factor {
    /// Inputs used as the modulus of an MTF or MGY, each with the element
    /// using it first.
    fn offers(g: &BondGraph) -> Vec<Factor> {
        let mut out: Vec<Factor> = Vec::new();
        for id in g.element_ids() {
            let el = g.element(id);
            if !matches!(el.kind, ElementKind::Mtf | ElementKind::Mgy) {
                continue;
            }
            if let Law::Linear(e) = &el.law {
                for input in g.resolved(e).inputs() {
                    if !out.iter().any(|f| f.input == input) {
                        out.push(Factor { input, element: id });
                    }
                }
            }
        }
        out
    }

    fn candidate(&self, g: &BondGraph, _scales: &Scales) -> Candidate {
        Candidate {
            id: Tag::Deviation.id(&self.input),
            name: format!("{} is off by a factor", self.subject(g)),
            kind: EffectKind::ParameterDeviation,
            acts_on: self.input.clone(),
            params: vec![self.factor_param()],
        }
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let factor = self.add_factor(g, c, values[0])?;
        debug_assert!(g.params().contains_key(&factor));
        Ok(Vec::new())
    }

    /// The input, either sign.
    fn qualitative_signature(&self, _g: &BondGraph) -> Option<Vec<QualTarget>> {
        Some(vec![(self.input.clone(), None)])
    }
}

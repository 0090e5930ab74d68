//! `law@<place>:<formula>`: a law discovery found where an effort (or flow)
//! is missing ([`modelgap_core::explain::screen`]), built in as an element:
//! a source on the place whose value is the formula — a sum of typed terms of
//! the signals acting there, each with its coefficient as a parameter. It
//! is bonded as a load is (a positive effort opposes the junction's flow; a
//! positive flow drains the node), as the estimate's unknown source was. A
//! term of the place's angle or position reads a new storage of zero effort
//! (`pos_<place>`) that integrates its flow from the start.
//!
//! The id holds the formula, so that the candidate, `fix` and a report all
//! read one definition; it is never on the menu — discovery offers it.

use modelgap_core::explain::estimate::Quantity;
use modelgap_core::explain::screen::Law;
use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::def::EffectDef;
use super::edit::{added, attach, bad, law, new_param};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{Element, ElementKind, Law as ElementLaw};
use crate::error::Result;
use crate::estimate::position_element;
use crate::expr::{Expr, split_signal};
use crate::graph::{BondGraph, ElementId};
use crate::simulate::ParamChange;

/// A discovered law on a place.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LawEffect {
    /// The 1-junction (an effort) or 0-junction (a flow).
    pub place: ElementId,
    /// The formula, in law syntax, its coefficients named as the candidate's parameters.
    pub formula: String,
}

impl LawEffect {
    /// The law read from an id's target (`1m:c_sign * tanh('1m'.f / 1e-2)`).
    pub fn read(g: &BondGraph, target: &str) -> Option<LawEffect> {
        let (place, formula) = target.split_once(':')?;
        let id = g.find(place)?;
        // A C is a place when it is a node of its own (alone on a 1-junction).
        let place = match g.element(id).kind {
            ElementKind::One | ElementKind::Zero => true,
            ElementKind::C => super::Node::of(g, id).is_some(),
            _ => false,
        };
        place.then(|| LawEffect {
            place: id,
            formula: formula.to_string(),
        })
    }
}

/// The candidate for a law the screen found on `g`: started at the
/// regression's coefficients, each bounded by what the data allow — the term
/// alone may not produce more than four times the largest missing effort
/// estimated (and never less than ten standard errors around its value).
/// `None` when the place is not in `g` or the formula does not parse.
pub fn law_candidate(g: &BondGraph, found: &Law) -> Option<Candidate> {
    g.find(&found.location)?;
    let formula = found.formula();
    crate::expr::parse(&formula).ok()?;
    let shapes: Vec<EffectParam> = (found.terms.iter())
        .filter_map(|t| t.shape.as_ref())
        .map(|sh| {
            let value = sh.value.clamp(sh.lower, sh.upper);
            let scale = if value != 0.0 {
                value.abs()
            } else {
                (sh.upper - sh.lower) / 10.0
            };
            EffectParam::new(&sh.name, &sh.unit, value, (sh.lower, sh.upper), scale)
        })
        .collect();
    let params = (found.terms.iter())
        .map(|t| {
            let c = t.coefficient;
            let mut bound = if t.term_max > 0.0 {
                4.0 * found.missing_max / t.term_max
            } else {
                f64::INFINITY
            };
            bound = bound.max(c.abs() + 10.0 * t.std_error);
            if !bound.is_finite() || bound <= 0.0 {
                bound = 10.0 * c.abs().max(1e-12);
            }
            let scale = c.abs().max(t.std_error).max(1e-3 * bound);
            EffectParam::new(
                &t.param,
                &t.unit,
                c.clamp(-bound, bound),
                (-bound, bound),
                scale,
            )
        })
        .chain(shapes)
        .collect();
    Some(Candidate {
        id: Tag::Law.id(&format!("{}:{formula}", found.location)),
        name: format!(
            "law found at {}: missing {} = {}",
            found.place,
            found.quantity.word(),
            found.symbolic()
        ),
        kind: EffectKind::MissingElement,
        acts_on: found.location.clone(),
        params,
    })
}

impl EffectDef for LawEffect {
    /// Never on the menu: discovery offers laws.
    fn offers(_g: &BondGraph) -> Vec<LawEffect> {
        Vec::new()
    }

    /// The formula's coefficients, each at 0 within ±1 (a law only
    /// discovery sizes: see [`law_candidate`]).
    fn candidate(&self, g: &BondGraph, _scales: &Scales) -> Candidate {
        let name = g.element(self.place).name.clone();
        let mut params: Vec<String> = crate::expr::parse(&self.formula)
            .map(|e| e.params().into_iter().collect())
            .unwrap_or_default();
        params.retain(|p| !g.params().contains_key(p));
        Candidate {
            id: Tag::Law.id(&format!("{name}:{}", self.formula)),
            name: format!("law at {name}: {}", self.formula),
            kind: EffectKind::MissingElement,
            acts_on: name,
            params: (params.iter())
                .map(|p| EffectParam::new(p, "", 0.0, (-1.0, 1.0), 1.0))
                .collect(),
        }
    }

    /// Adds each coefficient as a parameter, the position storage when the
    /// law reads it, and the source.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let place_name = g.element(self.place).name.clone();
        let suffix = super::edit::ident(&place_name);
        let expr = law(c, &self.formula)?;
        let mut renamed: Vec<(String, String)> = Vec::new();
        for (p, v) in c.params.iter().zip(values) {
            let fresh = new_param(
                g,
                &format!("{}_{suffix}", p.name),
                *v,
                &p.unit,
                &format!("coefficient of a discovered law {}", added(c)),
            )?;
            renamed.push((p.name.clone(), fresh));
        }
        // The position the law reads: a storage of zero effort integrating the flow.
        let wanted = position_element(&place_name);
        let reads_position = expr.signals().iter().any(|(el, _)| *el == wanted);
        let mut position = wanted.clone();
        if reads_position {
            let zero = law(c, "0 * q")?;
            let id = attach(
                g,
                self.place,
                Element::nonlinear(&wanted, ElementKind::C, Some(zero), None).described(&format!(
                    "position of {place_name} from the start, read by a discovered law {}",
                    added(c)
                )),
            )?;
            position = g.element(id).name.clone();
        }
        let expr = expr.map(&mut |e: &Expr| match e {
            Expr::Param(n) => (renamed.iter())
                .find(|(old, _)| old == n)
                .map(|(_, new)| Expr::Param(new.clone())),
            Expr::Local(l) => match split_signal(l) {
                Some((el, var)) if el == wanted && position != wanted => {
                    Some(Expr::signal(&position, var))
                }
                _ => None,
            },
            _ => None,
        });
        // A flow on a node: a 0-junction, or a C alone on a 1-junction (its node's junction
        // is put between them).
        let is_flow = matches!(
            g.element(self.place).kind,
            ElementKind::Zero | ElementKind::C
        );
        let at = match g.element(self.place).kind {
            ElementKind::C => super::Node::of(g, self.place)
                .ok_or_else(|| bad(c, "", "the capacitance is no node".to_string()))?
                .junction(g)?,
            _ => self.place,
        };
        let mut source = if is_flow {
            Element::sf(&format!("law_{suffix}"), "0")
        } else {
            Element::se(&format!("law_{suffix}"), "0")
        };
        source.law = ElementLaw::Source(expr);
        let what = if is_flow {
            Quantity::Flow
        } else {
            Quantity::Effort
        };
        attach(
            g,
            at,
            source.described(&format!(
                "discovered law: the missing {} (its bond points into it) {}",
                what.word(),
                added(c)
            )),
        )
        .map_err(|e| bad(c, "", format!("cannot attach the law: {e}")))?;
        Ok(Vec::new())
    }

    /// Every coefficient (`c_…`) at 0; shape parameters where they are.
    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        Some(
            (c.params.iter())
                .map(|p| {
                    if p.name.starts_with("c_") {
                        0.0
                    } else {
                        p.initial
                    }
                })
                .collect(),
        )
    }
}

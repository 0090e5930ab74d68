//! `deviation:<p>`: an existing parameter is off.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::def::{EffectDef, QualTarget};
use super::menu::param_place;
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{ElementKind, Law};
use crate::error::Result;
use crate::expr::Expr;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// An existing parameter is off (R is not 1.0 Ω but 1.2 Ω): its one
/// parameter is the new value.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Deviation {
    /// The parameter.
    pub param: String,
}

impl Deviation {
    /// The deviation of parameter `name` of `g`, if it has one.
    pub fn at(g: &BondGraph, name: &str) -> Option<Deviation> {
        g.params().contains_key(name).then(|| Deviation {
            param: name.to_string(),
        })
    }

    /// "armature resistance (R)", or "R" when it has no description.
    pub(super) fn subject(&self, g: &BondGraph) -> String {
        param_place(g, &self.param)
    }

    /// The new value of the parameter: bounds [v/5, 5v] (a factor of five
    /// either way), scale |v|; a zero nominal gets [−s, s] with `s` the
    /// scale of the quantity it multiplies (see [`zero_scale`]), or [0, s]
    /// when it is the resistance of a linear R (which cannot be negative:
    /// [`BondGraph::check_coefficients`]).
    pub(super) fn value_param(&self, g: &BondGraph, scales: &Scales) -> EffectParam {
        let name = self.param.as_str();
        let (value, unit) = g
            .params()
            .get(name)
            .map_or((0.0, ""), |p| (p.value, p.unit.as_str()));
        if value > 0.0 {
            EffectParam::new(name, unit, value, (value / 5.0, value * 5.0), value)
        } else if value < 0.0 {
            EffectParam::new(name, unit, value, (value * 5.0, value / 5.0), -value)
        } else {
            let s = zero_scale(g, scales, name);
            let resistance = g.element_ids().any(|id| {
                let el = g.element(id);
                el.kind == ElementKind::R && el.law == Law::Linear(Expr::Param(name.to_string()))
            });
            let lower = if resistance { 0.0 } else { -s };
            EffectParam::new(name, unit, 0.0, (lower, s), s)
        }
    }
}

impl EffectDef for Deviation {
    fn offers(g: &BondGraph) -> Vec<Deviation> {
        g.params()
            .keys()
            .map(|name| Deviation {
                param: name.clone(),
            })
            .collect()
    }

    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        Candidate {
            id: Tag::Deviation.id(&self.param),
            name: format!("{} is off", self.subject(g)),
            kind: EffectKind::ParameterDeviation,
            acts_on: self.param.clone(),
            params: vec![self.value_param(g, scales)],
        }
    }

    fn edit(&self, g: &mut BondGraph, _c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        g.set_param(&self.param, values[0])?;
        Ok(Vec::new())
    }

    /// The parameter itself, either sign.
    fn qualitative_signature(&self, _g: &BondGraph) -> Option<Vec<QualTarget>> {
        Some(vec![(self.param.clone(), None)])
    }
}

/// The scale of a parameter whose nominal value is 0, from what it acts on:
/// the coefficient of an R gets effort/flow of its junction, the value of an
/// Se the junction's effort, of an Sf its flow; anything else 1.
fn zero_scale(g: &BondGraph, scales: &Scales, name: &str) -> f64 {
    for id in g.element_ids() {
        let el = g.element(id);
        let e = match &el.law {
            Law::Linear(e) | Law::Source(e) => e,
            _ => continue,
        };
        if e != &Expr::Param(name.to_string()) {
            continue;
        }
        let Some(&(bond, _)) = g.ports(id).first() else {
            continue;
        };
        let j = g.other_end(bond, id);
        let (effort, flow) = (scales.effort(j).strength(), scales.flow(j).flow());
        return match el.kind {
            ElementKind::R => effort / flow,
            ElementKind::Se => effort,
            ElementKind::Sf => flow,
            _ => 1.0,
        };
    }
    1.0
}

//! `stiffness@<C>`: a cubic term in a C element's law — a hardening or
//! softening spring, a capacitor whose voltage bends with its charge, a tank
//! whose level is not proportional to its volume. For every C, in any domain
//! (units or none): its law `e(q)` becomes `e(q) + k3 q³`.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::def::{EffectDef, all_zero};
use super::edit::{bad, ident, law, new_param};
use super::menu::{element_place, law_value};
use super::node::{Node, NodeKind};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{ElementKind, Law};
use crate::error::Result;
use crate::graph::{BondGraph, ElementId};
use crate::simulate::ParamChange;

/// A cubic term `k3 q³` added to the effort law of a C element.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stiffness {
    /// The C element.
    pub element: ElementId,
}

impl Stiffness {
    /// The cubic term on element `id` of `g`, if it is a C with an effort law.
    pub fn at(g: &BondGraph, id: ElementId) -> Option<Stiffness> {
        let el = g.element(id);
        let has_law = matches!(
            &el.law,
            Law::Linear(_)
                | Law::Nonlinear {
                    effort: Some(_),
                    ..
                }
        );
        (el.kind == ElementKind::C && has_law).then_some(Stiffness { element: id })
    }

    /// The C's effort law as text in `q`.
    fn effort_law(self, g: &BondGraph) -> Option<String> {
        match &g.element(self.element).law {
            Law::Linear(c) => Some(format!("q / ({c})")),
            Law::Nonlinear {
                effort: Some(e), ..
            } => Some(e.to_string()),
            _ => None,
        }
    }

    /// The storage node the C sits on, when its kind is known (a thermal
    /// mass, a capacitor node, a tank).
    fn node(self, g: &BondGraph) -> Option<Node> {
        (g.ports(self.element).into_iter())
            .map(|(b, _)| g.other_end(b, self.element))
            .find_map(|j| Node::of(g, j))
            .filter(|n| n.units_known && n.kind != NodeKind::Generic)
    }

    /// The unit of `k3`: one over the C's coefficient unit per displacement
    /// squared, when its linear coefficient has a unit; on a node of known
    /// units, its effort per stored quantity cubed (`K/J^3`); else `e/q^3`.
    fn unit(self, g: &BondGraph) -> String {
        if let Some(node) = self.node(g) {
            let stored = match node.kind {
                NodeKind::Thermal => "J",
                NodeKind::Electrical => "C",
                _ => "m^3",
            };
            return format!("{}/{stored}^3", node.units().0);
        }
        match &g.element(self.element).law {
            Law::Linear(c) => (c.params().iter())
                .filter_map(|n| g.params().get(n))
                .map(|p| p.unit.trim())
                .find(|u| !u.is_empty())
                .map_or_else(|| "e/q^3".to_string(), |u| format!("1/(({u}) q^2)")),
            _ => "e/q^3".to_string(),
        }
    }
}

impl EffectDef for Stiffness {
    fn offers(g: &BondGraph) -> Vec<Stiffness> {
        g.element_ids()
            .filter_map(|id| Stiffness::at(g, id))
            .collect()
    }

    /// `k3` either sign: its scale makes the cubic term a tenth of the
    /// junction's peak effort at the peak displacement of a start-up; its
    /// bounds a hundred times that. A C that a start-up does not move (no
    /// input drives it at rest) gets its linear law's stiffness as the
    /// displacement scale's reciprocal.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let id = self.element;
        let el = g.element(id);
        let junction = g.ports(id).first().map(|(b, _)| g.other_end(*b, id));
        let effort_peak = junction.map_or(1.0, |j| {
            let e = scales.effort(j);
            e.peak_or(e.strength())
        });
        let stiffness = match &el.law {
            Law::Linear(c) => law_value(g, c).filter(|v| *v > 0.0).map(|c| 1.0 / c),
            _ => None,
        };
        let q_peak = scales
            .state_peak
            .get(&id)
            .copied()
            .filter(|q| *q > 0.0)
            .or_else(|| stiffness.map(|k| effort_peak / k))
            .filter(|q| q.is_finite() && *q > 0.0)
            .unwrap_or(1.0);
        let scale = (0.1 * effort_peak / q_peak.powi(3)).max(f64::MIN_POSITIVE);
        Candidate {
            id: Tag::Stiffness.id(&el.name),
            name: match self.node(g).map(|n| n.kind) {
                Some(NodeKind::Thermal) => format!(
                    "a heat capacity that changes with the heat stored: a cubic term in {}",
                    element_place(g, id)
                ),
                Some(NodeKind::Electrical) => format!(
                    "a capacitance that bends with its charge: a cubic term in {}",
                    element_place(g, id)
                ),
                Some(NodeKind::Hydraulic) => format!(
                    "a tank whose level or pressure is not proportional to its volume: a cubic \
                     term in {}",
                    element_place(g, id)
                ),
                _ => format!(
                    "a cubic stiffness term in {} (hardening or softening)",
                    element_place(g, id)
                ),
            },
            kind: EffectKind::MissingElement,
            acts_on: el.name.clone(),
            params: vec![EffectParam::new(
                "k3",
                self.unit(g),
                0.0,
                (-100.0 * scale, 100.0 * scale),
                scale,
            )],
        }
    }

    /// The C's law becomes `e = <its law> + k3 q³`.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let target = g.element(self.element).name.clone();
        let old = self.effort_law(g).ok_or_else(|| {
            bad(
                c,
                "",
                format!("the C element '{target}' has no effort law to add a cubic term to"),
            )
        })?;
        let unit = self.unit(g);
        let k3 = new_param(
            g,
            &format!("k3_{}", ident(&target)),
            values[0],
            &unit,
            &format!(
                "cubic stiffness: effort grows by k3 q^3 (added effect {})",
                c.id
            ),
        )?;
        let effort = law(c, &format!("{old} + {k3} * q^3"))?;
        g.element_mut(self.element).law = Law::Nonlinear {
            effort: Some(effort),
            flow: None,
        };
        Ok(Vec::new())
    }

    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        all_zero(c)
    }
}

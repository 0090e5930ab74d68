//! Where element effects attach: 1-junctions with an inertia of known unit.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::Domain;
use super::def::QualTarget;
use super::edit::ident;
use super::menu::{law_value, place};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{ElementKind, Law};
use crate::expr::Expr;
use crate::graph::{BondGraph, Direction, ElementId};
use crate::qual::Qual;

/// The domain of a 1-junction and the I element that sets it, or `None`
/// when no I bonded to it has a parameter with a domain unit and the
/// junction declares no electrical or mechanical domain (see the
/// [module docs](super)).
pub fn junction_domain(g: &BondGraph, junction: ElementId) -> Option<(Domain, ElementId)> {
    if g.element(junction).kind != ElementKind::One {
        return None;
    }
    // A declared domain names the physics when the units do not.
    let declared = g.element(junction).domain.and_then(|d| {
        use crate::element::PhysicalDomain as D;
        match d {
            D::Electrical => Some(Domain::Electrical),
            D::Rotational => Some(Domain::Rotational),
            D::Translational => Some(Domain::Translational),
            _ => None,
        }
    });
    for (bond, _) in g.ports(junction) {
        let other = g.other_end(bond, junction);
        let el = g.element(other);
        if el.kind != ElementKind::I {
            continue;
        }
        let exprs: Vec<&Expr> = match &el.law {
            Law::Linear(e) => vec![e],
            Law::Nonlinear { effort, flow } => flow.iter().chain(effort.iter()).collect(),
            _ => Vec::new(),
        };
        if let Some(d) = declared {
            return Some((d, other));
        }
        for e in exprs {
            for name in e.params() {
                if let Some(d) = g.params().get(&name).and_then(|p| Domain::of_unit(&p.unit)) {
                    return Some((d, other));
                }
            }
        }
    }
    None
}

/// A 1-junction with an inertia of known unit: where the element effects
/// (friction, loads, couplings, cogging, a brush drop) attach.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Junction {
    /// The 1-junction.
    pub id: ElementId,
    /// Its domain, from the unit of its inertia.
    pub domain: Domain,
    /// The I element that sets the domain.
    pub inertia: ElementId,
}

impl Junction {
    /// The junction `id`, when it is a 1-junction with an inertia of known unit.
    pub fn of(g: &BondGraph, id: ElementId) -> Option<Junction> {
        junction_domain(g, id).map(|(domain, inertia)| Junction {
            id,
            domain,
            inertia,
        })
    }

    /// Every such junction of `g`, in element order.
    pub fn all(g: &BondGraph) -> Vec<Junction> {
        g.element_ids()
            .filter_map(|id| Junction::of(g, id))
            .collect()
    }

    /// The junction's name (`1m`).
    pub(super) fn name(self, g: &BondGraph) -> &str {
        &g.element(self.id).name
    }

    /// The suffix of what an edit adds here (`1m`, made safe for a law).
    pub(super) fn suffix(self, g: &BondGraph) -> String {
        ident(self.name(g))
    }

    /// The nominal value of its inertia, when the I's law is linear and positive.
    pub(super) fn inertia_value(self, g: &BondGraph) -> Option<f64> {
        match &g.element(self.inertia).law {
            Law::Linear(x) => law_value(g, x).filter(|v| *v > 0.0),
            _ => None,
        }
    }

    /// The scale of an effort strength here (a friction level, a load, a drop).
    pub(super) fn effort_scale(self, scales: &Scales) -> f64 {
        scales.effort(self.id).strength()
    }

    /// The largest effort strength worth trying here: the junction's peak effort.
    pub(super) fn effort_peak(self, scales: &Scales) -> f64 {
        let e = scales.effort(self.id);
        e.peak_or(10.0 * e.strength())
    }

    /// The scale of the flow here.
    pub(super) fn flow_scale(self, scales: &Scales) -> f64 {
        scales.flow(self.id).flow()
    }

    /// A missing-element candidate on this junction.
    pub(super) fn candidate(
        self,
        g: &BondGraph,
        tag: Tag,
        name: String,
        params: Vec<EffectParam>,
    ) -> Candidate {
        missing_element(tag, self.name(g), name, params)
    }

    /// "the shaft (1m)" from the junction's description, or "junction 1m".
    pub(super) fn place(self, g: &BondGraph) -> String {
        place(g, self.id)
    }

    /// The parameters of the linear R elements on the junction, increasing:
    /// what more dissipation looks like to the qualitative diagnosis.
    pub(super) fn resistances_up(self, g: &BondGraph) -> Vec<QualTarget> {
        self.neighbours(g)
            .filter_map(|(el, _)| match (&el.kind, &el.law) {
                (ElementKind::R, Law::Linear(Expr::Param(p))) if g.params().contains_key(p) => {
                    Some((p.clone(), Some(Qual::Plus)))
                }
                _ => None,
            })
            .collect()
    }

    /// The load inputs on the junction (an Se whose value is an input), with
    /// the sign that opposes motion: positive when the bond points into the source.
    pub(super) fn loads(self, g: &BondGraph) -> Vec<QualTarget> {
        self.neighbours(g)
            .filter_map(|(el, dir)| match (&el.kind, &el.law) {
                (ElementKind::Se, Law::Source(Expr::Param(u))) if g.inputs().contains_key(u) => {
                    let sign = if dir == Direction::Out {
                        Qual::Plus
                    } else {
                        Qual::Minus
                    };
                    Some((u.clone(), Some(sign)))
                }
                _ => None,
            })
            .collect()
    }

    /// The parameters of the linear I laws on the junction, either sign.
    pub(super) fn inertias(self, g: &BondGraph) -> Vec<QualTarget> {
        self.neighbours(g)
            .filter_map(|(el, _)| match (&el.kind, &el.law) {
                (ElementKind::I, Law::Linear(e)) => Some(e.params()),
                _ => None,
            })
            .flatten()
            .map(|p| (p, None))
            .collect()
    }

    /// The elements bonded to the junction, with each bond's direction.
    fn neighbours(
        self,
        g: &BondGraph,
    ) -> impl Iterator<Item = (&crate::element::Element, Direction)> {
        g.ports(self.id)
            .into_iter()
            .map(move |(bond, dir)| (g.element(g.other_end(bond, self.id)), dir))
    }
}

/// `Some(targets)`, or `None` when there are none.
pub(super) fn non_empty(targets: Vec<QualTarget>) -> Option<Vec<QualTarget>> {
    if targets.is_empty() {
        None
    } else {
        Some(targets)
    }
}

/// A missing-element candidate of kind `tag` at the element called `at`.
pub(super) fn missing_element(
    tag: Tag,
    at: &str,
    name: String,
    params: Vec<EffectParam>,
) -> Candidate {
    Candidate {
        id: tag.id(at),
        name,
        kind: EffectKind::MissingElement,
        acts_on: at.to_string(),
        params,
    }
}

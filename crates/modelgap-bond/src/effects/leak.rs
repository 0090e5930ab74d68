//! `leak@<node>`: a linear loss from a storage node — leakage from a tank,
//! heat lost to ambient from a thermal mass, a leakage conductance across a
//! capacitor: an R with `f = G e`, `G` ≥ 0.

use modelgap_core::{Candidate, EffectParam};

use super::def::{EffectDef, all_zero};
use super::edit::{added, attach, law, new_param};
use super::node::{Node, NodeKind};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{Element, ElementKind};
use crate::error::Result;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// A linear loss from a node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Leak {
    /// The node.
    pub node: Node,
}

impl EffectDef for Leak {
    fn offers(g: &BondGraph) -> Vec<Leak> {
        Node::all(g).into_iter().map(|node| Leak { node }).collect()
    }

    /// `G` from 0 to ten times the node's peak flow over its peak effort
    /// (a loss that would carry every flow seen at every level), scale a
    /// tenth of that ratio.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let n = self.node;
        let ratio = n.flow_peak(scales) / n.effort_peak(scales);
        let what = match n.kind {
            NodeKind::Hydraulic => "leakage from",
            NodeKind::Thermal => "heat loss to ambient from",
            NodeKind::Electrical => "a leakage conductance at",
            NodeKind::Generic => "a linear loss from",
        };
        n.candidate(
            g,
            Tag::Leak,
            format!("{what} {}", n.place(g)),
            vec![EffectParam::new(
                "G",
                n.conductance_unit(),
                0.0,
                (0.0, 10.0 * ratio),
                0.1 * ratio,
            )],
        )
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let suffix = self.node.suffix(g);
        let gain = new_param(
            g,
            &format!("G_leak_{suffix}"),
            values[0],
            &self.node.conductance_unit(),
            &format!("loss from the node per unit of its effort {}", added(c)),
        )?;
        let flow = law(c, &format!("{gain} * e"))?;
        let at = self.node.junction(g)?;
        attach(
            g,
            at,
            Element::nonlinear(&format!("leak_{suffix}"), ElementKind::R, None, Some(flow))
                .described("a linear loss from the node"),
        )?;
        Ok(Vec::new())
    }

    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        all_zero(c)
    }
}

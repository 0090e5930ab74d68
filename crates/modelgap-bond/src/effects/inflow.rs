//! `inflow@<node>`: a constant flow into a storage node — an unmeasured
//! inflow to a tank, a heat source on a thermal mass, a bias current: a flow
//! source `Q` (either sign; positive fills the node).

use modelgap_core::{Candidate, EffectParam};

use super::def::{EffectDef, all_zero};
use super::edit::{added, attach, law, new_param};
use super::node::{Node, NodeKind};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{Element, ElementKind, Law};
use crate::error::Result;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// A constant flow into a node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Inflow {
    /// The node.
    pub node: Node,
}

impl EffectDef for Inflow {
    fn offers(g: &BondGraph) -> Vec<Inflow> {
        Node::all(g)
            .into_iter()
            .map(|node| Inflow { node })
            .collect()
    }

    /// `Q` within ± the node's peak flow, scale a tenth of it.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let n = self.node;
        let f = n.flow_peak(scales);
        let what = match n.kind {
            NodeKind::Hydraulic => "a constant inflow into",
            NodeKind::Thermal => "a heat source at",
            NodeKind::Electrical => "a constant current into",
            NodeKind::Generic => "a constant flow into",
        };
        n.candidate(
            g,
            Tag::Inflow,
            format!("{what} {}", n.place(g)),
            vec![EffectParam::new("Q", n.units().1, 0.0, (-f, f), 0.1 * f)],
        )
    }

    /// A flow source bonded from the node; its flow is `-Q` on that bond,
    /// so a positive `Q` fills the node.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let suffix = self.node.suffix(g);
        let q = new_param(
            g,
            &format!("Q_in_{suffix}"),
            values[0],
            self.node.units().1,
            &format!("constant flow into the node {}", added(c)),
        )?;
        let value = law(c, &format!("-{q}"))?;
        let mut source = Element::sf(&format!("inflow_{suffix}"), &q)
            .described("a constant flow into the node (its bond points out of the node)");
        source.law = Law::Source(value);
        debug_assert_eq!(source.kind, ElementKind::Sf);
        let at = self.node.junction(g)?;
        attach(g, at, source)?;
        Ok(Vec::new())
    }

    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        all_zero(c)
    }
}

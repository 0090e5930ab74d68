//! `store@<node>`: a second storage behind a resistance — a second thermal
//! mass behind a thermal resistance (the casing around a winding, the plate
//! under a sensor), a compliance behind a restriction (an accumulator, a
//! hose, trapped air in a hydraulic line), a second capacitance behind a
//! resistance (dielectric absorption). `node → 1 → {R (R2), 0 → C (C2)}`;
//! adds one state, which starts at zero effort (or at the steady state
//! when the loop starts from one).

use modelgap_core::{Candidate, EffectParam};

use super::def::EffectDef;
use super::edit::{added, attach, new_param};
use super::node::{Node, NodeKind};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::Element;
use crate::error::Result;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// A second storage `C2` exchanging with a node through a resistance `R2`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Store {
    /// The node.
    pub node: Node,
}

impl Store {
    /// What the second storage is, in the node's physics.
    fn words(self) -> (&'static str, &'static str) {
        match self.node.kind {
            NodeKind::Thermal => ("a second thermal mass", "a thermal resistance"),
            NodeKind::Hydraulic => (
                "a compliance (an accumulator, a hose, trapped air)",
                "a restriction",
            ),
            NodeKind::Electrical => ("a second capacitance", "a resistance"),
            NodeKind::Generic => ("a second storage", "a resistance"),
        }
    }
}

impl EffectDef for Store {
    fn offers(g: &BondGraph) -> Vec<Store> {
        Node::all(g)
            .into_iter()
            .map(|node| Store { node })
            .collect()
    }

    /// Starts at `C2` equal to the node's own capacity and a time constant
    /// `R2 C2` of the model's slowest mode; `C2` spans a factor of 100 either
    /// way and `R2` a factor of 100 either way of its start (a store that
    /// exchanges much faster is part of the node, much slower is not seen).
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let n = self.node;
        let c0 = n.capacity(g, scales);
        let tau = scales.slowest_rate.map_or(1.0, |r| 1.0 / r);
        let r0 = tau / c0;
        let (what, through) = self.words();
        n.candidate(
            g,
            Tag::Store,
            format!("{what} behind {through} at {}", n.place(g)),
            vec![
                EffectParam::new("C2", n.capacity_unit(), c0, (c0 / 100.0, c0 * 100.0), c0),
                EffectParam::new("R2", n.resistance_unit(), r0, (r0 / 100.0, r0 * 100.0), r0),
            ],
        )
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (n, suffix) = (self.node, self.node.suffix(g));
        let (what, through) = self.words();
        let tag = added(c);
        let capacity = new_param(
            g,
            &format!("C2_{suffix}"),
            values[0],
            &n.capacity_unit(),
            &format!("{what} {tag}"),
        )?;
        let resistance = new_param(
            g,
            &format!("R2_{suffix}"),
            values[1],
            &n.resistance_unit(),
            &format!("{through} to the second storage {tag}"),
        )?;
        let at = n.junction(g)?;
        let path = attach(
            g,
            at,
            Element::one(&format!("to_store_{suffix}"))
                .described("path to the second storage: common flow"),
        )?;
        attach(
            g,
            path,
            Element::r(&format!("R_store_{suffix}"), &resistance).described(through),
        )?;
        let store = attach(
            g,
            path,
            Element::zero(&format!("store_{suffix}")).described(&format!("{what}: its own effort")),
        )?;
        attach(
            g,
            store,
            Element::c(&format!("C_store_{suffix}"), &capacity).described(what),
        )?;
        Ok(Vec::new())
    }
}

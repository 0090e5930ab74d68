//! `overflow@<node>`: flow out of a storage node once its effort passes a
//! threshold — a tank overflowing its rim, a relief valve, a clamp: an R with
//! `f = k_o · max(e − e_max, 0)` (a one-sided dead zone).

use modelgap_core::{Candidate, EffectParam};

use super::def::EffectDef;
use super::edit::{added, attach, law, new_param};
use super::node::{Node, NodeKind};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{Element, ElementKind};
use crate::error::Result;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// Outflow above a threshold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Overflow {
    /// The node.
    pub node: Node,
}

impl EffectDef for Overflow {
    fn offers(g: &BondGraph) -> Vec<Overflow> {
        Node::all(g)
            .into_iter()
            .map(|node| Overflow { node })
            .collect()
    }

    /// `e_max` searched over a grid of 6 from a fifth of the node's peak
    /// effort to 1.2 times it (no overflow when above); `k_o` from 0 to a
    /// hundred times the peak flow over the peak effort (steep enough to
    /// hold the node near `e_max`), scale the ratio itself.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let n = self.node;
        let e = n.effort_peak(scales);
        let ratio = n.flow_peak(scales) / e;
        let what = match n.kind {
            NodeKind::Hydraulic => "overflow of",
            NodeKind::Thermal => "a relief of heat above a temperature at",
            NodeKind::Electrical => "a clamp above a voltage at",
            NodeKind::Generic => "an outflow above a threshold (one-sided dead zone) at",
        };
        n.candidate(
            g,
            Tag::Overflow,
            format!("{what} {}", n.place(g)),
            vec![
                EffectParam::new("e_max", n.units().0, 1.2 * e, (0.2 * e, 1.2 * e), 0.1 * e)
                    .with_grid(6),
                EffectParam::new(
                    "k_o",
                    n.conductance_unit(),
                    0.0,
                    (0.0, 100.0 * ratio),
                    ratio,
                ),
            ],
        )
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let suffix = self.node.suffix(g);
        let e_max = new_param(
            g,
            &format!("e_max_{suffix}"),
            values[0],
            self.node.units().0,
            &format!("effort above which the node overflows {}", added(c)),
        )?;
        let k = new_param(
            g,
            &format!("k_o_{suffix}"),
            values[1],
            &self.node.conductance_unit(),
            &format!("outflow per unit of effort above e_max {}", added(c)),
        )?;
        let flow = law(c, &format!("{k} * max(e - {e_max}, 0)"))?;
        let at = self.node.junction(g)?;
        attach(
            g,
            at,
            Element::nonlinear(
                &format!("overflow_{suffix}"),
                ElementKind::R,
                None,
                Some(flow),
            )
            .described("outflow above a threshold"),
        )?;
        Ok(Vec::new())
    }

    /// With `k_o = 0` nothing flows, whatever the threshold.
    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        let e_max = c.params.first().map_or(0.0, |p| p.initial);
        Some(vec![e_max, 0.0])
    }
}

//! `orifice@<node>`: turbulent outflow from a hydraulic or pneumatic node
//! through an orifice — a hole in a tank, a drain valve, a nozzle to
//! ambient: an R with `f = a · sign(e) · √|e|`, the square-root law of
//! Torricelli and Bernoulli (a leak is linear in the effort: laminar flow).
//! The law is not smoothed at `e = 0`: the adaptive solver steps through
//! its infinite slope as it does through a tank that runs dry.

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

/// A square-root outflow from a node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Orifice {
    /// The node.
    pub node: Node,
}

impl Orifice {
    /// The orifice on `node`, if it is hydraulic (or pneumatic).
    pub fn at(node: Node) -> Option<Orifice> {
        (node.kind == NodeKind::Hydraulic).then_some(Orifice { node })
    }

    /// The unit of the orifice coefficient: flow per square root of effort.
    fn unit(self) -> String {
        let (e, f) = self.node.units();
        format!("{f}/{e}^0.5")
    }
}

impl EffectDef for Orifice {
    fn offers(g: &BondGraph) -> Vec<Orifice> {
        Node::all(g).into_iter().filter_map(Orifice::at).collect()
    }

    /// `a` from 0 to ten times the node's peak flow over the square root of
    /// its peak effort (an orifice that would carry every flow seen at every
    /// level), scale a tenth of that.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let n = self.node;
        let ratio = n.flow_peak(scales) / n.effort_peak(scales).sqrt();
        n.candidate(
            g,
            Tag::Orifice,
            format!(
                "turbulent outflow through an orifice (flow ∝ √{}) from {}",
                if n.level { "level" } else { "pressure" },
                n.place(g)
            ),
            vec![EffectParam::new(
                "a",
                self.unit(),
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
            &format!("a_orifice_{suffix}"),
            values[0],
            &self.unit(),
            &format!(
                "orifice flow per square root of the node's effort {}",
                added(c)
            ),
        )?;
        let flow = law(c, &format!("{gain} * sign(e) * sqrt(abs(e))"))?;
        let at = self.node.junction(g)?;
        attach(
            g,
            at,
            Element::nonlinear(
                &format!("orifice_{suffix}"),
                ElementKind::R,
                None,
                Some(flow),
            )
            .described("turbulent outflow through an orifice"),
        )?;
        Ok(Vec::new())
    }

    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        all_zero(c)
    }
}

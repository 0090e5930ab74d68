//! `power@<node>`: a heat loss from a thermal node that grows as a power of
//! its temperature — natural convection (`p ≈ 1.25`–`1.33`), radiation over a
//! rise of tens of kelvin (a convex loss, `p` of 2 or so beside the linear
//! convection a calibration re-adjusts): an R with `f = k · sign(e) · |e|^p`,
//! `k ≥ 0`, `p` in [1, 4]. A leak is the linear case.

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

/// The exponents the search starts from.
const EXPONENT_GRID: usize = 4;
/// The exponent's bounds.
const EXPONENTS: (f64, f64) = (1.0, 4.0);

/// A loss growing as a power of a thermal node's temperature.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PowerLoss {
    /// The node.
    pub node: Node,
}

impl PowerLoss {
    /// The power loss on `node`, if it is thermal.
    pub fn at(node: Node) -> Option<PowerLoss> {
        (node.kind == NodeKind::Thermal).then_some(PowerLoss { node })
    }

    /// The unit of `k`: flow per effort to the power `p` (`W/K^p`).
    fn unit(self) -> String {
        let (e, f) = self.node.units();
        format!("{f}/{e}^p")
    }
}

impl EffectDef for PowerLoss {
    fn offers(g: &BondGraph) -> Vec<PowerLoss> {
        Node::all(g).into_iter().filter_map(PowerLoss::at).collect()
    }

    /// `p` searched over a grid of 4 from 1 to 4; `k` from 0 to ten times the
    /// node's peak flow over its peak effort to the power that makes that
    /// largest, scale a tenth of the peak flow over the peak effort squared
    /// (the grid's middle).
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let n = self.node;
        let (e, f) = (n.effort_peak(scales), n.flow_peak(scales));
        let smallest = e.powf(EXPONENTS.0).min(e.powf(EXPONENTS.1));
        n.candidate(
            g,
            Tag::Power,
            format!(
                "a heat loss growing as a power of the temperature (natural convection, \
                 radiation) from {}",
                n.place(g)
            ),
            vec![
                EffectParam::new(
                    "k",
                    self.unit(),
                    0.0,
                    (0.0, 10.0 * f / smallest),
                    0.1 * f / (e * e),
                ),
                EffectParam::new("p", "1", 2.0, EXPONENTS, 0.5).with_grid(EXPONENT_GRID),
            ],
        )
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let suffix = self.node.suffix(g);
        let k = new_param(
            g,
            &format!("k_power_{suffix}"),
            values[0],
            &self.unit(),
            &format!(
                "loss per unit of the node's effort to the power p {}",
                added(c)
            ),
        )?;
        let p = new_param(
            g,
            &format!("p_power_{suffix}"),
            values[1],
            "1",
            &format!("the exponent of the power loss {}", added(c)),
        )?;
        let flow = law(c, &format!("{k} * sign(e) * abs(e)^{p}"))?;
        let at = self.node.junction(g)?;
        attach(
            g,
            at,
            Element::nonlinear(&format!("power_{suffix}"), ElementKind::R, None, Some(flow))
                .described("a loss growing as a power of the effort"),
        )?;
        Ok(Vec::new())
    }

    /// With `k = 0` nothing flows, whatever the exponent.
    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        let p = c.params.get(1).map_or(2.0, |p| p.initial);
        Some(vec![0.0, p])
    }
}

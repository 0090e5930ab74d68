//! `offset@<output>`: a sensor that reads off by a constant — a zero that
//! drifted, an amplifier's offset, a level gauge mounted a little high: the
//! output is the measured variable plus `b`. Built as the output's expression
//! (`y + b`), so it adds no state and costs nothing in the simulation.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::def::{EffectDef, all_zero};
use super::edit::{added, bad, ident, new_param};
use super::lag::{sensed_output, sensed_outputs, signal_of};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::Measured;
use crate::error::Result;
use crate::expr::Expr;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// A constant offset on the output at this index of the graph's outputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SensorOffset {
    /// Index into [`BondGraph::outputs`].
    pub output: usize,
}

impl SensorOffset {
    /// The offset on output `name` of `g`, if it reads a variable.
    pub fn named(g: &BondGraph, name: &str) -> Option<SensorOffset> {
        sensed_output(g, name).map(|output| SensorOffset { output })
    }
}

impl EffectDef for SensorOffset {
    fn offers(g: &BondGraph) -> Vec<SensorOffset> {
        sensed_outputs(g)
            .map(|output| SensorOffset { output })
            .collect()
    }

    /// `b` within ± the largest value the output takes in the run (the
    /// recording's, when there is one), starting at 0; scale a hundredth of it.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let o = &g.outputs()[self.output];
        let peak = scales.output_peak(&o.name);
        Candidate {
            id: Tag::Offset.id(&o.name),
            name: format!(
                "an offset in the sensor of {} (a constant added to its reading)",
                o.name
            ),
            kind: EffectKind::MissingElement,
            acts_on: o.name.clone(),
            params: vec![EffectParam::new(
                "offset",
                &o.unit,
                0.0,
                (-peak, peak),
                0.01 * peak,
            )],
        }
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let o = g.outputs()[self.output].clone();
        let signal = signal_of(g, self.output).ok_or_else(|| {
            bad(
                c,
                "",
                format!("output '{}' reads no variable to offset", o.name),
            )
        })?;
        let b = new_param(
            g,
            &format!("offset_{}", ident(&o.name)),
            values[0],
            &o.unit,
            &format!("offset of the sensor of {} {}", o.name, added(c)),
        )?;
        g.set_output(
            &o.name,
            Measured::Expression(Expr::Add(vec![signal, Expr::Param(b)])),
        )?;
        Ok(Vec::new())
    }

    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        all_zero(c)
    }
}

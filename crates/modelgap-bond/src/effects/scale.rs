//! `scale@<output>`: a sensor that reads a constant factor off — a
//! tachometer's or an encoder's constant mis-set, a current shunt off its
//! nominal value, an amplifier's gain: the output is `k` times the measured
//! variable. Built as the output's expression (`k · y`), so it adds no state
//! and costs nothing in the simulation.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::def::EffectDef;
use super::edit::{added, bad, ident, new_param};
use super::lag::{sensed_output, sensed_outputs, signal_of};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::Measured;
use crate::error::Result;
use crate::expr::Expr;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// A gain on the output at this index of the graph's outputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SensorScale {
    /// Index into [`BondGraph::outputs`].
    pub output: usize,
}

impl SensorScale {
    /// The gain on output `name` of `g`, if it reads a variable.
    pub fn named(g: &BondGraph, name: &str) -> Option<SensorScale> {
        sensed_output(g, name).map(|output| SensorScale { output })
    }
}

impl EffectDef for SensorScale {
    fn offers(g: &BondGraph) -> Vec<SensorScale> {
        sensed_outputs(g)
            .map(|output| SensorScale { output })
            .collect()
    }

    /// `k` from 0.5 to 2, starting at 1 (scale 0.01).
    fn candidate(&self, g: &BondGraph, _scales: &Scales) -> Candidate {
        let o = &g.outputs()[self.output];
        Candidate {
            id: Tag::Scale.id(&o.name),
            name: format!(
                "the sensor of {} reads k times its value (its gain is not one)",
                o.name
            ),
            kind: EffectKind::MissingElement,
            acts_on: o.name.clone(),
            params: vec![EffectParam::new("k_sensor", "1", 1.0, (0.5, 2.0), 0.01)],
        }
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let o = g.outputs()[self.output].clone();
        let signal = signal_of(g, self.output).ok_or_else(|| {
            bad(
                c,
                "",
                format!("output '{}' reads no variable to scale", o.name),
            )
        })?;
        let k = new_param(
            g,
            &format!("k_sensor_{}", ident(&o.name)),
            values[0],
            "1",
            &format!("gain of the sensor of {} {}", o.name, added(c)),
        )?;
        g.set_output(
            &o.name,
            Measured::Expression(Expr::Mul(vec![Expr::Param(k), signal])),
        )?;
        Ok(Vec::new())
    }

    fn vanishing_values(_c: &Candidate) -> Option<Vec<f64>> {
        Some(vec![1.0])
    }
}

//! `clip@<output>`: a sensor that reads no further than its range — an ADC at
//! its rail, an amplifier that saturates, a gauge at the end of its scale: the
//! output is the measured variable held within `[lower, upper]`, the two rails
//! apart (a unipolar sensor's lower rail is never reached). Built as the
//! output's expression (`max(lower, min(y, upper))`), so it adds no state.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::def::EffectDef;
use super::edit::{added, bad, ident, new_param};
use super::lag::{sensed_output, sensed_outputs, signal_of};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::Measured;
use crate::error::Result;
use crate::expr::{Expr, Func};
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// How far past the run's largest magnitude a rail starts, where it clips
/// nothing: the run the scales come from is not the only one the candidate
/// meets (a tighter solver's peak lies a little higher).
const BEYOND: f64 = 1.1;

/// Grid starts of each rail: a rail beyond everything the output reads changes
/// nothing, so a local fit cannot find one from there.
const RAIL_GRID: usize = 5;

/// A sensor range `[lower, upper]` on the output at this index of the graph's outputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SensorClip {
    /// Index into [`BondGraph::outputs`].
    pub output: usize,
}

impl SensorClip {
    /// The range of output `name` of `g`, if it reads a variable.
    pub fn named(g: &BondGraph, name: &str) -> Option<SensorClip> {
        sensed_output(g, name).map(|output| SensorClip { output })
    }
}

impl EffectDef for SensorClip {
    fn offers(g: &BondGraph) -> Vec<SensorClip> {
        sensed_outputs(g)
            .map(|output| SensorClip { output })
            .collect()
    }

    /// `upper` from a twentieth of the largest magnitude the output takes in
    /// the run (the recording's, when there is one) to a tenth past it, where
    /// it does nothing; `lower` the same below zero; five grid starts each.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let o = &g.outputs()[self.output];
        let peak = scales.output_peak(&o.name);
        let rail = |name: &str, start: f64, bounds: (f64, f64)| {
            EffectParam::new(name, &o.unit, start, bounds, 0.1 * peak).with_grid(RAIL_GRID)
        };
        Candidate {
            id: Tag::Clip.id(&o.name),
            name: format!(
                "the sensor of {} clips (it reads nothing beyond its range)",
                o.name
            ),
            kind: EffectKind::MissingElement,
            acts_on: o.name.clone(),
            params: vec![
                rail("upper", BEYOND * peak, (0.05 * peak, BEYOND * peak)),
                rail("lower", -BEYOND * peak, (-BEYOND * peak, -0.05 * peak)),
            ],
        }
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let o = g.outputs()[self.output].clone();
        let signal = signal_of(g, self.output).ok_or_else(|| {
            bad(
                c,
                "",
                format!("output '{}' reads no variable to clip", o.name),
            )
        })?;
        let mut rail = |which: &str, value: f64| {
            new_param(
                g,
                &format!("{which}_{}", ident(&o.name)),
                value,
                &o.unit,
                &format!("{which} rail of the sensor of {} {}", o.name, added(c)),
            )
        };
        let upper = rail("upper", values[0])?;
        let lower = rail("lower", values[1])?;
        let within = Expr::Call(
            Func::Max,
            vec![
                Expr::Param(lower),
                Expr::Call(Func::Min, vec![signal, Expr::Param(upper)]),
            ],
        );
        g.set_output(&o.name, Measured::Expression(within))?;
        Ok(Vec::new())
    }

    /// Both rails at the ends of the run's range: nothing clipped.
    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        Some(vec![c.params[0].upper, c.params[1].lower])
    }
}

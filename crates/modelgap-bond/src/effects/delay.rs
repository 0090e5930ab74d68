//! `delay@<output>`: a sensor that reports late — a fieldbus, a sample-and-send
//! cycle, a transport line: the output is the measured variable a time `d`
//! ago, any fraction of a sample. Built as the first-order Padé all-pass
//! `(1 − s d/2) / (1 + s d/2) = 2 / (1 + s d/2) − 1`: twice a first-order lag
//! of `d/2` (the signal elements of [`lag`](super::SensorLag)) minus the
//! variable itself. One new state; exact in gain at every frequency and in
//! phase while the signal changes little within `d`.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::def::EffectDef;
use super::edit::{added, bad, ident, new_param};
use super::lag::{lag_stage, sensed_output, sensed_outputs, signal_of};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::Measured;
use crate::error::Result;
use crate::expr::Expr;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// A pure delay in front of the output at this index of the graph's outputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SensorDelay {
    /// Index into [`BondGraph::outputs`].
    pub output: usize,
}

impl SensorDelay {
    /// The delay on output `name` of `g`, if it reads a variable.
    pub fn named(g: &BondGraph, name: &str) -> Option<SensorDelay> {
        sensed_output(g, name).map(|output| SensorDelay { output })
    }
}

impl EffectDef for SensorDelay {
    fn offers(g: &BondGraph) -> Vec<SensorDelay> {
        sensed_outputs(g)
            .map(|output| SensorDelay { output })
            .collect()
    }

    /// `d` from a tenth of the sample interval to fifty intervals (a
    /// delay longer than that is not a sensor's), starting at one interval.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let o = &g.outputs()[self.output];
        let dt = scales.sample_time.filter(|d| *d > 0.0).unwrap_or(1e-3);
        Candidate {
            id: Tag::Delay.id(&o.name),
            name: format!("a delay in the sensor of {} (it reports late)", o.name),
            kind: EffectKind::MissingElement,
            acts_on: o.name.clone(),
            params: vec![EffectParam::new(
                "delay",
                "s",
                dt,
                (0.1 * dt, 50.0 * dt),
                dt,
            )],
        }
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let name = g.outputs()[self.output].name.clone();
        let signal = signal_of(g, self.output).ok_or_else(|| {
            bad(
                c,
                "",
                format!("output '{name}' reads no variable a delay can hold back"),
            )
        })?;
        let d = new_param(
            g,
            &format!("delay_{}", ident(&name)),
            values[0],
            "s",
            &format!("delay of the sensor of {name} {}", added(c)),
        )?;
        let half = Expr::Mul(vec![Expr::Num(0.5), Expr::Param(d)]);
        let node = lag_stage(g, c, &name, signal.clone(), half)?;
        let reading = Expr::Add(vec![
            Expr::Mul(vec![Expr::Num(2.0), Expr::signal(&node, "e")]),
            Expr::Neg(Box::new(signal)),
        ]);
        g.set_output(&name, Measured::Expression(reading))?;
        Ok(Vec::new())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::library;
    use crate::simulate::{Inputs, SimOptions, simulate, time_grid};

    #[test]
    fn a_delayed_speed_reads_what_the_shaft_did_a_moment_ago() {
        let g = library::dc_motor();
        let d = SensorDelay::named(&g, "omega").unwrap();
        let c = d.candidate(&g, &Scales::of(&g));
        assert_eq!(c.id, "delay@omega");
        let t = time_grid(0.2, 10_000.0);
        let plain = simulate(&g, &Inputs::new(), &t, &SimOptions::default()).unwrap();
        let (late, _) = d.apply(&g, &c, &[2e-3]).unwrap();
        let run = simulate(&late, &Inputs::new(), &t, &SimOptions::default()).unwrap();
        let (w, wd) = (plain.output("omega").unwrap(), run.output("omega").unwrap());
        // 2 ms = 20 samples: the delayed reading follows the true one 20 samples behind,
        // within what a first-order Padé keeps (the start-up is fast here).
        let peak = w.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let worst = (500..w.len())
            .map(|k| (wd[k] - w[k - 20]).abs())
            .fold(0.0_f64, f64::max);
        assert!(worst < 0.01 * peak, "{worst} of {peak}");
        let lagged = (500..w.len())
            .map(|k| (wd[k] - w[k]).abs())
            .fold(0.0_f64, f64::max);
        assert!(worst < 0.2 * lagged, "{worst} vs {lagged}");
    }
}

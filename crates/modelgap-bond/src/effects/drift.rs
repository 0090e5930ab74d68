//! `drift@<output>`: a sensor whose zero drifts at a steady rate — a strain
//! gauge or a thermocouple amplifier warming up, an integrating sensor's
//! bias, a level gauge settling: the output is the measured variable plus
//! `d t`, `t` the recording's own time (from its zero: the halves a law is
//! held out on keep their times, so the drift is one law on both). Built as
//! the output's expression, so it adds no state and costs nothing in the
//! simulation; a zero that is off at the start as well (or a recording
//! whose clock does not start at 0) is this with
//! [`offset`](super::SensorOffset) beside it.

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

/// A steady drift of the output at this index of the graph's outputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SensorDrift {
    /// Index into [`BondGraph::outputs`].
    pub output: usize,
}

impl SensorDrift {
    /// The drift of output `name` of `g`, if it reads a variable.
    pub fn named(g: &BondGraph, name: &str) -> Option<SensorDrift> {
        sensed_output(g, name).map(|output| SensorDrift { output })
    }
}

impl EffectDef for SensorDrift {
    fn offers(g: &BondGraph) -> Vec<SensorDrift> {
        sensed_outputs(g)
            .map(|output| SensorDrift { output })
            .collect()
    }

    /// `d` within ± the largest value the output takes in the run over the
    /// run's length (a drift of the whole reading at most), starting at 0,
    /// scale a hundredth of that.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let o = &g.outputs()[self.output];
        let peak = scales.output_peak(&o.name);
        let length = scales.duration.filter(|d| *d > 0.0).unwrap_or(1.0);
        let rate = peak / length;
        Candidate {
            id: Tag::Drift.id(&o.name),
            name: format!(
                "a drift in the sensor of {} (its zero moves at a steady rate)",
                o.name
            ),
            kind: EffectKind::MissingElement,
            acts_on: o.name.clone(),
            params: vec![EffectParam::new(
                "drift",
                format!("({})/s", o.unit),
                0.0,
                (-rate, rate),
                0.01 * rate,
            )],
        }
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let o = g.outputs()[self.output].clone();
        let signal = signal_of(g, self.output).ok_or_else(|| {
            bad(
                c,
                "",
                format!("output '{}' reads no variable to drift", o.name),
            )
        })?;
        let d = new_param(
            g,
            &format!("drift_{}", ident(&o.name)),
            values[0],
            &format!("({})/s", o.unit),
            &format!("drift of the sensor of {} {}", o.name, added(c)),
        )?;
        g.set_output(
            &o.name,
            Measured::Expression(Expr::Add(vec![
                signal,
                Expr::Mul(vec![Expr::Param(d), Expr::Time]),
            ])),
        )?;
        Ok(Vec::new())
    }

    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        all_zero(c)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // in tests, a panic is a failure

    use super::*;
    use crate::library;
    use crate::simulate::{Inputs, SimOptions, simulate, time_grid};

    #[test]
    fn a_drifting_speed_sensor_reads_the_speed_plus_its_rate_times_the_time() {
        let g = library::dc_motor();
        let d = SensorDrift::named(&g, "omega").unwrap();
        let c = d.candidate(&g, &Scales::of(&g));
        assert_eq!(c.id, "drift@omega");
        let t = time_grid(0.5, 1000.0);
        let opts = SimOptions::default();
        let plain = simulate(&g, &Inputs::new(), &t, &opts).unwrap();
        let (drifted, _) = d.apply(&g, &c, &[0.4]).unwrap();
        let run = simulate(&drifted, &Inputs::new(), &t, &opts).unwrap();
        let (w0, w1) = (plain.output("omega").unwrap(), run.output("omega").unwrap());
        for k in [0, 100, 499] {
            let want = w0[k] + 0.4 * t[k];
            assert!((w1[k] - want).abs() < 1e-5 * want.abs().max(1.0), "{k}");
        }
        // The current is untouched (to the solver's tolerance: a reading that depends on
        // the time is not integrated exactly): the sensor drifts, not the motor.
        let (i0, i1) = (plain.output("i").unwrap(), run.output("i").unwrap());
        let apart = (i0.iter().zip(i1)).fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(apart < 1e-6 * 10.0, "{apart}");
        let mut bad = c.clone();
        bad.id = "drift@nowhere".into();
        let err = crate::effects::BondEffect::from_candidate(&bad, &g).unwrap_err();
        assert!(err.to_string().contains("no output 'nowhere'"), "{err}");
    }
}

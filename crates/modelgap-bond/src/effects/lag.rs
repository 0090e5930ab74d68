//! `lag@<output>`: a sensor that lags — a speed read through a filter, a
//! thermocouple in its sheath, a pressure through a thin line: the output is
//! the measured variable `y` passed through a first-order lag `τ ẏ_m = y − y_m`.
//!
//! Built as bond-graph signal elements in front of the output: a modulated
//! flow source `MSf` whose flow is `y` (it reads the output's variable as a
//! signal and feeds no power back into the plant), a 0-junction, a C of
//! capacity `τ` and an R with `f = e`, so the 0-junction's effort obeys
//! `τ ė = y − e`; the output then reads that effort. One new state.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::def::EffectDef;
use super::edit::{added, bad, ident, law, new_param};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{Element, ElementKind, Law, Measured};
use crate::error::Result;
use crate::expr::Expr;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// A first-order lag in front of the output at this index of the graph's outputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SensorLag {
    /// Index into [`BondGraph::outputs`].
    pub output: usize,
}

impl SensorLag {
    /// The lag on output `name` of `g`, if it has one whose variable reads as a signal.
    pub fn named(g: &BondGraph, name: &str) -> Option<SensorLag> {
        sensed_output(g, name).map(|output| SensorLag { output })
    }
}

/// The index of output `name` of `g`, if it reads a variable a sensor effect
/// can act on ([`signal_of`]).
pub(super) fn sensed_output(g: &BondGraph, name: &str) -> Option<usize> {
    let output = g.outputs().iter().position(|o| o.name == name)?;
    signal_of(g, output).map(|_| output)
}

/// Every output of `g` that reads a variable a sensor effect can act on.
pub(super) fn sensed_outputs(g: &BondGraph) -> impl Iterator<Item = usize> + '_ {
    (0..g.outputs().len()).filter(move |&i| signal_of(g, i).is_some())
}

/// The output's variable as a signal expression (`spring.q`, `tank.e`), or
/// its own expression.
pub(super) fn signal_of(g: &BondGraph, output: usize) -> Option<Expr> {
    let o = g.outputs().get(output)?;
    match &o.measured {
        Measured::Effort(x) => Some(Expr::signal(x, "e")),
        Measured::Flow(x) => Some(Expr::signal(x, "f")),
        Measured::State(x) => {
            let var = match g.element(g.find(x)?).kind {
                ElementKind::I => "p",
                ElementKind::C => "q",
                _ => return None,
            };
            Some(Expr::signal(x, var))
        }
        Measured::Expression(e) => Some(e.clone()),
    }
}

impl EffectDef for SensorLag {
    fn offers(g: &BondGraph) -> Vec<SensorLag> {
        sensed_outputs(g)
            .map(|output| SensorLag { output })
            .collect()
    }

    /// `τ` from a tenth of the sample interval to a fifth of the recording,
    /// starting at one sample interval (scale the same); without a recording
    /// the interval and length of the model's own start-up.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let o = &g.outputs()[self.output];
        let dt = scales.sample_time.filter(|d| *d > 0.0).unwrap_or(1e-3);
        let length = scales.duration.filter(|d| *d > dt).unwrap_or(1000.0 * dt);
        Candidate {
            id: Tag::Lag.id(&o.name),
            name: format!("a lag in the sensor of {} (first order)", o.name),
            kind: EffectKind::MissingElement,
            acts_on: o.name.clone(),
            params: vec![EffectParam::new(
                "tau",
                "s",
                dt,
                (0.1 * dt, (0.2 * length).max(dt)),
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
                format!("output '{name}' reads no variable a lag can follow"),
            )
        })?;
        let suffix = ident(&name);
        let tau = new_param(
            g,
            &format!("tau_{suffix}"),
            values[0],
            "s",
            &format!("time constant of the sensor of {name} {}", added(c)),
        )?;
        let node = lag_stage(g, c, &name, signal, Expr::Param(tau))?;
        g.set_output(&name, Measured::Effort(node))?;
        Ok(Vec::new())
    }
}

/// Which end of the plant a lag stage sits at: it names the stage's elements.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Stage {
    /// In front of an output: what its sensor reads.
    Sensor,
    /// Behind a driven source: what its actuator delivers.
    Actuator,
}

/// Adds the signal elements of a first-order lag of time constant `tau`
/// following `signal` (see the module docs), for the sensor of output `name`;
/// returns the name of the 0-junction whose effort is the lagged signal.
pub(super) fn lag_stage(
    g: &mut BondGraph,
    c: &Candidate,
    name: &str,
    signal: Expr,
    tau: Expr,
) -> Result<String> {
    lag_stage_at(g, c, Stage::Sensor, name, signal, tau)
}

/// [`lag_stage`] for a sensor or an actuator (`name`: the output, or the source).
pub(super) fn lag_stage_at(
    g: &mut BondGraph,
    c: &Candidate,
    stage: Stage,
    name: &str,
    signal: Expr,
    tau: Expr,
) -> Result<String> {
    let suffix = ident(name);
    // The elements' names, and what the stage's node and source are in words.
    let (role, prefix, source_name, node_text, source_text) = match stage {
        Stage::Sensor => (
            "sensor",
            "",
            format!("sensed_{suffix}"),
            format!("the sensor of {name}: its reading"),
            format!("what the sensor of {name} follows"),
        ),
        Stage::Actuator => (
            "actuator",
            "actuator_",
            format!("commanded_{suffix}"),
            format!("the actuator of {name}: what it delivers"),
            format!("what the actuator of {name} is commanded"),
        ),
    };
    let node_name = format!("{role}_{suffix}");
    let store_name = format!("{prefix}lag_{suffix}");
    let leak_name = format!("{prefix}relax_{suffix}");
    let store_text = format!("the {role}'s lag");
    let leak_text = format!("the {role} relaxing to what it follows");
    let node = g.add(Element::zero(&node_name).described(&node_text))?;
    let mut source = Element::sf(&source_name, "0").described(&source_text);
    source.law = Law::Source(signal);
    let source = g.add(source)?;
    g.bond(source, node)?;
    let mut store = Element::c(&store_name, "1");
    store.law = Law::Linear(tau);
    store.description = store_text;
    let store = g.add(store)?;
    g.bond(node, store)?;
    let leak = g.add(
        Element::nonlinear(&leak_name, ElementKind::R, None, Some(law(c, "e")?))
            .described(&leak_text),
    )?;
    g.bond(node, leak)?;
    Ok(g.element(node).name.clone())
}

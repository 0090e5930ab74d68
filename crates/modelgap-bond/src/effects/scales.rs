//! The model's own scales: effort and flow levels of each junction over a
//! start-up from rest, peak states, the slowest mode.

use std::collections::BTreeMap;

use crate::compiled::CompiledModel;
use crate::element::ElementKind;
use crate::expr::Var;
use crate::graph::{BondGraph, ElementId};
use crate::simulate::{Inputs, Run, SimOptions, simulate_compiled, time_grid};
use crate::state_space::StateSpace;

/// Typical and peak magnitude of a quantity over a start-up.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Level {
    pub(super) typical: f64,
    pub(super) peak: f64,
}

impl Level {
    /// A strength's scale: the typical value within [1e-3, 1e-1] of the peak.
    pub(super) fn strength(self) -> f64 {
        positive_or(
            if self.peak > 0.0 {
                self.typical.clamp(1e-3 * self.peak, 0.1 * self.peak)
            } else {
                self.typical
            },
            1.0,
        )
    }

    /// A flow's scale: the typical value within [1e-3, 1] of the peak.
    pub(super) fn flow(self) -> f64 {
        positive_or(
            if self.peak > 0.0 {
                self.typical.clamp(1e-3 * self.peak, self.peak)
            } else {
                self.typical
            },
            1.0,
        )
    }

    /// The peak, or `fallback` when there is none.
    pub(super) fn peak_or(self, fallback: f64) -> f64 {
        positive_or(self.peak.max(self.typical), fallback)
    }
}

fn positive_or(x: f64, fallback: f64) -> f64 {
    if x.is_finite() && x > 0.0 {
        x
    } else {
        fallback
    }
}

/// A junction's level: the largest magnitude of the effort (or, with
/// `flow`, the flow) on its bonds.
fn level(g: &BondGraph, vars: &BTreeMap<Var, f64>, j: ElementId, flow: bool) -> f64 {
    (g.ports(j).iter())
        .map(|(b, _)| {
            let v = if flow {
                Var::F(b.number())
            } else {
                Var::E(b.number())
            };
            vars.get(&v).copied().unwrap_or(0.0).abs()
        })
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max)
}

/// The elements whose effort and flow levels the scales keep: junctions, sources, and
/// every C (alone on a 1-junction it is a node of its own, `Node::of`).
fn measured_elements(g: &BondGraph) -> Vec<ElementId> {
    (g.element_ids())
        .filter(|&id| {
            let kind = g.element(id).kind;
            kind.is_junction() || kind.is_source() || kind == ElementKind::C
        })
        .collect()
}

/// The model's own scales: per 1-junction effort and flow levels, per storage
/// element the peak state, and the slowest mode's rate (see the
/// [module docs](super) for how they are found). The candidates' scales and
/// bounds come from them.
#[derive(Clone, Debug, Default)]
pub struct Scales {
    effort: BTreeMap<ElementId, Level>,
    flow: BTreeMap<ElementId, Level>,
    pub(super) state_peak: BTreeMap<ElementId, f64>,
    pub(super) slowest_rate: Option<f64>,
    /// The run's sample interval and length (s): the time scales a sensor's
    /// lag is searched between.
    pub(super) sample_time: Option<f64>,
    pub(super) duration: Option<f64>,
    /// Each output's largest magnitude over the run, by name.
    outputs: BTreeMap<String, f64>,
}

impl Scales {
    /// The scales of `g`, from a start-up from rest under its default
    /// inputs; empty (every scale 1) when `g` cannot be simulated.
    pub fn of(g: &BondGraph) -> Scales {
        let mut s = Scales::default();
        let Ok(model) = CompiledModel::new(g) else {
            return s;
        };
        let u = model.input_defaults.clone();
        let ss = StateSpace::of_compiled(&model, None, Some(&u));
        let slowest = ss
            .modes()
            .into_iter()
            .find(|m| m.time_constant.is_finite() && m.time_constant > 0.0);
        s.slowest_rate = slowest.map(|m| m.eigenvalue.norm()).filter(|r| *r > 0.0);
        let horizon = slowest.map_or(1.0, |m| (5.0 * m.time_constant).clamp(1e-3, 1e3));
        let t = time_grid(horizon, 400.0 / horizon);
        let run = simulate_compiled(&model, &Inputs::new(), &t, &SimOptions::default()).ok();
        let steady = model.steady_state(&u, None).ok().or_else(|| {
            run.as_ref()
                .map(|r| r.states.iter().map(|v| *v.last().unwrap_or(&0.0)).collect())
        });
        let junctions = measured_elements(g);
        let level = |vars: &BTreeMap<Var, f64>, j, flow| level(g, vars, j, flow);
        if let Some(x) = &steady {
            let vars = model.variable_values(0.0, x, &u);
            for &j in &junctions {
                s.effort.entry(j).or_default().typical = level(&vars, j, false);
                s.flow.entry(j).or_default().typical = level(&vars, j, true);
            }
        }
        if let Some(run) = &run {
            s.measure(g, &model, run, false);
            s.measure_outputs(run);
        }
        s
    }

    /// Records each output's largest magnitude over `run`.
    fn measure_outputs(&mut self, run: &Run) {
        for (name, values) in run.output_names.iter().zip(&run.outputs) {
            let peak = values
                .iter()
                .filter(|v| v.is_finite())
                .fold(0.0_f64, |a, v| a.max(v.abs()));
            self.outputs.insert(name.clone(), peak);
        }
    }

    /// The largest magnitude output `name` took over the run, or 1 when it was
    /// not measured or stayed at 0: the size a sensor effect's parameters scale with.
    pub(super) fn output_peak(&self, name: &str) -> f64 {
        (self.outputs.get(name).copied())
            .filter(|p| *p > 0.0)
            .unwrap_or(1.0)
    }

    /// The scales of `g` over `run`, a simulation driven by a recording's
    /// inputs (see [`crate::BondModel`]'s candidates for a recording): each
    /// junction's typical effort and flow is its RMS over the run and its
    /// peak the largest magnitude; the slowest mode as in [`Scales::of`]. A
    /// recording overrides the inputs' defaults, so the scales must not
    /// come from them.
    pub fn of_run(g: &BondGraph, run: &Run) -> Scales {
        let mut s = Scales::default();
        let Ok(model) = CompiledModel::new(g) else {
            return s;
        };
        let u = model.input_defaults.clone();
        let ss = StateSpace::of_compiled(&model, None, Some(&u));
        s.slowest_rate = (ss.modes().into_iter())
            .find(|m| m.time_constant.is_finite() && m.time_constant > 0.0)
            .map(|m| m.eigenvalue.norm())
            .filter(|r| *r > 0.0);
        s.measure(g, &model, run, true);
        s.measure_outputs(run);
        s
    }

    /// Peaks of every junction's effort and flow over `run` (and, with
    /// `typical`, their RMS as the typical level), and each storage
    /// element's peak state.
    fn measure(&mut self, g: &BondGraph, model: &CompiledModel, run: &Run, typical: bool) {
        if let (Some(first), Some(last)) = (run.t.first(), run.t.last())
            && run.t.len() > 1
            && last > first
        {
            self.duration = Some(last - first);
            self.sample_time = Some((last - first) / (run.t.len() - 1) as f64);
        }
        let junctions = measured_elements(g);
        let level = |vars: &BTreeMap<Var, f64>, j, flow| level(g, vars, j, flow);
        let n = model.n_states();
        let mut x = vec![0.0; n];
        let mut u: Vec<f64> = model.input_defaults.clone();
        let mut squares: BTreeMap<(ElementId, bool), f64> = BTreeMap::new();
        for (k, &tk) in run.t.iter().enumerate() {
            for (xi, col) in x.iter_mut().zip(&run.states) {
                *xi = col[k];
            }
            for (name, col) in run.input_names.iter().zip(&run.inputs) {
                if let Some(j) = model.input_names.iter().position(|m| m == name) {
                    u[j] = col[k];
                }
            }
            let vars = model.variable_values(tk, &x, &u);
            for &j in &junctions {
                let (e, f) = (level(&vars, j, false), level(&vars, j, true));
                let le = self.effort.entry(j).or_default();
                le.peak = le.peak.max(e);
                let lf = self.flow.entry(j).or_default();
                lf.peak = lf.peak.max(f);
                *squares.entry((j, false)).or_default() += e * e;
                *squares.entry((j, true)).or_default() += f * f;
            }
        }
        if typical && !run.t.is_empty() {
            for ((j, flow), sum) in squares {
                let rms = (sum / run.t.len() as f64).sqrt();
                let level = if flow {
                    &mut self.flow
                } else {
                    &mut self.effort
                };
                level.entry(j).or_default().typical = rms;
            }
        }
        for id in g.element_ids() {
            let kind = g.element(id).kind;
            if !kind.is_storage() {
                continue;
            }
            let Some(&(bond, _)) = g.ports(id).first() else {
                continue;
            };
            let name = match kind {
                ElementKind::I => Var::P(bond.number()),
                _ => Var::Q(bond.number()),
            }
            .to_string();
            if let Some(v) = run.state(&name) {
                let peak = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
                self.state_peak.insert(id, peak);
            }
        }
    }

    pub(super) fn effort(&self, j: ElementId) -> Level {
        self.effort.get(&j).copied().unwrap_or_default()
    }

    pub(super) fn flow(&self, j: ElementId) -> Level {
        self.flow.get(&j).copied().unwrap_or_default()
    }
}

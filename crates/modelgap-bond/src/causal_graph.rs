//! The causal graph: variables as nodes, causal dependencies as signed
//! edges labelled with the parameters they carry, integrating edges where a
//! storage element integrates its input (`ṗ3 → p3`).
//!
//! Signs are those of the partial derivatives at an operating point (the
//! model's steady state under its default inputs), so the graph is right for
//! nonlinear laws too. The antecedents/consequents table (the paper's
//! Tables 4–5) is the graph read edge by edge.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::compiled::CompiledModel;
use crate::equations::{EquationKind, Equations};
use crate::error::Result;
use crate::expr::{Expr, Var, linear_form};
use crate::graph::BondGraph;
use crate::qual::Qual;
use crate::simulate::{Inputs, SimOptions, simulate_compiled, time_grid};
use crate::state_space::StateSpace;

/// Values of every variable, parameter and input at an operating point.
#[derive(Clone, Debug, PartialEq)]
pub struct OperatingPoint {
    /// Variable values (efforts, flows, states, derivatives).
    pub vars: BTreeMap<Var, f64>,
    /// Parameter values.
    pub params: BTreeMap<String, f64>,
    /// Input values.
    pub inputs: BTreeMap<String, f64>,
}

impl OperatingPoint {
    /// The steady state under the model's default inputs, by Newton's
    /// method; if there is none, the state reached after ten slowest time
    /// constants from rest.
    ///
    /// # Errors
    /// Causality, equation and simulation errors of the graph.
    pub fn steady(g: &BondGraph) -> Result<OperatingPoint> {
        let model = CompiledModel::new(g)?;
        let u = model.input_defaults.clone();
        let x = match model.steady_state(&u, None) {
            Ok(x) => x,
            Err(_) => {
                // No unique steady state (or Newton failed): run from rest
                // for ten slowest time constants and take where it is.
                let ss = StateSpace::of_compiled(&model, None, Some(&u));
                let tau = ss.modes().first().map_or(1.0, |m| m.time_constant);
                let horizon = if tau.is_finite() {
                    (10.0 * tau).clamp(1e-3, 1e3)
                } else {
                    1.0
                };
                let run = simulate_compiled(
                    &model,
                    &Inputs::new(),
                    &time_grid(horizon, 1000.0 / horizon),
                    &SimOptions::default(),
                )?;
                run.states
                    .iter()
                    .map(|s| *s.last().unwrap_or(&0.0))
                    .collect()
            }
        };
        Ok(OperatingPoint {
            vars: model.variable_values(0.0, &x, &u),
            params: g
                .params()
                .iter()
                .map(|(k, p)| (k.clone(), p.value))
                .collect(),
            inputs: model.input_names.iter().cloned().zip(u).collect(),
        })
    }

    fn eval(&self, e: &Expr, var: Option<(Var, f64)>, param: Option<(&str, f64)>) -> f64 {
        e.eval(&|leaf: &Expr| match leaf {
            Expr::Var(v) => match var {
                Some((w, x)) if w == *v => Some(x),
                _ => self.vars.get(v).copied(),
            },
            Expr::Param(p) => match param {
                Some((q, x)) if q == p => Some(x),
                _ => self.params.get(p).copied(),
            },
            Expr::Input(i) => self.inputs.get(i).copied(),
            Expr::Time => Some(0.0),
            _ => None,
        })
        .unwrap_or(f64::NAN)
    }

    /// Sign of ∂e/∂v at this point (central difference; exact for linear terms).
    fn sign_wrt_var(&self, e: &Expr, v: Var) -> Qual {
        let x = self.vars.get(&v).copied().unwrap_or(0.0);
        let h = 1e-6 * x.abs().max(1e-3);
        let d = (self.eval(e, Some((v, x + h)), None) - self.eval(e, Some((v, x - h)), None))
            / (2.0 * h);
        Qual::of(d, 1e-12 * d.abs().max(1e-300))
    }

    /// Sign of ∂e/∂u for an input `u` at this point.
    fn sign_wrt_input(&self, e: &Expr, input: &str) -> Qual {
        let mut shifted = self.clone();
        let x = self.inputs.get(input).copied().unwrap_or(0.0);
        let h = 1e-6 * x.abs().max(1e-9);
        shifted.inputs.insert(input.to_string(), x + h);
        let hi = shifted.eval(e, None, None);
        shifted.inputs.insert(input.to_string(), x - h);
        let lo = shifted.eval(e, None, None);
        Qual::of(hi - lo, 1e-9 * hi.abs().max(lo.abs()))
    }

    /// Sign of ∂e/∂p at this point.
    fn sign_wrt_param(&self, e: &Expr, p: &str) -> Qual {
        let x = self.params.get(p).copied().unwrap_or(0.0);
        let h = 1e-6 * x.abs().max(1e-9);
        let hi = self.eval(e, None, Some((p, x + h)));
        let lo = self.eval(e, None, Some((p, x - h)));
        let scale = hi.abs().max(lo.abs());
        Qual::of(hi - lo, 1e-9 * scale)
    }
}

/// A causal dependency: `from` is an antecedent of `to`.
#[derive(Clone, Debug, PartialEq)]
pub struct CausalEdge {
    /// Antecedent.
    pub from: Var,
    /// Consequent.
    pub to: Var,
    /// How an increase of `from` moves `to`.
    pub sign: Qual,
    /// True for `ṗn → pn` / `q̇n → qn`: an integration by a storage element.
    pub integrating: bool,
    /// The coefficient as printed on the edge (`R`, `1/L`, `-1`, `dt`).
    pub label: String,
    /// Parameters on this edge (those of the consequent's equation).
    pub params: Vec<String>,
}

/// How a parameter acts: an increase of `param` moves `on` with `sign`.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamEffect {
    /// The parameter.
    pub param: String,
    /// The variable whose equation holds it.
    pub on: Var,
    /// Sign of ∂on/∂param at the operating point.
    pub sign: Qual,
}

/// The causal graph of a bond graph.
#[derive(Clone, Debug, PartialEq)]
pub struct CausalGraph {
    /// Every variable, sorted.
    pub nodes: Vec<Var>,
    /// Every causal dependency, in equation order.
    pub edges: Vec<CausalEdge>,
    /// Where each parameter acts.
    pub param_effects: Vec<ParamEffect>,
    /// Input variables: (input name, the variable its source sets).
    pub inputs: Vec<(String, Var)>,
    /// Measured outputs: (output name, its variable).
    pub measured: Vec<(String, Var)>,
    /// The operating point the signs were taken at.
    pub operating_point: OperatingPoint,
}

impl CausalGraph {
    /// Builds the causal graph at the model's steady state.
    ///
    /// # Errors
    /// Causality, equation and simulation errors of the graph.
    pub fn from_graph(g: &BondGraph, eqs: &Equations) -> Result<CausalGraph> {
        let op = OperatingPoint::steady(g)?;
        Ok(CausalGraph::at(eqs, op))
    }

    /// Builds the causal graph with signs taken at `op`.
    pub fn at(eqs: &Equations, op: OperatingPoint) -> CausalGraph {
        let mut edges = Vec::new();
        let mut param_effects = Vec::new();
        let mut inputs = Vec::new();
        let mut nodes = std::collections::BTreeSet::new();
        // Every rule `target := rhs`: the causal equations, then the outputs
        // given as expressions (a sensor's gain and offset).
        let rules = (eqs
            .equations
            .iter()
            .map(|eq| (eq.target, &eq.rhs, Some(eq.kind))))
        .chain(
            (eqs.outputs.iter()).filter_map(|o| o.definition.as_ref().map(|d| (o.var, d, None))),
        );
        for (target, rhs, kind) in rules {
            nodes.insert(target);
            let params: Vec<String> = rhs.params().into_iter().collect();
            for v in rhs.vars() {
                nodes.insert(v);
                let label = match linear_form(rhs, &[Expr::Var(v)]) {
                    Some((c, _)) => c[0].simplify().to_string(),
                    None => format!("d{target}/d{v}"),
                };
                edges.push(CausalEdge {
                    from: v,
                    to: target,
                    sign: op.sign_wrt_var(rhs, v),
                    integrating: false,
                    label,
                    params: params.clone(),
                });
            }
            for p in &params {
                param_effects.push(ParamEffect {
                    param: p.clone(),
                    on: target,
                    sign: op.sign_wrt_param(rhs, p),
                });
            }
            // The modulus of a modulated element (an MTF's duty cycle) can be
            // faulty like a parameter: it is a candidate under its input's name.
            if kind == Some(EquationKind::Law) {
                for i in rhs.inputs() {
                    let sign = op.sign_wrt_input(rhs, &i);
                    param_effects.push(ParamEffect {
                        param: i,
                        on: target,
                        sign,
                    });
                }
            }
            if kind == Some(EquationKind::Source) {
                for i in rhs.inputs() {
                    inputs.push((i, target));
                }
            }
        }
        for s in &eqs.states {
            nodes.insert(s.var);
            edges.push(CausalEdge {
                from: s.derivative,
                to: s.var,
                sign: Qual::Plus,
                integrating: true,
                label: "dt".to_string(),
                params: Vec::new(),
            });
        }
        let measured = eqs
            .outputs
            .iter()
            .map(|o| (o.name.clone(), o.var))
            .collect();
        CausalGraph {
            nodes: nodes.into_iter().collect(),
            edges,
            param_effects,
            inputs,
            measured,
            operating_point: op,
        }
    }

    /// Edges into `v` (its antecedents).
    pub fn antecedents(&self, v: Var) -> impl Iterator<Item = &CausalEdge> {
        self.edges.iter().filter(move |e| e.to == v)
    }

    /// Edges out of `v` (its consequents).
    pub fn consequents(&self, v: Var) -> impl Iterator<Item = &CausalEdge> {
        self.edges.iter().filter(move |e| e.from == v)
    }

    /// The antecedents/consequents table (the paper's Tables 4–5) as text:
    /// one row per consequent with its antecedents, signs and parameters.
    pub fn table(&self) -> String {
        let mut s = String::from(
            "consequent | antecedents (sign, coefficient) | parameters (effect of an increase)\n",
        );
        let mut targets: Vec<Var> = self.edges.iter().map(|e| e.to).collect();
        targets.dedup();
        let mut seen = std::collections::BTreeSet::new();
        for t in targets {
            if !seen.insert(t) {
                continue;
            }
            let ants: Vec<String> = self
                .antecedents(t)
                .map(|e| format!("{} ({}, {})", e.from, e.sign, e.label))
                .collect();
            let params: Vec<String> = self
                .param_effects
                .iter()
                .filter(|p| p.on == t)
                .map(|p| format!("{}{}", p.param, p.sign))
                .collect();
            let _ = writeln!(s, "{t} | {} | {}", ants.join(", "), params.join(", "));
        }
        s
    }

    /// The graph in Graphviz DOT: variables as ellipses (measured ones
    /// doubled), parameters as boxes, integrating edges dashed and marked `dt`.
    pub fn to_dot(&self) -> String {
        let mut s = String::from(
            "digraph causal {\n  rankdir=LR;\n  node [shape=ellipse, fontname=\"Helvetica\"];\n",
        );
        for v in &self.nodes {
            let measured = self
                .measured
                .iter()
                .find(|(_, m)| m == v)
                .map(|(n, _)| n.as_str());
            match measured {
                Some(n) => {
                    let _ = writeln!(s, "  \"{v}\" [label=\"{v}\\n({n})\", peripheries=2];");
                }
                None => {
                    let _ = writeln!(s, "  \"{v}\";");
                }
            }
        }
        for (name, v) in &self.inputs {
            let _ = writeln!(
                s,
                "  \"in:{name}\" [label=\"{name}\", shape=plaintext];\n  \"in:{name}\" -> \"{v}\";"
            );
        }
        for e in &self.edges {
            let sign = match e.sign {
                Qual::Minus => "-",
                _ => "",
            };
            if e.integrating {
                let _ = writeln!(
                    s,
                    "  \"{}\" -> \"{}\" [label=\"dt\", style=dashed];",
                    e.from, e.to
                );
            } else {
                let label = if e.label == "1" {
                    sign.to_string()
                } else {
                    e.label.clone()
                };
                let _ = writeln!(
                    s,
                    "  \"{}\" -> \"{}\" [label=\"{}\"];",
                    e.from,
                    e.to,
                    label.replace('"', "'")
                );
            }
        }
        let mut params: Vec<&str> = self
            .param_effects
            .iter()
            .map(|p| p.param.as_str())
            .collect();
        params.sort_unstable();
        params.dedup();
        for p in params {
            let _ = writeln!(s, "  \"par:{p}\" [label=\"{p}\", shape=box];");
        }
        for p in &self.param_effects {
            let _ = writeln!(
                s,
                "  \"par:{}\" -> \"{}\" [style=dotted, label=\"{}\"];",
                p.param, p.on, p.sign
            );
        }
        s.push_str("}\n");
        s
    }
}

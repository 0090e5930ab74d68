//! Causal equations derived from a bond graph and its causality, and the
//! state equations in generalized momenta `p` and displacements `q`.
//!
//! Every bond has an effort `e_n` and a flow `f_n`; after causality each
//! is computed by exactly one element: the effort by the element at the
//! end without the causal stroke, the flow by the element with it. The
//! equations are kept in two orders: as derived (junctions first, then
//! each element's law, the paper's order) and sorted for computation.

use std::collections::{BTreeMap, BTreeSet};

use crate::causality::Causality;
use crate::element::{ElementKind, Law, Measured};
use crate::error::{BondError, Result};
use crate::expr::{Expr, Var, linear_form};
use crate::graph::{BondGraph, BondId, Direction, ElementId};

/// What produced an equation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EquationKind {
    /// A source's imposed value.
    Source,
    /// A junction's sum (efforts at a 1, flows at a 0).
    JunctionSum,
    /// A junction's equality of its common variable.
    JunctionEqual,
    /// An element's constitutive law (R, C, I, TF, GY).
    Law,
    /// A state derivative: `ṗn = en` (I) or `q̇n = fn` (C).
    StateDerivative,
}

/// One causal assignment `target := rhs`, with the element it comes from.
#[derive(Clone, Debug, PartialEq)]
pub struct CausalEquation {
    /// The variable computed.
    pub target: Var,
    /// Its expression in other variables, parameters and inputs.
    pub rhs: Expr,
    /// The element whose rule gives the equation.
    pub element: ElementId,
    /// What kind of rule it is.
    pub kind: EquationKind,
}

/// A state of the model: the momentum of an I or displacement of a C in integral causality.
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    /// `p_n` or `q_n`.
    pub var: Var,
    /// `ṗ_n` or `q̇_n`.
    pub derivative: Var,
    /// The storage element.
    pub element: ElementId,
    /// Its bond.
    pub bond: BondId,
}

/// A measured output resolved to a variable of the graph.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputVar {
    /// Output name (`i`, `omega`).
    pub name: String,
    /// The variable it reads: a bond variable or state, or [`Var::Y`] for an
    /// output given as an expression.
    pub var: Var,
    /// For an output given as an expression, the expression in bond
    /// variables, states, parameters, inputs and `t` that computes
    /// [`OutputVar::var`].
    pub definition: Option<Expr>,
}

/// The causal equations of a bond graph.
#[derive(Clone, Debug, PartialEq)]
pub struct Equations {
    /// Equations in derivation order (junctions, then element laws, as the paper prints them).
    pub equations: Vec<CausalEquation>,
    /// Indices into `equations` in an order where every right-hand side is known.
    pub order: Vec<usize>,
    /// States, in element order.
    pub states: Vec<State>,
    /// Input names, in the graph's order.
    pub inputs: Vec<String>,
    /// Measured outputs.
    pub outputs: Vec<OutputVar>,
}

impl Equations {
    /// Derives the causal equations.
    ///
    /// # Errors
    /// [`BondError::DerivativeCausality`] when a storage element is in derivative
    /// causality, [`BondError::NonInvertibleLaw`] when a nonlinear R is given only
    /// for the other causality, [`BondError::AlgebraicLoop`] naming the bonds of
    /// the loop, [`BondError::BadOutput`] for an output with no variable.
    pub fn derive(g: &BondGraph, c: &Causality) -> Result<Equations> {
        c.require_integral(g)?;
        let mut equations = Vec::new();
        let mut states = Vec::new();
        // Junctions first, then sources, then the other elements, each in element order.
        let ids: Vec<ElementId> = g.element_ids().collect();
        for &id in &ids {
            if g.element(id).kind.is_junction() {
                junction_equations(g, c, id, &mut equations);
            }
        }
        for &id in &ids {
            let kind = g.element(id).kind;
            if kind.is_junction() {
                continue;
            }
            element_equations(g, c, id, &mut equations, &mut states)?;
        }
        // Signals (another element's variable read by a law) become the
        // variables that causality gave them.
        for eq in &mut equations {
            eq.rhs = resolve_signals(g, c, &eq.rhs, &g.element(eq.element).name)?;
        }
        let inputs: Vec<String> = g.inputs().keys().cloned().collect();
        let outputs = resolve_outputs(g, c)?;
        let order = sort(g, &equations, &states)?;
        Ok(Equations {
            equations,
            order,
            states,
            inputs,
            outputs,
        })
    }

    /// The equation that computes `var`, if any.
    pub fn defining(&self, var: Var) -> Option<&CausalEquation> {
        self.equations.iter().find(|e| e.target == var)
    }

    /// `var` expressed in states, inputs and parameters only, by substituting
    /// the causal equations (simplified).
    pub fn substituted(&self, var: Var) -> Expr {
        let defs: BTreeMap<Var, &Expr> = (self.equations.iter().map(|e| (e.target, &e.rhs)))
            .chain((self.outputs.iter()).filter_map(|o| o.definition.as_ref().map(|d| (o.var, d))))
            .collect();
        substitute(&Expr::Var(var), &defs).simplify()
    }

    /// The state variables as expressions (`p3`, `p8`).
    pub fn state_exprs(&self) -> Vec<Expr> {
        self.states.iter().map(|s| Expr::Var(s.var)).collect()
    }

    /// The inputs as expressions.
    pub fn input_exprs(&self) -> Vec<Expr> {
        self.inputs.iter().map(|s| Expr::Input(s.clone())).collect()
    }

    /// The symbolic state-space form `ẋ = A x + B u`, `y = C x + D u` when the
    /// model is linear in its states and inputs (coefficients may be
    /// expressions of parameters); `None` otherwise.
    pub fn symbolic_state_space(&self) -> Option<SymbolicStateSpace> {
        let mut vars = self.state_exprs();
        vars.extend(self.input_exprs());
        let n = self.states.len();
        let split = |rows: Vec<Vec<Expr>>| -> (Vec<Vec<Expr>>, Vec<Vec<Expr>>) {
            rows.into_iter()
                .map(|r| {
                    let (a, b) = r.split_at(n);
                    (a.to_vec(), b.to_vec())
                })
                .unzip()
        };
        let mut dyn_rows = Vec::new();
        for s in &self.states {
            let (coeffs, rest) = linear_form(&self.substituted(s.derivative), &vars)?;
            if !is_zero(&rest) {
                return None;
            }
            dyn_rows.push(coeffs);
        }
        let mut out_rows = Vec::new();
        for o in &self.outputs {
            let (coeffs, rest) = linear_form(&self.substituted(o.var), &vars)?;
            if !is_zero(&rest) {
                return None;
            }
            out_rows.push(coeffs);
        }
        let (a, b) = split(dyn_rows);
        let (c, d) = split(out_rows);
        Some(SymbolicStateSpace {
            states: self.states.iter().map(|s| s.var).collect(),
            inputs: self.inputs.clone(),
            outputs: self.outputs.iter().map(|o| o.name.clone()).collect(),
            a,
            b,
            c,
            d,
        })
    }

    /// All parameter names the equations and the outputs use.
    pub fn params(&self) -> BTreeSet<String> {
        (self.equations.iter().map(|e| &e.rhs))
            .chain(self.outputs.iter().filter_map(|o| o.definition.as_ref()))
            .flat_map(Expr::params)
            .collect()
    }
}

/// `ẋ = A x + B u`, `y = C x + D u` with symbolic entries.
#[derive(Clone, Debug, PartialEq)]
pub struct SymbolicStateSpace {
    /// State variables (`p3`, `p8`).
    pub states: Vec<Var>,
    /// Input names.
    pub inputs: Vec<String>,
    /// Output names.
    pub outputs: Vec<String>,
    /// A, rows by state derivative.
    pub a: Vec<Vec<Expr>>,
    /// B, rows by state derivative.
    pub b: Vec<Vec<Expr>>,
    /// C, rows by output.
    pub c: Vec<Vec<Expr>>,
    /// D, rows by output.
    pub d: Vec<Vec<Expr>>,
}

fn is_zero(e: &Expr) -> bool {
    matches!(e.simplify(), Expr::Num(v) if v == 0.0)
}

fn substitute(e: &Expr, defs: &BTreeMap<Var, &Expr>) -> Expr {
    e.substitute_vars(|v| match v {
        Var::P(_) | Var::Q(_) => None,
        _ => defs.get(&v).map(|d| substitute(d, defs)),
    })
}

fn sum_expr(terms: Vec<(f64, Var)>) -> Expr {
    let mut parts = Vec::new();
    for (sign, v) in terms {
        if sign > 0.0 {
            parts.push(Expr::Var(v));
        } else {
            parts.push(Expr::Neg(Box::new(Expr::Var(v))));
        }
    }
    if parts.len() == 1 {
        parts.pop().unwrap_or(Expr::Num(0.0))
    } else if parts.is_empty() {
        Expr::Num(0.0)
    } else {
        Expr::Add(parts)
    }
}

/// The bond that imposes a junction's common variable.
pub fn strong_bond(g: &BondGraph, c: &Causality, junction: ElementId) -> Option<BondId> {
    let zero = g.element(junction).kind == ElementKind::Zero;
    g.ports(junction)
        .into_iter()
        .map(|(b, _)| b)
        .find(|&b| c.receives_effort(b, junction) == zero)
}

fn junction_equations(g: &BondGraph, c: &Causality, id: ElementId, out: &mut Vec<CausalEquation>) {
    let zero = g.element(id).kind == ElementKind::Zero;
    let ports = g.ports(id);
    let Some(s) = strong_bond(g, c, id) else {
        return;
    };
    let s_sign = ports
        .iter()
        .find(|p| p.0 == s)
        .map(|p| p.1.sign())
        .unwrap_or(1.0);
    type VarOf = fn(u32) -> Var;
    let (sum_var, eq_var): (VarOf, VarOf) = if zero {
        (Var::F, Var::E)
    } else {
        (Var::E, Var::F)
    };
    // The sum: the strong bond's summed variable from the others.
    let terms = ports
        .iter()
        .filter(|(b, _)| *b != s)
        .map(|(b, d)| (-s_sign * d.sign(), sum_var(b.number())))
        .collect();
    out.push(CausalEquation {
        target: sum_var(s.number()),
        rhs: sum_expr(terms),
        element: id,
        kind: EquationKind::JunctionSum,
    });
    for (b, _) in &ports {
        if *b != s {
            out.push(CausalEquation {
                target: eq_var(b.number()),
                rhs: Expr::Var(eq_var(s.number())),
                element: id,
                kind: EquationKind::JunctionEqual,
            });
        }
    }
}

/// Binds a law's own names (`e`, `f`, `p`, `q`) to its bond's variables;
/// signals (`Tank1.q`) are left for [`resolve_signals`].
fn bind(e: &Expr, bond: BondId) -> Expr {
    let n = bond.number();
    e.map(&mut |x| match x {
        Expr::Local(name) => Some(Expr::Var(match name.as_str() {
            "e" => Var::E(n),
            "f" => Var::F(n),
            "p" => Var::P(n),
            "q" => Var::Q(n),
            _ => return None,
        })),
        _ => None,
    })
}

/// The variable `which` (`e`, `f`, `p`, `q`) of an element: a one-port's
/// bond effort or flow, a junction's common effort (0) or flow (1), an I's
/// momentum, a C's displacement. `None` when the element has no such single
/// variable (a two-port, a 1-junction's effort, a resistor's state).
pub fn element_var(g: &BondGraph, c: &Causality, id: ElementId, which: &str) -> Option<Var> {
    let el = g.element(id);
    let bond = if el.kind.is_junction() {
        strong_bond(g, c, id)?
    } else if el.kind.is_two_port() {
        return None;
    } else {
        g.ports(id).first()?.0
    };
    let n = bond.number();
    match (which, el.kind) {
        ("e", ElementKind::One) | ("f", ElementKind::Zero) => None,
        ("e", _) => Some(Var::E(n)),
        ("f", _) => Some(Var::F(n)),
        ("p", ElementKind::I) => Some(Var::P(n)),
        ("q", ElementKind::C) => Some(Var::Q(n)),
        _ => None,
    }
}

/// Replaces every signal (`Tank1.q`) in `e` by the variable it names.
///
/// # Errors
/// [`BondError::BadLaw`] naming `reader` (the element or output whose law
/// reads the signal) when the element is unknown or has no such variable.
pub fn resolve_signals(g: &BondGraph, c: &Causality, e: &Expr, reader: &str) -> Result<Expr> {
    let mut error = None;
    let out = e.map(&mut |x| {
        let Expr::Local(name) = x else { return None };
        let (element, which) = crate::expr::split_signal(name)?;
        let var = g.find(element).and_then(|id| element_var(g, c, id, which));
        if var.is_none() && error.is_none() {
            error = Some(BondError::BadLaw {
                element: reader.to_string(),
                detail: format!("reads the signal '{name}', which names no variable of the model"),
            });
        }
        var.map(Expr::Var)
    });
    match error {
        Some(err) => Err(err),
        None => Ok(out),
    }
}

fn element_equations(
    g: &BondGraph,
    c: &Causality,
    id: ElementId,
    out: &mut Vec<CausalEquation>,
    states: &mut Vec<State>,
) -> Result<()> {
    let el = g.element(id);
    let ports = g.ports(id);
    let mut push = |target: Var, rhs: Expr, kind: EquationKind| {
        out.push(CausalEquation {
            target,
            rhs: g.resolved(&rhs),
            element: id,
            kind,
        });
    };
    let div = |a: Expr, b: Expr| Expr::Div(Box::new(a), Box::new(b));
    let mul = |a: Expr, b: Expr| Expr::Mul(vec![a, b]);
    let v = |x: Var| Expr::Var(x);
    match (el.kind, &el.law) {
        (ElementKind::Se, Law::Source(value)) => {
            push(
                Var::E(ports[0].0.number()),
                value.clone(),
                EquationKind::Source,
            );
        }
        (ElementKind::Sf, Law::Source(value)) => {
            push(
                Var::F(ports[0].0.number()),
                value.clone(),
                EquationKind::Source,
            );
        }
        (ElementKind::R, law) => {
            let b = ports[0].0;
            let n = b.number();
            let conductance = c.receives_effort(b, id);
            match (law, conductance) {
                (Law::Linear(r), false) => {
                    push(Var::E(n), mul(r.clone(), v(Var::F(n))), EquationKind::Law)
                }
                (Law::Linear(r), true) => {
                    push(Var::F(n), div(v(Var::E(n)), r.clone()), EquationKind::Law)
                }
                (
                    Law::Nonlinear {
                        effort: Some(e), ..
                    },
                    false,
                ) => push(Var::E(n), bind(e, b), EquationKind::Law),
                (Law::Nonlinear { flow: Some(f), .. }, true) => {
                    push(Var::F(n), bind(f, b), EquationKind::Law)
                }
                (_, conductance) => {
                    let (needed, given) = if conductance {
                        ("flow", "effort")
                    } else {
                        ("effort", "flow")
                    };
                    return Err(BondError::NonInvertibleLaw {
                        element: el.name.clone(),
                        needed: needed.to_string(),
                        given: given.to_string(),
                    });
                }
            }
        }
        (ElementKind::C, law) => {
            let b = ports[0].0;
            let n = b.number();
            let rhs = match law {
                Law::Linear(cap) => div(v(Var::Q(n)), cap.clone()),
                Law::Nonlinear {
                    effort: Some(e), ..
                } => bind(e, b),
                _ => unreachable_law(&el.name)?,
            };
            push(Var::E(n), rhs, EquationKind::Law);
            push(Var::Qdot(n), v(Var::F(n)), EquationKind::StateDerivative);
            states.push(State {
                var: Var::Q(n),
                derivative: Var::Qdot(n),
                element: id,
                bond: b,
            });
        }
        (ElementKind::I, law) => {
            let b = ports[0].0;
            let n = b.number();
            let rhs = match law {
                Law::Linear(l) => div(v(Var::P(n)), l.clone()),
                Law::Nonlinear { flow: Some(f), .. } => bind(f, b),
                _ => unreachable_law(&el.name)?,
            };
            push(Var::F(n), rhs, EquationKind::Law);
            push(Var::Pdot(n), v(Var::E(n)), EquationKind::StateDerivative);
            states.push(State {
                var: Var::P(n),
                derivative: Var::Pdot(n),
                element: id,
                bond: b,
            });
        }
        (kind, Law::Linear(m)) if kind.is_two_port() => {
            let (b_in, b_out) = match (ports[0].1, ports[1].1) {
                (Direction::In, _) => (ports[0].0, ports[1].0),
                _ => (ports[1].0, ports[0].0),
            };
            let (i, o) = (b_in.number(), b_out.number());
            let receives_e_in = c.receives_effort(b_in, id);
            if kind.is_transformer() {
                if receives_e_in {
                    push(Var::E(o), mul(m.clone(), v(Var::E(i))), EquationKind::Law);
                    push(Var::F(i), mul(m.clone(), v(Var::F(o))), EquationKind::Law);
                } else {
                    push(Var::E(i), div(v(Var::E(o)), m.clone()), EquationKind::Law);
                    push(Var::F(o), div(v(Var::F(i)), m.clone()), EquationKind::Law);
                }
            } else if receives_e_in {
                push(Var::F(o), div(v(Var::E(i)), m.clone()), EquationKind::Law);
                push(Var::F(i), div(v(Var::E(o)), m.clone()), EquationKind::Law);
            } else {
                push(Var::E(i), mul(m.clone(), v(Var::F(o))), EquationKind::Law);
                push(Var::E(o), mul(m.clone(), v(Var::F(i))), EquationKind::Law);
            }
        }
        _ => unreachable_law(&el.name)?,
    }
    Ok(())
}

fn unreachable_law<T>(name: &str) -> Result<T> {
    Err(BondError::BadLaw {
        element: name.to_string(),
        detail: "its law does not fit its kind".to_string(),
    })
}

fn resolve_outputs(g: &BondGraph, c: &Causality) -> Result<Vec<OutputVar>> {
    let mut out = Vec::new();
    for (k, o) in g.outputs().iter().enumerate() {
        if let Measured::Expression(e) = &o.measured {
            let reader = format!("output '{}'", o.name);
            out.push(OutputVar {
                name: o.name.clone(),
                var: Var::Y(k as u32 + 1),
                definition: Some(g.resolved(&resolve_signals(g, c, e, &reader)?)),
            });
            continue;
        }
        let name = o.measured.element().unwrap_or_default();
        let id = g.require(name, &format!(" in output '{}'", o.name))?;
        let which = match (&o.measured, g.element(id).kind) {
            (Measured::Effort(_), _) => "e",
            (Measured::Flow(_), _) => "f",
            (_, ElementKind::I) => "p",
            _ => "q",
        };
        let Some(var) = element_var(g, c, id, which) else {
            return Err(BondError::BadOutput {
                output: o.name.clone(),
                detail: format!("element '{name}' has no single variable '{which}'"),
            });
        };
        out.push(OutputVar {
            name: o.name.clone(),
            var,
            definition: None,
        });
    }
    Ok(out)
}

/// Orders the equations so that every right-hand side is known when it is
/// evaluated; a cycle is an algebraic loop, reported with its bonds.
fn sort(g: &BondGraph, eqs: &[CausalEquation], states: &[State]) -> Result<Vec<usize>> {
    let mut known: BTreeSet<Var> = states.iter().map(|s| s.var).collect();
    let mut done = vec![false; eqs.len()];
    let mut order = Vec::with_capacity(eqs.len());
    loop {
        let mut progressed = false;
        for (i, eq) in eqs.iter().enumerate() {
            if done[i] {
                continue;
            }
            if eq.rhs.vars().iter().all(|v| known.contains(v)) {
                done[i] = true;
                known.insert(eq.target);
                order.push(i);
                progressed = true;
            }
        }
        if order.len() == eqs.len() {
            return Ok(order);
        }
        if !progressed {
            break;
        }
    }
    // Report the loop: the bonds whose variables wait on each other.
    let all_waiting: Vec<&CausalEquation> = eqs
        .iter()
        .enumerate()
        .filter(|(i, _)| !done[*i])
        .map(|(_, e)| e)
        .collect();
    // Equations that merely wait on the loop (no other waiting equation needs
    // them) are not part of it: drop them until only the loop is left.
    let mut waiting = all_waiting.clone();
    while let Some(i) = waiting.iter().position(|e| {
        !waiting
            .iter()
            .any(|other| other.rhs.vars().contains(&e.target))
    }) {
        waiting.remove(i);
    }
    if waiting.is_empty() {
        waiting = all_waiting;
    }
    let mut bonds = BTreeSet::new();
    let mut elements = BTreeSet::new();
    for e in &waiting {
        if let Var::E(n) | Var::F(n) = e.target {
            bonds.insert(n);
        }
        elements.insert(g.element(e.element).name.clone());
    }
    Err(BondError::AlgebraicLoop {
        bonds: bonds
            .iter()
            .map(|b| b.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        elements: elements.into_iter().collect::<Vec<_>>().join(", "),
    })
}

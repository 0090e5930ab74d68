//! The derived equations compiled to a flat tape: what the simulator and
//! the linearisation evaluate, with no tree walk and no name lookup per step.

use std::collections::BTreeMap;

use crate::causality::assign_causality;
use crate::element::{ElementKind, Law};
use crate::equations::{EquationKind, Equations};
use crate::error::{BondError, Result, num};
use crate::expr::{Expr, Leaf, Tape, TapeBuilder, Var};
use crate::graph::BondGraph;

/// One element law as compiled: where its result lands and what it reads,
/// so that a law that is not finite can be named with its arguments.
#[derive(Clone, Debug)]
struct LawSite {
    /// The element.
    element: String,
    /// Which law (`effort`, `flow`, `parameter`, `modulus`, `value`).
    field: &'static str,
    /// The law as written in the model.
    text: String,
    /// Slot of the variable the law computes.
    target: usize,
    /// What the law reads, as printed (`f`, `m`, `t`), with its slot.
    args: Vec<(String, usize)>,
}

/// A model ready to evaluate: `ẋ = f(t, x, u)` and `y = g(t, x, u)`.
///
/// Slot layout: `[t, x…, u…, bond variables…, temporaries…]`. Parameters are
/// folded into the tape as constants; changing one means compiling again
/// (microseconds).
#[derive(Clone, Debug)]
pub struct CompiledModel {
    tape: Tape,
    n_states: usize,
    n_inputs: usize,
    deriv_slots: Vec<usize>,
    output_slots: Vec<usize>,
    var_slots: Vec<(Var, usize)>,
    /// State names (`p3`, `p8`), in state order.
    pub state_names: Vec<String>,
    /// What each state is (`the momentum of I:L`), in state order.
    pub state_descriptions: Vec<String>,
    /// The storage element of each state, in state order.
    pub state_elements: Vec<String>,
    /// Where simulations start unless told otherwise: the graph's initial
    /// states (0 for those it does not give), in state order.
    pub initial_state: Vec<f64>,
    /// The element laws in evaluation order, to name one that is not finite.
    laws: Vec<LawSite>,
    /// Input names, in input order (the graph's order).
    pub input_names: Vec<String>,
    /// Default value of each input.
    pub input_defaults: Vec<f64>,
    /// Output names, in the graph's order.
    pub output_names: Vec<String>,
    /// True when the equations are linear and time-invariant in states and
    /// inputs (no nonlinear law, no modulated element, no `t`).
    pub is_lti: bool,
    /// True when the state derivatives and outputs are affine in the states
    /// with coefficients that depend on nothing (`ẋ = A x + b(u)`,
    /// `y = C x + d(u)`): inputs may enter nonlinearly (a switch's `m · Vs`)
    /// but never multiply a state. With piecewise-constant inputs (PWM,
    /// zero-order hold) such a model is integrated exactly.
    pub is_state_affine: bool,
}

impl CompiledModel {
    /// Assigns causality, derives the equations and compiles them.
    ///
    /// # Errors
    /// Any error of [`assign_causality`] or [`Equations::derive`].
    pub fn new(g: &BondGraph) -> Result<CompiledModel> {
        let c = assign_causality(g)?;
        let eqs = Equations::derive(g, &c)?;
        CompiledModel::from_equations(g, &eqs)
    }

    /// Compiles already derived equations with the graph's parameter values.
    ///
    /// # Errors
    /// [`BondError::UnknownParameter`] if an equation mentions an undeclared name.
    pub fn from_equations(g: &BondGraph, eqs: &Equations) -> Result<CompiledModel> {
        let n_states = eqs.states.len();
        let n_inputs = eqs.inputs.len();
        let mut slots: BTreeMap<Var, usize> = BTreeMap::new();
        for (i, s) in eqs.states.iter().enumerate() {
            slots.insert(s.var, 1 + i);
        }
        let input_slot: BTreeMap<&str, usize> = eqs
            .inputs
            .iter()
            .enumerate()
            .map(|(i, n)| (n.as_str(), 1 + n_states + i))
            .collect();
        let mut next = 1 + n_states + n_inputs;
        for eq in &eqs.equations {
            slots.entry(eq.target).or_insert_with(|| {
                next += 1;
                next - 1
            });
        }
        for o in eqs.outputs.iter().filter(|o| o.definition.is_some()) {
            slots.insert(o.var, next);
            next += 1;
        }
        let mut builder = TapeBuilder::new(next);
        let mut is_lti = true;
        let mut deps: BTreeMap<Var, Dep> = eqs.states.iter().map(|s| (s.var, Dep::State)).collect();
        // Every assignment in evaluation order: the causal equations, then the outputs given
        // as expressions (after every variable they may read), with the output's name.
        let rules = (eqs.order.iter())
            .map(|&i| (eqs.equations[i].target, &eqs.equations[i].rhs, None))
            .chain((eqs.outputs.iter()).filter_map(|o| {
                (o.definition.as_ref()).map(|d| (o.var, d, Some(o.name.as_str())))
            }));
        for (target, rhs, output) in rules {
            let dst = slots[&target];
            if !affine_in_slots(rhs) {
                is_lti = false;
            }
            let d = dependence(rhs, &deps);
            deps.insert(target, d);
            let unbound = |detail: String| match output {
                Some(name) => BondError::BadOutput {
                    output: name.to_string(),
                    detail,
                },
                None => BondError::BadLaw {
                    element: target.to_string(),
                    detail,
                },
            };
            builder.assign(dst, rhs, &mut |leaf: &Expr| -> Result<Leaf> {
                match leaf {
                    Expr::Param(name) => g.param(name).map(Leaf::Const),
                    Expr::Input(name) => input_slot
                        .get(name.as_str())
                        .map(|&s| Leaf::Slot(s))
                        .ok_or_else(|| BondError::BadInput {
                            input: name.clone(),
                            detail: "is not declared by the model".to_string(),
                        }),
                    Expr::Var(v) => slots.get(v).map(|&s| Leaf::Slot(s)).ok_or_else(|| {
                        unbound(format!("{v} is used before any equation defines it"))
                    }),
                    Expr::Time => Ok(Leaf::Slot(0)),
                    other => Err(unbound(format!(
                        "unbound name {other} in a derived equation"
                    ))),
                }
            })?;
        }
        let tape = builder.finish();
        let deriv_slots = eqs.states.iter().map(|s| slots[&s.derivative]).collect();
        let output_slots = eqs
            .outputs
            .iter()
            .map(|o| slots.get(&o.var).copied())
            .collect::<Option<Vec<_>>>()
            .ok_or_else(|| BondError::BadOutput {
                output: eqs
                    .outputs
                    .iter()
                    .map(|o| o.name.clone())
                    .collect::<Vec<_>>()
                    .join(", "),
                detail: "reads a variable no equation computes".to_string(),
            })?;
        let laws = law_sites(g, eqs, &slots, &input_slot);
        let var_slots = slots.iter().map(|(v, s)| (*v, *s)).collect();
        let is_state_affine = eqs
            .states
            .iter()
            .map(|s| s.derivative)
            .chain(eqs.outputs.iter().map(|o| o.var))
            .all(|v| deps.get(&v).is_some_and(|d| *d <= Dep::State));
        Ok(CompiledModel {
            tape,
            var_slots,
            n_states,
            n_inputs,
            deriv_slots,
            output_slots,
            state_names: eqs.states.iter().map(|s| s.var.to_string()).collect(),
            state_descriptions: eqs
                .states
                .iter()
                .map(|s| {
                    let el = g.element(s.element);
                    let what = if matches!(s.var, Var::P(_)) {
                        "momentum"
                    } else {
                        "displacement"
                    };
                    format!("the {what} of {}:{}", el.kind, el.name)
                })
                .collect(),
            laws,
            state_elements: (eqs.states.iter())
                .map(|s| g.element(s.element).name.clone())
                .collect(),
            initial_state: (eqs.states.iter())
                .map(|s| {
                    let name = &g.element(s.element).name;
                    g.initial().get(name).map_or(0.0, |i| i.value)
                })
                .collect(),
            input_names: eqs.inputs.clone(),
            input_defaults: eqs
                .inputs
                .iter()
                .map(|n| g.inputs().get(n).map_or(0.0, |i| i.default))
                .collect(),
            output_names: eqs.outputs.iter().map(|o| o.name.clone()).collect(),
            is_lti,
            is_state_affine,
        })
    }

    /// Number of states.
    pub fn n_states(&self) -> usize {
        self.n_states
    }

    /// Number of inputs.
    pub fn n_inputs(&self) -> usize {
        self.n_inputs
    }

    /// Number of outputs.
    pub fn n_outputs(&self) -> usize {
        self.output_slots.len()
    }

    /// Number of ops on the tape (a measure of evaluation cost).
    pub fn n_ops(&self) -> usize {
        self.tape.n_ops()
    }

    /// A scratch buffer sized for [`CompiledModel::eval`].
    pub fn scratch(&self) -> Vec<f64> {
        vec![0.0; self.tape.n_slots()]
    }

    /// Evaluates everything at `(t, x, u)`; read results with
    /// [`CompiledModel::read_derivatives`] and [`CompiledModel::read_outputs`].
    #[inline]
    pub fn eval(&self, t: f64, x: &[f64], u: &[f64], scratch: &mut [f64]) {
        debug_assert_eq!(x.len(), self.n_states);
        debug_assert_eq!(u.len(), self.n_inputs);
        scratch[0] = t;
        scratch[1..1 + self.n_states].copy_from_slice(x);
        scratch[1 + self.n_states..1 + self.n_states + self.n_inputs].copy_from_slice(u);
        self.tape.eval(scratch);
    }

    /// The state derivatives after [`CompiledModel::eval`].
    #[inline]
    pub fn read_derivatives(&self, scratch: &[f64], dx: &mut [f64]) {
        for (d, &s) in dx.iter_mut().zip(&self.deriv_slots) {
            *d = scratch[s];
        }
    }

    /// The outputs after [`CompiledModel::eval`].
    #[inline]
    pub fn read_outputs(&self, scratch: &[f64], y: &mut [f64]) {
        for (o, &s) in y.iter_mut().zip(&self.output_slots) {
            *o = scratch[s];
        }
    }

    /// Every bond-graph variable's value at `(t, x, u)` (states, efforts,
    /// flows, derivatives): the operating point the causal graph's signs use.
    pub fn variable_values(&self, t: f64, x: &[f64], u: &[f64]) -> BTreeMap<Var, f64> {
        let mut scratch = self.scratch();
        self.eval(t, x, u, &mut scratch);
        self.var_slots
            .iter()
            .map(|&(v, s)| (v, scratch[s]))
            .collect()
    }

    /// The steady state `f(x, u) = 0` for constant inputs `u`, by Newton's
    /// method with a finite-difference Jacobian from `guess` (zero if `None`).
    ///
    /// # Errors
    /// [`BondError::BadOptions`] when Newton does not converge in 50
    /// iterations or the Jacobian is singular (a model with a free
    /// integrator, e.g. an unloaded mass, has no unique steady state).
    pub fn steady_state(&self, u: &[f64], guess: Option<&[f64]>) -> Result<Vec<f64>> {
        let n = self.n_states;
        let mut x: Vec<f64> = guess.map_or_else(|| vec![0.0; n], <[f64]>::to_vec);
        let mut scratch = self.scratch();
        let mut f = vec![0.0; n];
        let mut f2 = vec![0.0; n];
        let mut jac = nalgebra::DMatrix::zeros(n, n);
        for _ in 0..50 {
            self.eval(0.0, &x, u, &mut scratch);
            self.read_derivatives(&scratch, &mut f);
            let scale: f64 = x.iter().fold(1e-12_f64, |m, v| m.max(v.abs()));
            for j in 0..n {
                let h = 1e-7 * x[j].abs().max(1e-6 * scale).max(1e-4);
                let keep = x[j];
                x[j] = keep + h;
                self.eval(0.0, &x, u, &mut scratch);
                self.read_derivatives(&scratch, &mut f2);
                x[j] = keep;
                for i in 0..n {
                    jac[(i, j)] = (f2[i] - f[i]) / h;
                }
            }
            let rhs = nalgebra::DVector::from_iterator(n, f.iter().map(|v| -v));
            let dx = jac
                .clone()
                .lu()
                .solve(&rhs)
                .ok_or_else(|| BondError::NoSteadyState {
                    reason: "no unique one: the Jacobian is singular".to_string(),
                })?;
            let mut step = 0.0_f64;
            for (xi, d) in x.iter_mut().zip(dx.iter()) {
                *xi += d;
                step = step.max(d.abs() / xi.abs().max(1e-9 * scale.max(1.0)));
            }
            if x.iter().any(|v| !v.is_finite()) {
                break;
            }
            if step < 1e-12 {
                return Ok(x);
            }
        }
        Err(BondError::NoSteadyState {
            reason: "Newton's method did not converge".to_string(),
        })
    }

    /// The error for state `component` (or its derivative) found not finite
    /// at time `t` (s) by a solver: [`BondError::NonFiniteState`] with the
    /// state's name and element.
    pub fn non_finite_state(&self, component: usize, t: f64) -> BondError {
        BondError::NonFiniteState {
            state: self
                .state_names
                .get(component)
                .cloned()
                .unwrap_or_else(|| format!("#{component}")),
            what: self
                .state_descriptions
                .get(component)
                .cloned()
                .unwrap_or_else(|| "unknown".to_string()),
            t,
        }
    }

    /// Checks that every state derivative and output is finite at
    /// `(t, x, u)`; `start` says that this is where a simulation starts (for
    /// the message).
    ///
    /// # Errors
    /// [`BondError::LawNotFinite`] naming the first law (in evaluation
    /// order) that is not finite although what it reads is, with the law
    /// text and its arguments' values; else [`BondError::NonFiniteState`] or
    /// [`BondError::NonFiniteOutput`] for the first derivative or output
    /// that is not finite.
    pub fn check_finite(&self, t: f64, x: &[f64], u: &[f64], start: bool) -> Result<()> {
        let mut scratch = self.scratch();
        self.eval(t, x, u, &mut scratch);
        let bad_state = self
            .deriv_slots
            .iter()
            .zip(x)
            .position(|(&s, xi)| !(scratch[s].is_finite() && xi.is_finite()));
        let bad_output = self
            .output_slots
            .iter()
            .position(|&s| !scratch[s].is_finite());
        if bad_state.is_none() && bad_output.is_none() {
            return Ok(());
        }
        for law in &self.laws {
            let value = scratch[law.target];
            if value.is_finite() || law.args.iter().any(|(_, s)| !scratch[*s].is_finite()) {
                continue;
            }
            let args = law
                .args
                .iter()
                .map(|(name, s)| {
                    let unit = if name == "t" { " s" } else { "" };
                    format!("{name} = {}{unit}", num(scratch[*s]))
                })
                .collect::<Vec<_>>()
                .join(", ");
            let place = if start {
                "at the start".to_string()
            } else {
                format!("at t = {} s", num(t))
            };
            return Err(BondError::LawNotFinite {
                element: law.element.clone(),
                field: law.field.to_string(),
                law: law.text.clone(),
                value,
                point: if args.is_empty() {
                    place
                } else {
                    format!("{place} ({args})")
                },
            });
        }
        match (bad_state, bad_output) {
            (Some(i), _) => Err(self.non_finite_state(i, t)),
            (None, Some(o)) => Err(BondError::NonFiniteOutput {
                output: self.output_names[o].clone(),
                t,
            }),
            (None, None) => Ok(()),
        }
    }

    /// Slot of input `j` in the scratch buffer (for drivers that write inputs in place).
    pub fn input_slot(&self, j: usize) -> usize {
        1 + self.n_states + j
    }
}

/// The element laws of the equations, in evaluation order, with the law
/// text as written and what each reads (an element's own bond variable by
/// its local name, `e`, `f`, `p` or `q`).
fn law_sites(
    g: &BondGraph,
    eqs: &Equations,
    slots: &BTreeMap<Var, usize>,
    input_slot: &BTreeMap<&str, usize>,
) -> Vec<LawSite> {
    let mut out = Vec::new();
    for &i in &eqs.order {
        let eq = &eqs.equations[i];
        if !matches!(eq.kind, EquationKind::Law | EquationKind::Source) {
            continue;
        }
        let Some(&target) = slots.get(&eq.target) else {
            continue;
        };
        let el = g.element(eq.element);
        let produces_effort = matches!(eq.target, Var::E(_) | Var::Pdot(_));
        let (field, law) = match (&el.law, el.kind) {
            (Law::Source(e), ElementKind::Se) => ("effort", e),
            (Law::Source(e), _) => ("flow", e),
            (Law::Linear(e), k) if k.is_two_port() => ("modulus", e),
            (Law::Linear(e), _) => ("parameter", e),
            (Law::Nonlinear { effort, flow }, _) => {
                match (produces_effort, effort.as_ref(), flow.as_ref()) {
                    (true, Some(e), _) => ("effort", e),
                    (false, _, Some(f)) => ("flow", f),
                    (_, Some(e), None) => ("effort", e),
                    (_, None, Some(f)) => ("flow", f),
                    (_, None, None) => continue,
                }
            }
            (Law::None, _) => continue,
        };
        // One-ports name their own bond's variables as the law does.
        let own_bond = match g.ports(eq.element).as_slice() {
            [(b, _)] => Some(b.number()),
            _ => None,
        };
        let mut args = Vec::new();
        for v in eq.rhs.vars() {
            let Some(&slot) = slots.get(&v) else {
                continue;
            };
            let local = match v {
                Var::E(n) if Some(n) == own_bond => "e".to_string(),
                Var::F(n) if Some(n) == own_bond => "f".to_string(),
                Var::P(n) if Some(n) == own_bond => "p".to_string(),
                Var::Q(n) if Some(n) == own_bond => "q".to_string(),
                other => other.to_string(),
            };
            args.push((local, slot));
        }
        for name in eq.rhs.inputs() {
            if let Some(&slot) = input_slot.get(name.as_str()) {
                args.push((name, slot));
            }
        }
        if eq.rhs.depends_on_time() {
            args.push(("t".to_string(), 0));
        }
        out.push(LawSite {
            element: el.name.clone(),
            field,
            text: law.to_string(),
            target,
            args,
        });
    }
    out
}

/// What a variable depends on, from least to most: a constant, inputs only
/// (in any way), states affinely with constant coefficients (plus inputs),
/// or anything else (a state times an input, a nonlinear law, time).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Dep {
    Const,
    Input,
    State,
    Nonlinear,
}

/// The dependence of an expression, given that of the variables it reads.
fn dependence(e: &Expr, vars: &BTreeMap<Var, Dep>) -> Dep {
    let all = |v: &[Expr]| {
        v.iter()
            .map(|x| dependence(x, vars))
            .max()
            .unwrap_or(Dep::Const)
    };
    match e {
        Expr::Num(_) | Expr::Param(_) => Dep::Const,
        Expr::Input(_) => Dep::Input,
        Expr::Var(v) => vars.get(v).copied().unwrap_or(Dep::Nonlinear),
        Expr::Local(_) | Expr::Time => Dep::Nonlinear,
        Expr::Neg(a) => dependence(a, vars),
        Expr::Add(v) => all(v),
        Expr::Mul(v) => {
            let d: Vec<Dep> = v.iter().map(|x| dependence(x, vars)).collect();
            let states = d.iter().filter(|x| **x == Dep::State).count();
            if d.contains(&Dep::Nonlinear) || states > 1 || (states == 1 && d.contains(&Dep::Input))
            {
                Dep::Nonlinear
            } else {
                d.into_iter().max().unwrap_or(Dep::Const)
            }
        }
        Expr::Div(a, b) => match (dependence(a, vars), dependence(b, vars)) {
            (x, Dep::Const) => x,
            (x, Dep::Input) if x <= Dep::Input => Dep::Input,
            _ => Dep::Nonlinear,
        },
        Expr::Pow(a, b) => match dependence(a, vars).max(dependence(b, vars)) {
            x if x <= Dep::Input => x,
            _ => Dep::Nonlinear,
        },
        Expr::Call(_, v) => match all(v) {
            x if x <= Dep::Input => x,
            _ => Dep::Nonlinear,
        },
    }
}

/// True when an expression is affine in its slot leaves (vars, inputs)
/// with constant coefficients: what makes the compiled model LTI.
fn affine_in_slots(e: &Expr) -> bool {
    fn constant(e: &Expr) -> bool {
        match e {
            Expr::Num(_) | Expr::Param(_) => true,
            Expr::Var(_) | Expr::Input(_) | Expr::Local(_) | Expr::Time => false,
            Expr::Neg(a) => constant(a),
            Expr::Add(v) | Expr::Mul(v) => v.iter().all(constant),
            Expr::Div(a, b) | Expr::Pow(a, b) => constant(a) && constant(b),
            Expr::Call(_, v) => v.iter().all(constant),
        }
    }
    match e {
        Expr::Num(_) | Expr::Param(_) | Expr::Var(_) => true,
        // An input is affine, but a source written as a function of time is not LTI.
        Expr::Input(_) => true,
        Expr::Local(_) | Expr::Time => false,
        Expr::Neg(a) => affine_in_slots(a),
        Expr::Add(v) => v.iter().all(affine_in_slots),
        Expr::Mul(v) => {
            let non_const = v.iter().filter(|x| !constant(x)).count();
            non_const <= 1 && v.iter().all(affine_in_slots)
        }
        Expr::Div(a, b) => constant(b) && affine_in_slots(a),
        Expr::Pow(a, b) => constant(a) && constant(b),
        Expr::Call(_, v) => v.iter().all(constant),
    }
}

//! `modelgap bond equations`: the causality, the causal equations in the paper's notation,
//! the numeric state space and its eigenvalues with time constants.

use std::fmt::Write as _;

use anyhow::Context as _;
use clap::Args;
use modelgap::bond::compiled::CompiledModel;
use modelgap::bond::notation::{equations_latex, equations_text};
use modelgap::bond::{BondGraph, Equations, StateSpace, assign_causality};

use super::causality::causality_text;
use super::format::{Align, aligned, matrix, num, unit};
use super::model::{ModelArgs, load, outputs_at, steady_state};

/// Arguments of `modelgap bond equations`.
#[derive(Debug, Args)]
pub struct EquationsArgs {
    #[command(flatten)]
    model: ModelArgs,

    /// Print only the equations, as a LaTeX align* environment
    #[arg(long)]
    latex: bool,
}

/// Prints the equations of the model.
///
/// # Errors
///
/// Model errors, causal conflicts, derivative causality and algebraic loops.
pub fn run(args: &EquationsArgs) -> anyhow::Result<()> {
    let g = load(&args.model)?;
    let c =
        assign_causality(&g).with_context(|| format!("assigning causality to model {}", g.name))?;
    let eqs = Equations::derive(&g, &c)
        .with_context(|| format!("deriving the equations of model {}", g.name))?;
    if args.latex {
        return super::print(&equations_latex(&g, &eqs));
    }
    let mut s = String::new();
    let _ = writeln!(s, "model {}: {}", g.name, g.description);
    s.push('\n');
    s.push_str(&causality_text(&g, &c));
    s.push('\n');
    s.push_str(&equations_text(&g, &eqs));
    s.push('\n');
    s.push_str(&numeric_text(&g, &eqs)?);
    super::print(&s)
}

/// The numeric state space at the default inputs (linearised at the steady state when the
/// model is not linear), the steady state, and the modes.
fn numeric_text(g: &BondGraph, eqs: &Equations) -> anyhow::Result<String> {
    let model = CompiledModel::from_equations(g, eqs)?;
    let u0 = model.input_defaults.clone();
    let mut s = String::new();
    let inputs: Vec<String> = model
        .input_names
        .iter()
        .zip(&u0)
        .map(|(n, v)| {
            // Unit "1" marks a dimensionless input (a duty cycle): nothing to print.
            let unit = g.inputs().get(n).map_or("", |i| i.unit.as_str());
            let unit = if unit == "1" { "" } else { unit };
            format!("{n} = {} {unit}", num(*v)).trim_end().to_owned()
        })
        .collect();
    let steady = steady_state(g, &u0);
    let ss = if model.is_lti {
        let _ = writeln!(
            s,
            "numeric state space (linear model; default inputs {}):",
            inputs.join(", ")
        );
        StateSpace::of_compiled(&model, None, Some(&u0))
    } else {
        let x0 = steady
            .as_ref()
            .map_or_else(|_| vec![0.0; model.n_states()], Clone::clone);
        let _ = writeln!(
            s,
            "numeric state space (model not linear time-invariant: linearised at its steady state under the default inputs {}):",
            inputs.join(", ")
        );
        StateSpace::of_compiled(&model, Some(&x0), Some(&u0))
    };
    let dx: Vec<String> = ss.states.iter().map(|x| format!("d{x}")).collect();
    let blocks = [
        matrix("A", &ss.a, &dx, &ss.states),
        matrix("B", &ss.b, &dx, &ss.inputs),
        matrix("C", &ss.c, &ss.outputs, &ss.states),
        matrix("D", &ss.d, &ss.outputs, &ss.inputs),
    ];
    s.push_str(&blocks.join("\n"));
    match &steady {
        Ok(x) => {
            let y = outputs_at(g, x, &u0)?;
            let units: Vec<&str> = g.outputs().iter().map(|o| unit(&o.unit)).collect();
            let states: Vec<String> = ss
                .states
                .iter()
                .zip(x)
                .map(|(n, v)| format!("{n} = {}", num(*v)))
                .collect();
            let outputs: Vec<String> = ss
                .outputs
                .iter()
                .zip(&y)
                .zip(units.iter().chain(std::iter::repeat(&"")))
                .map(|((n, v), unit)| format!("{n} = {} {unit}", num(*v)).trim_end().to_owned())
                .collect();
            let _ = writeln!(
                s,
                "steady state: {}; outputs {}",
                states.join(", "),
                outputs.join(", ")
            );
        }
        Err(e) => {
            let _ = writeln!(s, "steady state: none ({e})");
        }
    }
    let _ = writeln!(s, "eigenvalues:");
    let mut rows = vec![vec![
        "lambda (1/s)".to_owned(),
        "time constant".to_owned(),
        "frequency".to_owned(),
    ]];
    for m in ss.modes() {
        let l = m.eigenvalue;
        let lambda = if l.im == 0.0 {
            num(l.re)
        } else {
            format!(
                "{} {} {}j",
                num(l.re),
                if l.im < 0.0 { "-" } else { "+" },
                num(l.im.abs())
            )
        };
        let tau = if m.time_constant.is_finite() {
            format!("{} s", num(m.time_constant))
        } else {
            "none (does not decay)".to_owned()
        };
        let freq = if l.im == 0.0 {
            String::new()
        } else {
            format!("{} Hz", num(l.im.abs() / std::f64::consts::TAU))
        };
        rows.push(vec![lambda, tau, freq]);
    }
    s.push_str(&aligned(&rows, 2, &[], Align::Right));
    Ok(s)
}

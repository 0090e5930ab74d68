//! The derived equations printed as text and LaTeX in the paper's notation:
//! junction equations (`ṗ3 = e1 − e2 − e4`, `f1 = f2 = f3 = f4`), then each
//! element's law (`e2 = R f2`, `f3 = p3/L`), then the state equation in
//! matrix form and the outputs.

use std::fmt::Write as _;

use crate::element::ElementKind;
use crate::equations::{CausalEquation, EquationKind, Equations, SymbolicStateSpace};
use crate::expr::{Expr, Var, var_latex};
use crate::graph::BondGraph;

/// One printed line: left-hand sides joined by `=` and a right-hand side.
struct Line {
    lhs: Vec<Var>,
    rhs: Option<Expr>,
}

fn lines(g: &BondGraph, eqs: &Equations) -> Vec<Line> {
    let state_of = |v: Var| -> Option<Var> {
        eqs.states
            .iter()
            .find(|s| match (s.derivative, v) {
                (Var::Pdot(n), Var::E(m)) | (Var::Qdot(n), Var::F(m)) => n == m,
                _ => false,
            })
            .map(|s| s.derivative)
    };
    let mut out = Vec::new();
    // Sources first, then junctions in element order, then laws in element order.
    for eq in eqs
        .equations
        .iter()
        .filter(|e| e.kind == EquationKind::Source)
    {
        out.push(Line {
            lhs: vec![eq.target],
            rhs: Some(eq.rhs.clone()),
        });
    }
    for id in g.element_ids() {
        let el = g.element(id);
        if !el.kind.is_junction() {
            continue;
        }
        let mine: Vec<&CausalEquation> = eqs.equations.iter().filter(|e| e.element == id).collect();
        if let Some(sum) = mine.iter().find(|e| e.kind == EquationKind::JunctionSum) {
            let lhs = match state_of(sum.target) {
                Some(d) => vec![d],
                None => vec![sum.target],
            };
            out.push(Line {
                lhs,
                rhs: Some(sum.rhs.clone()),
            });
        }
        let mut equal: Vec<Var> = g
            .ports(id)
            .iter()
            .map(|(b, _)| {
                if el.kind == ElementKind::One {
                    Var::F(b.number())
                } else {
                    Var::E(b.number())
                }
            })
            .collect();
        equal.sort();
        if equal.len() > 1 {
            out.push(Line {
                lhs: equal,
                rhs: None,
            });
        }
    }
    for eq in eqs.equations.iter().filter(|e| e.kind == EquationKind::Law) {
        out.push(Line {
            lhs: vec![eq.target],
            rhs: Some(eq.rhs.clone()),
        });
    }
    out
}

fn vec_text(items: &[String]) -> String {
    format!("[{}]", items.join("; "))
}

fn matrix_text(m: &[Vec<Expr>]) -> String {
    let rows: Vec<String> = m
        .iter()
        .map(|r| {
            format!(
                "[{}]",
                r.iter()
                    .map(|e| e.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
        .collect();
    format!("[{}]", rows.join(", "))
}

/// The equations as plain text, one per line.
///
/// For the DC motor the causal equations read as the paper's eq. 3–12
/// (`dp3 = e1 - e2 - e4`, `f1 = f2 = f3 = f4`, `e2 = R*f2`, `f3 = p3/L`, …),
/// followed by the state equation (13) and the outputs (14) in matrix form
/// when the model is linear, or substituted state equations otherwise.
pub fn equations_text(g: &BondGraph, eqs: &Equations) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "causal equations:");
    for line in lines(g, eqs) {
        let lhs = line
            .lhs
            .iter()
            .map(|v| v.to_string())
            .collect::<Vec<_>>()
            .join(" = ");
        match line.rhs {
            Some(r) => {
                let _ = writeln!(s, "  {lhs} = {r}");
            }
            None => {
                let _ = writeln!(s, "  {lhs}");
            }
        }
    }
    match eqs.symbolic_state_space() {
        Some(ss) => state_space_text(&mut s, &ss),
        None => {
            let _ = writeln!(s, "state equations:");
            for st in &eqs.states {
                let _ = writeln!(
                    s,
                    "  {} = {}",
                    st.derivative,
                    eqs.substituted(st.derivative)
                );
            }
            let _ = writeln!(s, "outputs:");
            for o in &eqs.outputs {
                let _ = writeln!(s, "  {} = {}", o.name, eqs.substituted(o.var));
            }
        }
    }
    s
}

fn state_space_text(s: &mut String, ss: &SymbolicStateSpace) {
    let x: Vec<String> = ss.states.iter().map(|v| v.to_string()).collect();
    let dx: Vec<String> = ss.states.iter().map(|v| format!("d{v}")).collect();
    let _ = writeln!(s, "state equations:");
    let _ = writeln!(
        s,
        "  {} = {} {} + {} {}",
        vec_text(&dx),
        matrix_text(&ss.a),
        vec_text(&x),
        matrix_text(&ss.b),
        vec_text(&ss.inputs)
    );
    let _ = writeln!(s, "outputs:");
    let d_zero =
        ss.d.iter()
            .flatten()
            .all(|e| matches!(e.simplify(), Expr::Num(v) if v == 0.0));
    let _ = write!(
        s,
        "  {} = {} {}",
        vec_text(&ss.outputs),
        matrix_text(&ss.c),
        vec_text(&x)
    );
    if !d_zero {
        let _ = write!(s, " + {} {}", matrix_text(&ss.d), vec_text(&ss.inputs));
    }
    s.push('\n');
}

fn bmatrix(m: &[Vec<Expr>]) -> String {
    let rows: Vec<String> = m
        .iter()
        .map(|r| {
            r.iter()
                .map(|e| e.to_latex())
                .collect::<Vec<_>>()
                .join(" & ")
        })
        .collect();
    format!(
        "\\begin{{bmatrix}} {} \\end{{bmatrix}}",
        rows.join(" \\\\ ")
    )
}

fn bvector(items: &[String]) -> String {
    format!(
        "\\begin{{bmatrix}} {} \\end{{bmatrix}}",
        items.join(" \\\\ ")
    )
}

fn name_latex(name: &str) -> String {
    Expr::Input(name.to_string()).to_latex()
}

/// The equations as a LaTeX `align*` environment.
pub fn equations_latex(g: &BondGraph, eqs: &Equations) -> String {
    let mut rows = Vec::new();
    for line in lines(g, eqs) {
        let lhs = line
            .lhs
            .iter()
            .map(|v| var_latex(*v))
            .collect::<Vec<_>>()
            .join(" = ");
        rows.push(match line.rhs {
            Some(r) => format!("{lhs} &= {}", r.to_latex()),
            None => format!("& {lhs}"),
        });
    }
    if let Some(ss) = eqs.symbolic_state_space() {
        let x: Vec<String> = ss.states.iter().map(|v| var_latex(*v)).collect();
        let u: Vec<String> = ss.inputs.iter().map(|n| name_latex(n)).collect();
        let dx: Vec<String> = ss
            .states
            .iter()
            .map(|v| {
                var_latex(match v {
                    Var::P(n) => Var::Pdot(*n),
                    Var::Q(n) => Var::Qdot(*n),
                    other => *other,
                })
            })
            .collect();
        rows.push(format!(
            "{} &= {} {} + {} {}",
            bvector(&dx),
            bmatrix(&ss.a),
            bvector(&x),
            bmatrix(&ss.b),
            bvector(&u)
        ));
        let y: Vec<String> = ss.outputs.iter().map(|n| name_latex(n)).collect();
        rows.push(format!(
            "{} &= {} {}",
            bvector(&y),
            bmatrix(&ss.c),
            bvector(&x)
        ));
    } else {
        for st in &eqs.states {
            rows.push(format!(
                "{} &= {}",
                var_latex(st.derivative),
                eqs.substituted(st.derivative).to_latex()
            ));
        }
    }
    format!(
        "\\begin{{align*}}\n{}\n\\end{{align*}}\n",
        rows.join(" \\\\\n")
    )
}

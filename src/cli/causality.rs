//! `modelgap bond causality`: the causal stroke of every bond, the causality of the storage
//! elements, and warnings for derivative causality and algebraic loops.

use std::fmt::Write as _;

use anyhow::Context as _;
use clap::Args;
use modelgap::bond::{BondGraph, Causality, Equations, assign_causality};

use super::format::{Align, aligned};
use super::model::{ModelArgs, load};

/// Arguments of `modelgap bond causality`.
#[derive(Debug, Args)]
pub struct CausalityArgs {
    #[command(flatten)]
    model: ModelArgs,
}

/// Prints the causality of the model.
///
/// # Errors
///
/// Model errors; a causal conflict (two sources imposing on one bond), naming the bond.
pub fn run(args: &CausalityArgs) -> anyhow::Result<()> {
    let g = load(&args.model)?;
    let c =
        assign_causality(&g).with_context(|| format!("assigning causality to model {}", g.name))?;
    let mut text = causality_text(&g, &c);
    // Derivation is where algebraic loops and non-invertible laws show; here they are
    // findings to report, not failures.
    if let Err(e) = Equations::derive(&g, &c) {
        let _ = writeln!(text, "warning: the equations cannot be derived: {e}");
    }
    super::print(&text)
}

/// The causality as text: one line per bond (the stroke `|` drawn at the end that receives
/// the effort), the storage elements' causality, and warnings.
pub fn causality_text(g: &BondGraph, c: &Causality) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "causality (the stroke | sits at the end that receives the effort):"
    );
    let mut rows = vec![vec![
        "bond".to_owned(),
        "power and stroke".to_owned(),
        "effort into".to_owned(),
        "flow into".to_owned(),
    ]];
    for id in g.bond_ids() {
        let bond = g.bond_at(id);
        let from = &g.element(bond.from).name;
        let to = &g.element(bond.to).name;
        let stroke_at_to = c.receives_effort(id, bond.to);
        let drawing = if stroke_at_to {
            format!("{from} --->| {to}")
        } else {
            format!("{from} |---> {to}")
        };
        let (effort_into, flow_into) = if stroke_at_to { (to, from) } else { (from, to) };
        rows.push(vec![
            id.to_string(),
            drawing,
            effort_into.clone(),
            flow_into.clone(),
        ]);
    }
    s.push_str(&aligned(&rows, 2, &[Align::Right], Align::Left));
    let storage: Vec<_> = g
        .element_ids()
        .filter(|&id| g.element(id).kind.is_storage())
        .collect();
    if !storage.is_empty() {
        let _ = writeln!(s, "storage elements:");
        for id in storage {
            let el = g.element(id);
            let bond = g
                .ports(id)
                .first()
                .map_or_else(|| "?".to_owned(), |(b, _)| b.to_string());
            let kind = if c.is_integral(g, id) {
                "integral"
            } else {
                "derivative"
            };
            let _ = writeln!(s, "  {} ({}, bond {bond}): {kind}", el.name, el.kind);
        }
    }
    if !c.derivative.is_empty() {
        let names: Vec<String> = c
            .derivative
            .iter()
            .map(|(e, b)| format!("{} (bond {b})", g.element(*e).name))
            .collect();
        let _ = writeln!(
            s,
            "warning: storage elements in derivative causality: {}; simulation needs integral causality",
            names.join(", ")
        );
    }
    if !c.chosen_r.is_empty() {
        let names: Vec<String> = c
            .chosen_r
            .iter()
            .map(|e| g.element(*e).name.clone())
            .collect();
        let _ = writeln!(
            s,
            "warning: the causality of R elements {} was chosen, not forced: an algebraic loop among R elements",
            names.join(", ")
        );
    }
    if !c.chosen_bonds.is_empty() {
        let bonds: Vec<String> = c.chosen_bonds.iter().map(|b| b.to_string()).collect();
        let _ = writeln!(
            s,
            "warning: nothing fixed the causality of bonds {}; it was chosen arbitrarily",
            bonds.join(", ")
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use modelgap::bond::library;

    use super::*;

    #[test]
    fn dc_motor_strokes_follow_the_paper() {
        let g = library::dc_motor();
        let c = assign_causality(&g).unwrap();
        let text = causality_text(&g, &c);
        // The voltage source imposes the effort on the electrical junction (bond 1), and
        // both inertias are in integral causality.
        assert!(text.contains("V --->| 1e"), "{text}");
        assert!(text.contains("L (I, bond 3): integral"), "{text}");
        assert!(text.contains("J (I, bond 8): integral"), "{text}");
        assert!(!text.contains("warning"), "{text}");
    }
}

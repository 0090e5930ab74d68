//! What the edits of the effect kinds share: errors naming the candidate,
//! fresh names, laws, new parameters and one-ports attached to a junction.

use modelgap_core::Candidate;

use super::Domain;
use crate::element::{Element, ElementKind};
use crate::error::{BondError, Result};
use crate::expr::{Expr, parse};
use crate::graph::{BondGraph, ElementId};

/// An error naming the candidate and the parameter (empty: the candidate as a whole).
pub(super) fn bad(c: &Candidate, param: &str, detail: String) -> BondError {
    BondError::BadEffect {
        candidate: c.id.clone(),
        param: param.to_string(),
        detail,
    }
}

/// `(added effect <id>)`: the end of the description of whatever an edit adds.
pub(super) fn added(c: &Candidate) -> String {
    format!("(added effect {})", c.id)
}

/// A name made of letters, digits and `_` (safe in a law).
pub(super) fn ident(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

/// `base` if neither a parameter nor an input has it, else `base_2`, `base_3`, ….
fn fresh_param(g: &BondGraph, base: &str) -> String {
    let taken = |n: &str| g.params().contains_key(n) || g.inputs().contains_key(n);
    if !taken(base) {
        return base.to_string();
    }
    (2..)
        .map(|k| format!("{base}_{k}"))
        .find(|n| !taken(n))
        .unwrap_or_else(|| base.to_string())
}

/// `base` if no element has it, else `base_2`, `base_3`, ….
pub(super) fn fresh_element(g: &BondGraph, base: &str) -> String {
    if g.find(base).is_none() {
        return base.to_string();
    }
    (2..)
        .map(|k| format!("{base}_{k}"))
        .find(|n| g.find(n).is_none())
        .unwrap_or_else(|| base.to_string())
}

/// Parses a law built by an edit.
pub(super) fn law(c: &Candidate, text: &str) -> Result<Expr> {
    parse(text).map_err(|e| {
        bad(
            c,
            "",
            format!("cannot build the law '{text}': {}", e.message),
        )
    })
}

/// Adds a parameter under a fresh name derived from `base` and returns the name.
pub(super) fn new_param(
    g: &mut BondGraph,
    base: &str,
    value: f64,
    unit: &str,
    description: &str,
) -> Result<String> {
    let name = fresh_param(g, base);
    g.add_param(&name, value, unit, description)?;
    Ok(name)
}

/// Adds a one-port (or a junction) on junction `j`, its bond pointing into it,
/// under a fresh name derived from its own.
pub(crate) fn attach(g: &mut BondGraph, j: ElementId, mut element: Element) -> Result<ElementId> {
    element.name = fresh_element(g, &element.name);
    let id = g.add(element)?;
    g.bond(j, id)?;
    Ok(id)
}

/// Attaches to `j` an R with effort `level · tanh(f / smoothing)`: a
/// dissipative effort of fixed size opposing the flow (Coulomb friction, a
/// contact drop). `names`: level parameter, smoothing parameter, element;
/// `descriptions` likewise.
pub(super) fn smoothed_sign(
    g: &mut BondGraph,
    c: &Candidate,
    j: ElementId,
    domain: Domain,
    names: [&str; 3],
    level: f64,
    descriptions: [&str; 3],
) -> Result<()> {
    let level = new_param(g, names[0], level, domain.effort_unit(), descriptions[0])?;
    let smooth = new_param(
        g,
        names[1],
        domain.coulomb_smoothing(),
        domain.flow_unit(),
        descriptions[1],
    )?;
    let effort = law(c, &format!("{level} * tanh(f / {smooth})"))?;
    attach(
        g,
        j,
        Element::nonlinear(names[2], ElementKind::R, Some(effort), None).described(descriptions[2]),
    )?;
    Ok(())
}

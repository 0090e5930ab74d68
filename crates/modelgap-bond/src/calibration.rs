//! A bond graph's own unknowns as one candidate: the parameters marked free
//! and the initial states marked free, fitted together by
//! [`modelgap_core::calibrate()`] through [`crate::BondModel`].
//!
//! The candidate's parameters are the free parameters by name (`k1`), then
//! the free initial states as `<element>(0)` (`Tank1(0)`), each within the
//! bounds the model file gives (see [`Range::around`] for the default).

use modelgap_core::{Candidate, EffectKind, EffectParam};

use crate::element::{InitialState, Range};
use crate::error::{BondError, Result};
use crate::graph::BondGraph;

/// The id of the calibration candidate.
pub const ID: &str = "calibration";

/// The typical size of an unknown: its value, or a tenth of its range when
/// it starts at 0.
fn scale(value: f64, r: Range) -> f64 {
    if value != 0.0 {
        value.abs()
    } else {
        ((r.upper - r.lower) / 10.0).max(f64::MIN_POSITIVE)
    }
}

/// The unknowns of `g` as one candidate; `None` when nothing is free.
pub fn candidate(g: &BondGraph) -> Option<Candidate> {
    let mut params = Vec::new();
    for (name, p) in g.params() {
        if let Some(r) = p.free {
            params.push(EffectParam::new(
                name,
                &p.unit,
                p.value,
                (r.lower, r.upper),
                scale(p.value, r),
            ));
        }
    }
    for (element, i) in g.initial() {
        if let Some(r) = i.free {
            params.push(EffectParam::new(
                format!("{element}(0)"),
                "", // a state's unit is not declared in model files
                i.value,
                (r.lower, r.upper),
                scale(i.value, r),
            ));
        }
    }
    (!params.is_empty()).then(|| Candidate {
        id: ID.to_string(),
        name: format!("calibration of {}", g.name),
        kind: EffectKind::Calibration,
        acts_on: g.name.clone(),
        params,
    })
}

/// `g` with the candidate's values set: parameters by name, initial states
/// by `<element>(0)`; what stays free stays free.
///
/// # Errors
/// [`BondError::BadEffect`] for values outside the bounds or a name `g`
/// does not have; the graph's own checks of a value
/// ([`BondGraph::set_param`]).
pub fn apply(g: &BondGraph, c: &Candidate, values: &[f64]) -> Result<BondGraph> {
    c.check_values(values)?;
    let mut g = g.clone();
    for (p, &v) in c.params.iter().zip(values) {
        if let Some(element) = p.name.strip_suffix("(0)") {
            let free = g.initial().get(element).and_then(|i| i.free);
            g.set_initial(element, InitialState { value: v, free })?;
        } else if g.params().contains_key(&p.name) {
            g.set_param(&p.name, v)?;
        } else {
            return Err(BondError::BadEffect {
                candidate: c.id.clone(),
                param: p.name.clone(),
                detail: format!("the model has no parameter or initial state '{}'", p.name),
            });
        }
    }
    Ok(g)
}

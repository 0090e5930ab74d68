//! `calibration`: the graph's own unknowns as one effect — the parameters
//! marked free and the initial states marked free — that
//! [`modelgap_core::calibrate()`] fits through
//! [`BondModel`](crate::BondModel)'s
//! [`free_parameters`](modelgap_core::Model::free_parameters). It is never on
//! the menu of missing effects.
//!
//! The candidate's parameters are the free parameters by name (`k1`), then
//! the free initial states as `<element>(0)` (`Tank1(0)`), each within the
//! bounds the model file gives (see [`Range::around`] for the default).

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::def::EffectDef;
use super::edit::bad;
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{InitialState, Range};
use crate::error::Result;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// The unknowns of a graph, fitted together.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Calibration;

/// The typical size of an unknown: its value, or a tenth of its range when
/// it starts at 0.
fn scale(value: f64, r: Range) -> f64 {
    if value != 0.0 {
        value.abs()
    } else {
        ((r.upper - r.lower) / 10.0).max(f64::MIN_POSITIVE)
    }
}

impl Calibration {
    /// The unknowns of `g` as one candidate; `None` when nothing is free.
    pub fn of(g: &BondGraph) -> Option<Candidate> {
        let mut params = Vec::new();
        for (name, p) in g.params() {
            if let Some(r) = p.free {
                params.push(
                    EffectParam::new(
                        name,
                        &p.unit,
                        p.value,
                        (r.lower, r.upper),
                        scale(p.value, r),
                    )
                    .with_prior(p.prior),
                );
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
            id: Tag::Calibration.id(""),
            name: format!("calibration of {}", g.name),
            kind: EffectKind::Calibration,
            acts_on: g.name.clone(),
            params,
        })
    }
}

impl EffectDef for Calibration {
    /// Calibration is not a missing effect: never on the menu.
    fn offers(_g: &BondGraph) -> Vec<Calibration> {
        Vec::new()
    }

    fn candidate(&self, g: &BondGraph, _scales: &Scales) -> Candidate {
        Calibration::of(g).unwrap_or_else(|| Candidate {
            id: Tag::Calibration.id(""),
            name: format!("calibration of {} (nothing free)", g.name),
            kind: EffectKind::Calibration,
            acts_on: g.name.clone(),
            params: Vec::new(),
        })
    }

    /// Sets the values: parameters by name, initial states by
    /// `<element>(0)`; what stays free stays free.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        for (p, &v) in c.params.iter().zip(values) {
            if let Some(element) = p.name.strip_suffix("(0)") {
                let free = g.initial().get(element).and_then(|i| i.free);
                g.set_initial(element, InitialState { value: v, free })?;
            } else if g.params().contains_key(&p.name) {
                g.set_param(&p.name, v)?;
            } else {
                return Err(bad(
                    c,
                    &p.name,
                    format!("the model has no parameter or initial state '{}'", p.name),
                ));
            }
        }
        Ok(Vec::new())
    }
}

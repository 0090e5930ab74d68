//! `deadzone@<source>`: a dead zone in an actuator, in any domain — a valve
//! that does not open below a command, a motor driver that passes nothing
//! below a threshold voltage, a heater that needs a minimum power: the value
//! `v` a source driven by an input imposes becomes
//! `sign(v) · max(|v| − δ, 0)`.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::def::{EffectDef, all_zero};
use super::edit::{bad, ident, law, new_param};
use super::menu::element_place;
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{ElementKind, Law};
use crate::error::Result;
use crate::expr::Expr;
use crate::graph::{BondGraph, ElementId};
use crate::simulate::ParamChange;

/// A dead zone of width `δ` either side of zero in what a source imposes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DeadZone {
    /// The source (Se or Sf) whose value an input drives.
    pub source: ElementId,
}

impl DeadZone {
    /// The dead zone on element `id` of `g`, if it is a source whose value
    /// names an input (an actuator the recording drives).
    pub fn at(g: &BondGraph, id: ElementId) -> Option<DeadZone> {
        let el = g.element(id);
        let Law::Source(v) = &el.law else {
            return None;
        };
        let driven =
            (v.inputs().iter().chain(v.params().iter())).any(|n| g.inputs().contains_key(n));
        (el.kind.is_source() && driven).then_some(DeadZone { source: id })
    }

    /// The largest value the source imposed over the run the scales come from (a
    /// recording's inputs, never an input's default when a recording is given); 1
    /// when it imposed nothing.
    pub(super) fn peak(self, g: &BondGraph, scales: &Scales) -> f64 {
        let level = if g.element(self.source).kind == ElementKind::Sf {
            scales.flow(self.source)
        } else {
            scales.effort(self.source)
        };
        level.peak_or(1.0)
    }

    /// The unit of what the source imposes: the unit of the input it names
    /// when the law is that input alone, else `e` or `f`.
    pub(super) fn unit(self, g: &BondGraph) -> String {
        let el = g.element(self.source);
        if let Law::Source(Expr::Param(n) | Expr::Input(n)) = &el.law
            && let Some(input) = g.inputs().get(n)
            && !input.unit.trim().is_empty()
        {
            return input.unit.clone();
        }
        match el.kind {
            ElementKind::Sf => "f".to_string(),
            _ => "e".to_string(),
        }
    }
}

/// The name of the source at `id` and the value it imposes, for an edit of `c` that reshapes
/// that value (`what`: "to offset", "to scale"); an error naming it when it is no source.
pub(super) fn source_value(
    g: &BondGraph,
    id: ElementId,
    c: &Candidate,
    what: &str,
) -> Result<(String, Expr)> {
    let el = g.element(id);
    match &el.law {
        Law::Source(v) => Ok((el.name.clone(), v.clone())),
        _ => Err(bad(
            c,
            "",
            format!("'{}' is not a source with a value {what}", el.name),
        )),
    }
}

impl EffectDef for DeadZone {
    fn offers(g: &BondGraph) -> Vec<DeadZone> {
        g.element_ids()
            .filter_map(|id| DeadZone::at(g, id))
            .collect()
    }

    /// `δ` from 0 to the largest value the source imposed over the run the
    /// scales come from (a recording's inputs, never an input's default when
    /// a recording is given), starting at 0, scale a tenth of that.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let el = g.element(self.source);
        let peak = self.peak(g, scales);
        Candidate {
            id: Tag::DeadZone.id(&el.name),
            name: format!(
                "a dead zone in {}: nothing passes below a threshold",
                element_place(g, self.source)
            ),
            kind: EffectKind::MissingElement,
            acts_on: el.name.clone(),
            params: vec![EffectParam::new(
                "delta",
                self.unit(g),
                0.0,
                (0.0, peak),
                0.1 * peak,
            )],
        }
    }

    /// The source's law `v` becomes `sign(v) * max(abs(v) - delta, 0)`.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (target, v) = source_value(g, self.source, c, "to put a dead zone in")?;
        let unit = self.unit(g);
        let delta = new_param(
            g,
            &format!("delta_{}", ident(&target)),
            values[0],
            &unit,
            &format!(
                "dead zone: nothing passes while |value| < delta (added effect {})",
                c.id
            ),
        )?;
        let value = law(c, &format!("sign({v}) * max(abs({v}) - {delta}, 0)"))?;
        g.element_mut(self.source).law = Law::Source(value);
        Ok(Vec::new())
    }

    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        all_zero(c)
    }
}

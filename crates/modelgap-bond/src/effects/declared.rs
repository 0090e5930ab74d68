//! `declared:<name>`: an effect the model file declares (`[[candidates]]`): an
//! element with its own law, bonded from a junction the author chose, whose
//! parameters are fitted within the bounds the file gives. explain ranks it
//! with the built-in candidates; `fix` builds it in as a real element and
//! takes it off the file's list.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::def::EffectDef;
use super::edit::bad;
use super::scales::Scales;
use super::tag::Tag;
use crate::error::Result;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// The declared candidate at this index of [`BondGraph::declared`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Declared {
    /// Its index in the graph's list.
    pub index: usize,
}

impl Declared {
    /// The declared candidate called `name`.
    pub fn named(g: &BondGraph, name: &str) -> Option<Declared> {
        (g.declared().iter())
            .position(|d| d.element.name == name)
            .map(|index| Declared { index })
    }
}

impl EffectDef for Declared {
    fn offers(g: &BondGraph) -> Vec<Declared> {
        (0..g.declared().len())
            .map(|index| Declared { index })
            .collect()
    }

    /// Its parameters start at their values, within their bounds, scale the
    /// value (a tenth of the range for a value of 0).
    fn candidate(&self, g: &BondGraph, _scales: &Scales) -> Candidate {
        let d = &g.declared()[self.index];
        let el = &d.element;
        let params = (d.params.iter())
            .map(|(name, p)| {
                let (lo, hi) = p.free.map_or((p.value, p.value), |r| (r.lower, r.upper));
                let scale = if p.value != 0.0 {
                    p.value.abs()
                } else {
                    ((hi - lo) / 10.0).max(f64::MIN_POSITIVE)
                };
                EffectParam::new(name, &p.unit, p.value, (lo, hi), scale)
            })
            .collect();
        let name = if el.description.is_empty() {
            format!("{} ({} at {}, declared)", el.name, el.kind, d.at)
        } else {
            format!("{} [{}, declared]", el.description, el.name)
        };
        Candidate {
            id: Tag::Declared.id(&el.name),
            name,
            kind: EffectKind::MissingElement,
            acts_on: d.at.clone(),
            params,
        }
    }

    /// Adds the parameters at the fitted values and the element bonded from
    /// its junction, and takes the candidate off the model's list.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let mut d = g
            .declared()
            .get(self.index)
            .cloned()
            .ok_or_else(|| bad(c, "", "the model declares no such candidate".to_string()))?;
        for ((_, p), v) in d.params.iter_mut().zip(values) {
            p.value = *v;
            p.free = None;
            p.description = if p.description.is_empty() {
                format!("(added effect {})", c.id)
            } else {
                format!("{} (added effect {})", p.description, c.id)
            };
        }
        *g = g.with_declared(&d)?;
        g.remove_declared(&d.element.name);
        Ok(Vec::new())
    }
}

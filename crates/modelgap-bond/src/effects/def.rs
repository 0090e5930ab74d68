//! [`EffectDef`]: what every kind of effect defines.

use modelgap_core::Candidate;

use super::scales::Scales;
use crate::error::Result;
use crate::graph::BondGraph;
use crate::qual::Qual;
use crate::simulate::ParamChange;

/// A parameter of the graph the qualitative diagnosis may show for an
/// effect, with the sign of its deviation (`None`: either sign).
pub type QualTarget = (String, Option<Qual>);

/// One kind of candidate effect, placed on a graph: where it acts, the
/// candidate it offers, the edit it makes and how the paper's diagnosis
/// would see it.
///
/// Each kind is a small struct naming where it acts (a parameter, a
/// [`Junction`](super::Junction), an element) and lives in its own file;
/// [`BondEffect`](super::BondEffect) is the enum over them.
pub trait EffectDef {
    /// Every place this kind applies on `g`, in menu order.
    fn offers(g: &BondGraph) -> Vec<Self>
    where
        Self: Sized;

    /// The candidate: id, plain name, kind, where it acts, and its
    /// parameters with unit, initial value, bounds, scale and grid.
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate;

    /// Edits `g` in place with the candidate's `values` (already checked
    /// against its bounds): appends parameters, elements and bonds or
    /// changes laws, and returns the parameter changes to make during a
    /// simulation (abrupt changes only). `c` is the candidate read into this
    /// kind (its id goes into the descriptions of what is added).
    ///
    /// # Errors
    /// [`BondError::BadEffect`](crate::BondError::BadEffect) when the place
    /// cannot take the edit (an I without a linear law); graph errors for a
    /// broken edit (a bug).
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>>;

    /// The parameters the paper's fault trees would name for this effect,
    /// with their sign (see [`BondModel`](crate::BondModel)'s qualitative
    /// agreement); `None` when the trees cannot name it.
    fn qualitative_signature(&self, _g: &BondGraph) -> Option<Vec<QualTarget>> {
        None
    }

    /// The values of candidate `c` of this kind at which it does nothing at
    /// all; `None` when there are none (a deviation, a fault, a coupling).
    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>>
    where
        Self: Sized,
    {
        let _ = c;
        None
    }

    /// `g` with the candidate applied at `values`: the values are checked
    /// ([`Candidate::check_values`]), the edit made on a copy and the result
    /// validated. Ids are append-only, so the ids of `g` stay valid.
    ///
    /// # Errors
    /// [`BondError::BadEffect`](crate::BondError::BadEffect) for a wrong
    /// number of values or one that is not finite or outside its bounds; as
    /// [`EffectDef::edit`]; graph errors from validation.
    fn apply(
        &self,
        g: &BondGraph,
        c: &Candidate,
        values: &[f64],
    ) -> Result<(BondGraph, Vec<ParamChange>)> {
        c.check_values(values)?;
        let mut g = g.clone();
        let changes = self.edit(&mut g, c, values)?;
        g.validate()?;
        Ok((g, changes))
    }
}

/// The values at which an added strength does nothing: every parameter at 0.
pub(super) fn all_zero(c: &Candidate) -> Option<Vec<f64>> {
    Some(vec![0.0; c.params.len()])
}

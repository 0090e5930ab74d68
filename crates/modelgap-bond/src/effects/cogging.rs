//! `cogging@<j>`: cogging torque `A sin(N θ)` on a shaft.

use modelgap_core::{Candidate, EffectParam};

use super::def::EffectDef;
use super::edit::{added, attach, law, new_param};
use super::scales::Scales;
use super::tag::Tag;
use super::{COGGING_GRID, Domain, Junction};
use crate::element::{Element, ElementKind};
use crate::error::Result;
use crate::expr::{Expr, Func};
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// Cogging torque on a rotational junction: a nonlinear C of effort
/// `A_cog · sin(N_cog · θ)`, θ the shaft angle from the start (a new state);
/// `N_cog` in [2, 24] with [`COGGING_GRID`] grid starts. The fault trees
/// have no position-dependent element: no qualitative signature.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cogging {
    /// The shaft.
    pub junction: Junction,
}

impl Cogging {
    /// Cogging on `junction`, if it is rotational.
    pub fn at(junction: Junction) -> Option<Cogging> {
        (junction.domain == Domain::Rotational).then_some(Cogging { junction })
    }
}

impl EffectDef for Cogging {
    fn offers(g: &BondGraph) -> Vec<Cogging> {
        Junction::all(g)
            .into_iter()
            .filter_map(Cogging::at)
            .collect()
    }

    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let j = self.junction;
        let (scale, peak) = (j.effort_scale(scales), j.effort_peak(scales));
        j.candidate(
            g,
            Tag::Cogging,
            format!("cogging torque on {} (position-dependent)", j.place(g)),
            vec![
                // Cogging is a ripple on the torque, not a load: bounded to a
                // tenth of the peak effort (a large amplitude also makes every
                // prediction slow, with the solver following the ripple).
                EffectParam::new(
                    "A_cog",
                    j.domain.effort_unit(),
                    0.1 * scale,
                    (-0.1 * peak, 0.1 * peak),
                    scale,
                ),
                EffectParam::new("N_cog", "1", 6.0, (2.0, 24.0), 6.0).with_grid(COGGING_GRID),
            ],
        )
    }

    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let (j, suffix) = (self.junction, self.junction.suffix(g));
        let tag = added(c);
        let a = new_param(
            g,
            &format!("A_cog_{suffix}"),
            values[0],
            j.domain.effort_unit(),
            &format!("cogging torque amplitude {tag}"),
        )?;
        let n = new_param(
            g,
            &format!("N_cog_{suffix}"),
            values[1],
            "1",
            &format!("cogging periods per revolution {tag}"),
        )?;
        let effort = law(c, &format!("{a} * sin({n} * q)"))?;
        attach(
            g,
            j.id,
            Element::nonlinear(
                &format!("cogging_{suffix}"),
                ElementKind::C,
                Some(effort),
                None,
            )
            .described("cogging torque: a periodic function of the shaft angle q (from the start)"),
        )?;
        Ok(Vec::new())
    }

    /// The amplitude at 0, the period count anywhere (its initial value).
    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        Some(
            c.params
                .iter()
                .map(|p| if p.name == "N_cog" { p.initial } else { 0.0 })
                .collect(),
        )
    }
}

/// True when an expression calls `sin` or `cos`: a periodic law (cogging),
/// whose position has no steady state of its own.
pub(crate) fn is_periodic(e: &Expr) -> bool {
    let mut found = false;
    e.walk(&mut |x| {
        if matches!(x, Expr::Call(Func::Sin | Func::Cos, _)) {
            found = true;
        }
    });
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn periodic_laws_are_recognised() {
        let law = crate::expr::parse("A * sin(N * q)").unwrap();
        assert!(is_periodic(&law));
        assert!(!is_periodic(&crate::expr::parse("q / C").unwrap()));
    }
}

//! `flux-limit@<I>`: magnetic saturation towards a flux the core cannot pass.

/// Bounds of the limiting flux, in multiples of the peak flux the model
/// reaches on the recording: a saturated core carries less flux than the
/// linear one (its larger current drops more across the resistances), so the
/// limit may lie below the model's peak.
const LIMITS: (f64, f64) = (0.3, 10.0);
/// Log-spaced grid starts of the limiting flux.
const LIMIT_GRID: usize = 4;
/// Bounds of the knee's exponent `n` (1: a Frohlich core, `ψ = L i /
/// (1 + |i|/i_s)`; 2: a flux of tanh or atan shape).
const KNEES: (f64, f64) = (1.0, 3.0);
/// Grid starts of the knee's exponent.
const KNEE_GRID: usize = 3;
/// Bounds of the pole's exponent `m`.
const POLES: (f64, f64) = (0.0, 3.0);
/// The smallest `1 − |p/ψ_lim|^n` the law evaluates: an integrator step that
/// overshoots the limit meets a large, finite current, not a NaN.
const FLOOR: f64 = 1e-6;

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::Saturation;
use super::def::EffectDef;
use super::edit::{ident, new_param};
use super::menu::linear_element_words;
use super::scales::Scales;
use super::tag::Tag;
use crate::error::Result;
use crate::graph::{BondGraph, ElementId};
use crate::simulate::ParamChange;

/// Magnetic saturation of an electrical I towards a limiting flux: its law
/// becomes `f = p / L · (1 − |p / ψ_lim|^n)^(−m)`. The current grows without
/// bound as the flux nears `ψ_lim` (Wb), which [`Saturation`]'s power law
/// can only approach: the inverse of a flux `L i_s tanh(i/i_s)` (n ≈ 2,
/// m ≈ 1/3), of `L i_s atan(i/i_s)` (n ≈ 2, m ≈ 0.8) and, exactly, of a
/// Frohlich core `L i / (1 + |i|/i_s)` (n = 1, m = 1). `m = 0` is the
/// linear law.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FluxLimit {
    /// The I element.
    pub element: ElementId,
}

impl FluxLimit {
    /// The flux limit of the I element `id` of `g`, if it is an I.
    pub fn at(g: &BondGraph, id: ElementId) -> Option<FluxLimit> {
        Saturation::at(g, id).map(|s| FluxLimit { element: s.element })
    }
}

impl EffectDef for FluxLimit {
    /// Where [`Saturation`] is offered: every electrical I with a linear law.
    fn offers(g: &BondGraph) -> Vec<FluxLimit> {
        (Saturation::offers(g).into_iter())
            .map(|s| FluxLimit { element: s.element })
            .collect()
    }

    /// `ψ_lim` from 0.3 to 10 times the peak flux the model reaches on the
    /// recording (else `L` times the junction's flow scale), log-spaced
    /// starts; `n` in [1, 3] started at 1, 2 and 3; `m` from 0 in [0, 3].
    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let el = g.element(self.element);
        let p_peak = Saturation {
            element: self.element,
        }
        .peak_flux(g, scales);
        let what = linear_element_words(g, self.element);
        Candidate {
            id: Tag::FluxLimit.id(&el.name),
            name: format!("magnetic saturation of {what} towards a flux limit"),
            kind: EffectKind::MissingElement,
            acts_on: el.name.clone(),
            params: vec![
                EffectParam::new(
                    "psi_lim",
                    "Wb",
                    2.0 * p_peak,
                    (LIMITS.0 * p_peak, LIMITS.1 * p_peak),
                    0.1 * p_peak,
                )
                .with_log_grid(LIMIT_GRID),
                EffectParam::new("n_lim", "1", 2.0, KNEES, 0.2).with_grid(KNEE_GRID),
                EffectParam::new("m_lim", "1", 0.0, POLES, 0.1),
            ],
        }
    }

    /// Changes the law of the I to `f = p / L · max(1 − |p/ψ_lim|^n, 10⁻⁶)^(−m)`.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let core = Saturation {
            element: self.element,
        };
        let (target, old) = core.linear_law(g, c)?;
        let stem = ident(&target);
        let note = |what: &str| format!("flux limit: {what} (added effect {})", c.id);
        let psi = new_param(
            g,
            &format!("psi_lim_{stem}"),
            values[0],
            "Wb",
            &note("the flux the core approaches as its current grows without bound"),
        )?;
        let n = new_param(
            g,
            &format!("n_lim_{stem}"),
            values[1],
            "1",
            &note("the exponent of the knee"),
        )?;
        let m = new_param(
            g,
            &format!("m_lim_{stem}"),
            values[2],
            "1",
            &note("the exponent of the pole"),
        )?;
        core.set_current(
            g,
            c,
            &format!("p / ({old}) * max(1 - abs(p / {psi})^{n}, {FLOOR:e})^(-{m})"),
        )?;
        Ok(Vec::new())
    }

    /// With `m = 0` the law is linear, whatever the limit and the knee.
    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        let at = |i: usize, or: f64| c.params.get(i).map_or(or, |p| p.initial);
        Some(vec![at(0, 1.0), at(1, 2.0), 0.0])
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // in tests, a panic is a failure

    use super::*;
    use crate::library;
    use crate::simulate::{Inputs, SimOptions, simulate, time_grid};

    #[test]
    fn the_motors_inductance_is_offered_a_flux_limit_that_vanishes_at_m_zero() {
        let g = library::dc_motor();
        let offers = FluxLimit::offers(&g);
        assert_eq!(offers.len(), 1, "{offers:?}");
        let f = offers[0];
        assert_eq!(g.element(f.element).name, "L");
        let c = f.candidate(&g, &Scales::of(&g));
        assert_eq!(c.id, "flux-limit@L");
        let t = time_grid(0.5, 1000.0);
        let opts = SimOptions::default();
        let plain = simulate(&g, &Inputs::new(), &t, &opts).unwrap();
        let zero = FluxLimit::vanishing_values(&c).unwrap();
        let (same, _) = f.apply(&g, &c, &zero).unwrap();
        let same = simulate(&same, &Inputs::new(), &t, &opts).unwrap();
        let (i0, i1) = (plain.output("i").unwrap(), same.output("i").unwrap());
        let peak = |i: &[f64]| i.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        // The same current (to the adaptive solver's tolerance: the linear model is
        // integrated exactly, the nonlinear one is not).
        let apart = (i0.iter().zip(i1)).fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(apart < 1e-5 * peak(i0), "{apart}");
        // A Frohlich core whose limit lies just above the start-up's peak flux: the
        // current's peak rises, and stays finite.
        let peak_flux = c.params[0].initial / 2.0;
        let (sat, _) = f.apply(&g, &c, &[1.2 * peak_flux, 1.0, 1.0]).unwrap();
        let run = simulate(&sat, &Inputs::new(), &t, &opts).unwrap();
        let i2 = run.output("i").unwrap();
        assert!(i2.iter().all(|i| i.is_finite()));
        assert!(peak(i2) > 1.05 * peak(i0), "{} vs {}", peak(i2), peak(i0));
    }

    #[test]
    fn a_flux_limit_is_refused_on_an_element_that_is_no_inductance() {
        let g = library::dc_motor();
        let mut c = (crate::effects::candidates(&g).into_iter())
            .find(|c| c.id == "flux-limit@L")
            .expect("on the menu");
        c.id = "flux-limit@R".into();
        let err = crate::effects::BondEffect::from_candidate(&c, &g).unwrap_err();
        assert!(err.to_string().contains("no I element 'R'"), "{err}");
    }
}

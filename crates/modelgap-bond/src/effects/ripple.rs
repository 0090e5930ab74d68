//! `ripple@<GY>`: a motor constant that varies around a turn.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::def::EffectDef;
use super::edit::{added, attach, bad, ident, law, new_param};
use super::menu::linear_element_words;
use super::scales::Scales;
use super::tag::Tag;
use super::{Domain, Junction};
use crate::element::{Element, ElementKind, Law};
use crate::error::Result;
use crate::estimate::position_element;
use crate::expr::Expr;
use crate::graph::{BondGraph, ElementId};
use crate::simulate::ParamChange;

/// Periods per revolution the ripple may have (dimensionless), and the grid
/// of starts over them: every whole order (a ripple's phase over a run of
/// many turns leaves no basin between whole orders).
const ORDERS: (f64, f64) = (1.0, 12.0);
const ORDER_GRID: usize = 12;

/// Largest relative ripple of the modulus either way (dimensionless): beyond
/// half, the constant would change sign within a turn.
const RIPPLE_BOUND: f64 = 0.5;

/// A gyrator between a winding and a shaft whose modulus varies with the
/// shaft's angle: `k (1 + a_s sin Nθ + a_c cos Nθ)`, θ the angle from the
/// start (a new storage of zero effort on the shaft). A winding whose field
/// is not sinusoidal gives a torque ripple in proportion to the current and,
/// by the same modulus, a ripple of the back-EMF in proportion to the speed
/// — one effect acting at both ends, where a law at one place sees half of
/// it. `a_s`, `a_c` in ±0.5, `N` in [1, 12], started at every whole order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ModulusRipple {
    /// The gyrator (a GY with a linear modulus).
    pub element: ElementId,
    /// Its rotational end: the shaft whose angle the modulus follows.
    pub shaft: ElementId,
}

impl ModulusRipple {
    /// The ripple of the GY `id` of `g`: a GY with a linear modulus bonded to
    /// a rotational 1-junction.
    pub fn at(g: &BondGraph, id: ElementId) -> Option<ModulusRipple> {
        let el = g.element(id);
        if el.kind != ElementKind::Gy || !matches!(el.law, Law::Linear(_)) {
            return None;
        }
        let shaft = (g.ports(id).into_iter())
            .map(|(b, _)| g.other_end(b, id))
            .find(|&j| Junction::of(g, j).is_some_and(|j| j.domain == Domain::Rotational))?;
        Some(ModulusRipple { element: id, shaft })
    }
}

impl EffectDef for ModulusRipple {
    fn offers(g: &BondGraph) -> Vec<ModulusRipple> {
        g.element_ids()
            .filter_map(|id| ModulusRipple::at(g, id))
            .collect()
    }

    fn candidate(&self, g: &BondGraph, _scales: &Scales) -> Candidate {
        let el = g.element(self.element);
        let what = linear_element_words(g, self.element);
        let shaft = g.element(self.shaft).name.clone();
        Candidate {
            id: Tag::Ripple.id(&el.name),
            name: format!("{what} varies around a turn of {shaft} (torque and back-EMF ripple)"),
            kind: EffectKind::MissingElement,
            acts_on: el.name.clone(),
            params: vec![
                EffectParam::new("a_rip_s", "1", 0.0, (-RIPPLE_BOUND, RIPPLE_BOUND), 0.05),
                EffectParam::new("a_rip_c", "1", 0.0, (-RIPPLE_BOUND, RIPPLE_BOUND), 0.05),
                EffectParam::new("N_rip", "1", 6.0, ORDERS, 6.0).with_grid(ORDER_GRID),
            ],
        }
    }

    /// The GY becomes an MGY of modulus `k (1 + a_s sin(N θ) + a_c cos(N θ))`,
    /// θ read from a storage of zero effort on the shaft.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let target = g.element(self.element).name.clone();
        let Law::Linear(old) = g.element(self.element).law.clone() else {
            return Err(bad(
                c,
                "",
                format!("the GY '{target}' has no linear modulus to vary"),
            ));
        };
        let suffix = ident(&target);
        let tag = added(c);
        let names = [
            ("a_rip_s", "ripple of the modulus: amplitude of sin(N θ)"),
            ("a_rip_c", "ripple of the modulus: amplitude of cos(N θ)"),
            ("N_rip", "ripple of the modulus: periods per revolution"),
        ];
        let mut p = Vec::with_capacity(3);
        for ((base, what), v) in names.iter().zip(values) {
            p.push(new_param(
                g,
                &format!("{base}_{suffix}"),
                *v,
                "1",
                &format!("{what} {tag}"),
            )?);
        }
        let shaft = g.element(self.shaft).name.clone();
        let zero = law(c, "0 * q")?;
        let angle = attach(
            g,
            self.shaft,
            Element::nonlinear(&position_element(&shaft), ElementKind::C, Some(zero), None)
                .described(&format!(
                    "angle of {shaft} from the start, read by the modulus of {target} {tag}"
                )),
        )?;
        let theta = Expr::signal(&g.element(angle).name, "q");
        let modulus = law(
            c,
            &format!(
                "({old}) * (1 + {} * sin({} * THETA) + {} * cos({} * THETA))",
                p[0], p[2], p[1], p[2]
            ),
        )?
        .map(&mut |e: &Expr| match e {
            Expr::Param(n) if n == "THETA" => Some(theta.clone()),
            _ => None,
        });
        let el = g.element_mut(self.element);
        el.kind = ElementKind::Mgy;
        el.law = Law::Linear(modulus);
        Ok(Vec::new())
    }

    /// With both amplitudes 0 the modulus is constant, whatever `N`.
    fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        let n = c.params.get(2).map_or(6.0, |p| p.initial);
        Some(vec![0.0, 0.0, n])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::library;
    use crate::simulate::{Inputs, SimOptions, simulate, time_grid};

    #[test]
    fn the_motor_constant_is_offered_and_ripples_the_torque_and_the_emf_around_a_turn() {
        let g = library::dc_motor();
        let offers = ModulusRipple::offers(&g);
        assert_eq!(offers.len(), 1, "{offers:?}");
        let r = offers[0];
        assert_eq!(g.element(r.element).name, "k");
        assert_eq!(g.element(r.shaft).name, "1m");
        let c = r.candidate(&g, &Scales::of(&g));
        assert_eq!(c.id, "ripple@k");
        let orders = &c.params[2];
        assert_eq!((orders.lower, orders.upper, orders.grid), (1.0, 12.0, 12));
        let t = time_grid(1.0, 1000.0);
        let opts = SimOptions::default();
        let plain = simulate(&g, &Inputs::new(), &t, &opts).unwrap();
        // At its vanishing values the modulus is k, whatever N.
        let zero = ModulusRipple::vanishing_values(&c).unwrap();
        let (same, _) = r.apply(&g, &c, &zero).unwrap();
        let same = simulate(&same, &Inputs::new(), &t, &opts).unwrap();
        let (w0, w1) = (
            plain.output("omega").unwrap(),
            same.output("omega").unwrap(),
        );
        assert!((w0[999] - w1[999]).abs() < 1e-9 * w0[999].abs().max(1.0));
        // A ripple of 20 %: the GY became an MGY reading the shaft's angle, and at speed
        // the back-EMF's ripple drives a current ripple of amperes (12 V × 0.2 over 1 Ω,
        // less what the inductance filters).
        let (rippled, _) = r.apply(&g, &c, &[0.2, 0.0, 6.0]).unwrap();
        let k = rippled.find("k").unwrap();
        assert_eq!(rippled.element(k).kind, ElementKind::Mgy);
        let run = simulate(&rippled, &Inputs::new(), &t, &opts).unwrap();
        let (i0, i2) = (plain.output("i").unwrap(), run.output("i").unwrap());
        let spread = (500..1000)
            .map(|n| (i2[n] - i0[n]).abs())
            .fold(0.0_f64, f64::max);
        assert!(spread > 0.1, "{spread} A");
        assert!(i2.iter().all(|i| i.is_finite()));
    }

    #[test]
    fn a_ripple_is_refused_on_an_element_that_is_no_gyrator_of_a_shaft() {
        let g = library::dc_motor();
        let menu = crate::effects::candidates(&g);
        let mut c = (menu.into_iter())
            .find(|c| c.id == "ripple@k")
            .expect("on the menu");
        c.id = "ripple@R".into();
        let err = crate::effects::BondEffect::from_candidate(&c, &g).unwrap_err();
        assert!(
            err.to_string().contains("'R' is not a GY of the model"),
            "{err}"
        );
    }
}

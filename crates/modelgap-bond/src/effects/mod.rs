//! Candidate effects of a bond graph: what the model may be missing, and the
//! graph edits that add it.
//!
//! [`candidates`] lists, for a graph, every effect the measurement loop may
//! fit: a deviation of each parameter, an abrupt change of each parameter at
//! an unknown time (a fault), and the physical elements the model may lack,
//! attached where they make physical sense. [`apply`] turns a candidate and
//! its parameter values into an edited graph (elements, bonds and parameters
//! appended; old ids stay valid) plus the parameter changes an abrupt fault
//! makes during a simulation.
//!
//! # Where element candidates attach
//!
//! The domain of a 1-junction comes from the I elements bonded to it: the
//! unit of a parameter in the I's law says what it stores. A unit with the
//! token `H` (or `Wb/A`) is electrical, `kg m^2` (also `kg*m^2`, `kg·m²`) is
//! rotational, `kg` is translational. A model author makes the domain
//! explicit by giving the inertia parameter its unit. Only 1-junctions with
//! such an I get element candidates; a junction without one (the far side of
//! a transformer, a 0-junction) gets none, to keep the menu short and every
//! edit well-posed (an element on a common-flow junction with an inertia
//! never loses integral causality).
//!
//! - rotational and translational 1-junctions: viscous friction, Coulomb
//!   friction (smoothed), a constant load, extra inertia, a flexible coupling
//!   to a second inertia; rotational ones also cogging torque;
//! - electrical 1-junctions: a brush/contact voltage drop;
//! - each electrical I with a linear law: magnetic saturation.
//!
//! # Scales
//!
//! Each parameter carries a `scale` (a typical size: finite-difference steps
//! and scaling in the fit) and bounds. Scales come from the model itself: a
//! start-up from rest under the default inputs, simulated over five slowest
//! time constants, gives each 1-junction a *typical* effort and flow (the
//! largest magnitude on its bonds at the steady state; for the DC motor's
//! shaft the friction torque `k i_ss`, for its armature loop the supply
//! voltage) and a *peak* effort and flow (the largest over the start-up: the
//! stall torque `k V / R` of the motor, nearly). An effort strength (a
//! friction torque, a load, a brush drop) has the typical effort as its scale,
//! kept within [10⁻³, 10⁻¹] of the peak, and may reach the peak effort (a
//! friction beyond what the drive can ever apply would hold the machine
//! still). A model that cannot be simulated gets scale 1 everywhere.

//!
//! Submodules: `menu` ([`candidates`]), `scales` (the model's own scales),
//! `edit` ([`apply`]).

mod edit;
mod menu;
mod scales;

use modelgap_core::{Candidate, EffectKind};

use crate::element::{ElementKind, Law};
use crate::expr::{Expr, Func};
use crate::graph::{BondGraph, Direction, ElementId};

pub use edit::apply;
pub use menu::candidates;

/// The name of the fault-time parameter of every abrupt-change candidate.
///
/// The measurement loop recognises a parameter with this name and unit `s`,
/// replaces its bounds with the recording's time span and searches it by
/// scanning (a local fit cannot find a fault time).
pub const T_FAULT: &str = "t_fault";

/// Smoothing speed (rad/s) of the Coulomb friction on a rotational junction:
/// the friction torque is `tau_c · tanh(ω / ω_s)`, full strength above a few
/// `ω_s`. Fixed (not fitted) and written into the graph as a parameter that a
/// user can edit.
pub const COULOMB_SMOOTHING_RAD_S: f64 = 1.0;

/// Smoothing speed (m/s) of the Coulomb friction on a translational junction.
pub const COULOMB_SMOOTHING_M_S: f64 = 1e-3;

/// Smoothing current (A) of the brush/contact voltage drop
/// `v_b · tanh(i / i_s)`. Fixed, written into the graph as a parameter.
pub const CONTACT_SMOOTHING_A: f64 = 1e-2;

/// Number of start values the fit tries for the cogging period count
/// `N_cog` across its bounds [2, 24]: the even counts, since the cogging
/// count of a motor is the least common multiple of its slot and (even)
/// pole counts. A local fit cannot find a period count from afar.
pub const COGGING_GRID: usize = 12;

/// The physical domain of a 1-junction, from the inertia bonded to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Domain {
    /// An electrical loop: common current, I is an inductance (H).
    Electrical,
    /// A shaft: common angular speed, I is an inertia (kg m²).
    Rotational,
    /// A moving body: common velocity, I is a mass (kg).
    Translational,
}

impl Domain {
    /// The domain a storage parameter's unit belongs to, if any (see the module docs).
    pub fn of_unit(unit: &str) -> Option<Domain> {
        let compact: String = unit
            .chars()
            .filter(|c| !matches!(c, ' ' | '*' | '·' | '.'))
            .collect();
        if matches!(compact.as_str(), "kgm^2" | "kgm²" | "kgm2") {
            return Some(Domain::Rotational);
        }
        if compact == "kg" {
            return Some(Domain::Translational);
        }
        if compact == "Wb/A" || unit.split(|c: char| !c.is_alphanumeric()).any(|t| t == "H") {
            return Some(Domain::Electrical);
        }
        None
    }

    fn effort_unit(self) -> &'static str {
        match self {
            Domain::Electrical => "V",
            Domain::Rotational => "N m",
            Domain::Translational => "N",
        }
    }

    fn flow_unit(self) -> &'static str {
        match self {
            Domain::Electrical => "A",
            Domain::Rotational => "rad/s",
            Domain::Translational => "m/s",
        }
    }

    fn inertia_unit(self) -> &'static str {
        match self {
            Domain::Electrical => "H",
            Domain::Rotational => "kg m^2",
            Domain::Translational => "kg",
        }
    }

    fn damping_unit(self) -> &'static str {
        match self {
            Domain::Electrical => "Ohm",
            Domain::Rotational => "N m s/rad",
            Domain::Translational => "N s/m",
        }
    }

    fn stiffness_unit(self) -> &'static str {
        match self {
            Domain::Electrical => "1/F",
            Domain::Rotational => "N m/rad",
            Domain::Translational => "N/m",
        }
    }

    fn effort_word(self) -> &'static str {
        match self {
            Domain::Electrical => "voltage",
            Domain::Rotational => "torque",
            Domain::Translational => "force",
        }
    }

    fn inertia_word(self) -> &'static str {
        match self {
            Domain::Electrical => "inductance",
            Domain::Rotational => "inertia",
            Domain::Translational => "mass",
        }
    }

    /// Parameter-name stems: (effort strength, inertia increment, second inertia).
    fn stems(self) -> (&'static str, &'static str, &'static str) {
        match self {
            Domain::Rotational => ("tau", "dJ", "J2"),
            Domain::Translational => ("F", "dm", "m2"),
            Domain::Electrical => ("v", "dL", "L2"),
        }
    }

    fn coulomb_smoothing(self) -> f64 {
        match self {
            Domain::Rotational => COULOMB_SMOOTHING_RAD_S,
            Domain::Translational => COULOMB_SMOOTHING_M_S,
            Domain::Electrical => CONTACT_SMOOTHING_A,
        }
    }
}

/// The domain of a 1-junction and the I element that sets it, or `None`
/// when no I bonded to it has a parameter with a domain unit (see the module docs).
pub fn junction_domain(g: &BondGraph, junction: ElementId) -> Option<(Domain, ElementId)> {
    if g.element(junction).kind != ElementKind::One {
        return None;
    }
    for (bond, _) in g.ports(junction) {
        let other = g.other_end(bond, junction);
        let el = g.element(other);
        if el.kind != ElementKind::I {
            continue;
        }
        let exprs: Vec<&Expr> = match &el.law {
            Law::Linear(e) => vec![e],
            Law::Nonlinear { effort, flow } => flow.iter().chain(effort.iter()).collect(),
            _ => Vec::new(),
        };
        for e in exprs {
            for name in e.params() {
                if let Some(d) = g.params().get(&name).and_then(|p| Domain::of_unit(&p.unit)) {
                    return Some((d, other));
                }
            }
        }
    }
    None
}

/// The values at which a missing-element candidate has no effect at all:
/// its strengths (viscous `b`, friction, load, inertia increment, cogging
/// amplitude, brush drop, saturation coefficient) at 0 and any other
/// parameter (the cogging period count) at its initial value. `None` for
/// deviations, abrupt changes and the coupling (a second inertia cannot
/// vanish: `J2 → 0` is singular).
pub fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
    let (prefix, _) = c.id.split_once('@')?;
    if c.kind != EffectKind::MissingElement || prefix == "coupling" {
        return None;
    }
    Some(
        c.params
            .iter()
            .map(|p| if p.name == "N_cog" { p.initial } else { 0.0 })
            .collect(),
    )
}

/// The parameters of the graph a candidate's edit mentions, with the
/// deviation sign that the qualitative diagnosis would show for it (`None`:
/// either sign). Used by [`crate::model::BondModel`]'s qualitative check.
pub(crate) fn qualitative_targets(
    g: &BondGraph,
    c: &Candidate,
) -> Option<Vec<(String, Option<crate::qual::Qual>)>> {
    use crate::qual::Qual;
    if let Some((_, target)) = c.id.split_once(':') {
        return Some(vec![(target.to_string(), None)]);
    }
    let (kind, target) = c.id.split_once('@')?;
    let j = g.find(target)?;
    // Linear R parameters and load inputs on the junction.
    let mut r_params = Vec::new();
    let mut loads = Vec::new();
    let mut inertias = Vec::new();
    for (bond, dir) in g.ports(j) {
        let other = g.other_end(bond, j);
        let el = g.element(other);
        match (&el.kind, &el.law) {
            (ElementKind::R, Law::Linear(Expr::Param(p))) if g.params().contains_key(p) => {
                r_params.push(p.clone());
            }
            (ElementKind::Se, Law::Source(Expr::Param(u))) if g.inputs().contains_key(u) => {
                // The bond leaves the junction into the source: a positive value opposes motion.
                let sign = if dir == Direction::Out {
                    Qual::Plus
                } else {
                    Qual::Minus
                };
                loads.push((u.clone(), Some(sign)));
            }
            (ElementKind::I, Law::Linear(e)) => {
                inertias.extend(e.params().into_iter().map(|p| (p, None)));
            }
            _ => {}
        }
    }
    let plus = |v: Vec<String>| -> Vec<(String, Option<Qual>)> {
        v.into_iter().map(|p| (p, Some(Qual::Plus))).collect()
    };
    let out = match kind {
        "viscous" | "brush" => plus(r_params),
        "coulomb" | "load" => {
            let mut v = loads;
            v.extend(plus(r_params));
            v
        }
        "inertia" => inertias,
        _ => return None,
    };
    if out.is_empty() { None } else { Some(out) }
}

/// True when an expression calls `sin` or `cos`: a periodic law.
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
    fn storage_units_give_the_junction_domain() {
        for (unit, domain) in [
            ("H", Some(Domain::Electrical)),
            ("Wb/A", Some(Domain::Electrical)),
            ("kg m^2", Some(Domain::Rotational)),
            ("kg*m^2", Some(Domain::Rotational)),
            ("kg·m²", Some(Domain::Rotational)),
            ("kg", Some(Domain::Translational)),
            ("Hz", None),
            ("N m/A", None),
            ("", None),
        ] {
            assert_eq!(Domain::of_unit(unit), domain, "{unit}");
        }
    }

    #[test]
    fn periodic_laws_are_recognised() {
        let law = crate::expr::parse("A * sin(N * q)").unwrap();
        assert!(is_periodic(&law));
        assert!(!is_periodic(&crate::expr::parse("q / C").unwrap()));
    }
}

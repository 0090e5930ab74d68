//! The menu of candidate effects of a graph.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::scales::Scales;
use super::{COGGING_GRID, Domain, T_FAULT, junction_domain};
use crate::element::{ElementKind, Law};
use crate::expr::Expr;
use crate::graph::{BondGraph, ElementId};

/// Damping ratio of the initial flexible coupling.
const COUPLING_DAMPING_RATIO: f64 = 0.1;

/// The coupling's initial resonance, as a multiple of the slowest mode's rate.
const COUPLING_FREQUENCY_FACTOR: f64 = 10.0;

/// A parameter of a candidate.
fn param(name: &str, unit: &str, initial: f64, bounds: (f64, f64), scale: f64) -> EffectParam {
    EffectParam {
        name: name.to_string(),
        unit: unit.to_string(),
        initial,
        lower: bounds.0,
        upper: bounds.1,
        scale,
        grid: 0,
    }
}

/// The head of a description: the text before a `:` or a ` (`.
fn head(description: &str) -> &str {
    let cut = [description.find(':'), description.find(" (")]
        .into_iter()
        .flatten()
        .min()
        .unwrap_or(description.len());
    description[..cut].trim()
}

/// "the shaft (1m)" from a junction's description, or "junction 1m".
fn place(g: &BondGraph, j: ElementId) -> String {
    let el = g.element(j);
    let h = head(&el.description);
    if h.is_empty() {
        format!("junction {}", el.name)
    } else if h.starts_with("the ") || h.starts_with("a ") {
        format!("{h} ({})", el.name)
    } else {
        format!("the {h} ({})", el.name)
    }
}

/// The nominal value of a linear law, evaluated with the graph's parameters
/// and input defaults.
fn law_value(g: &BondGraph, e: &Expr) -> Option<f64> {
    e.eval(&|leaf: &Expr| match leaf {
        Expr::Param(n) => g
            .param(n)
            .ok()
            .or_else(|| g.inputs().get(n).map(|i| i.default)),
        Expr::Input(n) => g.inputs().get(n).map(|i| i.default),
        _ => None,
    })
    .filter(|v| v.is_finite())
}

/// The deviation/fault parameter of an existing parameter: bounds [v/5, 5v]
/// (a factor of five either way), scale |v|; a zero nominal gets [−s, s]
/// with `s` the scale of the quantity it multiplies (see [`zero_scale`]),
/// or [0, s] when it is the resistance of a linear R (which cannot be
/// negative: [`BondGraph::check_coefficients`]).
fn value_param(g: &BondGraph, scales: &Scales, name: &str, value: f64, unit: &str) -> EffectParam {
    if value > 0.0 {
        param(name, unit, value, (value / 5.0, value * 5.0), value)
    } else if value < 0.0 {
        param(name, unit, value, (value * 5.0, value / 5.0), -value)
    } else {
        let s = zero_scale(g, scales, name);
        let resistance = g.element_ids().any(|id| {
            let el = g.element(id);
            el.kind == ElementKind::R && el.law == Law::Linear(Expr::Param(name.to_string()))
        });
        let lower = if resistance { 0.0 } else { -s };
        param(name, unit, 0.0, (lower, s), s)
    }
}

/// The scale of a parameter whose nominal value is 0, from what it acts on:
/// the coefficient of an R gets effort/flow of its junction, the value of an
/// Se the junction's effort, of an Sf its flow; anything else 1.
fn zero_scale(g: &BondGraph, scales: &Scales, name: &str) -> f64 {
    for id in g.element_ids() {
        let el = g.element(id);
        let e = match &el.law {
            Law::Linear(e) | Law::Source(e) => e,
            _ => continue,
        };
        if e != &Expr::Param(name.to_string()) {
            continue;
        }
        let Some(&(bond, _)) = g.ports(id).first() else {
            continue;
        };
        let j = g.other_end(bond, id);
        let (effort, flow) = (scales.effort(j).strength(), scales.flow(j).flow());
        return match el.kind {
            ElementKind::R => effort / flow,
            ElementKind::Se => effort,
            ElementKind::Sf => flow,
            _ => 1.0,
        };
    }
    1.0
}

/// The fault-time parameter ([`T_FAULT`]): initial 0, bounds [0, 1e9] s,
/// which the measurement loop replaces by the recording's span.
fn t_fault_param() -> EffectParam {
    param(T_FAULT, "s", 0.0, (0.0, 1e9), 1.0)
}

/// Inputs used as the modulus of an MTF or MGY, with the element using each first.
fn modulus_inputs(g: &BondGraph) -> Vec<(String, ElementId)> {
    let mut out: Vec<(String, ElementId)> = Vec::new();
    for id in g.element_ids() {
        let el = g.element(id);
        if !matches!(el.kind, ElementKind::Mtf | ElementKind::Mgy) {
            continue;
        }
        if let Law::Linear(e) = &el.law {
            for input in g.resolved(e).inputs() {
                if !out.iter().any(|(n, _)| *n == input) {
                    out.push((input, id));
                }
            }
        }
    }
    out
}

/// The factor on a modulus input: initial 1, bounds [0.5, 1.5].
fn factor_param(input: &str) -> EffectParam {
    param(&format!("{input}_factor"), "1", 1.0, (0.5, 1.5), 1.0)
}

/// The candidate effects of a graph, in a stable order: parameter
/// deviations, modulus deviations, abrupt changes, then missing elements
/// junction by junction, then saturations.
///
/// - `deviation:<p>` (kind [`EffectKind::ParameterDeviation`]) for every
///   parameter `p`: one parameter named `p`, initial the nominal value,
///   bounds a factor of five either way (for a zero nominal `[−s, s]` with
///   `s` the scale of what it acts on), scale `|nominal|`.
/// - `deviation:<u>` for every input `u` used as an MTF/MGY modulus: a
///   factor `<u>_factor` on the input (initial 1, bounds [0.5, 1.5]).
/// - `fault:<p>` / `fault:<u>` (kind [`EffectKind::AbruptChange`]): the new
///   value (as above) and the fault time [`T_FAULT`] (unit `s`, initial 0,
///   bounds [0, 1e9]). **Contract with the measurement loop:** a parameter
///   named exactly `t_fault` with unit `s` is a fault time; the loop sets its
///   bounds from the recording and searches it by scanning.
/// - On each rotational or translational 1-junction (see the module docs):
///   `viscous@<j>` (`b` ≥ 0), `coulomb@<j>` (`tau_c` ≥ 0, smoothed with the
///   fixed [`COULOMB_SMOOTHING_RAD_S`](super::COULOMB_SMOOTHING_RAD_S)), `load@<j>` (`tau_0`, either sign; a
///   positive load opposes forward motion), `inertia@<j>` (`dJ` ≥ −0.9 J,
///   added to the junction's inertia), `coupling@<j>` (a second inertia `J2`
///   behind a spring `k_s` and damper `c`; adds two states; starts at `J2 =
///   J`, a resonance ten times the slowest mode and damping ratio 0.1), and
///   on rotational ones `cogging@<j>` (`A_cog · sin(N_cog · θ)`, θ the shaft
///   angle from the start; `N_cog` in [2, 24] with [`COGGING_GRID`] grid
///   starts). Translational junctions use `F_c`, `F_0`, `dm`, `m2`.
/// - On each electrical 1-junction: `brush@<j>` (`v_b` ≥ 0, smoothed with
///   the fixed [`CONTACT_SMOOTHING_A`](super::CONTACT_SMOOTHING_A)).
/// - For each electrical I with a linear law: `saturation@<I>`
///   (`f = p / L · (1 + a_sat p²)`, `a_sat` ≥ 0 in 1/Wb², scale `0.1 / p_peak²`
///   with `p_peak` the peak flux of a start-up).
///
/// Bounds of the element strengths: a friction level, a brush drop and a
/// cogging amplitude reach the junction's peak effort (`tau_0` and `A_cog`
/// either sign); viscous `b` reaches the peak effort at the typical flow
/// (at least ten times its scale; a negative correction of an existing
/// friction is the deviation candidate's job); `a_sat` reaches `10 / p_peak²`;
/// the coupling's `k_s`, `J2` and `c` span a factor of 100 around their
/// start (`c` down to 0).
///
/// Every parameter has finite bounds containing its initial value and a
/// positive scale (see the module docs for where scales come from).
///
/// # Example
/// ```
/// # use modelgap_bond::{effects, library};
/// let menu = effects::candidates(&library::dc_motor());
/// assert!(menu.iter().any(|c| c.id == "coulomb@1m"));
/// assert!(menu.iter().any(|c| c.id == "deviation:R"));
/// ```
pub fn candidates(g: &BondGraph) -> Vec<Candidate> {
    let scales = Scales::of(g);
    let mut out = Vec::new();
    // Deviations of every parameter.
    for (name, p) in g.params() {
        let what = if p.description.is_empty() {
            name.clone()
        } else {
            format!("{} ({name})", head(&p.description))
        };
        out.push(Candidate {
            id: format!("deviation:{name}"),
            name: format!("{what} is off"),
            kind: EffectKind::ParameterDeviation,
            acts_on: name.clone(),
            params: vec![value_param(g, &scales, name, p.value, &p.unit)],
        });
    }
    let moduli = modulus_inputs(g);
    for (input, el) in &moduli {
        out.push(Candidate {
            id: format!("deviation:{input}"),
            name: format!(
                "the effective modulus of {} ({input}) is off by a factor",
                element_place(g, *el)
            ),
            kind: EffectKind::ParameterDeviation,
            acts_on: input.clone(),
            params: vec![factor_param(input)],
        });
    }
    // Abrupt changes.
    for (name, p) in g.params() {
        let what = if p.description.is_empty() {
            name.clone()
        } else {
            format!("{} ({name})", head(&p.description))
        };
        out.push(Candidate {
            id: format!("fault:{name}"),
            name: format!("{what} changes abruptly at an unknown time"),
            kind: EffectKind::AbruptChange,
            acts_on: name.clone(),
            params: vec![
                value_param(g, &scales, name, p.value, &p.unit),
                t_fault_param(),
            ],
        });
    }
    for (input, el) in &moduli {
        out.push(Candidate {
            id: format!("fault:{input}"),
            name: format!(
                "the effective modulus of {} ({input}) changes abruptly at an unknown time",
                element_place(g, *el)
            ),
            kind: EffectKind::AbruptChange,
            acts_on: input.clone(),
            params: vec![factor_param(input), t_fault_param()],
        });
    }
    // Missing elements.
    for j in g.element_ids() {
        let Some((domain, i_el)) = junction_domain(g, j) else {
            continue;
        };
        match domain {
            Domain::Electrical => out.push(brush_candidate(g, &scales, j)),
            Domain::Rotational | Domain::Translational => {
                out.extend(mechanical_candidates(g, &scales, j, domain, i_el));
            }
        }
    }
    for id in g.element_ids() {
        if let Some(c) = saturation_candidate(g, &scales, id) {
            out.push(c);
        }
    }
    out
}

/// "switch and diode (switch)" or "element switch".
fn element_place(g: &BondGraph, id: ElementId) -> String {
    let el = g.element(id);
    let h = head(&el.description);
    if h.is_empty() {
        format!("element {}", el.name)
    } else {
        format!("{h} [{}]", el.name)
    }
}

fn brush_candidate(g: &BondGraph, scales: &Scales, j: ElementId) -> Candidate {
    let e = scales.effort(j);
    Candidate {
        id: format!("brush@{}", g.element(j).name),
        name: format!("brush/contact voltage drop in {}", place(g, j)),
        kind: EffectKind::MissingElement,
        acts_on: g.element(j).name.clone(),
        params: vec![param(
            "v_b",
            "V",
            0.0,
            (0.0, e.peak_or(10.0 * e.strength())),
            e.strength(),
        )],
    }
}

fn mechanical_candidates(
    g: &BondGraph,
    scales: &Scales,
    j: ElementId,
    d: Domain,
    i_el: ElementId,
) -> Vec<Candidate> {
    let jname = g.element(j).name.clone();
    let at = place(g, j);
    let e = scales.effort(j);
    let f = scales.flow(j);
    let e_scale = e.strength();
    let e_peak = e.peak_or(10.0 * e_scale);
    let f_scale = f.flow();
    let (stem, d_stem, two_stem) = d.stems();
    let eu = d.effort_unit();
    let word = d.effort_word();
    let inertia = match &g.element(i_el).law {
        Law::Linear(x) => law_value(g, x).filter(|v| *v > 0.0),
        _ => None,
    };
    let mk = |id: &str, name: String, params: Vec<EffectParam>| Candidate {
        id: format!("{id}@{jname}"),
        name,
        kind: EffectKind::MissingElement,
        acts_on: jname.clone(),
        params,
    };
    let mut out = Vec::new();
    let b_scale = e_scale / f_scale;
    let b_upper = (e_peak / f_scale).max(10.0 * b_scale);
    out.push(mk(
        "viscous",
        format!("viscous friction on {at}"),
        vec![param("b", d.damping_unit(), 0.0, (0.0, b_upper), b_scale)],
    ));
    out.push(mk(
        "coulomb",
        format!("Coulomb friction on {at}"),
        vec![param(&format!("{stem}_c"), eu, 0.0, (0.0, e_peak), e_scale)],
    ));
    out.push(mk(
        "load",
        format!("constant load {word} on {at}"),
        vec![param(
            &format!("{stem}_0"),
            eu,
            0.0,
            (-e_peak, e_peak),
            e_scale,
        )],
    ));
    if let Some(m) = inertia {
        out.push(mk(
            "inertia",
            format!("extra {} on {at}", d.inertia_word()),
            vec![param(
                d_stem,
                d.inertia_unit(),
                0.0,
                (-0.9 * m, 100.0 * m),
                m,
            )],
        ));
        // Coupling: J2 = J, resonance sqrt(k (1/J + 1/J2)) at ten times the
        // slowest mode, damping ratio 0.1 on the reduced inertia.
        let rate = scales.slowest_rate.unwrap_or(1.0);
        let w = COUPLING_FREQUENCY_FACTOR * rate;
        let reduced = m * m / (m + m);
        let k0 = w * w * reduced;
        let c0 = 2.0 * COUPLING_DAMPING_RATIO * (k0 * reduced).sqrt();
        out.push(mk(
            "coupling",
            format!("flexible coupling of {at} to a second {}", d.inertia_word()),
            vec![
                param("k_s", d.stiffness_unit(), k0, (k0 / 100.0, k0 * 100.0), k0),
                param("c", d.damping_unit(), c0, (0.0, c0 * 100.0), c0),
                param(two_stem, d.inertia_unit(), m, (m / 100.0, m * 100.0), m),
            ],
        ));
    }
    if d == Domain::Rotational {
        let mut n = param("N_cog", "1", 6.0, (2.0, 24.0), 6.0);
        n.grid = COGGING_GRID;
        out.push(mk(
            "cogging",
            format!("cogging torque on {at} (position-dependent)"),
            vec![
                // Cogging is a ripple on the torque, not a load: bounded to a
                // tenth of the peak effort (a large amplitude also makes every
                // prediction slow, with the solver following the ripple).
                param(
                    "A_cog",
                    eu,
                    0.1 * e_scale,
                    (-0.1 * e_peak, 0.1 * e_peak),
                    e_scale,
                ),
                n,
            ],
        ));
    }
    out
}

fn saturation_candidate(g: &BondGraph, scales: &Scales, id: ElementId) -> Option<Candidate> {
    let el = g.element(id);
    if el.kind != ElementKind::I {
        return None;
    }
    let Law::Linear(x) = &el.law else {
        return None;
    };
    let electrical = x.params().iter().any(|n| {
        g.params()
            .get(n)
            .is_some_and(|p| Domain::of_unit(&p.unit) == Some(Domain::Electrical))
    });
    if !electrical {
        return None;
    }
    let l = law_value(g, x).filter(|v| *v > 0.0)?;
    // Peak flux of the start-up, else L times the junction's flow scale.
    let p_peak = scales
        .state_peak
        .get(&id)
        .copied()
        .filter(|p| *p > 0.0)
        .or_else(|| {
            let (bond, _) = *g.ports(id).first()?;
            Some(l * scales.flow(g.other_end(bond, id)).flow())
        })
        .unwrap_or(1.0);
    let a = 1.0 / (p_peak * p_peak);
    let what = match x {
        Expr::Param(n) => g
            .params()
            .get(n)
            .map(|p| head(&p.description).to_string())
            .filter(|s| !s.is_empty())
            .map_or_else(|| n.clone(), |h| format!("{h} ({n})")),
        _ => el.name.clone(),
    };
    Some(Candidate {
        id: format!("saturation@{}", el.name),
        name: format!("magnetic saturation of {what}"),
        kind: EffectKind::MissingElement,
        acts_on: el.name.clone(),
        params: vec![param("a_sat", "1/Wb^2", 0.0, (0.0, 10.0 * a), 0.1 * a)],
    })
}

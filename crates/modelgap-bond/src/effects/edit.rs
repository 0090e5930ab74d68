//! Graph edits: a candidate and its values become an edited graph.

use modelgap_core::Candidate;

use super::{Domain, junction_domain};
use crate::element::{Element, ElementKind, Law};
use crate::error::{BondError, Result};
use crate::expr::{Expr, parse};
use crate::graph::{BondGraph, ElementId};
use crate::simulate::ParamChange;

/// Slack (relative to the bound, or to the scale for a bound at 0) within
/// which a value still counts as inside its bounds: rounding in a fit's projection.
const BOUND_SLACK: f64 = 1e-12;

fn bad(c: &Candidate, param: &str, detail: String) -> BondError {
    BondError::BadEffect {
        candidate: c.id.clone(),
        param: param.to_string(),
        detail,
    }
}

/// Checks the count, finiteness and bounds of a candidate's values.
fn check_values(c: &Candidate, values: &[f64]) -> Result<()> {
    if values.len() != c.params.len() {
        return Err(bad(
            c,
            "",
            format!(
                "expected {} value{} ({}), found {}",
                c.params.len(),
                if c.params.len() == 1 { "" } else { "s" },
                c.params
                    .iter()
                    .map(|p| p.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                values.len()
            ),
        ));
    }
    for (p, &v) in c.params.iter().zip(values) {
        if !v.is_finite() {
            return Err(bad(
                c,
                &p.name,
                format!("parameter '{}' must be finite, found {v}", p.name),
            ));
        }
        let slack = |bound: f64| BOUND_SLACK * bound.abs().max(p.scale.abs());
        if v < p.lower - slack(p.lower) || v > p.upper + slack(p.upper) {
            return Err(bad(
                c,
                &p.name,
                format!(
                    "parameter '{}' = {v} {} is outside its bounds [{}, {}]",
                    p.name, p.unit, p.lower, p.upper
                ),
            ));
        }
    }
    Ok(())
}

/// A name made of letters, digits and `_` (safe in a law).
fn ident(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

/// `base` if neither a parameter nor an input has it, else `base_2`, `base_3`, ….
fn fresh_param(g: &BondGraph, base: &str) -> String {
    let taken = |n: &str| g.params().contains_key(n) || g.inputs().contains_key(n);
    if !taken(base) {
        return base.to_string();
    }
    (2..)
        .map(|k| format!("{base}_{k}"))
        .find(|n| !taken(n))
        .unwrap_or_else(|| base.to_string())
}

/// `base` if no element has it, else `base_2`, `base_3`, ….
fn fresh_element(g: &BondGraph, base: &str) -> String {
    if g.find(base).is_none() {
        return base.to_string();
    }
    (2..)
        .map(|k| format!("{base}_{k}"))
        .find(|n| g.find(n).is_none())
        .unwrap_or_else(|| base.to_string())
}

/// Parses a law built by this module.
fn law(c: &Candidate, text: &str) -> Result<Expr> {
    parse(text).map_err(|e| {
        bad(
            c,
            "",
            format!("cannot build the law '{text}': {}", e.message),
        )
    })
}

/// Adds a parameter under a fresh name derived from `base` and returns the name.
fn new_param(
    g: &mut BondGraph,
    base: &str,
    value: f64,
    unit: &str,
    description: &str,
) -> Result<String> {
    let name = fresh_param(g, base);
    g.add_param(&name, value, unit, description)?;
    Ok(name)
}

/// Adds a one-port on junction `j`, its bond pointing into it.
fn attach(g: &mut BondGraph, j: ElementId, mut element: Element) -> Result<ElementId> {
    element.name = fresh_element(g, &element.name);
    let id = g.add(element)?;
    g.bond(j, id)?;
    Ok(id)
}

/// Applies a candidate at `values`: the edited graph, and the parameter
/// changes to make during a simulation (abrupt changes only).
///
/// Deviations set the parameter (a modulus input gets a factor parameter
/// `<u>_factor` on its MTF/MGY law); abrupt changes leave the graph as is
/// (a modulus gets its factor at 1) and return a [`ParamChange`] at
/// `t_fault`; missing elements append elements, bonds and parameters (named
/// `<stem>_<junction>`, with `_2`, `_3`, … when taken), or change the law of
/// the junction's I (extra inertia, saturation). Ids are append-only, so the
/// ids of `g` stay valid in the result.
///
/// # Errors
/// [`BondError::BadEffect`] naming the candidate and the parameter for a
/// wrong number of values, a value that is not finite or outside its bounds,
/// or a candidate this graph does not offer (unknown parameter, junction or
/// element); graph errors if the edit breaks the graph (a bug).
///
/// # Example
/// ```
/// # use modelgap_bond::{effects, library, CompiledModel};
/// let motor = library::dc_motor();
/// let menu = effects::candidates(&motor);
/// let coulomb = menu.iter().find(|c| c.id == "coulomb@1m").unwrap();
/// let (edited, changes) = effects::apply(&motor, coulomb, &[0.01]).unwrap();
/// assert!(changes.is_empty());
/// assert!(edited.find("coulomb_1m").is_some());
/// assert!(CompiledModel::new(&edited).is_ok());
/// ```
pub fn apply(
    g: &BondGraph,
    candidate: &Candidate,
    values: &[f64],
) -> Result<(BondGraph, Vec<ParamChange>)> {
    check_values(candidate, values)?;
    let c = candidate;
    let mut g = g.clone();
    let mut changes = Vec::new();
    if let Some((kind, target)) = c.id.split_once(':') {
        match kind {
            "deviation" => {
                if g.params().contains_key(target) {
                    g.set_param(target, values[0])?;
                } else {
                    let factor = modulus_factor(&mut g, c, target, values[0])?;
                    debug_assert!(g.params().contains_key(&factor));
                }
            }
            "fault" => {
                let name = if g.params().contains_key(target) {
                    target.to_string()
                } else {
                    modulus_factor(&mut g, c, target, 1.0)?
                };
                changes.push(ParamChange {
                    at: values[1],
                    name,
                    value: values[0],
                });
            }
            _ => return Err(unknown(c)),
        }
        g.validate()?;
        return Ok((g, changes));
    }
    let Some((kind, target)) = c.id.split_once('@') else {
        return Err(unknown(c));
    };
    if kind == "saturation" {
        saturate(&mut g, c, target, values[0])?;
        g.validate()?;
        return Ok((g, changes));
    }
    let j = g.find(target).ok_or_else(|| {
        bad(
            c,
            "",
            format!("the model has no junction '{target}' for this effect"),
        )
    })?;
    let Some((domain, i_el)) = junction_domain(&g, j) else {
        return Err(bad(
            c,
            "",
            format!("'{target}' is not a 1-junction with an inertia (I) of known unit"),
        ));
    };
    let suffix = ident(target);
    let (stem, d_stem, two_stem) = domain.stems();
    let tag = format!("(added effect {})", c.id);
    match (kind, domain) {
        ("viscous", Domain::Rotational | Domain::Translational) => {
            let b = new_param(
                &mut g,
                &format!("b_{suffix}"),
                values[0],
                domain.damping_unit(),
                &format!("viscous friction coefficient {tag}"),
            )?;
            attach(
                &mut g,
                j,
                Element::r(&format!("viscous_{suffix}"), &b).described("viscous friction"),
            )?;
        }
        ("coulomb", Domain::Rotational | Domain::Translational) => {
            let base = format!("{stem}_c_{suffix}");
            let smooth = if domain == Domain::Rotational {
                "omega_s"
            } else {
                "v_s"
            };
            smoothed_sign(
                &mut g,
                c,
                j,
                domain,
                [
                    &base,
                    &format!("{smooth}_{suffix}"),
                    &format!("coulomb_{suffix}"),
                ],
                values[0],
                [
                    &format!("Coulomb friction level {tag}"),
                    "speed below which Coulomb friction fades (fixed smoothing)",
                    "Coulomb friction: level times a smoothed sign of the speed",
                ],
            )?;
        }
        ("brush", Domain::Electrical) => {
            smoothed_sign(
                &mut g,
                c,
                j,
                domain,
                [
                    &format!("v_b_{suffix}"),
                    &format!("i_s_{suffix}"),
                    &format!("brush_{suffix}"),
                ],
                values[0],
                [
                    &format!("brush/contact voltage drop {tag}"),
                    "current below which the contact drop fades (fixed smoothing)",
                    "brush/contact voltage drop: level times a smoothed sign of the current",
                ],
            )?;
        }
        ("load", Domain::Rotational | Domain::Translational) => {
            let load = new_param(
                &mut g,
                &format!("{stem}_0_{suffix}"),
                values[0],
                domain.effort_unit(),
                &format!(
                    "constant load {} (positive opposes forward motion) {tag}",
                    domain.effort_word()
                ),
            )?;
            attach(
                &mut g,
                j,
                Element::se(&format!("load_{suffix}"), &load).described(&format!(
                    "constant load {}; its bond points into it, so a positive load opposes motion",
                    domain.effort_word()
                )),
            )?;
        }
        ("inertia", Domain::Rotational | Domain::Translational) => {
            let Law::Linear(old) = g.element(i_el).law.clone() else {
                return Err(bad(c, "", "the junction's I has no linear law".to_string()));
            };
            let extra = new_param(
                &mut g,
                &format!("{d_stem}_{suffix}"),
                values[0],
                domain.inertia_unit(),
                &format!("extra {} {tag}", domain.inertia_word()),
            )?;
            let new_law = law(c, &format!("({old}) + {extra}"))?;
            g.element_mut(i_el).law = Law::Linear(new_law);
        }
        ("coupling", Domain::Rotational | Domain::Translational) => {
            couple(&mut g, c, j, domain, &suffix, two_stem, values, &tag)?;
        }
        ("cogging", Domain::Rotational) => {
            let a = new_param(
                &mut g,
                &format!("A_cog_{suffix}"),
                values[0],
                domain.effort_unit(),
                &format!("cogging torque amplitude {tag}"),
            )?;
            let n = new_param(
                &mut g,
                &format!("N_cog_{suffix}"),
                values[1],
                "1",
                &format!("cogging periods per revolution {tag}"),
            )?;
            let effort = law(c, &format!("{a} * sin({n} * q)"))?;
            attach(
                &mut g,
                j,
                Element::nonlinear(
                    &format!("cogging_{suffix}"),
                    ElementKind::C,
                    Some(effort),
                    None,
                )
                .described(
                    "cogging torque: a periodic function of the shaft angle q (from the start)",
                ),
            )?;
        }
        _ => return Err(unknown(c)),
    }
    g.validate()?;
    Ok((g, changes))
}

fn unknown(c: &Candidate) -> BondError {
    bad(
        c,
        "",
        "not an effect of this model (expected deviation:, fault:, viscous@, coulomb@, load@, inertia@, coupling@, cogging@, brush@ or saturation@ on a matching junction)".to_string(),
    )
}

/// Attaches to `j` an R with effort `level · tanh(f / smoothing)`: a
/// dissipative effort of fixed size opposing the flow (Coulomb friction, a
/// contact drop). `names`: level parameter, smoothing parameter, element;
/// `descriptions` likewise.
fn smoothed_sign(
    g: &mut BondGraph,
    c: &Candidate,
    j: ElementId,
    domain: Domain,
    names: [&str; 3],
    level: f64,
    descriptions: [&str; 3],
) -> Result<()> {
    let level = new_param(g, names[0], level, domain.effort_unit(), descriptions[0])?;
    let smooth = new_param(
        g,
        names[1],
        domain.coulomb_smoothing(),
        domain.flow_unit(),
        descriptions[1],
    )?;
    let effort = law(c, &format!("{level} * tanh(f / {smooth})"))?;
    attach(
        g,
        j,
        Element::nonlinear(names[2], ElementKind::R, Some(effort), None).described(descriptions[2]),
    )?;
    Ok(())
}

/// Puts a factor parameter (value `value`) on every MTF/MGY law that uses
/// input `input`; returns the factor's name.
fn modulus_factor(g: &mut BondGraph, c: &Candidate, input: &str, value: f64) -> Result<String> {
    let users: Vec<ElementId> = g
        .element_ids()
        .filter(|&id| {
            let el = g.element(id);
            matches!(el.kind, ElementKind::Mtf | ElementKind::Mgy)
                && matches!(&el.law, Law::Linear(e) if g.resolved(e).inputs().contains(input))
        })
        .collect();
    if users.is_empty() {
        return Err(bad(
            c,
            "",
            format!("the model has no parameter or modulus input '{input}'"),
        ));
    }
    let factor = new_param(
        g,
        &format!("{}_factor", ident(input)),
        value,
        "1",
        &format!(
            "factor on the modulus input {input} (added effect {})",
            c.id
        ),
    )?;
    for id in users {
        if let Law::Linear(old) = g.element(id).law.clone() {
            let new_law = law(c, &format!("{factor} * ({old})"))?;
            g.element_mut(id).law = Law::Linear(new_law);
        }
    }
    Ok(factor)
}

/// Changes the law of the I called `target` to `f = p / L · (1 + a p²)`.
fn saturate(g: &mut BondGraph, c: &Candidate, target: &str, a: f64) -> Result<()> {
    let id = g
        .find(target)
        .filter(|&id| g.element(id).kind == ElementKind::I)
        .ok_or_else(|| bad(c, "", format!("the model has no I element '{target}'")))?;
    let Law::Linear(old) = g.element(id).law.clone() else {
        return Err(bad(
            c,
            "",
            format!("the I element '{target}' has no linear law to saturate"),
        ));
    };
    let a_name = new_param(
        g,
        &format!("a_sat_{}", ident(target)),
        a,
        "1/Wb^2",
        &format!(
            "saturation: current grows by a_sat p^2 at flux p (added effect {})",
            c.id
        ),
    )?;
    let flow = law(c, &format!("p / ({old}) * (1 + {a_name} * p^2)"))?;
    g.element_mut(id).law = Law::Nonlinear {
        effort: None,
        flow: Some(flow),
    };
    Ok(())
}

/// Bonds a second inertia to junction `j` through a spring and a damper:
/// `j → 0 → {1_twist: C (1/k_s), R (c)} and {1_load: I (J2)}`. The 0-junction
/// carries the coupling torque, the twist junction the relative speed.
#[allow(clippy::too_many_arguments)] // one call site; the pieces are all different
fn couple(
    g: &mut BondGraph,
    c: &Candidate,
    j: ElementId,
    domain: Domain,
    suffix: &str,
    two_stem: &str,
    values: &[f64],
    tag: &str,
) -> Result<()> {
    let k = new_param(
        g,
        &format!("k_s_{suffix}"),
        values[0],
        domain.stiffness_unit(),
        &format!("coupling stiffness {tag}"),
    )?;
    let damping = new_param(
        g,
        &format!("c_{suffix}"),
        values[1],
        domain.damping_unit(),
        &format!("coupling damping {tag}"),
    )?;
    let inertia = new_param(
        g,
        &format!("{two_stem}_{suffix}"),
        values[2],
        domain.inertia_unit(),
        &format!("second {} behind the coupling {tag}", domain.inertia_word()),
    )?;
    let zero = attach(
        g,
        j,
        Element::zero(&format!("coupling_{suffix}"))
            .described(&format!("coupling: common {}", domain.effort_word())),
    )?;
    let twist = attach(
        g,
        zero,
        Element::one(&format!("twist_{suffix}")).described("coupling twist: relative speed"),
    )?;
    let compliance = law(c, &format!("1 / {k}"))?;
    let mut spring = Element::c(&format!("spring_{suffix}"), &k).described("coupling spring");
    spring.law = Law::Linear(compliance);
    attach(g, twist, spring)?;
    attach(
        g,
        twist,
        Element::r(&format!("damper_{suffix}"), &damping).described("coupling damper"),
    )?;
    let far = attach(
        g,
        zero,
        Element::one(&format!("far_{suffix}")).described("far side of the coupling: its own speed"),
    )?;
    attach(
        g,
        far,
        Element::i(&format!("{two_stem}_{suffix}"), &inertia).described(&format!(
            "second {} behind the coupling",
            domain.inertia_word()
        )),
    )?;
    Ok(())
}

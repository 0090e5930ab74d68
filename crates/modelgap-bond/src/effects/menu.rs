//! The menu: every kind of effect offered on a graph, in a stable order,
//! and the plain names of places that candidates use.

use modelgap_core::Candidate;

use super::bond_effect::BondEffect;
use super::def::EffectDef;
use super::scales::Scales;
use super::{
    ActuatorDelay, ActuatorGain, ActuatorLag, ActuatorLimit, ActuatorOffset, Backlash, Brush,
    Cogging, Coulomb, Coupling, DeadZone, Declared, Deviation, Factor, Fault, FluxLimit, Heating,
    Inertia, Inflow, Leak, Load, ModulusRipple, Orifice, Overflow, PowerLoss, Saturation,
    SensorClip, SensorDelay, SensorDrift, SensorLag, SensorOffset, SensorScale, Stiffness, Store,
    Viscous,
};
use crate::element::{ElementKind, Law};
use crate::expr::Expr;
use crate::graph::{BondGraph, ElementId};

/// The candidate effects of a graph, in a stable order: parameter
/// deviations, modulus deviations, abrupt changes, then missing elements
/// junction by junction, then saturations.
///
/// - `deviation:<p>` (kind [`EffectKind::ParameterDeviation`](modelgap_core::EffectKind::ParameterDeviation)) for every
///   parameter `p`: one parameter named `p`, initial the nominal value,
///   bounds a factor of five either way (for a zero nominal `[−s, s]` with
///   `s` the scale of what it acts on), scale `|nominal|`.
/// - `deviation:<u>` for every input `u` used as an MTF/MGY modulus: a
///   factor `<u>_factor` on the input (initial 1, bounds [0.5, 1.5]).
/// - `fault:<p>` / `fault:<u>` (kind [`EffectKind::AbruptChange`](modelgap_core::EffectKind::AbruptChange)): the new
///   value (as above) and the fault time [`T_FAULT`](super::T_FAULT) (unit `s`, initial 0,
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
///   angle from the start; `N_cog` in [2, 24] with [`COGGING_GRID`](super::COGGING_GRID) grid
///   starts). Translational junctions use `F_c`, `F_0`, `dm`, `m2`.
/// - On each electrical 1-junction: `brush@<j>` (`v_b` ≥ 0, smoothed with
///   the fixed [`CONTACT_SMOOTHING_A`](super::CONTACT_SMOOTHING_A)).
/// - For each C with an effort law, in any domain: `stiffness@<C>`, a cubic
///   term `k3 q³` (`k3` either sign; scale: a tenth of the junction's peak
///   effort at the C's peak displacement of a start-up).
/// - On each storage node (a 0-junction with a C, any domain; the words
///   follow the C's unit: hydraulic, thermal, electrical or generic):
///   `leak@<n>` (`f = G e`, `G` ≥ 0), `inflow@<n>` (a constant `Q`, either
///   sign), `overflow@<n>` (`f = k_o max(e − e_max, 0)`, `e_max` on a grid),
///   `store@<n>` (a second storage `C2` behind a resistance `R2`: a second
///   thermal mass, a hydraulic compliance; adds a state) and, on hydraulic
///   and pneumatic nodes, `orifice@<n>` (`f = a sign(e) √|e|`, `a` ≥ 0).
/// - On each source whose value names an input, in any domain:
///   `deadzone@<source>` (the value `v` becomes `sign(v) max(|v| − δ, 0)`,
///   `δ` from 0 to the largest value the source imposed), and `gain@<source>`
///   (the value becomes `k v`, `k` in [0.2, 2]) and `limit@<source>` (the
///   value becomes `sign(v) min(|v|, v_max)`, `v_max` from a twentieth of the
///   largest value the source imposed to that value, eight grid starts),
///   `actuator-lag@<source>` (the source follows its command through a
///   first-order lag `τ`, bounded as a sensor's lag; one state) and
///   `actuator-delay@<source>` (a delay `d` behind, bounded as a sensor's
///   delay; a first-order Padé all-pass, one state).
/// - On each output: `lag@<output>` (a first-order lag `τ` in its sensor, from
///   a tenth of the sample interval to a fifth of the recording; one state),
///   `offset@<output>` (a constant `b` added to its reading, within ± the
///   output's peak) and `scale@<output>` (its reading `k` times the value, `k`
///   in [0.5, 2]; both the output's expression, no state), and
///   `delay@<output>` (it reports `d` late, from a tenth of a sample interval
///   to fifty; a first-order Padé all-pass, one state).
/// - Each effect the model file declares (`[[candidates]]`): `declared:<name>`.
/// - For each electrical I with a linear law: `saturation@<I>`
///   (`f = p / L · (1 + a_sat p²)^m_sat`, `a_sat` ≥ 0 in 1/Wb², scale `0.1 / p_peak²`
///   with `p_peak` the peak flux of a start-up; `m_sat` in [1, 6] from three grid
///   starts).
/// - For each electrical R with a linear law on an electrical 1-junction:
///   `heating@<R>` (`e = R (1 + a_heat E) f`, `E` the energy it has
///   dissipated since the start, a new state; `a_heat` from 0 to `4 / E_run`,
///   `E_run = R I² T` with the junction's typical current over the run).
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
    candidates_with(g, &Scales::of(g))
}

/// The candidates of `g` with these scales (from a recording's run: see
/// [`Scales::of_run`]).
pub fn candidates_with(g: &BondGraph, scales: &Scales) -> Vec<Candidate> {
    offered(g).iter().map(|e| e.candidate(g, scales)).collect()
}

/// Every effect offered on `g`, in the order of [`candidates`]: each kind's
/// offers in turn, the elements on junctions grouped junction by junction.
pub fn offered(g: &BondGraph) -> Vec<BondEffect> {
    fn of<K: EffectDef + Into<BondEffect>>(g: &BondGraph) -> impl Iterator<Item = BondEffect> {
        K::offers(g).into_iter().map(Into::into)
    }
    let mut out: Vec<BondEffect> = Vec::new();
    out.extend(of::<Deviation>(g));
    out.extend(of::<Factor>(g));
    out.extend(of::<Fault>(g));
    // Junction by junction (a stable sort keeps the kinds' order on each).
    let mut on_junctions: Vec<BondEffect> = of::<Brush>(g)
        .chain(of::<Viscous>(g))
        .chain(of::<Coulomb>(g))
        .chain(of::<Load>(g))
        .chain(of::<Inertia>(g))
        .chain(of::<Coupling>(g))
        .chain(of::<Backlash>(g))
        .chain(of::<Cogging>(g))
        .collect();
    on_junctions.sort_by_key(|e| e.junction().map(|j| j.id));
    out.extend(on_junctions);
    out.extend(of::<Saturation>(g));
    out.extend(of::<FluxLimit>(g));
    out.extend(of::<ModulusRipple>(g));
    out.extend(of::<Heating>(g));
    out.extend(of::<Stiffness>(g));
    // Storage nodes, node by node.
    let mut on_nodes: Vec<(ElementId, BondEffect)> = (Leak::offers(g).into_iter())
        .map(|k| (k.node.id, k.into()))
        .chain(Inflow::offers(g).into_iter().map(|k| (k.node.id, k.into())))
        .chain(
            Overflow::offers(g)
                .into_iter()
                .map(|k| (k.node.id, k.into())),
        )
        .chain(
            Orifice::offers(g)
                .into_iter()
                .map(|k| (k.node.id, k.into())),
        )
        .chain(
            PowerLoss::offers(g)
                .into_iter()
                .map(|k| (k.node.id, k.into())),
        )
        .chain(Store::offers(g).into_iter().map(|k| (k.node.id, k.into())))
        .collect();
    on_nodes.sort_by_key(|(id, _)| *id);
    out.extend(on_nodes.into_iter().map(|(_, e)| e));
    out.extend(of::<DeadZone>(g));
    out.extend(of::<ActuatorGain>(g));
    out.extend(of::<ActuatorOffset>(g));
    out.extend(of::<ActuatorLimit>(g));
    out.extend(of::<ActuatorLag>(g));
    out.extend(of::<ActuatorDelay>(g));
    out.extend(of::<SensorLag>(g));
    out.extend(of::<SensorOffset>(g));
    out.extend(of::<SensorDrift>(g));
    out.extend(of::<SensorClip>(g));
    out.extend(of::<SensorScale>(g));
    out.extend(of::<SensorDelay>(g));
    out.extend(of::<Declared>(g));
    out
}

/// The head of a description: the text before a `:` or a ` (`.
pub(super) fn head(description: &str) -> &str {
    let cut = [description.find(':'), description.find(" (")]
        .into_iter()
        .flatten()
        .min()
        .unwrap_or(description.len());
    description[..cut].trim()
}

/// What an element with a linear law is, in words: its parameter's
/// description and name ("armature resistance (R)"), else the parameter's
/// name, else the element's.
pub(super) fn linear_element_words(g: &BondGraph, id: ElementId) -> String {
    let el = g.element(id);
    match &el.law {
        Law::Linear(Expr::Param(n)) => g
            .params()
            .get(n)
            .map(|p| head(&p.description).to_string())
            .filter(|s| !s.is_empty())
            .map_or_else(|| n.clone(), |h| format!("{h} ({n})")),
        _ => el.name.clone(),
    }
}

/// "the shaft (1m)" from a junction's description, or "junction 1m".
pub(crate) fn place(g: &BondGraph, j: ElementId) -> String {
    let el = g.element(j);
    // A C alone on a 1-junction is a node of its own (`Node::of`): named as an element.
    if el.kind == ElementKind::C {
        return element_place(g, j);
    }
    let h = head(&el.description);
    if h.is_empty() {
        format!("junction {}", el.name)
    } else if h.starts_with("the ") || h.starts_with("a ") {
        format!("{h} ({})", el.name)
    } else {
        format!("the {h} ({})", el.name)
    }
}

/// "switch and diode [switch]" or "element switch".
pub(super) fn element_place(g: &BondGraph, id: ElementId) -> String {
    let el = g.element(id);
    let h = head(&el.description);
    if h.is_empty() {
        format!("element {}", el.name)
    } else {
        format!("{h} [{}]", el.name)
    }
}

/// "armature resistance (R)" from a parameter's description, or "R".
pub(super) fn param_place(g: &BondGraph, name: &str) -> String {
    match g.params().get(name) {
        Some(p) if !p.description.is_empty() => format!("{} ({name})", head(&p.description)),
        _ => name.to_string(),
    }
}

/// The nominal value of a linear law, evaluated with the graph's parameters
/// and input defaults.
pub(super) fn law_value(g: &BondGraph, e: &Expr) -> Option<f64> {
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

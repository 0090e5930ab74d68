//! Discovery's first stage for a bond graph: the missing effort at each
//! junction, estimated from a recording ([`missing_signals`]).
//!
//! At each place an unknown effort or flow could act — a 1-junction with an
//! inertia (a shaft, a moving body, an armature loop, a mass in any domain)
//! or a 0-junction with a storage (a tank, a thermal mass, a capacitor node) —
//! the graph gets one more source, an `Se` (an `Sf` on a 0-junction) whose
//! value `d(t)` is unknown, bonded as a load is (a positive effort opposes the
//! junction's flow; a positive flow drains the node). The model's states and
//! `d` are estimated together by an extended Kalman filter and a
//! Rauch–Tung–Striebel smoother over the whole recording: the nominal model
//! plus one unknown-input state, `d` a random walk whose intensity is chosen
//! by the likelihood of the measurements. What comes out is `d(t)` with its
//! one-sigma band — the missing torque, force, voltage drop, leak — and the
//! smoothed signals acting there (the junction's flow, the angle or position
//! it integrates to, the springs bonded to it, the inputs), ready for the
//! screen to see its law. Where the outputs cannot see the place, the band
//! says so, and the share of the output residual the place can remove is low.
//!
//! Each step is discretised exactly for the model linearised at the current
//! estimate (the exponential of the augmented Jacobian: stiff models are
//! stable at the recording's sample step), and reused while the Jacobian does
//! not change (a linear model costs one exponential).

use modelgap_core::explain::estimate::{ActingSignal, MissingSignal, Quantity, SignalRole};
use modelgap_core::{Candidate, Recording};
use nalgebra::{DMatrix, DVector};

use crate::compiled::CompiledModel;
use crate::effects::{Domain, Junction, Node, attach, place};
use crate::element::{Element, ElementKind, Law, Measured, Output};
use crate::error::Result;
use crate::expr::Expr;
use crate::graph::{BondGraph, ElementId};
use crate::model::BondModel;
use crate::simulate::Drive;

/// The name of the unknown input the estimate adds.
const UNKNOWN: &str = "d_missing";
/// Random-walk intensities tried, in decades above the reference (the squared effort
/// that would explain the nominal's error, spread over the record). The reference is
/// inflated where the nominal model runs far from the data (a pendulum it swings round and
/// round, 135 rad off, while the real one turns over a few times): there the likeliest
/// intensity lay four decades below it, under every one tried from −1, and the estimate
/// was noise (a band of 0.22 N m about a torque of 0.06 N m) where it is now pinned.
const Q_DECADES: [f64; 10] = [-5.5, -4.0, -2.5, -1.0, 0.5, 2.0, 3.5, 5.0, 6.5, 8.0];
/// Rounds of [`measurement_noise`]'s search: each output's noise in turn, then the
/// random walk's intensity again.
const NOISE_ROUNDS: usize = 2;
/// Measurement-noise levels tried per output, in decades of the floor given.
const R_DECADES: [f64; 13] = [
    -3.0, -2.5, -2.0, -1.5, -1.0, -0.5, 0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0,
];

/// A place an unknown effort or flow may act.
#[derive(Clone, Debug)]
struct Place {
    id: ElementId,
    quantity: Quantity,
    unit: String,
    /// What the place's flow (effort on a node) integrates to, if it is a
    /// mechanical place: an angle or a position.
    integral: Option<(SignalRole, String)>,
    flow_unit: String,
    /// What the flow (effort on a node) is called: `speed`, `current`, `level`.
    flow_word: &'static str,
}

/// What a 1-junction's flow is called in its domain: `speed`, `velocity`,
/// `current`, or `flow` in none known.
fn flow_word(domain: Option<Domain>) -> &'static str {
    match domain {
        Some(Domain::Rotational) => "speed",
        Some(Domain::Translational) => "velocity",
        Some(Domain::Electrical) => "current",
        None => "flow",
    }
}

/// The places of `g`: 1-junctions with an I bonded, 0-junctions with a C.
fn places(g: &BondGraph) -> Vec<Place> {
    let mut out = Vec::new();
    for id in g.element_ids() {
        let el = g.element(id);
        match el.kind {
            ElementKind::One => {
                let has_i = (g.ports(id).into_iter())
                    .any(|(b, _)| g.element(g.other_end(b, id)).kind == ElementKind::I);
                if !has_i {
                    continue;
                }
                let domain = Junction::of(g, id).map(|j| j.domain);
                let (unit, flow_unit) = match domain {
                    Some(d) => (d.effort_unit().to_string(), d.flow_unit().to_string()),
                    None => (source_unit(g, id), String::new()),
                };
                let integral = match domain {
                    Some(Domain::Rotational) => Some((SignalRole::Angle, "rad".to_string())),
                    Some(Domain::Translational) => Some((SignalRole::Position, "m".to_string())),
                    Some(Domain::Electrical) => None,
                    None => {
                        // A place of no known domain: its position, unless a spring gives it.
                        let spring = (g.ports(id).into_iter())
                            .any(|(b, _)| g.element(g.other_end(b, id)).kind == ElementKind::C);
                        (!spring).then(|| (SignalRole::Displacement, String::new()))
                    }
                };
                let flow_word = flow_word(domain);
                out.push(Place {
                    id,
                    quantity: Quantity::Effort,
                    unit,
                    integral,
                    flow_unit,
                    flow_word,
                });
            }
            // A 0-junction with a C, or a C alone on a 1-junction (a capacitor in a
            // series loop: what leaks across it has nowhere else to act).
            ElementKind::Zero | ElementKind::C => {
                if let Some(node) = Node::of(g, id) {
                    let (e, f) = node.units();
                    let known = |u: &str| {
                        if u == "e" || u == "f" {
                            String::new()
                        } else {
                            u.to_string()
                        }
                    };
                    let flow_word = match node.kind {
                        crate::effects::NodeKind::Hydraulic if node.level => "level",
                        crate::effects::NodeKind::Hydraulic => "pressure",
                        crate::effects::NodeKind::Thermal => "temperature",
                        crate::effects::NodeKind::Electrical => "voltage",
                        crate::effects::NodeKind::Generic => "effort",
                    };
                    out.push(Place {
                        id,
                        quantity: Quantity::Flow,
                        unit: known(f),
                        integral: None,
                        flow_unit: known(e),
                        flow_word,
                    });
                }
            }
            _ => {}
        }
    }
    out
}

/// The unit of an input driving a source on junction `j` (the effort unit of
/// a place whose domain is not known), or empty.
fn source_unit(g: &BondGraph, j: ElementId) -> String {
    for (b, _) in g.ports(j) {
        let el = g.element(g.other_end(b, j));
        if let (ElementKind::Se, Law::Source(e)) = (&el.kind, &el.law) {
            for name in e.inputs().into_iter().chain(e.params()) {
                if let Some(i) = g.inputs().get(&name) {
                    return i.unit.clone();
                }
            }
        }
    }
    String::new()
}

/// A signal in law syntax: `'1m'.f` for a name that is not an identifier.
pub(crate) fn signal_name(element: &str, var: &str) -> String {
    Expr::signal(element, var).to_string()
}

/// The element name of the position state a law adds on junction `name`.
pub(crate) fn position_element(name: &str) -> String {
    let ident: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    format!("pos_{ident}")
}

/// The missing effort (or flow) at every place of `model` (with `effects`
/// applied), estimated from `rec` against `outputs` with noise `sigma`.
/// Places that cannot be estimated (the edit breaks causality, the outputs
/// do not see them) are left out.
///
/// # Errors
/// The nominal model cannot be simulated on the recording.
pub fn missing_signals(
    model: &BondModel,
    rec: &Recording,
    effects: &[(&Candidate, &[f64])],
    outputs: &[String],
    sigma: &[f64],
) -> Result<Vec<MissingSignal>> {
    Ok(every_place(model, rec, effects, outputs, sigma, false)?
        .into_iter()
        .map(|(m, _)| m)
        .collect())
}

/// The white measurement noise of each of `outputs` (σ, in its unit) that
/// `model` (with `effects` applied) finds likeliest on `rec` when a free
/// effort or flow acts at its place that explains most: the smoother of
/// [`missing_signals`] with each output's noise level chosen by likelihood
/// too (from a thousandth to a thousand times `sigma`). What a model lacking
/// nothing but that effort would still leave: a noise floor that the signal's
/// own fast content does not inflate. Outputs the recording lacks are left
/// out; empty when no place can be estimated.
///
/// # Errors
/// The nominal model cannot be simulated on the recording.
pub fn measurement_noise(
    model: &BondModel,
    rec: &Recording,
    effects: &[(&Candidate, &[f64])],
    outputs: &[String],
    sigma: &[f64],
) -> Result<Vec<(String, f64)>> {
    let best = every_place(model, rec, effects, outputs, sigma, true)?
        .into_iter()
        .max_by(|a, b| a.0.explained.total_cmp(&b.0.explained));
    Ok(best.map(|(_, noise)| noise).unwrap_or_default())
}

/// Each measured output's noise σ, by name.
type Noise = Vec<(String, f64)>;

/// Each place's estimate and the noise its smoother took ([`estimate_at`]),
/// for the model with `effects` applied, on `rec` against `outputs`.
fn every_place(
    model: &BondModel,
    rec: &Recording,
    effects: &[(&Candidate, &[f64])],
    outputs: &[String],
    sigma: &[f64],
    scan_noise: bool,
) -> Result<Vec<(MissingSignal, Noise)>> {
    let (graph, _) = model.edited(effects)?;
    let nominal = model.run(rec, effects)?;
    let x0 = |name: &str| nominal.state(name).and_then(|s| s.first().copied());
    let measured: Vec<(usize, &[f64], f64)> = (outputs.iter().zip(sigma))
        .filter_map(|(o, s)| {
            let values = rec.signal(o)?.values.as_slice();
            let j = nominal.output_names.iter().position(|n| n == o)?;
            Some((j, values, *s))
        })
        .collect();
    if measured.is_empty() {
        return Ok(Vec::new());
    }
    Ok(places(&graph)
        .iter()
        .filter_map(|p| {
            estimate_at(
                model, &graph, p, rec, &x0, outputs, &measured, &nominal, scan_noise,
            )
        })
        .collect())
}

/// The graph with the unknown source at `p` and outputs for what acts there:
/// the graph, the acting signals (name, label, unit, role, output name) and
/// the compiled model.
#[allow(clippy::type_complexity)]
fn augmented(
    graph: &BondGraph,
    p: &Place,
) -> Option<(
    CompiledModel,
    Vec<(String, String, String, SignalRole, String)>,
)> {
    let mut g = graph.clone();
    let name = g.element(p.id).name.clone();
    g.add_input(UNKNOWN, 0.0, &p.unit, "the missing effort or flow")
        .ok()?;
    let source = match p.quantity {
        Quantity::Effort => Element::se("missing_source", UNKNOWN),
        Quantity::Flow => Element::sf("missing_source", UNKNOWN),
    };
    // A C alone on a 1-junction: its node's junction, put between them.
    let at = match g.element(p.id).kind {
        ElementKind::C => Node::of(&g, p.id)?.junction(&mut g).ok()?,
        _ => p.id,
    };
    attach(&mut g, at, source).ok()?;
    let mut acting = Vec::new();
    let mut add =
        |g: &mut BondGraph, measured: Measured, label: String, unit: String, law: String, role| {
            let out = format!("__acting_{}", acting.len());
            g.add_output(Output {
                name: out.clone(),
                measured,
                unit: unit.clone(),
            })
            .ok()?;
            acting.push((law, label, unit, role, out));
            Some(())
        };
    let words = place(graph, p.id);
    match p.quantity {
        Quantity::Effort => {
            add(
                &mut g,
                Measured::Flow(name.clone()),
                format!("{} of {words}", p.flow_word),
                p.flow_unit.clone(),
                signal_name(&name, "f"),
                SignalRole::Flow,
            )?;
            for (b, _) in graph.ports(p.id) {
                let other = graph.element(graph.other_end(b, p.id));
                if other.kind == ElementKind::C {
                    add(
                        &mut g,
                        Measured::State(other.name.clone()),
                        format!("displacement of {}", other.name),
                        String::new(),
                        signal_name(&other.name, "q"),
                        SignalRole::Displacement,
                    )?;
                }
            }
            for j in coupled_junctions(graph, p.id) {
                let domain = Junction::of(graph, j).map(|d| d.domain);
                let word = flow_word(domain);
                let jname = graph.element(j).name.clone();
                add(
                    &mut g,
                    Measured::Flow(jname.clone()),
                    format!("{word} of {}", place(graph, j)),
                    domain.map_or(String::new(), |d| d.flow_unit().to_string()),
                    signal_name(&jname, "f"),
                    SignalRole::Coupled,
                )?;
            }
        }
        Quantity::Flow => {
            add(
                &mut g,
                Measured::Effort(name.clone()),
                format!("{} of {words}", p.flow_word),
                p.flow_unit.clone(),
                signal_name(&name, "e"),
                SignalRole::Effort,
            )?;
        }
    }
    let cm = CompiledModel::new(&g).ok()?;
    Some((cm, acting))
}

/// The 1-junctions one gyrator or transformer away from the 1-junction `id`
/// (the winding's loop of a motor, seen from its shaft), each once.
fn coupled_junctions(g: &BondGraph, id: ElementId) -> Vec<ElementId> {
    let mut out: Vec<ElementId> = Vec::new();
    for (b, _) in g.ports(id) {
        let t = g.other_end(b, id);
        if !matches!(
            g.element(t).kind,
            ElementKind::Gy | ElementKind::Tf | ElementKind::Mgy | ElementKind::Mtf
        ) {
            continue;
        }
        for (c, _) in g.ports(t) {
            let j = g.other_end(c, t);
            if j != id && g.element(j).kind == ElementKind::One && !out.contains(&j) {
                out.push(j);
            }
        }
    }
    out
}

/// One place's estimate, and each measured output's noise σ the smoother used:
/// the one given, or with `scan_noise` the likeliest.
#[allow(clippy::too_many_arguments)]
fn estimate_at(
    model: &BondModel,
    graph: &BondGraph,
    p: &Place,
    rec: &Recording,
    x0: &dyn Fn(&str) -> Option<f64>,
    outputs: &[String],
    measured: &[(usize, &[f64], f64)],
    nominal: &crate::simulate::Run,
    scan_noise: bool,
) -> Option<(MissingSignal, Noise)> {
    let (cm, acting) = augmented(graph, p)?;
    let n = cm.n_states();
    let d_slot = cm.input_names.iter().position(|i| i == UNKNOWN)?;
    // The measured outputs in the augmented model, with their noise.
    let ys: Vec<(usize, &[f64], f64, &[f64])> = (measured.iter())
        .filter_map(|&(j, values, s)| {
            let name = &nominal.output_names[j];
            let k = cm.output_names.iter().position(|o| o == name)?;
            let rms =
                (values.iter().map(|v| v * v).sum::<f64>() / values.len().max(1) as f64).sqrt();
            let s = s.max(1e-6 * rms).max(1e-300);
            Some((k, values, s, nominal.outputs[j].as_slice()))
        })
        .collect();
    if ys.is_empty() || outputs.is_empty() {
        return None;
    }
    let input_names: Vec<String> = graph.inputs().keys().cloned().collect();
    let inputs = model.inputs_of(graph, rec);
    let drives: Vec<Drive> = (cm.input_names.iter())
        .map(|name| {
            inputs.get(name).cloned().unwrap_or_else(|| {
                Drive::Constant(graph.inputs().get(name).map_or(0.0, |i| i.default))
            })
        })
        .collect();
    let t = rec.t();
    let nt = t.len();
    let mut x_start: Vec<f64> = (cm.state_names.iter())
        .map(|s| x0(s).unwrap_or(0.0))
        .collect();
    if x_start.len() != n {
        x_start.resize(n, 0.0);
    }
    let xs: Vec<f64> = (0..n)
        .map(|i| {
            let name = &cm.state_names[i];
            let peak = nominal
                .state(name)
                .map_or(0.0, |s| s.iter().fold(0.0_f64, |a, v| a.max(v.abs())));
            if peak > 0.0 { peak } else { 1.0 }
        })
        .collect();
    let f = Filter::new(&cm, &drives, d_slot, t, &ys, xs);
    let dscale = f.reference_scale(&x_start)?;
    let q_ref = dscale * dscale / (t[nt - 1] - t[0]).max(1e-300);
    // The random walk's intensity and each output's noise: the ones the measurements find
    // likeliest (the intensity, each noise in turn, the intensity again).
    let mut r = vec![1.0; ys.len()];
    let best_q = |r: &[f64]| -> Option<(f64, f64)> {
        let mut best: Option<(f64, f64)> = None;
        for dec in Q_DECADES {
            let q = q_ref * 10f64.powf(dec);
            if let Some(ll) = f.log_likelihood(&x_start, dscale, q, r)
                && best.is_none_or(|(_, b)| ll > b)
            {
                best = Some((q, ll));
            }
        }
        best
    };
    let (mut q, _) = best_q(&r)?;
    for _ in 0..NOISE_ROUNDS * usize::from(scan_noise) {
        for j in 0..r.len() {
            let mut tried: Vec<(f64, f64)> = Vec::new();
            for dec in R_DECADES {
                let mut rj = r.clone();
                rj[j] = 10f64.powf(dec);
                if let Some(ll) = f.log_likelihood(&x_start, dscale, q, &rj) {
                    tried.push((dec, ll));
                }
            }
            if let Some(dec) = likeliest(&tried) {
                r[j] = 10f64.powf(dec);
            }
        }
        if let Some((q_again, _)) = best_q(&r) {
            q = q_again;
        }
    }
    let smoothed = f.smooth(&x_start, dscale, q, &r)?;
    // What acts there, on the smoothed states; and the outputs they predict.
    let mut scratch = cm.scratch();
    let mut u = vec![0.0; cm.n_inputs()];
    let mut cursors = vec![0usize; drives.len()];
    let mut y = vec![0.0; cm.n_outputs()];
    let mut acting_values: Vec<Vec<f64>> = vec![Vec::with_capacity(nt); acting.len()];
    let mut before = 0.0;
    let mut after = 0.0;
    for k in 0..nt {
        f.inputs_at(t[k], &smoothed.z[k], &mut u, &mut cursors);
        cm.eval(t[k], &smoothed.z[k][..n], &u, &mut scratch);
        cm.read_outputs(&scratch, &mut y);
        for (a, (_, _, _, _, out)) in acting.iter().enumerate() {
            if let Some(j) = cm.output_names.iter().position(|o| o == out) {
                acting_values[a].push(y[j]);
            }
        }
        for &(j, values, s, nom) in &ys {
            before += ((values[k] - nom[k]) / s).powi(2);
            after += ((values[k] - y[j]) / s).powi(2);
        }
    }
    let mut signals: Vec<ActingSignal> = Vec::new();
    for ((law, label, unit, role, _), values) in acting.into_iter().zip(acting_values) {
        if values.len() != nt {
            continue;
        }
        if role == SignalRole::Flow
            && let Some((irole, iunit)) = &p.integral
        {
            // The angle or position: the flow integrated from the start.
            let mut pos = Vec::with_capacity(nt);
            let mut acc = 0.0;
            pos.push(0.0);
            for k in 1..nt {
                acc += 0.5 * (values[k] + values[k - 1]) * (t[k] - t[k - 1]);
                pos.push(acc);
            }
            let name = graph.element(p.id).name.clone();
            signals.push(ActingSignal {
                name: signal_name(&position_element(&name), "q"),
                label: match irole {
                    SignalRole::Angle => format!("angle of {}", place(graph, p.id)),
                    _ => format!("position of {}", place(graph, p.id)),
                },
                unit: iunit.clone(),
                role: *irole,
                values: pos,
            });
        }
        let signal = ActingSignal {
            name: law,
            label,
            unit,
            role,
            values,
        };
        // The place's own flow first.
        if role == SignalRole::Flow {
            signals.insert(0, signal);
        } else {
            signals.push(signal);
        }
    }
    for name in &input_names {
        if let Some(s) = rec.signal(name) {
            signals.push(ActingSignal {
                name: name.clone(),
                label: format!("input {name}"),
                unit: graph
                    .inputs()
                    .get(name)
                    .map_or(String::new(), |i| i.unit.clone()),
                role: SignalRole::Input,
                values: s.values.clone(),
            });
        }
    }
    let explained = if before > 0.0 {
        (1.0 - after / before).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let noise: Vec<(String, f64)> = (ys.iter().zip(&r))
        .map(|(&(k, _, s, _), r)| (cm.output_names[k].clone(), s * r))
        .collect();
    let m = MissingSignal {
        location: graph.element(p.id).name.clone(),
        place: place(graph, p.id),
        quantity: p.quantity,
        unit: p.unit.clone(),
        t: t.to_vec(),
        value: smoothed.z.iter().map(|z| z[n]).collect(),
        band: smoothed.var.iter().map(|v| v.max(0.0).sqrt()).collect(),
        acting: signals,
        explained,
    };
    Some((m, noise))
}

/// The log-scale point of greatest likelihood among `tried` (`(log10 x, ll)`,
/// in increasing `x`): the best point, moved to the top of the parabola
/// through it and its neighbours when it has both (within half a step).
fn likeliest(tried: &[(f64, f64)]) -> Option<f64> {
    let (i, _) = (tried.iter().enumerate()).max_by(|a, b| a.1.1.total_cmp(&b.1.1))?;
    let x = tried[i].0;
    if i == 0 || i + 1 == tried.len() {
        return Some(x);
    }
    let ((x0, y0), (x1, y1), (x2, y2)) = (tried[i - 1], tried[i], tried[i + 1]);
    let denom = (x1 - x0) * (y1 - y2) - (x1 - x2) * (y1 - y0);
    if denom == 0.0 || !denom.is_finite() {
        return Some(x1);
    }
    let top = x1 - 0.5 * ((x1 - x0).powi(2) * (y1 - y2) - (x1 - x2).powi(2) * (y1 - y0)) / denom;
    let half = 0.25 * (x2 - x0);
    Some(if top.is_finite() {
        top.clamp(x1 - half, x1 + half)
    } else {
        x1
    })
}

/// The smoother's result: the augmented state and the variance of `d` per sample.
struct Smoothed {
    z: Vec<Vec<f64>>,
    var: Vec<f64>,
}

/// The extended Kalman filter over the augmented state `[x; d]`.
struct Filter<'a> {
    cm: &'a CompiledModel,
    drives: &'a [Drive],
    d_slot: usize,
    t: &'a [f64],
    /// Output index in the compiled model, measured values, noise, nominal prediction.
    ys: Vec<(usize, &'a [f64], f64, &'a [f64])>,
    /// State scales (finite-difference steps, the start's uncertainty).
    xs: Vec<f64>,
}

/// A step's linearisation: `z⁺ = z + Φ fz`, covariance through `F`.
#[derive(Clone)]
struct Step {
    a: DMatrix<f64>,
    h: f64,
    f: DMatrix<f64>,
    phi: DMatrix<f64>,
}

/// One forward pass's record for the smoother.
struct Forward {
    z_post: Vec<DVector<f64>>,
    p_post: Vec<DMatrix<f64>>,
    z_prior: Vec<DVector<f64>>,
    p_prior: Vec<DMatrix<f64>>,
    f: Vec<DMatrix<f64>>,
}

impl<'a> Filter<'a> {
    fn new(
        cm: &'a CompiledModel,
        drives: &'a [Drive],
        d_slot: usize,
        t: &'a [f64],
        ys: &[(usize, &'a [f64], f64, &'a [f64])],
        xs: Vec<f64>,
    ) -> Filter<'a> {
        Filter {
            cm,
            drives,
            d_slot,
            t,
            ys: ys.to_vec(),
            xs,
        }
    }

    fn inputs_at(&self, t: f64, z: &[f64], u: &mut [f64], cursors: &mut [usize]) {
        for (j, d) in self.drives.iter().enumerate() {
            u[j] = d.value(t, &mut cursors[j]);
        }
        u[self.d_slot] = z[self.cm.n_states()];
    }

    /// `ż = [f(x, u, d); 0]` and the outputs `y(x, u, d)` at `z`.
    fn eval(
        &self,
        t: f64,
        z: &[f64],
        u: &mut [f64],
        scratch: &mut [f64],
        dz: &mut [f64],
        y: &mut [f64],
    ) {
        let n = self.cm.n_states();
        u[self.d_slot] = z[n];
        self.cm.eval(t, &z[..n], u, scratch);
        self.cm.read_derivatives(scratch, &mut dz[..n]);
        dz[n] = 0.0;
        self.cm.read_outputs(scratch, y);
    }

    /// Jacobians of `ż` (m × m) and of the measured outputs (ny × m) at `z`, with the values.
    #[allow(clippy::type_complexity)]
    fn linearise(
        &self,
        t: f64,
        z: &[f64],
        dscale: f64,
        u: &mut [f64],
        scratch: &mut [f64],
    ) -> (DMatrix<f64>, DVector<f64>, DMatrix<f64>, DVector<f64>) {
        let n = self.cm.n_states();
        let m = n + 1;
        let ny = self.cm.n_outputs();
        let mut dz0 = vec![0.0; m];
        let mut y0 = vec![0.0; ny];
        self.eval(t, z, u, scratch, &mut dz0, &mut y0);
        let mut a = DMatrix::zeros(m, m);
        let mut hm = DMatrix::zeros(self.ys.len(), m);
        let mut zp = z.to_vec();
        let mut dz = vec![0.0; m];
        let mut y = vec![0.0; ny];
        for j in 0..m {
            let scale = if j < n { self.xs[j] } else { dscale };
            let step = 1e-6 * scale.max(z[j].abs());
            zp[j] = z[j] + step;
            self.eval(t, &zp, u, scratch, &mut dz, &mut y);
            zp[j] = z[j];
            for i in 0..n {
                a[(i, j)] = (dz[i] - dz0[i]) / step;
            }
            for (r, &(k, _, _, _)) in self.ys.iter().enumerate() {
                hm[(r, j)] = (y[k] - y0[k]) / step;
            }
        }
        let ym = DVector::from_iterator(self.ys.len(), self.ys.iter().map(|&(k, _, _, _)| y0[k]));
        (a, DVector::from_vec(dz0), hm, ym)
    }

    /// The exact discretisation of the linearised step: `F = e^{Ah}` and
    /// `Φ = ∫₀ʰ e^{As} ds`, reused while `A` and `h` do not change.
    fn discretise(
        a: &DMatrix<f64>,
        h: f64,
        cache: &mut Option<Step>,
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        if let Some(c) = cache
            && c.h == h
            && (&c.a - a).amax() <= 1e-9 * a.amax().max(1e-300)
        {
            return (c.f.clone(), c.phi.clone());
        }
        let m = a.nrows();
        let mut big = DMatrix::zeros(2 * m, 2 * m);
        big.view_mut((0, 0), (m, m)).copy_from(&(a * h));
        big.view_mut((0, m), (m, m))
            .copy_from(&(DMatrix::identity(m, m) * h));
        let e = big.exp();
        let f = e.view((0, 0), (m, m)).into_owned();
        let phi = e.view((0, m), (m, m)).into_owned();
        *cache = Some(Step {
            a: a.clone(),
            h,
            f: f.clone(),
            phi: phi.clone(),
        });
        (f, phi)
    }

    fn start(&self, x0: &[f64], dscale: f64) -> (DVector<f64>, DMatrix<f64>) {
        let n = x0.len();
        let mut z = DVector::zeros(n + 1);
        let mut p = DMatrix::zeros(n + 1, n + 1);
        for i in 0..n {
            z[i] = x0[i];
            p[(i, i)] = (1e-3 * self.xs[i]).powi(2);
        }
        p[(n, n)] = (10.0 * dscale).powi(2);
        (z, p)
    }

    /// The forward pass: log-likelihood, and the record when `keep`; each
    /// output's noise is its given σ times `r_scale`.
    fn forward(
        &self,
        x0: &[f64],
        dscale: f64,
        q: f64,
        r_scale: &[f64],
        keep: bool,
    ) -> Option<(f64, Option<Forward>)> {
        let n = x0.len();
        let m = n + 1;
        let nt = self.t.len();
        let mut u = vec![0.0; self.cm.n_inputs()];
        let mut cursors = vec![0usize; self.drives.len()];
        let mut scratch = self.cm.scratch();
        let r_diag: Vec<f64> = (self.ys.iter().zip(r_scale))
            .map(|(&(_, _, s, _), r)| (s * r).powi(2))
            .collect();
        let (mut z, mut p) = self.start(x0, dscale);
        let mut ll = 0.0;
        let mut cache: Option<Step> = None;
        let mut rec = keep.then(|| Forward {
            z_post: Vec::with_capacity(nt),
            p_post: Vec::with_capacity(nt),
            z_prior: Vec::with_capacity(nt),
            p_prior: Vec::with_capacity(nt),
            f: Vec::with_capacity(nt),
        });
        let q_floor: Vec<f64> = (0..n).map(|i| (1e-9 * self.xs[i]).powi(2)).collect();
        for k in 0..nt {
            // Measurement update at t_k.
            for (j, d) in self.drives.iter().enumerate() {
                u[j] = d.value(self.t[k], &mut cursors[j]);
            }
            let (_, _, hm, ym) =
                self.linearise(self.t[k], z.as_slice(), dscale, &mut u, &mut scratch);
            let ny = self.ys.len();
            let nu = DVector::from_iterator(ny, (0..ny).map(|r| self.ys[r].1[k] - ym[r]));
            let mut s = &hm * &p * hm.transpose();
            for r in 0..ny {
                s[(r, r)] += r_diag[r];
            }
            let chol = s.clone().cholesky()?;
            let sinv_nu = chol.solve(&nu);
            let logdet: f64 = 2.0 * (0..ny).map(|r| chol.l()[(r, r)].ln()).sum::<f64>();
            ll -= 0.5 * (logdet + nu.dot(&sinv_nu));
            let pht = &p * hm.transpose();
            let gain = chol.solve(&pht.transpose()).transpose();
            z += &gain * &nu;
            let ikh = DMatrix::identity(m, m) - &gain * &hm;
            let mut rr = DMatrix::zeros(ny, ny);
            for r in 0..ny {
                rr[(r, r)] = r_diag[r];
            }
            p = &ikh * &p * ikh.transpose() + &gain * rr * gain.transpose();
            if !z.iter().all(|v| v.is_finite()) {
                return None;
            }
            if let Some(r) = rec.as_mut() {
                r.z_post.push(z.clone());
                r.p_post.push(p.clone());
            }
            if k + 1 == nt {
                break;
            }
            // Prediction to t_{k+1}, linearised at the update, inputs at mid-interval.
            let h = self.t[k + 1] - self.t[k];
            let tm = 0.5 * (self.t[k] + self.t[k + 1]);
            let mut cm = cursors.clone();
            for (j, d) in self.drives.iter().enumerate() {
                u[j] = d.value(tm, &mut cm[j]);
            }
            let (a, fz, _, _) = self.linearise(tm, z.as_slice(), dscale, &mut u, &mut scratch);
            let (f, phi) = Self::discretise(&a, h, &mut cache);
            z += &phi * fz;
            p = &f * &p * f.transpose();
            for i in 0..n {
                p[(i, i)] += q_floor[i];
            }
            p[(n, n)] += q * h;
            p = 0.5 * (&p + p.transpose());
            if let Some(r) = rec.as_mut() {
                r.z_prior.push(z.clone());
                r.p_prior.push(p.clone());
                r.f.push(f);
            }
        }
        Some((ll, rec))
    }

    fn log_likelihood(&self, x0: &[f64], dscale: f64, q: f64, r_scale: &[f64]) -> Option<f64> {
        self.forward(x0, dscale, q, r_scale, false)
            .map(|(ll, _)| ll)
            .filter(|v| v.is_finite())
    }

    /// The Rauch–Tung–Striebel smoother over the forward pass.
    fn smooth(&self, x0: &[f64], dscale: f64, q: f64, r_scale: &[f64]) -> Option<Smoothed> {
        let (_, rec) = self.forward(x0, dscale, q, r_scale, true)?;
        let r = rec?;
        let nt = r.z_post.len();
        let n = x0.len();
        let mut zs = r.z_post.clone();
        let mut ps = r.p_post.clone();
        for k in (0..nt.saturating_sub(1)).rev() {
            let prior = &r.p_prior[k];
            let Some(chol) = prior.clone().cholesky() else {
                continue;
            };
            // C = P_k|k Fᵀ (P_k+1|k)⁻¹
            let c = chol.solve(&(&r.f[k] * &r.p_post[k])).transpose();
            let dz = &zs[k + 1] - &r.z_prior[k];
            zs[k] = &r.z_post[k] + &c * dz;
            let dp = &ps[k + 1] - prior;
            ps[k] = &r.p_post[k] + &c * dp * c.transpose();
        }
        Some(Smoothed {
            z: zs.iter().map(|z| z.as_slice().to_vec()).collect(),
            var: ps.iter().map(|p| p[(n, n)]).collect(),
        })
    }

    /// The size of a missing effort that would explain the outputs' residual
    /// about the nominal prediction: the residual's RMS over the RMS response
    /// to a unit constant effort (the model linearised at the start).
    fn reference_scale(&self, x0: &[f64]) -> Option<f64> {
        let n = x0.len();
        let nt = self.t.len();
        let mut u = vec![0.0; self.cm.n_inputs()];
        let mut cursors = vec![0usize; self.drives.len()];
        let mut scratch = self.cm.scratch();
        for (j, d) in self.drives.iter().enumerate() {
            u[j] = d.value(self.t[0], &mut cursors[j]);
        }
        let mut z0 = x0.to_vec();
        z0.push(0.0);
        let (a, _, hm, _) = self.linearise(self.t[0], &z0, 1.0, &mut u, &mut scratch);
        let h = (self.t[nt - 1] - self.t[0]) / (nt - 1).max(1) as f64;
        let (f, _) = Self::discretise(&a, h, &mut None);
        // The deviation from the nominal a unit effort makes, held from the start.
        let mut s = DVector::zeros(n + 1);
        s[n] = 1.0;
        let (mut gain2, mut resid2) = (0.0, 0.0);
        for k in 0..nt {
            let resp = &hm * &s;
            for (r, &(_, values, sig, nom)) in self.ys.iter().enumerate() {
                gain2 += (resp[r] / sig).powi(2);
                resid2 += ((values[k] - nom[k]) / sig).powi(2);
            }
            s = &f * &s;
            if !s.iter().all(|v| v.is_finite()) {
                break;
            }
        }
        let g = gain2.sqrt();
        (g.is_finite() && g > 0.0).then(|| (resid2.sqrt() / g).max(1e-300))
    }
}

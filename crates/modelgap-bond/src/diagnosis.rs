//! Fault diagnosis of a recording with the paper's method: residuals from
//! a parallel model, detection against a band, fault trees of the deviating
//! measurements, the first hypothesis set, and its shrinking by temporal
//! signatures — progressively, as more measurements leave their bands.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;

use modelgap_core::Recording;
use modelgap_core::residual::{Threshold, first_exceedance, steady_state};

use crate::causal_graph::CausalGraph;
use crate::causality::assign_causality;
use crate::equations::Equations;
use crate::error::{BondError, Result};
use crate::expr::Var;
use crate::fault_tree::{FaultTree, Hypothesis, fault_tree, first_hypothesis_set};
use crate::graph::BondGraph;
use crate::qual::Qual;
use crate::signature::{ObservedSignature, Signature, matches, predict};
use crate::simulate::{Inputs, Run, SimOptions, simulate};
use crate::state_space::StateSpace;

/// Options of [`diagnose`].
#[derive(Clone, Debug, PartialEq)]
pub struct DiagnosisOptions {
    /// The band a residual must leave to count as non-zero. Default: the
    /// paper's 2 % of the steady-state value of the nominal prediction.
    pub threshold: Threshold,
    /// Consecutive samples out of the band that make a detection. Default 3.
    pub persistence: usize,
    /// Local time constant (s) under which a storage element's integration
    /// counts as fast and its signatures are discarded. Default: 2 sample periods
    /// (an integration faster than that is over before the next sample).
    pub fast_time_constant: Option<f64>,
    /// Start the parallel model at its steady state under the recording's
    /// first input values (instead of at rest). Default false.
    pub steady_start: bool,
    /// Options of the parallel model's simulation.
    pub sim: SimOptions,
}

impl Default for DiagnosisOptions {
    fn default() -> DiagnosisOptions {
        DiagnosisOptions {
            threshold: Threshold::FractionOfSteadyState { fraction: 0.02 },
            persistence: 3,
            fast_time_constant: None,
            steady_start: false,
            sim: SimOptions::default(),
        }
    }
}

/// How a residual behaves over the recording.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Behaviour {
    /// Never leaves its band.
    Zero,
    /// Leaves its band and comes back before the end.
    Transitory,
    /// Still out of its band at the end.
    Permanent,
}

impl std::fmt::Display for Behaviour {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Behaviour::Zero => "zero",
            Behaviour::Transitory => "transitory",
            Behaviour::Permanent => "permanent",
        })
    }
}

/// One measurement's residual and what it shows.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputResidual {
    /// The measurement.
    pub output: String,
    /// measured − predicted, per sample.
    pub residual: Vec<f64>,
    /// The band's half-width.
    pub band: f64,
    /// When the residual first left its band (s).
    pub detected_at: Option<f64>,
    /// The deviation's sign when it first left its band.
    pub first_deviation: Qual,
    /// Transitory or permanent.
    pub behaviour: Behaviour,
}

/// The hypothesis set at one moment of the progressive diagnosis.
#[derive(Clone, Debug, PartialEq)]
pub struct Stage {
    /// Time (s).
    pub at: f64,
    /// Measurements out of their band by then, with their deviation.
    pub deviating: Vec<(String, Qual)>,
    /// Candidates from the fault trees (first hypothesis set).
    pub from_trees: BTreeSet<Hypothesis>,
    /// Candidates left after signature matching.
    pub after_signatures: BTreeSet<Hypothesis>,
}

/// The result of [`diagnose`].
#[derive(Clone, Debug)]
pub struct Diagnosis {
    /// The parallel model's prediction.
    pub nominal: Run,
    /// Residual per measurement.
    pub residuals: Vec<OutputResidual>,
    /// First detection time (s), if any residual left its band.
    pub detected_at: Option<f64>,
    /// Fault trees of the deviating measurements (final stage).
    pub trees: Vec<FaultTree>,
    /// What each residual shows at detection.
    pub observed: Vec<ObservedSignature>,
    /// Predicted signatures of every candidate from the trees.
    pub predicted: BTreeMap<Hypothesis, Vec<Signature>>,
    /// States whose integration was counted as fast.
    pub fast_states: Vec<String>,
    /// The hypothesis set as each measurement left its band.
    pub stages: Vec<Stage>,
    /// The final (minimal) hypothesis set.
    pub hypotheses: BTreeSet<Hypothesis>,
    /// Non-fatal findings (e.g. signatures ruled out every candidate).
    pub warnings: Vec<String>,
}

impl Diagnosis {
    /// The parameters of the final set, without deviations, sorted.
    pub fn parameters(&self) -> Vec<String> {
        let set: BTreeSet<String> = self.hypotheses.iter().map(|h| h.param.clone()).collect();
        set.into_iter().collect()
    }

    /// Overall behaviour: permanent if any residual is, else transitory if any is.
    pub fn behaviour(&self) -> Behaviour {
        let b: Vec<Behaviour> = self.residuals.iter().map(|r| r.behaviour).collect();
        if b.contains(&Behaviour::Permanent) {
            Behaviour::Permanent
        } else if b.contains(&Behaviour::Transitory) {
            Behaviour::Transitory
        } else {
            Behaviour::Zero
        }
    }

    /// A readable report of every step.
    pub fn report(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "residuals:");
        for r in &self.residuals {
            let _ = writeln!(
                s,
                "  {:<8} band ±{:.4e}  detected {}  first deviation {}  {}",
                r.output,
                r.band,
                r.detected_at
                    .map_or("never".to_string(), |t| format!("at {t:.4} s")),
                r.first_deviation,
                r.behaviour
            );
        }
        if self.detected_at.is_none() {
            let _ = writeln!(s, "no residual left its band: no fault detected");
            return s;
        }
        for t in &self.trees {
            s.push_str(&t.to_text());
        }
        let _ = writeln!(s, "observed signatures at detection:");
        for o in &self.observed {
            let _ = writeln!(s, "  {o}");
        }
        if !self.fast_states.is_empty() {
            let _ = writeln!(
                s,
                "fast states (signatures through them discarded): {}",
                self.fast_states.join(", ")
            );
        }
        let _ = writeln!(s, "predicted signatures (magnitude, slope, curvature):");
        for (h, sigs) in &self.predicted {
            let _ = writeln!(
                s,
                "  {h}: {}",
                sigs.iter()
                    .map(|x| x.to_string())
                    .collect::<Vec<_>>()
                    .join("  ")
            );
        }
        let _ = writeln!(s, "hypothesis sets:");
        for st in &self.stages {
            let _ = writeln!(
                s,
                "  t = {:.4} s, deviating {}: trees {} -> signatures {}",
                st.at,
                st.deviating
                    .iter()
                    .map(|(n, q)| format!("{n}{q}"))
                    .collect::<Vec<_>>()
                    .join(" "),
                set_text(&st.from_trees),
                set_text(&st.after_signatures)
            );
        }
        let _ = writeln!(s, "minimal hypothesis set: {}", set_text(&self.hypotheses));
        for w in &self.warnings {
            let _ = writeln!(s, "warning: {w}");
        }
        s
    }
}

/// A hypothesis set as `{R+, m-}`.
pub fn set_text(set: &BTreeSet<Hypothesis>) -> String {
    format!(
        "{{{}}}",
        set.iter()
            .map(|h| h.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    )
}

/// Diagnoses a recording against a model: the model runs in parallel,
/// driven by the recording's inputs, and its outputs are compared with the
/// recording's measurements.
///
/// # Errors
/// Model errors; [`BondError::BadOutput`] if the recording has none of the
/// model's outputs; simulation errors.
pub fn diagnose(g: &BondGraph, rec: &Recording, opts: &DiagnosisOptions) -> Result<Diagnosis> {
    let c = assign_causality(g)?;
    let eqs = Equations::derive(g, &c)?;
    let cg = CausalGraph::from_graph(g, &eqs)?;
    let input_names: Vec<String> = g.inputs().keys().cloned().collect();
    let inputs = Inputs::from_recording(rec, &input_names);
    let mut sim = opts.sim.clone();
    let mut warnings = Vec::new();
    if opts.steady_start && sim.initial_state.is_none() {
        let model = crate::compiled::CompiledModel::new(g)?;
        let u0: Vec<f64> = input_names
            .iter()
            .zip(&model.input_defaults)
            .map(|(n, d)| rec.signal(n).map_or(*d, |s| s.values[0]))
            .collect();
        match model.steady_state(&u0, None) {
            Ok(x) => sim.initial_state = Some(x),
            Err(e) => warnings.push(format!(
                "no steady state to start from ({e}); the parallel model starts at rest"
            )),
        }
    }
    let nominal = simulate(g, &inputs, rec.t(), &sim)?;
    let t = rec.t();
    let dt = if t.len() > 1 {
        (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64
    } else {
        1e-3
    };
    let mut residuals = Vec::new();
    for (name, pred) in nominal.output_names.iter().zip(&nominal.outputs) {
        let Some(meas) = rec.signal(name) else {
            continue;
        };
        let residual: Vec<f64> = meas.values.iter().zip(pred).map(|(m, p)| m - p).collect();
        let band = match opts.threshold {
            // The paper: 2 % of the steady state of the (nominal) signal.
            Threshold::FractionOfSteadyState { fraction } => fraction * steady_state(pred).abs(),
            other => other.band(&meas.values),
        };
        let det = first_exceedance(t, &residual, band, opts.persistence);
        let first_deviation = det.map_or(Qual::Zero, |k| Qual::of(residual[k], band));
        let tail = (t.len() / 20).max(1);
        let end_out = residual[t.len() - tail..].iter().any(|r| r.abs() > band);
        let behaviour = match (det, end_out) {
            (None, _) => Behaviour::Zero,
            (Some(_), true) => Behaviour::Permanent,
            (Some(_), false) => Behaviour::Transitory,
        };
        residuals.push(OutputResidual {
            output: name.clone(),
            residual,
            band,
            detected_at: det.map(|k| t[k]),
            first_deviation,
            behaviour,
        });
    }
    if residuals.is_empty() {
        return Err(BondError::BadOutput {
            output: nominal.output_names.join(", "),
            detail: format!(
                "none of the model's outputs is in the recording (it has: {})",
                rec.names().join(", ")
            ),
        });
    }
    let detected_at = residuals
        .iter()
        .filter_map(|r| r.detected_at)
        .min_by(f64::total_cmp);
    // Fast states: local time constant −1/A_ii below the threshold.
    let tau_fast = opts.fast_time_constant.unwrap_or(2.0 * dt);
    let ss = StateSpace::linearise(g, None, None)?;
    let mut fast: BTreeSet<Var> = BTreeSet::new();
    let mut fast_states = Vec::new();
    for (i, st) in eqs.states.iter().enumerate() {
        let aii = ss.a[(i, i)];
        if aii < 0.0 && -1.0 / aii < tau_fast {
            fast.insert(st.var);
            fast_states.push(st.var.to_string());
        }
    }
    let mut diag = Diagnosis {
        nominal,
        residuals,
        detected_at,
        trees: Vec::new(),
        observed: Vec::new(),
        predicted: BTreeMap::new(),
        fast_states,
        stages: Vec::new(),
        hypotheses: BTreeSet::new(),
        warnings,
    };
    let Some(t_det) = detected_at else {
        return Ok(diag);
    };
    // Quiet level of each residual: what it shows before the fault (solver
    // tolerance, measurement noise), at least a thousandth of its band.
    let k_det = t.partition_point(|&x| x < t_det).min(t.len() - 1);
    let quiet: Vec<f64> = diag
        .residuals
        .iter()
        .map(|r| {
            let pre = &r.residual[..(k_det / 2).max(1)];
            (4.0 * modelgap_core::residual::rms(pre)).max(1e-3 * r.band)
        })
        .collect();
    // The fault's onset: the last quiet sample before the first detection.
    let k0 = diag
        .residuals
        .iter()
        .zip(&quiet)
        .find(|(r, _)| r.detected_at == Some(t_det))
        .map_or(k_det, |(r, q)| onset(&r.residual, k_det, *q));
    diag.observed = diag
        .residuals
        .iter()
        .zip(&quiet)
        .map(|(r, q)| observe(r, k0, *q))
        .collect();
    // Progressive: a stage each time another measurement leaves its band.
    let mut times: Vec<f64> = diag
        .residuals
        .iter()
        .filter_map(|r| r.detected_at)
        .collect();
    times.sort_by(f64::total_cmp);
    times.dedup();
    for &at in &times {
        let deviating: Vec<(String, Qual)> = diag
            .residuals
            .iter()
            .filter(|r| r.detected_at.is_some_and(|d| d <= at))
            .map(|r| (r.output.clone(), r.first_deviation))
            .collect();
        let trees: Vec<FaultTree> = deviating
            .iter()
            .map(|(n, q)| fault_tree(&cg, n, *q))
            .collect::<Result<Vec<_>>>()?;
        let from_trees = first_hypothesis_set(&trees);
        let mut after = BTreeSet::new();
        for h in &from_trees {
            let sigs = diag
                .predicted
                .entry(h.clone())
                .or_insert_with(|| predict(&cg, h, &fast))
                .clone();
            let ok = diag.observed.iter().all(|o| {
                sigs.iter()
                    .find(|s| s.output == o.output)
                    .is_none_or(|s| matches(s, o))
            });
            if ok {
                after.insert(h.clone());
            }
        }
        diag.trees = trees;
        diag.stages.push(Stage {
            at,
            deviating,
            from_trees,
            after_signatures: after,
        });
    }
    // Residual behaviour: a permanent residual needs a candidate that moves
    // that output's steady state the same way; transitory candidates (L, J,
    // filter elements) cannot explain it.
    if let Some(last) = diag.stages.last().cloned() {
        let permanent: Vec<(usize, Qual)> = diag
            .residuals
            .iter()
            .enumerate()
            .filter(|(_, r)| r.behaviour == Behaviour::Permanent)
            .map(|(j, r)| {
                let tail = &r.residual[r.residual.len() - (r.residual.len() / 20).max(1)..];
                (j, Qual::of(tail.iter().sum::<f64>(), 0.0))
            })
            .collect();
        if !permanent.is_empty() {
            let u_end: Vec<f64> = input_names
                .iter()
                .zip(&diag.nominal.inputs)
                .map(|(_, v)| *v.last().unwrap_or(&0.0))
                .collect();
            let x_end: Vec<f64> = diag
                .nominal
                .states
                .iter()
                .map(|v| *v.last().unwrap_or(&0.0))
                .collect();
            let names: Vec<String> = diag.residuals.iter().map(|r| r.output.clone()).collect();
            let mut kept = BTreeSet::new();
            for h in &last.after_signatures {
                let ok = match steady_effect(g, h, &u_end, &x_end, &names) {
                    Some(effect) => permanent.iter().all(|&(j, s)| effect[j] == s),
                    None => true,
                };
                if ok {
                    kept.insert(h.clone());
                }
            }
            diag.stages.push(Stage {
                at: *t.last().unwrap_or(&0.0),
                deviating: last.deviating.clone(),
                from_trees: last.after_signatures.clone(),
                after_signatures: kept,
            });
        }
    }
    if let Some(last) = diag.stages.last() {
        diag.hypotheses = if last.after_signatures.is_empty() && !last.from_trees.is_empty() {
            diag.warnings.push(
                "the observed signatures rule out every candidate of the fault trees; keeping the fault-tree set".to_string(),
            );
            last.from_trees.clone()
        } else {
            last.after_signatures.clone()
        };
    }
    Ok(diag)
}

/// The last sample at or before `k` where the residual is still quiet.
fn onset(r: &[f64], k: usize, quiet: f64) -> usize {
    let mut k0 = k;
    while k0 > 0 && r[k0].abs() > quiet {
        k0 -= 1;
    }
    k0
}

/// How a small deviation of `h` moves the steady state of each output in
/// `names` (for the inputs `u`), or `None` when no steady state is found.
fn steady_effect(
    g: &BondGraph,
    h: &Hypothesis,
    u: &[f64],
    guess: &[f64],
    names: &[String],
) -> Option<Vec<Qual>> {
    let outputs_at = |g: &BondGraph, u: &[f64]| -> Option<Vec<f64>> {
        let model = crate::compiled::CompiledModel::new(g).ok()?;
        let x = model.steady_state(u, Some(guess)).ok()?;
        let mut scratch = model.scratch();
        let mut y = vec![0.0; model.n_outputs()];
        model.eval(0.0, &x, u, &mut scratch);
        model.read_outputs(&scratch, &mut y);
        Some(
            names
                .iter()
                .map(|n| {
                    model
                        .output_names
                        .iter()
                        .position(|m| m == n)
                        .map_or(0.0, |i| y[i])
                })
                .collect(),
        )
    };
    let y0 = outputs_at(g, u)?;
    let factor = 1.0 + 0.1 * f64::from(h.deviation.as_i8());
    let y1 = if let Ok(v) = g.param(&h.param) {
        let mut g2 = g.clone();
        g2.set_param(&h.param, v * factor).ok()?;
        outputs_at(&g2, u)?
    } else {
        let j = g.inputs().keys().position(|k| k == &h.param)?;
        let mut u2 = u.to_vec();
        u2[j] *= factor;
        outputs_at(g, &u2)?
    };
    Some(
        y0.iter()
            .zip(&y1)
            .map(|(a, b)| Qual::of(b - a, 1e-6 * a.abs().max(1e-12)))
            .collect(),
    )
}

/// Reads the onset signature of a residual after the fault's onset `k0`
/// (the last quiet sample). A change of a derivative starts from zero, so
/// the first sample out of the quiet level has the sign of the first
/// changed derivative, and the growth to the next sample gives its order
/// (`r ∝ (t − t0)^k` grows by `((n + 1)/n)^k` from the n-th sample after
/// onset to the next). A jump
/// leaves its band in the very first sample and does not grow.
fn observe(r: &OutputResidual, k0: usize, quiet: f64) -> ObservedSignature {
    let n = r.residual.len();
    let none = ObservedSignature {
        output: r.output.clone(),
        magnitude: Qual::Zero,
        jump: false,
        slope: Qual::Zero,
        order: None,
    };
    if r.detected_at.is_none() {
        return none;
    }
    let Some(k1) = (k0 + 1..n).find(|&k| r.residual[k].abs() > quiet) else {
        return none;
    };
    let a = r.residual[k1];
    let b = r.residual[(k1 + 1).min(n - 1)];
    let growth = if a.signum() == b.signum() {
        b.abs() / a.abs()
    } else {
        0.0
    };
    let jump = k1 == k0 + 1 && a.abs() > r.band && growth < 1.41;
    // r ∝ (t − t0)^k: from sample n to n + 1 after onset it grows by ((n + 1)/n)^k.
    let since = (k1 - k0) as f64;
    let per_order = ((since + 1.0) / since).ln();
    let order = if jump {
        0
    } else {
        ((growth.max(1.0).ln() / per_order).round() as usize).max(1)
    };
    let slope = Qual::of(b - a, 0.0);
    ObservedSignature {
        output: r.output.clone(),
        magnitude: Qual::of(a, 0.0),
        jump,
        slope,
        order: Some(order),
    }
}

//! Fault diagnosis of a recording with the paper's method: residuals from
//! a parallel model, detection against a band, fault trees of the deviating
//! measurements, the first hypothesis set, and its shrinking by temporal
//! signatures — progressively, as more measurements leave their bands.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;

use modelgap_core::Recording;
use modelgap_core::residual::{Threshold, first_exceedance, savgol_derivatives, steady_state};

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
    /// counts as fast and its signatures are discarded. Default: 10 sample periods.
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
    if opts.steady_start && sim.initial_state.is_none() {
        let model = crate::compiled::CompiledModel::new(g)?;
        let u0: Vec<f64> = input_names
            .iter()
            .zip(&model.input_defaults)
            .map(|(n, d)| rec.signal(n).map_or(*d, |s| s.values[0]))
            .collect();
        let ss = StateSpace::of_compiled(&model, None, Some(&u0));
        sim.initial_state = ss.steady_state(&u0);
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
    let tau_fast = opts.fast_time_constant.unwrap_or(10.0 * dt);
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
        warnings: Vec::new(),
    };
    let Some(t_det) = detected_at else {
        return Ok(diag);
    };
    let k_det = t.partition_point(|&x| x < t_det);
    diag.observed = diag
        .residuals
        .iter()
        .map(|r| observe(t, r, k_det, opts.persistence))
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

/// Reads magnitude, jump and slope of a residual at the detection index.
fn observe(t: &[f64], r: &OutputResidual, k_det: usize, persistence: usize) -> ObservedSignature {
    let n = t.len();
    let band = r.band;
    // Magnitude once the detection is confirmed.
    let k_conf = (k_det + persistence.max(1) - 1).min(n - 1);
    let out_now = r.detected_at.is_some_and(|d| d <= t[k_conf]);
    let magnitude = if out_now {
        Qual::of(r.residual[k_conf], band)
    } else {
        Qual::Zero
    };
    // A jump: within two samples before detection the residual was inside a quarter band.
    let jump = out_now && {
        let k0 = k_det.saturating_sub(2);
        r.residual[k0..=k_det.min(n - 1)]
            .iter()
            .any(|x| x.abs() < 0.25 * band)
            && r.residual[k_det.min(n - 1)].abs() > band
            && r.detected_at
                .is_some_and(|d| (d - t[k_det.min(n - 1)]).abs() < 1e-12)
    };
    // Slope just after detection from a local quadratic fit over a short window.
    let lo = k_det.min(n - 1);
    let hi = (k_det + 8).min(n);
    let slope = if hi - lo >= 4 {
        let (_, d1, _) = savgol_derivatives(&t[lo..hi], &r.residual[lo..hi], hi - lo, 2);
        let window = t[hi - 1] - t[lo];
        Qual::of(d1[0], 0.25 * band / window.max(1e-12))
    } else {
        Qual::Zero
    };
    ObservedSignature {
        output: r.output.clone(),
        magnitude,
        jump,
        slope,
    }
}

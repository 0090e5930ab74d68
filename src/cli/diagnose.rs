//! `modelgap bond diagnose`: the paper's diagnosis of a recording against a model, as a
//! report or as JSON.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Args;
use modelgap::Threshold;
use modelgap::bond::BondGraph;
use modelgap::bond::diagnosis::{Diagnosis, DiagnosisOptions, diagnose, set_text};
use modelgap::bond::fault_tree::Hypothesis;
use modelgap::residual::stats;
use serde_json::{Value, json};

use super::model::{
    CsvArgs, ModelArgs, load, parse_count, parse_number, read_recording_arg_with, steady_state,
};

/// Arguments of `modelgap bond diagnose`.
#[derive(Debug, Args)]
pub struct DiagnoseArgs {
    #[command(flatten)]
    model: ModelArgs,

    /// The recording to diagnose (.csv, .mcap or .parquet): the model's inputs and some of its outputs
    #[arg(long, value_name = "FILE")]
    data: PathBuf,

    #[command(flatten)]
    csv: CsvArgs,

    /// The band a residual must leave: fraction:F (of the nominal output's steady state),
    /// noise:K (K noise standard deviations of the measurement) or abs:B (in the output's
    /// unit)
    #[arg(long, value_name = "KIND:VALUE", default_value = "fraction:0.02", value_parser = parse_threshold)]
    threshold: Threshold,

    /// Consecutive samples out of the band that make a detection
    #[arg(long, value_name = "N", default_value_t = 3, value_parser = parse_count, allow_negative_numbers = true)]
    persistence: usize,

    /// Start the parallel model at its steady state under the recording's first input values
    #[arg(long)]
    steady_start: bool,

    /// Print the diagnosis as JSON
    #[arg(long)]
    json: bool,
}

/// Parses `fraction:F`, `noise:K` or `abs:B`.
pub fn parse_threshold(text: &str) -> Result<Threshold, String> {
    let (kind, value) = text
        .split_once(':')
        .ok_or_else(|| format!("expected fraction:F, noise:K or abs:B, found `{text}`"))?;
    let value = parse_number(value)?;
    if value < 0.0 {
        return Err(format!("the threshold must be >= 0, found {value}"));
    }
    match kind.trim() {
        "fraction" => Ok(Threshold::FractionOfSteadyState { fraction: value }),
        "noise" => Ok(Threshold::Noise { sigmas: value }),
        "abs" => Ok(Threshold::Absolute(value)),
        other => Err(format!(
            "unknown threshold kind `{other}` (expected fraction, noise or abs)"
        )),
    }
}

/// Diagnoses the recording and prints the report (or JSON).
///
/// # Errors
///
/// Model errors, a missing or unreadable data file, a recording with none of the model's
/// outputs, simulation errors.
pub fn run(args: &DiagnoseArgs) -> anyhow::Result<()> {
    let g = load(&args.model)?;
    let path = &args.data;
    let rec = read_recording_arg_with("--data", "recording", path, &args.csv)?;
    let mut opts = DiagnosisOptions {
        threshold: args.threshold,
        persistence: args.persistence,
        steady_start: args.steady_start,
        ..DiagnosisOptions::default()
    };
    if args.steady_start {
        // The steady state under the recording's first input values, solved from
        // f(x, u) = 0 (exact also for models with products of inputs, such as a switch).
        let u0: Vec<f64> = g
            .inputs()
            .iter()
            .map(|(name, input)| rec.signal(name).map_or(input.default, |s| s.values[0]))
            .collect();
        opts.sim.initial_state = Some(
            steady_state(&g, &u0)
                .with_context(|| format!("finding the steady state of model {}", g.name))?,
        );
    }
    let diag = diagnose(&g, &rec, &opts)
        .with_context(|| format!("diagnosing {} against model {}", path.display(), g.name))?;
    if args.json {
        let value = to_json(&g, args, &rec, &diag);
        let text = serde_json::to_string_pretty(&value)?;
        super::print(&format!("{text}\n"))
    } else {
        let mut s = format!(
            "model {}: diagnosis of {} ({} samples, {} s)\n",
            g.name,
            path.display(),
            rec.len(),
            super::format::num(rec.duration())
        );
        s.push_str(&diag.report());
        super::print(&s)
    }
}

/// Hypotheses as strings like `R+`.
fn hypotheses<'a>(set: impl IntoIterator<Item = &'a Hypothesis>) -> Vec<String> {
    set.into_iter().map(ToString::to_string).collect()
}

/// The diagnosis as one JSON object.
fn to_json(
    g: &BondGraph,
    args: &DiagnoseArgs,
    rec: &modelgap::Recording,
    diag: &Diagnosis,
) -> Value {
    let residuals: Vec<Value> = diag
        .residuals
        .iter()
        .map(|r| {
            let measured = rec.values(&r.output).unwrap_or_default();
            let predicted = diag.nominal.output(&r.output).unwrap_or_default();
            let s = if measured.len() == predicted.len() {
                Some(stats(measured, predicted))
            } else {
                None
            };
            json!({
                "output": r.output,
                "band": r.band,
                "detected_at": r.detected_at,
                "first_deviation": r.first_deviation.to_string(),
                "behaviour": r.behaviour.to_string(),
                "rms": s.map(|s| s.rms),
                "max_abs": s.map(|s| s.max_abs),
            })
        })
        .collect();
    let trees: Vec<Value> = diag
        .trees
        .iter()
        .map(|t| {
            json!({
                "output": t.output,
                "value": t.qual.to_string(),
                "candidates": hypotheses(&t.candidates()),
                "text": t.to_text(),
            })
        })
        .collect();
    let observed: Vec<Value> = diag
        .observed
        .iter()
        .map(|o| {
            json!({
                "output": o.output,
                "magnitude": o.magnitude.to_string(),
                "jump": o.jump,
                "slope": o.slope.to_string(),
            })
        })
        .collect();
    let predicted: serde_json::Map<String, Value> = diag
        .predicted
        .iter()
        .map(|(h, sigs)| {
            let sigs: Vec<Value> = sigs
                .iter()
                .map(|s| {
                    json!({
                        "output": s.output,
                        "magnitude": s.orders[0].to_string(),
                        "slope": s.orders[1].to_string(),
                        "curvature": s.orders[2].to_string(),
                    })
                })
                .collect();
            (h.to_string(), Value::Array(sigs))
        })
        .collect();
    let stages: Vec<Value> = diag
        .stages
        .iter()
        .map(|st| {
            json!({
                "at": st.at,
                "deviating": st
                    .deviating
                    .iter()
                    .map(|(n, q)| format!("{n}{q}"))
                    .collect::<Vec<_>>(),
                "from_trees": hypotheses(&st.from_trees),
                "after_signatures": hypotheses(&st.after_signatures),
            })
        })
        .collect();
    let threshold = match args.threshold {
        Threshold::FractionOfSteadyState { fraction } => json!({ "fraction": fraction }),
        Threshold::Noise { sigmas } => json!({ "noise_sigmas": sigmas }),
        Threshold::Absolute(band) => json!({ "absolute": band }),
    };
    json!({
        "model": g.name,
        "data": args.data.display().to_string(),
        "samples": rec.len(),
        "threshold": threshold,
        "persistence": args.persistence,
        "steady_start": args.steady_start,
        "detected_at": diag.detected_at,
        "behaviour": diag.behaviour().to_string(),
        "residuals": residuals,
        "trees": trees,
        "observed": observed,
        "predicted": predicted,
        "fast_states": diag.fast_states,
        "stages": stages,
        "hypotheses": hypotheses(&diag.hypotheses),
        "hypothesis_set": set_text(&diag.hypotheses),
        "parameters": diag.parameters(),
        "warnings": diag.warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thresholds_parse_each_kind() {
        assert_eq!(
            parse_threshold("fraction:0.02"),
            Ok(Threshold::FractionOfSteadyState { fraction: 0.02 })
        );
        assert_eq!(
            parse_threshold("noise:4"),
            Ok(Threshold::Noise { sigmas: 4.0 })
        );
        assert_eq!(parse_threshold("abs:0.01"), Ok(Threshold::Absolute(0.01)));
        assert!(parse_threshold("0.02").is_err());
        assert!(parse_threshold("band:1").is_err());
        assert!(parse_threshold("abs:-1").is_err());
    }
}

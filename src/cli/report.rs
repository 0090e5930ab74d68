//! What `compare`, `explain`, `fix` and `demo` share: the loop's arguments (model,
//! recording, start, input hold, noise floors, report directory), loading them with errors
//! that name the file, running explain behind a progress bar, writing the report, and the
//! JSON shapes of a comparison and an explanation.
//!
//! Ctrl-C stops explain between candidate fits ([`super::interrupt`]): the run ends with
//! the verdict `interrupted`, only the fits that finished ranked, nothing written, exit
//! code 130.

use std::collections::BTreeMap;
use std::io::IsTerminal as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use anyhow::Context as _;
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use modelgap::bond::BondModel;
use modelgap::bond::model::Start;
use modelgap::bond::simulate::Hold;
use modelgap::report::format_number as num;
use modelgap::story::{build_report, write_report_dir};
use modelgap::{
    CompareOptions, Comparison, ExplainOptions, Explanation, Model, RankedCandidate, Recording,
    compare, explain,
};
use serde_json::{Map, Value, json};

use super::BadInput;
use super::model::{
    Assignment, ModelArgs, check_report_dir, load, parse_assignment, parse_positive,
    read_recording_arg,
};

/// The arguments every loop command takes: the model, the recording and how to hold one
/// against the other.
#[derive(Debug, Args)]
pub struct LoopArgs {
    #[command(flatten)]
    pub model: ModelArgs,

    /// The recording (.csv or .mcap): the model's inputs and some of its outputs
    #[arg(long, value_name = "FILE")]
    pub data: PathBuf,

    /// Start the model at its steady state under the recording's first input values
    /// (default: at rest)
    #[arg(long)]
    pub steady_start: bool,

    /// How recorded inputs are held between samples: zoh (a commanded input that changes at
    /// a sample and stays) or linear (a sampled analog input)
    #[arg(long, value_enum, default_value_t = HoldArg::Zoh)]
    pub hold: HoldArg,

    /// The noise floor of a measured output, NAME=SIGMA in the output's unit (repeatable);
    /// outputs without one have it estimated from the recording
    #[arg(long = "noise", value_name = "NAME=SIGMA", value_parser = parse_noise_floor)]
    pub noise: Vec<Assignment>,

    /// Write the report here: report.html (plots, ranking, verdict) and comparison.mcap
    /// (for Foxglove)
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,

    /// Failure band: this many noise floors around zero (default 4)
    #[arg(
        long,
        value_name = "K",
        default_value_t = 4.0,
        conflicts_with = "band_fraction",
        value_parser = parse_positive,
        allow_negative_numbers = true
    )]
    pub band_sigmas: f64,

    /// Failure band: this fraction of each output's steady state instead (the DC-motor
    /// paper's threshold is 0.02)
    #[arg(long, value_name = "F", value_parser = parse_positive, allow_negative_numbers = true)]
    pub band_fraction: Option<f64>,
}

/// How recorded inputs are held between samples (`--hold`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum HoldArg {
    /// Each sample's value until the next sample (zero-order hold)
    Zoh,
    /// Straight lines between samples
    Linear,
}

impl From<HoldArg> for Hold {
    fn from(h: HoldArg) -> Hold {
        match h {
            HoldArg::Zoh => Hold::Zero,
            HoldArg::Linear => Hold::Linear,
        }
    }
}

/// Parses `NAME=SIGMA` with a positive, finite SIGMA.
pub fn parse_noise_floor(text: &str) -> Result<Assignment, String> {
    let a = parse_assignment(text)?;
    if a.value > 0.0 {
        Ok(a)
    } else {
        Err(format!(
            "the noise floor of `{}` must be positive, found {}",
            a.name, a.value
        ))
    }
}

/// The model and the recording of a loop command, loaded and checked against each other.
pub struct Loaded {
    /// The model, with its start and input hold.
    pub model: BondModel,
    /// The model file, when `--model` named one (not a built-in).
    pub model_file: Option<PathBuf>,
    /// The recording.
    pub rec: Recording,
    /// Noise floors given with `--noise`, by output.
    pub noise: BTreeMap<String, f64>,
    /// Findings worth telling the user (a model input the recording lacks).
    pub notes: Vec<String>,
    /// The failure band, in noise floors.
    pub band_sigmas: f64,
    /// The failure band as a fraction of the steady state, when chosen.
    pub band_fraction: Option<f64>,
}

impl Loaded {
    /// Compare options with the user's noise floors.
    pub fn compare_options(&self) -> CompareOptions {
        CompareOptions {
            noise: self.noise.clone(),
            band_sigmas: self.band_sigmas,
            band_fraction: self.band_fraction,
            ..CompareOptions::default()
        }
    }
}

/// Loads the model and the recording of `args` and checks that they fit together.
///
/// # Errors
///
/// [`BadInput`] for a missing data file or a directory (naming it), a recording that
/// measures none of the model's outputs (naming both sides) and a `--noise` for an output
/// the model does not predict; model and recording read errors, with the file in the context.
pub fn load_loop(args: &LoopArgs) -> anyhow::Result<Loaded> {
    let graph = load(&args.model)?;
    let model_file = Path::new(&args.model.model)
        .is_file()
        .then(|| PathBuf::from(&args.model.model));
    if let Some(dir) = &args.report {
        check_report_dir("--report", dir)?;
    }
    let path = &args.data;
    let rec = read_recording_arg("--data", "recording", path)?;
    let start = if args.steady_start {
        Start::SteadyState
    } else {
        Start::Rest
    };
    let model = BondModel::new(graph)
        .with_start(start)
        .with_hold(args.hold.into());
    let noise: BTreeMap<String, f64> = args
        .noise
        .iter()
        .map(|a| (a.name.clone(), a.value))
        .collect();
    let notes = check_fit(&model, &rec, &noise, path)?;
    if !(args.band_sigmas.is_finite() && args.band_sigmas > 0.0) {
        return Err(BadInput(format!(
            "--band-sigmas must be positive, found {}",
            args.band_sigmas
        ))
        .into());
    }
    if let Some(f) = args.band_fraction
        && !(f.is_finite() && f > 0.0)
    {
        return Err(BadInput(format!("--band-fraction must be positive, found {f}")).into());
    }
    Ok(Loaded {
        model,
        model_file,
        rec,
        noise,
        notes,
        band_sigmas: args.band_sigmas,
        band_fraction: args.band_fraction,
    })
}

/// Checks that `rec` measures some of the model's outputs and that every given noise floor
/// names one; returns notes on the model inputs the recording lacks (those whose default is
/// not 0) and the outputs it does not measure.
///
/// # Errors
///
/// [`BadInput`] as described at [`load_loop`].
pub fn check_fit(
    model: &BondModel,
    rec: &Recording,
    noise: &BTreeMap<String, f64>,
    path: &Path,
) -> anyhow::Result<Vec<String>> {
    let outputs = model.outputs();
    if !outputs.iter().any(|o| rec.signal(o).is_some()) {
        return Err(BadInput(format!(
            "the recording measures none of the outputs of model {} ({}); its signals are {} in {}",
            model.name(),
            outputs.join(", "),
            rec.names().join(", "),
            path.display()
        ))
        .into());
    }
    for name in noise.keys() {
        if !outputs.contains(name) {
            return Err(BadInput(format!(
                "--noise {name}=…: model {} has no output `{name}` (its outputs: {})",
                model.name(),
                outputs.join(", ")
            ))
            .into());
        }
        if rec.signal(name).is_none() {
            return Err(BadInput(format!(
                "--noise {name}=…: the recording does not measure `{name}` in {}",
                path.display()
            ))
            .into());
        }
    }
    let mut notes = Vec::new();
    let held: Vec<String> = model
        .graph()
        .inputs()
        .iter()
        // An input at 0 by default (a load torque) is the usual "not there"; one with
        // another default (a supply voltage) is worth a word.
        .filter(|(name, input)| rec.signal(name).is_none() && input.default != 0.0)
        .map(|(name, input)| format!("{name} = {} {}", num(input.default), input.unit))
        .collect();
    if !held.is_empty() {
        notes.push(format!(
            "model inputs the recording lacks are held at their defaults: {}",
            held.join(", ")
        ));
    }
    for name in &outputs {
        if rec.signal(name).is_none() {
            notes.push(format!(
                "the recording does not measure output `{name}`: it is left out"
            ));
        }
    }
    Ok(notes)
}

/// The loop arguments as they would be typed again (`--model M --data D ...`), for the
/// "next:" hints.
pub fn args_text(args: &LoopArgs) -> String {
    args_text_with_model(args, None)
}

/// As [`args_text`], with `model` in place of `--model` and its `--set`s (a model file
/// written by `fix` holds the values already).
pub fn args_text_with_model(args: &LoopArgs, model: Option<&Path>) -> String {
    let quote = |t: &str| {
        if t.is_empty() || t.contains(|c: char| c.is_whitespace() || "'\"$`\\".contains(c)) {
            format!("'{}'", t.replace('\'', "'\\''"))
        } else {
            t.to_owned()
        }
    };
    let mut parts = Vec::new();
    match model {
        Some(path) => parts.push(format!("--model {}", quote(&path.display().to_string()))),
        None => {
            parts.push(format!("--model {}", quote(&args.model.model)));
            for a in &args.model.set {
                parts.push(format!("--set {}={}", a.name, a.value));
            }
        }
    }
    parts.push(format!(
        "--data {}",
        quote(&args.data.display().to_string())
    ));
    if args.steady_start {
        parts.push("--steady-start".to_owned());
    }
    if args.hold == HoldArg::Linear {
        parts.push("--hold linear".to_owned());
    }
    for a in &args.noise {
        parts.push(format!("--noise {}={}", a.name, a.value));
    }
    parts.join(" ")
}

/// Notes as `note: …` lines for standard error.
pub fn print_notes(notes: &[String]) {
    for n in notes {
        eprintln!("note: {n}");
    }
}

/// Runs explain on the loaded model and recording with a progress bar on standard error
/// (hidden when `quiet` or when standard error is not a terminal).
///
/// # Errors
///
/// Explain's errors (the model cannot simulate the recording at all).
pub fn run_explain(loaded: &Loaded, quiet: bool) -> anyhow::Result<Explanation> {
    run_explain_model(&loaded.model, &loaded.rec, &loaded.noise, quiet)
}

/// Runs explain on any model (a bond graph or a cloth scene) and recording, with the noise
/// floors the user gave, behind the progress bar of [`run_explain`].
///
/// # Errors
///
/// Explain's errors (the model cannot simulate the recording at all).
pub fn run_explain_model(
    model: &dyn Model,
    rec: &Recording,
    noise: &BTreeMap<String, f64>,
    quiet: bool,
) -> anyhow::Result<Explanation> {
    let bar = if quiet || !std::io::stderr().is_terminal() {
        ProgressBar::hidden()
    } else {
        let total = model.candidates().len() as u64;
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
        if let Ok(style) =
            ProgressStyle::with_template("{spinner} fitting candidate effects {pos}/{len} {msg}")
        {
            bar.set_style(style);
        }
        bar.enable_steady_tick(Duration::from_millis(120));
        bar
    };
    let progress_bar = bar.clone();
    let opts = ExplainOptions {
        noise: noise.clone(),
        progress: Some(Arc::new(move |done, total| {
            progress_bar.set_length(total as u64);
            progress_bar.set_position(done as u64);
            if done == total {
                progress_bar.set_message("(then a second effect on top, if needed)");
            }
        })),
        ..ExplainOptions::default()
    };
    // Ctrl-C stops the fits between candidates: the verdict is then
    // `interrupted` (a second Ctrl-C ends the process).
    let opts = ExplainOptions {
        cancel: Some(super::interrupt::flag()),
        ..opts
    };
    let result = explain(model, rec, &opts);
    bar.finish_and_clear();
    result.with_context(|| format!("explaining the recording with model {}", model.name()))
}

/// After explain: when Ctrl-C interrupted it, prints what there is — the finished fits and
/// the verdict `interrupted` as text, or the JSON with `"interrupted": true` — and returns
/// [`super::interrupt::Interrupted`] (exit code 130) so that nothing is written.
///
/// # Errors
///
/// [`super::interrupt::Interrupted`] when the run was interrupted; printing errors.
pub fn stop_if_interrupted(ex: &Explanation, json: bool, top: usize) -> anyhow::Result<()> {
    if ex.verdict != modelgap::Verdict::Interrupted {
        return Ok(());
    }
    if json {
        super::print(&json_text(&explanation_json(ex))?)?;
    } else {
        super::print(&modelgap::story::explanation_text(ex, top))?;
    }
    Err(super::interrupt::Interrupted("no verdict; nothing was written".to_owned()).into())
}

/// Compares a model (the loaded one, or one with effects built in) with the recording.
///
/// # Errors
///
/// The model cannot simulate the recording.
pub fn run_compare(model: &dyn Model, loaded: &Loaded) -> anyhow::Result<Comparison> {
    compare(model, &loaded.rec, &loaded.compare_options())
        .with_context(|| format!("comparing model {} with the recording", model.name()))
}

/// What a report shows: the comparisons, the explanation, and the recording's name.
pub struct ReportParts<'a> {
    /// The model as given against the recording.
    pub before: &'a Comparison,
    /// The explanation, if explain ran.
    pub explanation: Option<&'a Explanation>,
    /// The model with the effects added against the recording, if any were added.
    pub after: Option<&'a Comparison>,
    /// The recording, as named in the title (its file name).
    pub data: &'a str,
    /// A verdict in place of the explanation's (`fix --effect`).
    pub verdict: Option<String>,
}

/// Writes `report.html` and `comparison.mcap` into `dir` and returns the page's path.
///
/// # Errors
///
/// The directory or a file cannot be written.
pub fn write_report(dir: &Path, parts: ReportParts<'_>) -> anyhow::Result<PathBuf> {
    let ReportParts {
        before,
        explanation,
        after,
        data,
        verdict,
    } = parts;
    super::interrupt::check("the report was not written")?;
    let mut report = build_report(before, explanation, after);
    report.title = format!("modelgap: {} against {data}", before.model);
    if let Some(v) = verdict {
        report.verdict = v;
    }
    write_report_dir(dir, &report, before, after)
        .with_context(|| format!("writing the report into {}", dir.display()))?;
    Ok(dir.join("report.html"))
}

/// The file name of a recording, for titles.
pub fn data_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// The line that says where the report went.
pub fn report_line(page: &Path) -> String {
    let mcap = page.with_file_name("comparison.mcap");
    format!(
        "report: {} (open it in a browser); {} for Foxglove\n",
        page.display(),
        mcap.display()
    )
}

/// The error before → after per output, as text.
pub fn before_after_text(before: &Comparison, after: &Comparison) -> String {
    let mut s = String::new();
    for o in &before.outputs {
        let Some(a) = after.output(&o.name) else {
            continue;
        };
        let change = if o.stats.rms > 0.0 {
            let ratio = a.stats.rms / o.stats.rms;
            if ratio <= 1.0 {
                format!("{:.0} % lower", 100.0 * (1.0 - ratio))
            } else {
                format!("{:.0} % higher", 100.0 * (ratio - 1.0))
            }
        } else {
            String::from("was already 0")
        };
        s.push_str(&format!(
            "  {:<8} RMS {} → {} {} ({change}; {:.1}× → {:.1}× the noise floor {}), failure windows {} → {}\n",
            o.name,
            num(o.stats.rms),
            num(a.stats.rms),
            o.unit,
            o.rms_over_floor(),
            a.rms_over_floor(),
            num(o.noise_floor),
            o.windows.len(),
            a.windows.len(),
        ));
    }
    s
}

/// A number for JSON: `null` when not finite (JSON has no NaN or infinity).
pub fn finite(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

/// A comparison as JSON: per output its statistics, noise floor, band and failure windows.
pub fn comparison_json(c: &Comparison) -> Value {
    let outputs: Vec<Value> = c
        .outputs
        .iter()
        .map(|o| {
            let windows: Vec<Value> = o
                .windows
                .iter()
                .map(|w| {
                    json!({
                        "start": finite(w.start),
                        "end": finite(w.end),
                        "peak": finite(w.peak),
                        "peak_time": finite(w.peak_time),
                        "sign": w.sign,
                    })
                })
                .collect();
            json!({
                "name": o.name,
                "unit": o.unit,
                "rms": finite(o.stats.rms),
                "nrms": finite(o.stats.nrms),
                "max_abs": finite(o.stats.max_abs),
                "mean": finite(o.stats.mean),
                "noise_floor": finite(o.noise_floor),
                "noise_given": o.noise_given,
                "rms_over_floor": finite(o.rms_over_floor()),
                "band": finite(o.band),
                "windows": windows,
                "effective_samples": finite(o.effective_samples),
                "quantum": o.quantum.map(finite),
                "not_judged": o.finding,
            })
        })
        .collect();
    json!({
        "model": c.model,
        "samples": c.t.len(),
        "duration": finite(c.t.last().copied().unwrap_or(0.0) - c.t.first().copied().unwrap_or(0.0)),
        "outputs": outputs,
        "warnings": c.warnings,
    })
}

/// One ranked (or chosen) candidate as JSON, its RMS after keyed by output name.
pub fn candidate_json(ex: &Explanation, r: &RankedCandidate) -> Value {
    let params: Vec<Value> = r
        .params
        .iter()
        .map(|p| {
            json!({
                "name": p.name,
                "unit": p.unit,
                "value": finite(p.value),
                "std_error": finite(p.std_error),
            })
        })
        .collect();
    let rms_after: Map<String, Value> = ex
        .outputs
        .iter()
        .zip(&r.rms_after)
        .map(|(o, v)| (o.name.clone(), finite(*v)))
        .collect();
    json!({
        "id": r.candidate.id,
        "name": r.candidate.name,
        "kind": r.candidate.kind.to_string(),
        "acts_on": r.candidate.acts_on,
        "params": params,
        "rms_after": rms_after,
        "score": finite(r.score),
        "qualitative": r.qualitative,
        "equivalent": r.equivalent,
        "termination": format!("{:?}", r.termination).to_lowercase(),
        "error": r.error,
    })
}

/// An explanation as JSON: the verdict, per output the floor and RMS before and after, the
/// ranking, the chosen effects, the margin, the effective sample size and the warnings.
/// Non-finite numbers (a failed fit's score) are `null`.
pub fn explanation_json(ex: &Explanation) -> Value {
    let outputs: Vec<Value> = ex
        .outputs
        .iter()
        .map(|o| {
            let remaining: Vec<Value> = o
                .remaining_windows
                .iter()
                .map(|w| json!({"start": finite(w.start), "end": finite(w.end), "peak": finite(w.peak)}))
                .collect();
            json!({
                "name": o.name,
                "unit": o.unit,
                "noise_floor": finite(o.noise_floor),
                "rms_before": finite(o.rms_before),
                "rms_after": finite(o.rms_after),
                "remaining_windows": remaining,
                "judgement": o.judgement.as_ref().map(judgement_json),
            })
        })
        .collect();
    let ranked: Vec<Value> = ex.ranked.iter().map(|r| candidate_json(ex, r)).collect();
    let chosen: Vec<Value> = ex
        .chosen
        .iter()
        .map(|c| {
            let mut v = candidate_json(ex, c);
            // The qualitative check runs on the ranking; a chosen effect carries its result.
            if c.qualitative.is_none()
                && let Some(r) = ex.ranked.iter().find(|r| r.candidate.id == c.candidate.id)
            {
                v["qualitative"] = json!(r.qualitative);
            }
            v
        })
        .collect();
    json!({
        "model": ex.model,
        "verdict": ex.verdict.to_string(),
        "verdict_text": modelgap::story::verdict_sentence(ex),
        "interrupted": ex.verdict == modelgap::Verdict::Interrupted,
        "reasons": ex.reasons,
        "outputs": outputs,
        "ranked": ranked,
        "chosen": chosen,
        "margin": finite(ex.margin),
        "effective_samples": finite(ex.effective_samples),
        "warnings": ex.warnings,
    })
}

/// The judge's reading of one output's residual as JSON.
fn judgement_json(j: &modelgap::judge::Judgement) -> Value {
    json!({
        "at_floor": j.at_floor,
        "noise_sigma": finite(j.noise_sigma),
        "coloured": j.coloured,
        "correlation_samples": finite(j.correlation_samples),
        "quantum": j.quantum.map(finite),
        "windows": j.windows,
        "bias_z": finite(j.bias_z),
        "input_correlation": j.input.as_ref().map(|c| json!({
            "input": c.input,
            "lag": c.lag,
            "z": finite(c.z),
        })),
        "reasons": j.reasons,
    })
}

/// Pretty JSON text with a final newline.
///
/// # Errors
///
/// Serialisation errors (none for the values built here).
pub fn json_text(value: &Value) -> anyhow::Result<String> {
    Ok(format!("{}\n", serde_json::to_string_pretty(value)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_floor_must_be_positive() {
        assert_eq!(parse_noise_floor("i=0.01").unwrap().value, 0.01);
        assert!(parse_noise_floor("i=0").is_err());
        assert!(parse_noise_floor("i=-1").is_err());
        assert!(parse_noise_floor("i").is_err());
    }

    #[test]
    fn non_finite_numbers_become_null() {
        assert_eq!(finite(f64::NAN), Value::Null);
        assert_eq!(finite(f64::NEG_INFINITY), Value::Null);
        assert_eq!(finite(1.5), json!(1.5));
    }
}

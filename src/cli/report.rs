//! What `compare`, `explain`, `fix` and `demo` share: the loop's arguments (model,
//! recording, start, input hold, noise floors, report directory), loading them with errors
//! that name the file ([`modelgap::load_model`], [`modelgap::load_recording`]), running
//! explain behind a progress bar, and writing the report. Every model kind goes the same
//! way: what differs between a bond graph and a cloth scene is the model's
//! [`Story`] (how its results read), not this module.
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
use modelgap::load::Hold;
pub use modelgap::story::ReportParts;
use modelgap::story::Story;
use modelgap::{
    CompareOptions, Comparison, ExplainOptions, Explanation, Model, Recording, compare, explain,
};
use serde_json::Value;

use super::BadInput;
use super::model::{
    Assignment, CsvArgs, ModelArgs, check_report_dir, parse_assignment, parse_positive,
};

/// The arguments every loop command takes: the model, the recording and how to hold one
/// against the other.
#[derive(Debug, Args)]
pub struct LoopArgs {
    #[command(flatten)]
    pub model: ModelArgs,

    /// The recording (.csv, .mcap or .parquet): the model's inputs and some of its outputs
    #[arg(long, value_name = "FILE")]
    pub data: PathBuf,

    #[command(flatten)]
    pub csv: CsvArgs,

    /// Start the model at its steady state under the recording's first input values
    /// (default: at rest)
    #[arg(long)]
    pub steady_start: bool,

    /// How recorded inputs are held between samples (bond graphs): auto (each input that
    /// steps held at its samples' values, any other the way the model predicts the recording
    /// better; said in a note), zoh (a commanded input that changes at a sample and stays),
    /// linear (straight lines between samples) or cubic (a smooth cubic through them: a
    /// sampled analog input)
    #[arg(long, value_enum, default_value_t = HoldArg::Auto)]
    pub hold: HoldArg,

    /// The noise floor of a measured output, NAME=SIGMA in the output's unit (repeatable);
    /// all=SIGMA sets every measured output at once (a cloth's every marker coordinate,
    /// SIGMA per coordinate), and a NAME=SIGMA beside it overrides it for that output;
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
    /// Chosen per input from the recording: an input that steps is held at its samples'
    /// values, any other the way the model predicts the recording better
    Auto,
    /// Each sample's value until the next sample (zero-order hold)
    Zoh,
    /// Straight lines between samples
    Linear,
    /// A smooth cubic through the samples (a sampled analog input)
    Cubic,
}

impl From<HoldArg> for Option<Hold> {
    fn from(h: HoldArg) -> Option<Hold> {
        match h {
            HoldArg::Auto => None,
            HoldArg::Zoh => Some(Hold::Zero),
            HoldArg::Linear => Some(Hold::Linear),
            HoldArg::Cubic => Some(Hold::Cubic),
        }
    }
}

impl HoldArg {
    /// The flag that asks for this hold again in a command line (nothing for the default).
    pub fn flag(self) -> &'static str {
        match self {
            HoldArg::Auto => "",
            HoldArg::Zoh => " --hold zoh",
            HoldArg::Linear => " --hold linear",
            HoldArg::Cubic => " --hold cubic",
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

/// The model and the recording of a loop command, loaded and checked against each other:
/// any kind of model ([`modelgap::load_model`]).
pub struct Loaded {
    /// The model, with its start and input hold.
    pub model: Box<dyn Model>,
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
    /// A model and a recording with the default options (the demo), checked against each
    /// other; `label` names the recording in messages.
    ///
    /// # Errors
    ///
    /// [`BadInput`] for a recording that measures none of the model's outputs.
    pub fn new(model: Box<dyn Model>, rec: Recording, label: &str) -> anyhow::Result<Loaded> {
        let notes = check_fit(model.as_ref(), &rec, &BTreeMap::new(), label)?;
        Ok(Loaded {
            model,
            model_file: None,
            rec,
            noise: BTreeMap::new(),
            notes,
            band_sigmas: CompareOptions::default().band_sigmas,
            band_fraction: None,
        })
    }

    /// The notes, with those the model found while it ran (a cloth's stretch
    /// tolerance out of reach), each once.
    pub fn notes_now(&self) -> Vec<String> {
        let mut notes = self.notes.clone();
        for n in self.model.notes(&self.rec) {
            if !notes.contains(&n) {
                notes.push(n);
            }
        }
        notes
    }

    /// Compare options with the user's noise floors.
    pub fn compare_options(&self) -> CompareOptions {
        CompareOptions {
            noise: self.noise.clone(),
            band_sigmas: self.band_sigmas,
            band_fraction: self.band_fraction,
            ..CompareOptions::default()
        }
    }

    /// How the results read for this model.
    pub fn story(&self) -> &dyn Story {
        self.model.story()
    }

    /// Compares `model` (the loaded one, or one with effects built in) with the recording.
    ///
    /// # Errors
    ///
    /// The model cannot simulate the recording.
    pub fn compare(&self, model: &dyn Model) -> anyhow::Result<Comparison> {
        compare(model, &self.rec, &self.compare_options())
            .with_context(|| format!("comparing model {} with the recording", model.name()))
    }

    /// Runs explain with a progress bar on standard error (hidden when `quiet` or when
    /// standard error is not a terminal); Ctrl-C stops it between fits.
    ///
    /// # Errors
    ///
    /// Explain's errors (the model cannot simulate the recording at all).
    pub fn explain(&self, quiet: bool) -> anyhow::Result<Explanation> {
        run_explain(self.model.as_ref(), &self.rec, &self.noise, quiet)
    }

    /// Writes the report into `dir` the way the model's story writes it, and returns the
    /// page's path; nothing is written after Ctrl-C.
    ///
    /// # Errors
    ///
    /// [`super::interrupt::Interrupted`]; the directory or a file cannot be written.
    pub fn write_report(&self, dir: &Path, parts: &ReportParts<'_>) -> anyhow::Result<PathBuf> {
        super::interrupt::check("the report was not written")?;
        self.story()
            .write_report(dir, &self.rec, parts)
            .with_context(|| format!("writing the report into {}", dir.display()))
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
    let opts = args.model.load_options(args.steady_start, args.hold.into());
    let model = modelgap::load::load(&args.model.model, &opts).map_err(|e| match e {
        // "setting L = 0" says which --set already.
        modelgap::Error::Set { .. } => anyhow::Error::new(e),
        _ => anyhow::Error::new(e).context(format!("loading model {}", args.model.model)),
    })?;
    let model_file = Path::new(&args.model.model)
        .is_file()
        .then(|| PathBuf::from(&args.model.model));
    if let Some(dir) = &args.report {
        check_report_dir("--report", dir)?;
    }
    let path = &args.data;
    if path.is_dir() {
        return Err(BadInput(format!(
            "--data {} is a directory: give a recording file (.csv, .mcap or .parquet)",
            path.display()
        ))
        .into());
    }
    if !path.exists() {
        return Err(BadInput(format!("--data: recording {} not found", path.display())).into());
    }
    let (rec, mut notes) = modelgap::load::load_recording_with(path, &model, &args.csv.options())
        .with_context(|| format!("reading recording {}", path.display()))?;
    let mut model = model;
    if args.hold == HoldArg::Auto {
        notes.extend(modelgap::load::settle_holds(&mut model, &rec));
    }
    let model = model.into_model();
    let noise = noise_floors(&args.noise, model.as_ref(), &rec);
    notes.extend(check_fit(
        model.as_ref(),
        &rec,
        &noise,
        &path.display().to_string(),
    )?);
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

/// The noise floors of `--noise`: `all=SIGMA` for every output of the model that the
/// recording measures (unless the model has an output called `all`), then each
/// `NAME=SIGMA`, which overrides it for its output whatever the order.
fn noise_floors(given: &[Assignment], model: &dyn Model, rec: &Recording) -> BTreeMap<String, f64> {
    let outputs = model.outputs();
    let is_all = |a: &&Assignment| a.name == "all" && !outputs.iter().any(|o| o == "all");
    let mut noise = BTreeMap::new();
    if let Some(all) = given.iter().rfind(is_all) {
        for o in outputs.iter().filter(|o| rec.signal(o).is_some()) {
            noise.insert(o.clone(), all.value);
        }
    }
    for a in given.iter().filter(|a| !is_all(a)) {
        noise.insert(a.name.clone(), a.value);
    }
    noise
}

/// Checks that `rec` measures some of the model's outputs and that every given noise floor
/// names one; returns the model's notes on the recording ([`Model::notes`]).
///
/// # Errors
///
/// [`BadInput`] as described at [`load_loop`]; `label` names the recording.
pub fn check_fit(
    model: &dyn Model,
    rec: &Recording,
    noise: &BTreeMap<String, f64>,
    label: &str,
) -> anyhow::Result<Vec<String>> {
    let outputs = model.outputs();
    if !outputs.iter().any(|o| rec.signal(o).is_some()) {
        return Err(BadInput(format!(
            "the recording measures none of the outputs of model {} ({}); its signals are {} in {label}",
            model.name(),
            shorten(&outputs),
            rec.names().join(", ")
        ))
        .into());
    }
    for name in noise.keys() {
        if !outputs.contains(name) {
            return Err(BadInput(format!(
                "--noise {name}=…: model {} has no output `{name}` (its outputs: {})",
                model.name(),
                shorten(&outputs)
            ))
            .into());
        }
        if rec.signal(name).is_none() {
            return Err(BadInput(format!(
                "--noise {name}=…: the recording does not measure `{name}` in {label}"
            ))
            .into());
        }
    }
    Ok(model.notes(rec))
}

/// Names as `a, b, c`, the first and last few when there are many (a cloth's thousands of
/// marker coordinates).
fn shorten(names: &[String]) -> String {
    if names.len() <= 12 {
        names.join(", ")
    } else {
        format!(
            "{}, …, {} ({} in all)",
            names[..6].join(", "),
            names[names.len() - 3..].join(", "),
            names.len()
        )
    }
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
    parts.extend(args.csv.to_args());
    if args.steady_start {
        parts.push("--steady-start".to_owned());
    }
    if args.hold != HoldArg::Auto {
        parts.push(args.hold.flag().trim_start().to_owned());
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

/// Runs explain on a model and recording with the noise floors the user gave, behind a
/// progress bar on standard error (hidden when `quiet` or when standard error is not a
/// terminal); Ctrl-C stops it between fits.
///
/// # Errors
///
/// Explain's errors (the model cannot simulate the recording at all).
pub fn run_explain(
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
pub fn stop_if_interrupted(
    story: &dyn Story,
    ex: &Explanation,
    json: bool,
    top: usize,
) -> anyhow::Result<()> {
    if ex.verdict != modelgap::Verdict::Interrupted {
        return Ok(());
    }
    if json {
        super::print(&json_text(&story.explanation_json(ex))?)?;
    } else {
        super::print(&story.explanation_text(ex, top))?;
    }
    Err(super::interrupt::Interrupted("no verdict; nothing was written".to_owned()).into())
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
}

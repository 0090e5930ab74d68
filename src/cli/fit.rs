//! `modelgap fit`: calibrate a model's unknowns — the parameters marked `free` in its file
//! or named with `--free`, and its free initial states — jointly, by simulation error on a
//! recording; print each value with its ± and whether it ended on a bound, the error per
//! output before and after, and write the calibrated model file.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Args;
use modelgap::report::format_number as num;
use modelgap::{CalibrationOptions, LoadOptions};
use serde_json::json;

use super::BadInput;
use super::model::{CsvArgs, ModelArgs};
use super::report::{HoldArg, check_fit, json_text};

/// Arguments of `modelgap fit`.
#[derive(Debug, Args)]
pub struct FitArgs {
    #[command(flatten)]
    pub model: ModelArgs,

    /// The recording (.csv, .mcap or .parquet): the model's inputs and some of its outputs
    #[arg(long, value_name = "FILE")]
    pub data: PathBuf,

    #[command(flatten)]
    pub csv: CsvArgs,

    /// Also fit this parameter, within LO:HI (default: from 0 to 1000 times its value, its
    /// sign kept) (repeatable)
    #[arg(long = "free", value_name = "NAME[=LO:HI]", value_parser = parse_free)]
    pub free: Vec<FreeArg>,

    /// Write the calibrated model file here (never the input model)
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,

    /// Start the model at its steady state under the recording's first input values
    /// (default: from its initial states)
    #[arg(long)]
    pub steady_start: bool,

    /// How recorded inputs are held between samples: auto (each input that steps held at its
    /// samples' values, any other the way the model predicts the recording better), zoh (a
    /// commanded input), linear (straight lines between samples) or cubic (a smooth cubic
    /// through them: a sampled analog input)
    #[arg(long, value_enum, default_value_t = HoldArg::Auto)]
    pub hold: HoldArg,

    /// Print the result as JSON: `parameters` (name, unit, value, std_error, at_bound, start,
    /// bounds), `correlation`, `rms_before` and `rms_after` per output
    #[arg(long)]
    pub json: bool,
}

/// `--free NAME` or `--free NAME=LO:HI`.
#[derive(Clone, Debug, PartialEq)]
pub struct FreeArg {
    /// The parameter.
    pub name: String,
    /// Its bounds, when given.
    pub bounds: Option<(f64, f64)>,
}

/// Parses `NAME` or `NAME=LO:HI` (finite, LO < HI).
fn parse_free(text: &str) -> Result<FreeArg, String> {
    let (name, bounds) = match text.split_once('=') {
        None => (text.trim(), None),
        Some((name, range)) => {
            let (lo, hi) = range
                .split_once(':')
                .ok_or_else(|| format!("expected NAME=LO:HI, found `{text}`"))?;
            let num = |s: &str| {
                s.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| format!("`{s}` in `{text}` is not a finite number"))
            };
            let (lo, hi) = (num(lo)?, num(hi)?);
            if lo >= hi {
                return Err(format!("`{text}`: LO must be below HI"));
            }
            (name.trim(), Some((lo, hi)))
        }
    };
    if name.is_empty() {
        return Err(format!("expected a parameter name in `{text}`"));
    }
    Ok(FreeArg {
        name: name.to_string(),
        bounds,
    })
}

/// Calibrates, prints and writes the calibrated model.
///
/// # Errors
///
/// Model and recording errors; [`BadInput`] for a model with nothing free, an `--out` that
/// is the input model; the model's errors when it cannot simulate the recording.
pub fn run(args: &FitArgs) -> anyhow::Result<()> {
    let opts = LoadOptions {
        free: (args.free.iter())
            .map(|f| (f.name.clone(), f.bounds))
            .collect(),
        ..args.model.load_options(args.steady_start, args.hold.into())
    };
    let model = modelgap::load::load(&args.model.model, &opts)
        .with_context(|| format!("loading model {}", args.model.model))?;
    let model_file = std::path::Path::new(&args.model.model)
        .is_file()
        .then(|| PathBuf::from(&args.model.model));
    if let Some(out) = &args.out {
        super::fix::check_out(out, model_file.as_deref())?;
    }
    let (rec, mut notes) =
        modelgap::load::load_recording_with(&args.data, &model, &args.csv.options())?;
    let mut model = model;
    if args.hold == HoldArg::Auto {
        notes.extend(modelgap::load::settle_holds(&mut model, &rec));
    }
    let model = model.into_model();
    let label = args.data.display().to_string();
    notes.extend(check_fit(
        model.as_ref(),
        &rec,
        &Default::default(),
        &label,
    )?);
    if model.free_parameters().is_none() {
        return Err(BadInput(format!(
            "model {} has nothing to calibrate: mark parameters `free = true` in its file, or \
             name them with --free NAME[=LO:HI]",
            model.name()
        ))
        .into());
    }
    let cal = modelgap::calibrate(
        model.as_ref(),
        &rec,
        &CalibrationOptions {
            cancel: Some(super::interrupt::flag()),
            ..CalibrationOptions::default()
        },
    )?;
    super::interrupt::check("the calibration was not finished; nothing was written")?;
    let text = cal.model.to_file_text();
    if let (Some(out), Some(text)) = (&args.out, &text) {
        super::fix::write_checked(out, text)?;
    }
    if args.json {
        let value = json!({
            "model": model.name(),
            "data": label,
            "termination": cal.termination.to_string(),
            "effective_samples": cal.effective_samples,
            "parameters": cal.values,
            "correlation": cal.correlation,
            "rms_before": cal.rms_before.iter().map(|(n, v)| json!({"output": n, "rms": v})).collect::<Vec<_>>(),
            "rms_after": cal.rms_after.iter().map(|(n, v)| json!({"output": n, "rms": v})).collect::<Vec<_>>(),
            "out": args.out.as_ref().map(|p| p.display().to_string()),
            "notes": notes,
        });
        return super::print(&json_text(&value)?);
    }
    super::report::print_notes(&notes);
    let mut out = format!(
        "calibrated {} on {} ({} samples; fit {}):\n",
        model.name(),
        label,
        rec.len(),
        cal.termination
    );
    let width = cal.values.iter().map(|v| v.name.len()).max().unwrap_or(0);
    for v in &cal.values {
        let unit = modelgap::story::unit_suffix(&v.unit);
        let value = match (v.std_error, v.at_bound) {
            (_, Some(bound)) => format!("{}{unit} (at its {bound} bound)", num(v.value)),
            (Some(se), None) => format!("{} ± {}{unit}", num(v.value), num(se)),
            (None, None) => format!(
                "{}{unit} (not determined: the outputs cannot tell it from the other unknowns)",
                num(v.value)
            ),
        };
        out.push_str(&format!(
            "  {:width$}  {value}   (from {}{unit})\n",
            v.name,
            num(v.start),
        ));
    }
    let n = cal.values.len();
    for i in 0..n {
        for j in i + 1..n {
            let r = cal.correlation[i][j];
            if r.abs() > 0.95 {
                out.push_str(&format!(
                    "  note: {} and {} move together (correlation {r:+.3}): the data barely tell them apart\n",
                    cal.values[i].name, cal.values[j].name
                ));
            }
        }
    }
    out.push_str("RMS error before → after:\n");
    for ((name, before), (_, after)) in cal.rms_before.iter().zip(&cal.rms_after) {
        out.push_str(&format!(
            "  {name}: {} → {} {}\n",
            num(*before),
            num(*after),
            model.unit(name)
        ));
    }
    match &args.out {
        Some(p) => out.push_str(&format!(
            "wrote {}\nnext: `modelgap explain --model {} --data {}{}{}{}` names what is still missing\n",
            p.display(),
            p.display(),
            args.data.display(),
            if args.steady_start { " --steady-start" } else { "" },
            args.hold.flag(),
            args.csv
                .to_args()
                .iter()
                .map(|a| format!(" {a}"))
                .collect::<String>()
        )),
        None => out.push_str("(no --out: nothing written)\n"),
    }
    super::print(&out)
}

//! `modelgap explain`: which physical effect is the model missing? Fits every candidate
//! effect the model offers against the recording, ranks them by evidence and gives the
//! verdict — nothing missing, one effect, two on top of each other, a partial explanation,
//! not explained, cannot judge — as text, JSON or a report.

use clap::Args;
use modelgap::{Comparison, Effect, Explanation, Verdict};
use serde_json::json;

use super::model::parse_whole;
use super::report::{
    Loaded, LoopArgs, ReportParts, args_text, data_name, json_text, load_loop, print_notes,
    report_line, stop_if_interrupted,
};

/// Arguments of `modelgap explain`.
#[derive(Debug, Args)]
pub struct ExplainArgs {
    #[command(flatten)]
    pub common: LoopArgs,

    /// Print the explanation as JSON: the verdict, per output the noise floor and RMS before
    /// and after, the ranked candidates with fitted parameters, and the chosen effects
    #[arg(long)]
    pub json: bool,

    /// How many ranked candidates to print
    #[arg(long, value_name = "N", default_value_t = 8, value_parser = parse_whole, allow_negative_numbers = true)]
    pub top: usize,
}

/// Explains the recording and prints the ranking and the verdict (and writes the report
/// with `--report`).
///
/// # Errors
///
/// Model and recording errors (see [`super::report::load_loop`]), a model that cannot
/// simulate the recording, a report that cannot be written.
pub fn run(args: &ExplainArgs) -> anyhow::Result<()> {
    let loaded = load_loop(&args.common)?;
    if !args.json {
        print_notes(&loaded.notes);
    }
    let story = loaded.story();
    let ex = loaded.explain(args.json)?;
    stop_if_interrupted(story, &ex, args.json, args.top)?;
    let page = match &args.common.report {
        Some(dir) => {
            let (before, after) = before_after(&loaded, &ex)?;
            Some(loaded.write_report(
                dir,
                &ReportParts {
                    before: &before,
                    explanation: Some(&ex),
                    after: after.as_ref().map(|(e, c)| (e.as_slice(), c)),
                    data: &data_name(&args.common.data),
                    verdict: None,
                },
            )?)
        }
        None => None,
    };
    if args.json {
        let mut value = story.explanation_json(&ex);
        value["data"] = json!(args.common.data.display().to_string());
        value["notes"] = json!(loaded.notes_now());
        if let Some(page) = &page {
            value["report"] = json!(page.display().to_string());
        }
        return super::print(&json_text(&value)?);
    }
    // What the model found while it ran (a stretch tolerance out of reach).
    let late: Vec<String> = loaded
        .notes_now()
        .into_iter()
        .filter(|n| !loaded.notes.contains(n))
        .collect();
    print_notes(&late);
    let mut out = format!(
        "model {} explaining {} ({} candidate effects fitted)\n",
        ex.model,
        args.common.data.display(),
        ex.ranked.len()
    );
    out.push_str(&story.explanation_text(&ex, args.top));
    if let Some(page) = &page {
        out.push_str(&report_line(page));
    }
    if matches!(
        ex.verdict,
        Verdict::EffectFound | Verdict::TwoEffects | Verdict::Partial
    ) {
        out.push_str(&format!(
            "next: `modelgap fix {} --out {}-fixed.{}` adds it to the model and shows the error \
             fall\n",
            args_text(&args.common),
            ex.model,
            loaded.model.file_extension()
        ));
    }
    super::print(&out)
}

/// The effects added to a model and its comparison with them built in.
pub type After = (Vec<Effect>, Comparison);

/// The comparison of the model as given and, when effects were chosen, the effects and the
/// comparison of the model with them built in.
///
/// # Errors
///
/// The model cannot simulate the recording, or the effects cannot be built in.
pub fn before_after(
    loaded: &Loaded,
    ex: &Explanation,
) -> anyhow::Result<(Comparison, Option<After>)> {
    let before = loaded.compare(loaded.model.as_ref())?;
    let effects = ex.effects();
    if effects.is_empty() {
        return Ok((before, None));
    }
    let fixed = loaded.model.with_effects(&effects)?;
    let after = loaded.compare(fixed.as_ref())?;
    Ok((before, Some((effects, after))))
}

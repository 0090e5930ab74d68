//! `modelgap compare`: hold a model against a recording and show where it fails — the error
//! per measured output (per marker and region for a cloth scene), its noise floor, the band
//! and the windows where the residual leaves it — as text, JSON or a report.

use clap::Args;
use serde_json::json;

use super::report::{
    LoopArgs, ReportParts, args_text, data_name, json_text, load_loop, print_notes, report_line,
};

/// Arguments of `modelgap compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub common: LoopArgs,

    /// Print the comparison as JSON: per output its RMS, normalised RMS, largest error, noise
    /// floor, band, failure windows and effective samples (a cloth scene: per marker and
    /// region)
    #[arg(long)]
    pub json: bool,
}

/// Compares and prints the comparison (and writes the report with `--report`).
///
/// # Errors
///
/// Model and recording errors (see [`super::report::load_loop`]), a model that cannot
/// simulate the recording, a report that cannot be written.
pub fn run(args: &CompareArgs) -> anyhow::Result<()> {
    let loaded = load_loop(&args.common)?;
    let before = loaded.compare(loaded.model.as_ref())?;
    let story = loaded.story();
    let page = match &args.common.report {
        Some(dir) => Some(loaded.write_report(
            dir,
            &ReportParts {
                before: &before,
                explanation: None,
                after: None,
                data: &data_name(&args.common.data),
                verdict: None,
            },
        )?),
        None => None,
    };
    if args.json {
        let mut value = story.comparison_json(&before);
        value["data"] = json!(args.common.data.display().to_string());
        value["notes"] = json!(loaded.notes_now());
        if let Some(page) = &page {
            value["report"] = json!(page.display().to_string());
        }
        return super::print(&json_text(&value)?);
    }
    print_notes(&loaded.notes_now());
    let mut out = story.comparison_text(&before);
    if let Some(page) = &page {
        out.push_str(&report_line(page));
    }
    if story.fails(&before) {
        out.push_str(&format!(
            "next: `modelgap explain {}` names the effect that is missing\n",
            args_text(&args.common)
        ));
    }
    super::print(&out)
}

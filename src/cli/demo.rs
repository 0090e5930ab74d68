//! `modelgap demo`: the main job on bundled data. A DC-motor recording hides a physical
//! effect the built-in model lacks; the demo shows where the model fails, ranks the effects
//! that could be missing, adds the chosen one with its fitted value and shows the error
//! fall, writes the report, and ends with the DC-motor paper's Table 7 diagnosis.
//!
//! The recording (`examples/data/motor_hidden_effect.csv`, made by
//! `cargo run --example make_demo_data`) is embedded at compile time, so the demo runs
//! from any directory. Every number printed comes from this run; the hidden truth printed
//! at the end is [`demo_case`], and a test checks that the bundled file is still the
//! recording of that case.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Args;
use modelgap::bond::hidden::{Hidden, HiddenCase};
use modelgap::bond::table7::{Table7Options, table7, table7_text};
use modelgap::bond::{BondModel, library};
use modelgap::report::format_number as num;
use modelgap::story::{comparison_text, explanation_text};
use modelgap::{Effect, Model as _, RankedCandidate, Recording};

use super::report::{
    Loaded, ReportParts, before_after_text, report_line, run_compare, run_explain, write_report,
};

/// The bundled recording, as CSV text.
const DEMO_CSV: &str = include_str!("../../examples/data/motor_hidden_effect.csv");

/// Where the bundled recording lives in the repository.
const DEMO_PATH: &str = "examples/data/motor_hidden_effect.csv";

/// Ranked candidates shown.
const TOP: usize = 6;

/// Arguments of `modelgap demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Write the report (report.html and comparison.mcap) into this directory
    #[arg(long, value_name = "DIR", default_value = "modelgap-report")]
    pub report: PathBuf,

    /// Leave out the second part, the DC-motor paper's Table 7 diagnosis
    #[arg(long)]
    pub skip_table7: bool,
}

/// The bundled recording.
///
/// # Errors
///
/// The embedded CSV does not read (a build with a broken data file).
pub fn demo_recording() -> anyhow::Result<Recording> {
    modelgap::io::csv::read_signals(DEMO_CSV.as_bytes())
        .with_context(|| format!("reading the bundled recording {DEMO_PATH}"))
}

/// The hidden-effect case the bundled recording was made from, as in
/// `examples/make_demo_data.rs`: Coulomb friction of 0.012 N m on the DC motor's shaft.
pub fn demo_case() -> HiddenCase {
    HiddenCase {
        name: "demo".to_owned(),
        model: "dc-motor".to_owned(),
        hidden: vec![Hidden {
            id: "coulomb@1m".to_owned(),
            values: vec![0.012],
        }],
        drive_scale: 1.0,
    }
}

/// Runs the demo and prints its story.
///
/// # Errors
///
/// A report that cannot be written; simulation errors (none for the bundled data).
pub fn run(args: &DemoArgs) -> anyhow::Result<()> {
    let rec = demo_recording()?;
    let case = demo_case();
    let model = BondModel::new(library::builtin(&case.model)?);
    let loaded = Loaded {
        model,
        model_file: None,
        rec,
        noise: Default::default(),
        notes: Vec::new(),
        band_sigmas: modelgap::CompareOptions::default().band_sigmas,
        band_fraction: None,
    };
    let rec = &loaded.rec;

    let mut out = String::from(
        "modelgap demo: hold a motor model against a recording, find the physical effect it is\n\
         missing, add it and watch the error fall; then the DC-motor paper's Table 7 diagnosis.\n\n",
    );
    // 1. The recording.
    let v = rec.values("V").unwrap_or_default();
    let (v_min, v_max) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(*x), b.max(*x))
        });
    out.push_str(&format!(
        "1. The recording ({DEMO_PATH}, bundled): {} samples of {} over {} s.\n   \
         The voltage V steps between {} V and {} V: the motor starts, reverses, slows down.\n   \
         The model is the built-in {}. The recording hides a physical effect the model lacks,\n   \
         plus a sensor lag and noise that no candidate models.\n\n",
        rec.len(),
        rec.names().join(", "),
        num(rec.duration()),
        num(v_min),
        num(v_max),
        loaded.model.name(),
    ));

    // 2. Where the model fails.
    let before = run_compare(&loaded.model, &loaded)?;
    out.push_str("2. Where the model fails (the residual leaves its band of 4 noise σ):\n\n");
    out.push_str(&indent(&comparison_text(&before)));

    // 3. What is missing.
    super::print(&out)?;
    out.clear();
    let ex = run_explain(&loaded, false)?;
    out.push_str(&format!(
        "\n3. What is missing: {} candidate effects (parameters that are off, elements the model lacks,\n   \
         abrupt changes) fitted to the recording and ranked by evidence:\n\n",
        ex.ranked.len()
    ));
    out.push_str(&indent(&explanation_text(&ex, TOP)));

    // 4. The effect added.
    let effects: Vec<Effect> = ex.effects();
    let after = if effects.is_empty() {
        out.push_str("\n4. Nothing to add: the model already leaves only what noise leaves.\n");
        None
    } else {
        let fixed = loaded.model.with_effects(&effects)?;
        let after = run_compare(fixed.as_ref(), &loaded)?;
        out.push_str("\n4. With the effect added to the model:\n\n");
        for r in &ex.chosen {
            out.push_str(&format!("   added: {}\n", super::fix::effect_line(r)));
        }
        out.push_str("   error before → after:\n");
        out.push_str(&indent(&before_after_text(&before, &after)));
        out.push_str(&truth_text(&case, &ex.chosen));
        Some(after)
    };

    // 5. The report.
    let page = write_report(
        &args.report,
        ReportParts {
            before: &before,
            explanation: Some(&ex),
            after: after.as_ref(),
            data: "motor_hidden_effect.csv",
            verdict: None,
        },
    )?;
    out.push_str("\n5. The report, for people who were not watching the terminal:\n   ");
    out.push_str(&report_line(&page));
    out.push_str(
        "   On your own data: `modelgap explain --model dc-motor --data your.csv`, then\n   \
         `modelgap fix --model dc-motor --data your.csv --out fixed.toml` (see `modelgap help`).\n",
    );
    super::print(&out)?;

    // 6. Table 7.
    if args.skip_table7 {
        return Ok(());
    }
    let rows = table7(&Table7Options::default()).context("running the Table 7 faults")?;
    let mut out = String::from(
        "\n6. The DC-motor paper's Table 7 (bond-graph fault diagnosis of a buck converter feeding the\n   \
         motor): each ±20 % fault simulated, detected against the 2 % band, diagnosed by fault trees\n   \
         and temporal signatures, beside the paper's answer:\n\n",
    );
    out.push_str(&indent(&table7_text(&rows)));
    out.push_str(&indent(&super::table7::summary(&rows)));
    out.push_str(
        "\nNext: `modelgap bond table7 --json`, `modelgap bond diagnose --model dc-motor --data \
         examples/data/dc_motor_r_fault.csv --steady-start`.\n",
    );
    super::print(&out)
}

/// The hidden truth beside what was found, for the candidates that were hidden.
fn truth_text(case: &HiddenCase, chosen: &[RankedCandidate]) -> String {
    let mut s = String::new();
    for h in &case.hidden {
        let found = chosen
            .iter()
            .find(|c| c.candidate.id == h.id || c.equivalent.contains(&h.id));
        let Some(found) = found else {
            s.push_str(&format!(
                "   The recording was made with {} = {:?} hidden in it: explain did not choose it.\n",
                h.id, h.values
            ));
            continue;
        };
        for (p, truth) in found.params.iter().zip(&h.values) {
            let uncertainty = if p.std_error.is_finite() {
                format!(" ± {}", num(p.std_error))
            } else {
                String::new()
            };
            s.push_str(&format!(
                "   The truth hidden in the recording (examples/make_demo_data.rs): {} = {} {};\n   \
                 explain, not told it, found {}{uncertainty} {}.\n",
                p.name,
                num(*truth),
                p.unit,
                num(p.value),
                p.unit
            ));
        }
    }
    s
}

/// Every line of `text` indented by three spaces.
fn indent(text: &str) -> String {
    text.lines()
        .map(|l| {
            if l.trim().is_empty() {
                "\n".to_owned()
            } else {
                format!("   {l}\n")
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use modelgap::bond::hidden::{RecordingOptions, record};

    use super::*;

    /// The bundled file is the recording of [`demo_case`] with the default options, its
    /// outputs rounded to 6 significant digits (`examples/make_demo_data.rs`): so the truth
    /// the demo prints is the truth in the file.
    #[test]
    fn bundled_recording_is_the_demo_case() {
        let bundled = demo_recording().unwrap();
        let case = demo_case();
        let fresh = record(&case, &RecordingOptions::default()).unwrap();
        assert_eq!(bundled.t(), fresh.t());
        assert_eq!(bundled.names(), fresh.names());
        for name in fresh.names() {
            let a = bundled.values(name).unwrap();
            let b = fresh.values(name).unwrap();
            let worst = a
                .iter()
                .zip(b)
                .map(|(x, y)| (x - y).abs() / y.abs().max(1e-9))
                .fold(0.0, f64::max);
            // Six significant digits: a relative difference of at most 5e-6.
            assert!(worst <= 5e-6, "{name}: {worst}");
        }
    }
}

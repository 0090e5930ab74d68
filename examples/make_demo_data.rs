//! Writes the recording that `modelgap demo` tells its story on: the built-in DC motor with
//! Coulomb friction of 0.012 N m on its shaft that the model does not have, a sensor lag and
//! white plus coloured noise (as the cases of `modelgap::bond::hidden`), driven by a voltage
//! that steps up, reverses and steps down; 4 s at 1 kHz.
//!
//! Run with `cargo run --example make_demo_data` (writes
//! `examples/data/motor_hidden_effect.csv`), or
//! `cargo run --example make_demo_data -- CASE OUT.csv` for a case of
//! `modelgap::bond::hidden::cases()` (`coulomb`, `load`, `brush`, `inertia`, `nothing`, ...).
//!
//! The demo's friction is three times that of the `coulomb` case, so that the model's
//! failure shows as one clean window per drive phase. The measured outputs are rounded to 6
//! significant digits, far below the noise (0.2 % of each output's largest value), so the
//! file stays small. `modelgap demo` embeds the file at compile time and holds the same
//! case (`src/cli/demo.rs`); a unit test there checks the file is still this recording.

use std::io::Write as _;
use std::path::PathBuf;

use anyhow::Context as _;
use modelgap::bond::hidden::{Hidden, HiddenCase, RecordingOptions, cases, record};
use modelgap::io::csv;
use modelgap::{Recording, Signal};

/// The demo's case: Coulomb friction on the DC motor's shaft (`tau_c`, N m).
fn demo_case() -> HiddenCase {
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

/// Significant digits of the measured outputs in the file.
const DIGITS: usize = 6;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let name = args.next().unwrap_or_else(|| "demo".to_owned());
    let out = args.next().map_or_else(
        || PathBuf::from("examples/data/motor_hidden_effect.csv"),
        PathBuf::from,
    );
    let case = if name == "demo" {
        demo_case()
    } else {
        cases()
            .into_iter()
            .find(|c| c.name == name)
            .with_context(|| format!("no hidden-effect case named `{name}`"))?
    };
    let opts = RecordingOptions::default();
    let rec = record(&case, &opts).with_context(|| format!("recording case {name}"))?;
    let rec = rounded(&rec, DIGITS)?;

    let mut text = Vec::new();
    writeln!(
        text,
        "# the built-in {} with a hidden effect (case `{}`: {}), {} s at {} Hz;",
        case.model,
        case.name,
        hidden_text(&case),
        opts.duration,
        opts.rate_hz
    )?;
    writeln!(
        text,
        "# sensor lag {} s; noise {} (white) + {} (AR(1), rho {})",
        opts.sensor_lag, opts.white, opts.coloured, opts.rho
    )?;
    writeln!(
        text,
        "# of each output's largest value, seed {}. Made by `cargo run --example make_demo_data`.",
        opts.seed
    )?;
    csv::write_signals(&rec, &mut text)?;
    std::fs::write(&out, &text).with_context(|| format!("writing {}", out.display()))?;
    println!(
        "wrote {} ({} samples of {}, {} KB): case `{}`, hidden {}",
        out.display(),
        rec.len(),
        rec.names().join(", "),
        text.len() / 1024,
        case.name,
        hidden_text(&case)
    );
    Ok(())
}

/// The hidden effects of a case as text (`coulomb@1m = [0.012]`).
fn hidden_text(case: &HiddenCase) -> String {
    if case.hidden.is_empty() {
        return "nothing hidden".to_owned();
    }
    case.hidden
        .iter()
        .map(|h| format!("{} = {:?}", h.id, h.values))
        .collect::<Vec<_>>()
        .join(" and ")
}

/// The recording with every value rounded to `digits` significant digits (time untouched).
fn rounded(rec: &Recording, digits: usize) -> anyhow::Result<Recording> {
    let signals = rec
        .signals()
        .iter()
        .map(|s| Signal {
            name: s.name.clone(),
            values: s
                .values
                .iter()
                .map(|v| round_significant(*v, digits))
                .collect(),
        })
        .collect();
    Ok(Recording::new(rec.t().to_vec(), signals)?)
}

/// `v` rounded to `digits` significant digits.
fn round_significant(v: f64, digits: usize) -> f64 {
    format!("{v:.*e}", digits.saturating_sub(1))
        .parse()
        .unwrap_or(v)
}

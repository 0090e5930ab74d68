//! `modelgap bond arr`: analytical redundancy relations from the causal
//! equations and the sensors, the fault signature matrix, detectability and
//! isolability; with `--data`, the ARR residuals evaluated on a recording.

use anyhow::Context as _;
use clap::Args;
use modelgap::bond::arr::{arr_residuals, derive_arrs};
use modelgap::bond::{Equations, assign_causality};

use super::model::{CsvArgs, ModelArgs, load, read_recording_arg_with};

/// Arguments of `modelgap bond arr`.
#[derive(Debug, Args)]
pub struct ArrArgs {
    #[command(flatten)]
    model: ModelArgs,

    /// A recording (CSV, MCAP or Parquet) to evaluate the ARRs on: prints each ARR's RMS and largest value
    #[arg(long, value_name = "FILE")]
    data: Option<std::path::PathBuf>,

    #[command(flatten)]
    csv: CsvArgs,
}

/// Prints the ARRs and the fault signature matrix.
///
/// # Errors
///
/// Model errors, causal conflicts, unreadable recordings.
pub fn run(args: &ArrArgs) -> anyhow::Result<()> {
    let g = load(&args.model)?;
    let c =
        assign_causality(&g).with_context(|| format!("assigning causality to model {}", g.name))?;
    let eqs = Equations::derive(&g, &c)
        .with_context(|| format!("deriving the equations of model {}", g.name))?;
    let analysis =
        derive_arrs(&g, &eqs).with_context(|| format!("deriving the ARRs of model {}", g.name))?;
    let mut out = analysis.to_text();
    if let Some(path) = &args.data {
        let rec = read_recording_arg_with("--data", "recording", path, &args.csv)?;
        let residuals = arr_residuals(&analysis.arrs, &rec)
            .with_context(|| format!("evaluating the ARRs on {}", path.display()))?;
        out.push_str(&format!("\nARR residuals on {}:\n", path.display()));
        for (arr, r) in analysis.arrs.iter().zip(&residuals) {
            let rms = (r.iter().map(|x| x * x).sum::<f64>() / r.len().max(1) as f64).sqrt();
            let max = r.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            out.push_str(&format!(
                "  {:<6} rms {rms:.4e}  max |r| {max:.4e}\n",
                arr.name
            ));
        }
    }
    super::print(&out)
}

//! The comparison as MCAP for Foxglove: measured, model and residual channels side by side.

use crate::io::atomic::{AtomicFile, commit_buffered};
use std::collections::BTreeSet;
use std::io::{BufWriter, Seek, Write};
use std::path::Path;

use super::format::describe;
use crate::error::{CoreError, Result};
use crate::io::foxglove::round_to;
use crate::io::mcap::{McapCompression, McapWriter, number_object_schema};

/// Topic of the measured outputs.
pub const MEASURED_TOPIC: &str = "/measured";
/// Topic of the model's prediction before the effect was added.
pub const MODEL_TOPIC: &str = "/model";
/// Topic of the model's prediction after the effect was added.
pub const MODEL_AFTER_TOPIC: &str = "/model_after";
/// Topic of the residual `measured − model` (before the effect was added).
pub const RESIDUAL_TOPIC: &str = "/residual";
/// Topic of the residual `measured − model after`.
pub const RESIDUAL_AFTER_TOPIC: &str = "/residual_after";

/// A comparison of measured outputs with a model's prediction, for
/// [`write_comparison_mcap`]. Outputs are columns: `measured[k]` is the output `names[k]`,
/// one value per time in `t`.
#[derive(Clone, Copy, Debug)]
pub struct ComparisonChannels<'a> {
    /// Sample times (s), finite, ≥ 0 and strictly increasing (at least 1 ns apart).
    pub t: &'a [f64],
    /// The outputs' names, unique and non-empty; the fields of every message.
    pub names: &'a [String],
    /// The measured outputs, one column per name.
    pub measured: &'a [Vec<f64>],
    /// The model's prediction before the effect was added, one column per name.
    pub before: &'a [Vec<f64>],
    /// The prediction after the effect was added, one column per name, when there is one.
    pub after: Option<&'a [Vec<f64>]>,
}

/// Writes a comparison as MCAP to `writer`: one JSON message per sample on each of
/// [`MEASURED_TOPIC`] (`/measured`), [`MODEL_TOPIC`] (`/model`), [`RESIDUAL_TOPIC`]
/// (`/residual`, measured − model) and, when `after` is given, [`MODEL_AFTER_TOPIC`]
/// (`/model_after`) and [`RESIDUAL_AFTER_TOPIC`] (`/residual_after`).
///
/// Each message is a flat object with one number per output (`{"i": 1.25, "omega": 98.1}`)
/// and its `log_time` is the sample time, so Foxglove's Plot panel shows
/// `/measured.i`, `/model.i` and `/model_after.i` side by side on the recording's time axis.
/// The measured values are written as given; the model's and the residuals are rounded to
/// `KEPT_DIGITS` (7) significant digits of each output's full scale (its largest |value|),
/// 1e-7 of full scale, which keeps the files small.
/// Every topic reads back with [`crate::io::mcap::read_signals`] (whose times start at the
/// first message, so they equal `t` when `t` starts at 0).
///
/// # Errors
///
/// [`CoreError::LengthMismatch`] naming the output and series (`"i (after)"`) when a column
/// has not one value per sample; [`CoreError::InvalidArgument`] when the number of columns
/// differs from the number of names, a name is empty or repeated, a time is negative, not
/// finite or not after the previous one, or a value is not finite (JSON has no NaN);
/// [`CoreError::McapWrite`], [`CoreError::McapTime`] or [`CoreError::Io`] when writing fails.
///
/// # Example
///
/// ```
/// # use std::io::Cursor;
/// # use modelgap_core::report::{write_comparison, ComparisonChannels};
/// # use modelgap_core::io::mcap::read_signals;
/// let names = vec!["i".to_owned()];
/// let c = ComparisonChannels {
///     t: &[0.0, 0.5],
///     names: &names,
///     measured: &[vec![1.0, 2.0]],
///     before: &[vec![1.0, 1.5]],
///     after: None,
/// };
/// let mut file = Cursor::new(Vec::new());
/// write_comparison(&c, &mut file)?;
/// let residual = read_signals(file.get_ref(), "/residual")?;
/// assert_eq!(residual.values("i")?, &[0.0, 0.5]);
/// # Ok::<(), modelgap_core::CoreError>(())
/// ```
pub fn write_comparison<W: Write + Seek>(c: &ComparisonChannels<'_>, writer: W) -> Result<W> {
    validate(c)?;
    let decimals = kept_decimals(c);
    let rounded = |columns: &[Vec<f64>]| -> Vec<Vec<f64>> {
        columns
            .iter()
            .zip(&decimals)
            .map(|(column, &d)| column.iter().map(|&v| round_to(v, d)).collect())
            .collect()
    };
    let residual = rounded(&difference(c.measured, c.before));
    let residual_after = c.after.map(|after| rounded(&difference(c.measured, after)));
    let before = rounded(c.before);
    let after = c.after.map(rounded);

    let mut streams: Vec<(&str, &str, &[Vec<f64>])> = vec![
        (MEASURED_TOPIC, "modelgap.Measured", c.measured),
        (MODEL_TOPIC, "modelgap.Model", &before),
    ];
    if let Some(after) = &after {
        streams.push((MODEL_AFTER_TOPIC, "modelgap.ModelAfter", after));
    }
    streams.push((RESIDUAL_TOPIC, "modelgap.Residual", &residual));
    if let Some(r) = &residual_after {
        streams.push((RESIDUAL_AFTER_TOPIC, "modelgap.ResidualAfter", r));
    }

    let names: Vec<&str> = c.names.iter().map(String::as_str).collect();
    let mut out = McapWriter::new(writer, McapCompression::Zstd)?;
    let mut channels = Vec::with_capacity(streams.len());
    for &(topic, schema_name, _) in &streams {
        let schema = number_object_schema(schema_name, &names);
        channels.push(out.add_json_channel(topic, schema_name, &schema)?);
    }
    // Time-ordered across topics, as players expect.
    for (i, &t) in c.t.iter().enumerate() {
        for (&channel, &(_, _, columns)) in channels.iter().zip(&streams) {
            let message: serde_json::Map<String, serde_json::Value> = c
                .names
                .iter()
                .zip(columns)
                .map(|(name, column)| (name.clone(), serde_json::Value::from(column[i])))
                .collect();
            out.write_json(channel, t, &serde_json::Value::Object(message))?;
        }
    }
    out.finish()
}

/// Writes a comparison to an MCAP file (created or truncated); like [`write_comparison`],
/// with the path in every error.
///
/// # Errors
///
/// As [`write_comparison`], plus [`CoreError::Io`] when the file cannot be created.
pub fn write_comparison_mcap(c: &ComparisonChannels<'_>, path: &Path) -> Result<()> {
    // Checked before the file is created, so bad input leaves no empty file behind.
    validate(c)?;
    let file = AtomicFile::create(path)?;
    let w = write_comparison(c, BufWriter::new(file)).map_err(|e| e.with_path(path))?;
    commit_buffered(w)
}

/// Significant digits kept of each output's full scale in the model and residual topics.
pub const KEPT_DIGITS: i32 = 7;

/// Per output, the decimals that keep [`KEPT_DIGITS`] digits of its full scale (the largest
/// |value| measured or predicted): 1e-7 of full scale, far finer than any sensor (a 16-bit
/// converter resolves 1.5e-5) and than the recordings' own digits.
fn kept_decimals(c: &ComparisonChannels<'_>) -> Vec<u8> {
    (0..c.names.len())
        .map(|k| {
            let columns = [Some(c.measured), Some(c.before), c.after];
            let scale = columns
                .iter()
                .flatten()
                .flat_map(|cols| cols[k].iter())
                .fold(0.0_f64, |m, v| m.max(v.abs()));
            if scale > 0.0 {
                let d = KEPT_DIGITS - 1 - scale.log10().floor() as i32;
                d.clamp(0, 15) as u8
            } else {
                15
            }
        })
        .collect()
}

fn difference(a: &[Vec<f64>], b: &[Vec<f64>]) -> Vec<Vec<f64>> {
    a.iter()
        .zip(b)
        .map(|(x, y)| x.iter().zip(y).map(|(x, y)| x - y).collect())
        .collect()
}

fn validate(c: &ComparisonChannels<'_>) -> Result<()> {
    let mut seen = BTreeSet::new();
    for name in c.names {
        if name.is_empty() || !seen.insert(name.as_str()) {
            return Err(CoreError::InvalidArgument {
                name: "names",
                reason: if name.is_empty() {
                    "an output name is empty".to_owned()
                } else {
                    format!("the output name `{name}` appears more than once")
                },
            });
        }
    }
    for (i, &t) in c.t.iter().enumerate() {
        let bad = if !t.is_finite() || t < 0.0 {
            Some("expected a finite time ≥ 0 s (mcap log times start at 0)".to_owned())
        } else if i > 0 && t <= c.t[i - 1] {
            Some(format!(
                "it is not after the previous time, {} s",
                c.t[i - 1]
            ))
        } else {
            None
        };
        if let Some(reason) = bad {
            return Err(CoreError::InvalidArgument {
                name: "t",
                reason: format!("time at sample {i} is {} s: {reason}", describe(t)),
            });
        }
    }
    let mut sets = vec![("measured", c.measured), ("before", c.before)];
    if let Some(after) = c.after {
        sets.push(("after", after));
    }
    for (series, columns) in sets {
        if columns.len() != c.names.len() {
            return Err(CoreError::InvalidArgument {
                name: "columns",
                reason: format!(
                    "`{series}` has {} columns for {} output names",
                    columns.len(),
                    c.names.len()
                ),
            });
        }
        for (name, column) in c.names.iter().zip(columns) {
            if column.len() != c.t.len() {
                return Err(CoreError::LengthMismatch {
                    name: format!("{name} ({series})"),
                    expected: c.t.len(),
                    found: column.len(),
                });
            }
            if let Some(i) = column.iter().position(|v| !v.is_finite()) {
                return Err(CoreError::InvalidArgument {
                    name: "values",
                    reason: format!(
                        "output `{name}` ({series}) is {} at sample {i}; json holds finite \
                         numbers only",
                        describe(column[i])
                    ),
                });
            }
        }
    }
    Ok(())
}

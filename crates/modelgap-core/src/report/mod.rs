//! The report a person reads to understand a comparison without the terminal: one
//! self-contained HTML page with SVG plots, and an MCAP file for Foxglove.
//!
//! The page shows, in order: the title, the verdict in a box, summary paragraphs, a table,
//! then the measured signals against the model before and after an effect was added (each
//! with the residual beneath on the same time axis, its noise band and failure windows
//! shaded, and a zoom where the error is largest, so an error thinner than a line still
//! shows), any separate residual plots, the ranking of candidate effects as a bar chart, and
//! any domain plots the caller adds (a cloth error map, for example). Every plot has a caption that says what to look at. The page needs no network,
//! no fonts and no JavaScript.
//!
//! The inputs are plain structs ([`Report`], [`SeriesPlot`], [`ResidualPlot`],
//! [`RankingBar`]) so any model, bond graph or cloth, can fill them. All text is plain text
//! and escaped here. Long series are decimated for drawing (the minimum and maximum of each
//! pixel column, which keeps the visual envelope), so a page with 200 000-sample signals
//! stays small. Non-finite values (a model that diverged) are drawn as gaps.
//!
//! [`write_comparison_mcap`] writes the same comparison for Foxglove: the topics
//! `/measured`, `/model`, `/model_after` and `/residual`, one flat JSON object of the outputs
//! per sample, so Foxglove's Plot panel shows them side by side.
//!
//! # Example
//!
//! ```
//! use modelgap_core::report::{render_html, Report, ResidualPlot, SeriesPlot};
//!
//! let t: Vec<f64> = (0..500).map(|k| f64::from(k) * 1e-3).collect();
//! let measured: Vec<f64> = t.iter().map(|t| (10.0 * t).sin()).collect();
//! let before: Vec<f64> = t.iter().map(|t| 0.8 * (10.0 * t).sin()).collect();
//! let residual: Vec<f64> = measured.iter().zip(&before).map(|(m, p)| m - p).collect();
//! let report = Report {
//!     title: "Motor current".into(),
//!     verdict: "The model is 20 % too weak".into(),
//!     series: vec![SeriesPlot {
//!         title: "current i".into(),
//!         unit: "A".into(),
//!         t: t.clone(),
//!         measured,
//!         before,
//!         after: None,
//!         band: 0.02,
//!         windows: Vec::new(),
//!     }],
//!     residuals: vec![ResidualPlot {
//!         title: "current i".into(),
//!         unit: "A".into(),
//!         t,
//!         before: residual,
//!         after: None,
//!         band: 0.02,
//!         windows: Vec::new(),
//!     }],
//!     ..Report::default()
//! };
//! report.validate()?;
//! let html = render_html(&report);
//! assert!(html.starts_with("<!DOCTYPE html>") && html.matches("<svg").count() == 2);
//! # Ok::<(), modelgap_core::CoreError>(())
//! ```

use crate::error::{CoreError, Result};
use crate::residual::FailureWindow;
use format::describe;

mod decimate;
mod format;
mod foxglove;
mod html;
mod ranking;
mod svg;

pub use format::{escape, format_number};
pub use foxglove::{
    ComparisonChannels, MEASURED_TOPIC, MODEL_AFTER_TOPIC, MODEL_TOPIC, RESIDUAL_AFTER_TOPIC,
    RESIDUAL_TOPIC, write_comparison, write_comparison_mcap,
};
pub use html::{render_html, write_html};
pub use ranking::ranking_svg;
pub use svg::{missing_svg, residual_svg, series_svg};

/// A measured signal against the model's prediction before and, optionally, after an effect
/// was added: one figure of the report, with the residual `measured − model` drawn beneath
/// on the same time axis (against [`SeriesPlot::band`], with [`SeriesPlot::windows`]
/// shaded) and a zoom on the stretch where the error is largest.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SeriesPlot {
    /// The plot's title, usually the signal's name (plain text).
    pub title: String,
    /// The signal's unit ("A", "rad/s"), shown on the y axis; may be empty.
    pub unit: String,
    /// Sample times (s), finite and non-decreasing.
    pub t: Vec<f64>,
    /// The measurement, one value per sample.
    pub measured: Vec<f64>,
    /// The model's prediction before the effect was added, one value per sample.
    pub before: Vec<f64>,
    /// The model's prediction after the effect was added, one value per sample.
    pub after: Option<Vec<f64>>,
    /// Half-width of the band around zero that noise alone would fill in the residual, in
    /// the signal's unit (finite, ≥ 0; 0 draws no band).
    pub band: f64,
    /// The windows where the residual before leaves the band, shaded in the residual strip.
    pub windows: Vec<FailureWindow>,
}

/// A residual (`measured − predicted`) before and, optionally, after an effect was added,
/// with its noise band and the windows where the residual before leaves the band.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ResidualPlot {
    /// The plot's title, usually the signal's name (plain text).
    pub title: String,
    /// The signal's unit, shown on the y axis; may be empty.
    pub unit: String,
    /// Sample times (s), finite and non-decreasing.
    pub t: Vec<f64>,
    /// The residual of the model before the effect was added, one value per sample.
    pub before: Vec<f64>,
    /// The residual of the model after the effect was added, one value per sample.
    pub after: Option<Vec<f64>>,
    /// Half-width of the band around zero that noise alone would fill, in the signal's unit
    /// (finite, ≥ 0): drawn as a grey area `±band`.
    pub band: f64,
    /// The windows where the residual before leaves the band, shaded light red.
    pub windows: Vec<FailureWindow>,
}

/// One candidate effect in the ranking bar chart.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RankingBar {
    /// The effect's plain name ("Coulomb friction on the motor shaft").
    pub label: String,
    /// How much error the effect removes, in the ranking's unit (finite; may be negative).
    pub value: f64,
    /// Whether this is the chosen effect (drawn highlighted).
    pub highlight: bool,
    /// A short note shown after the label (fitted parameters, evidence); may be empty.
    pub note: String,
}

/// Everything one report page shows. All strings are plain text; the renderer escapes them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// The page title.
    pub title: String,
    /// Summary paragraphs, plain text, one `<p>` each.
    pub summary_html_paragraphs: Vec<String>,
    /// The verdict in one or two sentences, shown in a box at the top.
    pub verdict: String,
    /// A table of numbers; the first row is the header. Rows may differ in length.
    pub table: Vec<Vec<String>>,
    /// Measured against model, one plot per signal.
    pub series: Vec<SeriesPlot>,
    /// Residuals with bands and failure windows, one plot per signal.
    pub residuals: Vec<ResidualPlot>,
    /// The ranked candidate effects, best first.
    pub ranking: Vec<RankingBar>,
    /// The unit of [`RankingBar::value`] ("% of RMS² explained", "ΔBIC").
    pub ranking_unit: String,
    /// Domain plots as `(caption, svg text)`. The caption is plain text; the SVG is inserted
    /// into the page as is, so it must come from trusted code.
    pub extra_svgs: Vec<(String, String)>,
}

impl Report {
    /// Checks that every plot can be drawn: one value per sample in every series, finite
    /// non-decreasing times, finite non-negative bands, finite windows and ranking values.
    ///
    /// [`render_html`] draws a notice in place of a plot that fails these checks; this tells
    /// the caller what is wrong instead. Non-finite signal values are allowed (drawn as gaps).
    ///
    /// # Errors
    ///
    /// [`CoreError::LengthMismatch`] naming the plot and series (`"current i: after"`) when a
    /// series has not one value per sample; [`CoreError::InvalidArgument`] naming the plot
    /// when its times, band, windows or ranking values are not finite or out of order.
    pub fn validate(&self) -> Result<()> {
        for p in &self.series {
            validate_series(p)?;
        }
        for p in &self.residuals {
            validate_residual(p)?;
        }
        validate_ranking(&self.ranking)
    }
}

/// Checks one [`SeriesPlot`] (see [`Report::validate`]).
pub(crate) fn validate_series(p: &SeriesPlot) -> Result<()> {
    validate_time(&p.title, &p.t)?;
    same_length(&p.title, "measured", p.t.len(), &p.measured)?;
    same_length(&p.title, "before", p.t.len(), &p.before)?;
    if let Some(after) = &p.after {
        same_length(&p.title, "after", p.t.len(), after)?;
    }
    validate_band_windows(&p.title, p.band, &p.windows)
}

/// Checks one [`ResidualPlot`] (see [`Report::validate`]).
pub(crate) fn validate_residual(p: &ResidualPlot) -> Result<()> {
    validate_time(&p.title, &p.t)?;
    same_length(&p.title, "before", p.t.len(), &p.before)?;
    if let Some(after) = &p.after {
        same_length(&p.title, "after", p.t.len(), after)?;
    }
    validate_band_windows(&p.title, p.band, &p.windows)
}

/// Checks a plot's noise band and failure windows (see [`Report::validate`]).
fn validate_band_windows(title: &str, band: f64, windows: &[FailureWindow]) -> Result<()> {
    if !(band.is_finite() && band >= 0.0) {
        return Err(CoreError::InvalidArgument {
            name: "band",
            reason: format!(
                "the band of plot `{title}` is {}, expected a finite value ≥ 0",
                describe(band)
            ),
        });
    }
    for (k, w) in windows.iter().enumerate() {
        let finite = [w.start, w.end, w.peak, w.peak_time]
            .iter()
            .all(|v| v.is_finite());
        if !finite || w.end < w.start {
            return Err(CoreError::InvalidArgument {
                name: "windows",
                reason: format!(
                    "failure window {k} of plot `{title}` runs from {} s to {} s \
                     (peak {} at {} s), expected finite values with start ≤ end",
                    describe(w.start),
                    describe(w.end),
                    describe(w.peak),
                    describe(w.peak_time)
                ),
            });
        }
    }
    Ok(())
}

/// Checks the ranking bars (see [`Report::validate`]).
pub(crate) fn validate_ranking(bars: &[RankingBar]) -> Result<()> {
    match bars.iter().find(|b| !b.value.is_finite()) {
        Some(bar) => Err(CoreError::InvalidArgument {
            name: "ranking",
            reason: format!(
                "the ranking bar `{}` has the value {}, expected a finite number",
                bar.label,
                describe(bar.value)
            ),
        }),
        None => Ok(()),
    }
}

fn validate_time(title: &str, t: &[f64]) -> Result<()> {
    for (i, w) in t.windows(2).enumerate() {
        if w[1] < w[0] {
            return Err(CoreError::InvalidArgument {
                name: "t",
                reason: format!(
                    "time of plot `{title}` decreases at sample {}: {} s after {} s",
                    i + 1,
                    w[1],
                    w[0]
                ),
            });
        }
    }
    if let Some(i) = t.iter().position(|v| !v.is_finite()) {
        return Err(CoreError::InvalidArgument {
            name: "t",
            reason: format!("time of plot `{title}` is {} at sample {i}", describe(t[i])),
        });
    }
    Ok(())
}

fn same_length(title: &str, series: &str, expected: usize, values: &[f64]) -> Result<()> {
    if values.len() == expected {
        Ok(())
    } else {
        Err(CoreError::LengthMismatch {
            name: format!("{title}: {series}"),
            expected,
            found: values.len(),
        })
    }
}

#[cfg(test)]
mod tests;

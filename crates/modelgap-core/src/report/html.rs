//! The report page: one self-contained HTML file (inline CSS and SVG, no scripts, no
//! external assets).

use std::fmt::Write as _;
use std::path::Path;

use super::format::{escape, format_number, with_unit};
use super::ranking::ranking_svg;
use super::svg::{residual_svg, series_svg, zoom_window};
use super::{Report, ResidualPlot, SeriesPlot};
use crate::error::Result;
use crate::residual::FailureWindow;

/// The most failure windows listed by time in a residual plot's caption.
const MAX_LISTED_WINDOWS: usize = 6;

const STYLE: &str = "
:root { color-scheme: light; }
body { margin: 0; background: #f4f5f7; color: #212529;
  font: 16px/1.5 system-ui, -apple-system, 'Segoe UI', Roboto, 'Helvetica Neue', Arial, sans-serif; }
main { max-width: 1000px; margin: 0 auto; padding: 28px 24px 48px; background: #fff;
  box-shadow: 0 0 0 1px #e3e5e8; min-height: 100vh; box-sizing: border-box; }
h1 { font-size: 1.9em; line-height: 1.2; margin: 0 0 4px; }
.kicker { color: #646a73; font-size: 0.85em; letter-spacing: 0.06em; text-transform: uppercase;
  margin: 0 0 18px; }
h2 { font-size: 1.3em; margin: 40px 0 6px; padding-bottom: 4px; border-bottom: 1px solid #e3e5e8; }
.verdict { border: 1px solid #b7c9ec; border-left: 8px solid #1f5fbf; background: #eef3fc;
  border-radius: 6px; padding: 14px 18px; margin: 0 0 22px; }
.verdict .label { font-size: 0.8em; font-weight: 700; color: #1f5fbf; letter-spacing: 0.08em;
  text-transform: uppercase; }
.verdict p { font-size: 1.3em; font-weight: 600; margin: 4px 0 0; line-height: 1.35; }
.summary p { margin: 0 0 12px; }
.intro { color: #3d434a; margin: 4px 0 12px; }
table { border-collapse: collapse; margin: 18px 0 8px; font-size: 0.92em; }
th, td { padding: 6px 12px; border-bottom: 1px solid #e3e5e8; text-align: left; vertical-align: top; }
th { background: #f4f5f7; font-weight: 600; border-bottom: 2px solid #cfd3d8; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
tbody tr:nth-child(even) td { background: #fafbfc; }
figure { margin: 18px 0 26px; }
figure svg { display: block; width: 100%; height: auto; border: 1px solid #e3e5e8; border-radius: 4px; }
figcaption { color: #3d434a; font-size: 0.93em; margin-top: 8px; }
figcaption b { color: #212529; }
footer { color: #646a73; font-size: 0.85em; margin-top: 40px; border-top: 1px solid #e3e5e8;
  padding-top: 10px; }
@media print { body { background: #fff; } main { box-shadow: none; } figure { break-inside: avoid; } }
";

/// Renders the whole report as one self-contained HTML page: title, verdict box, summary,
/// table, then the measured-against-model plots, the residual plots, the ranking and the
/// extra plots, each with a caption that says what to look at.
///
/// All text is escaped; [`Report::extra_svgs`] are inserted as is. Sections without content
/// are left out. A plot that fails [`Report::validate`] is replaced by a notice saying why,
/// so this never fails; call [`Report::validate`] (or use [`write_html`]) to get the error.
///
/// # Example
///
/// ```
/// # use modelgap_core::report::{render_html, Report};
/// let report = Report { title: "R < 2 Ω?".into(), verdict: "Nothing is missing".into(), ..Report::default() };
/// let html = render_html(&report);
/// assert!(html.contains("<h1>R &lt; 2 Ω?</h1>"));
/// ```
pub fn render_html(report: &Report) -> String {
    let mut page = String::with_capacity(64 * 1024);
    let title = if report.title.is_empty() {
        "modelgap report"
    } else {
        report.title.as_str()
    };
    // Writing into a String cannot fail; the `let _ =` below ignore an impossible error.
    let _ = write!(
        page,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <meta name=\"generator\" content=\"modelgap\">\n<title>{}</title>\n\
         <style>{STYLE}</style>\n</head>\n<body>\n<main>\n\
         <p class=\"kicker\">modelgap report · model against measurement</p>\n<h1>{}</h1>\n",
        escape(title),
        escape(title)
    );
    if !report.verdict.is_empty() {
        let _ = writeln!(
            page,
            "<div class=\"verdict\"><div class=\"label\">Verdict</div><p>{}</p></div>",
            escape(&report.verdict)
        );
    }
    if !report.summary_html_paragraphs.is_empty() {
        page.push_str("<section class=\"summary\">\n");
        for paragraph in &report.summary_html_paragraphs {
            let _ = writeln!(page, "<p>{}</p>", escape(paragraph));
        }
        page.push_str("</section>\n");
    }
    push_table(&mut page, &report.table);

    if !report.series.is_empty() {
        page.push_str(
            "<h2>Measured against the model</h2>\n<p class=\"intro\">Each figure lays the \
             model's prediction over the measurement. Where the red line (the model as it was) \
             leaves the dark grey one (the measurement), the model is missing something. The \
             error is often thinner than a line at full scale, so beneath each plot, on the same \
             time axis, is the residual measured − model against the band noise alone would \
             fill, and at the bottom a zoom on the stretch where the error is largest.</p>\n",
        );
        for p in &report.series {
            push_figure(&mut page, &series_svg(p), &series_caption(p));
        }
    }
    if !report.residuals.is_empty() {
        page.push_str(
            "<h2>Residuals: where the model fails</h2>\n<p class=\"intro\">A residual is \
             measured − model, sample by sample. A right model leaves only noise, inside the \
             grey band.</p>\n",
        );
        for p in &report.residuals {
            push_figure(&mut page, &residual_svg(p), &residual_caption(p));
        }
    }
    if !report.ranking.is_empty() {
        page.push_str(
            "<h2>Which effect is missing</h2>\n<p class=\"intro\">Each candidate effect was \
             fitted to the measurement; the ranking orders them by how much of the error they \
             remove.</p>\n",
        );
        let unit = if report.ranking_unit.is_empty() {
            String::new()
        } else {
            format!(" ({})", escape(&report.ranking_unit))
        };
        let caption = format!(
            "Bar length is the error an effect removes{unit}. <b>The highlighted bar is the \
             effect chosen</b>; a bar near zero means that effect cannot explain the residual."
        );
        push_figure(
            &mut page,
            &ranking_svg(&report.ranking, &report.ranking_unit),
            &caption,
        );
    }
    if !report.extra_svgs.is_empty() {
        page.push_str("<h2>More plots</h2>\n");
        for (caption, svg) in &report.extra_svgs {
            push_figure(&mut page, svg, &escape(caption));
        }
    }
    page.push_str(
        "<footer>Made by modelgap. Long signals are thinned for drawing (the lowest and highest \
         value in each pixel column, so every peak still shows); the MCAP file written with \
         this report holds every sample for Foxglove.</footer>\n</main>\n</body>\n</html>\n",
    );
    page
}

/// Validates the report and writes its page ([`render_html`]) to `path`.
///
/// # Errors
///
/// The errors of [`Report::validate`]; [`CoreError::Io`](crate::CoreError::Io) when the file cannot be written.
pub fn write_html(report: &Report, path: &Path) -> Result<()> {
    report.validate()?;
    crate::io::atomic::write_atomic(path, render_html(report).as_bytes())
}

/// `caption_html` must already be escaped.
fn push_figure(page: &mut String, svg: &str, caption_html: &str) {
    page.push_str("<figure>\n");
    page.push_str(svg.trim());
    let _ = write!(
        page,
        "\n<figcaption>{caption_html}</figcaption>\n</figure>\n"
    );
}

fn push_table(page: &mut String, table: &[Vec<String>]) {
    let Some((header, rows)) = table.split_first() else {
        return;
    };
    let columns = table.iter().map(Vec::len).max().unwrap_or(0);
    if columns == 0 {
        return;
    }
    page.push_str("<table>\n<thead><tr>");
    for k in 0..columns {
        let _ = write!(
            page,
            "<th>{}</th>",
            escape(header.get(k).map_or("", String::as_str))
        );
    }
    page.push_str("</tr></thead>\n<tbody>\n");
    for row in rows {
        page.push_str("<tr>");
        for k in 0..columns {
            let cell = row.get(k).map_or("", String::as_str);
            if looks_numeric(cell) {
                let _ = write!(page, "<td class=\"num\">{}</td>", escape(cell));
            } else {
                let _ = write!(page, "<td>{}</td>", escape(cell));
            }
        }
        page.push_str("</tr>\n");
    }
    page.push_str("</tbody>\n</table>\n");
}

/// Whether a cell starts with a number ("0.25 A", "−3.1 %", "12"), to right-align it.
fn looks_numeric(cell: &str) -> bool {
    let s = cell.trim();
    let s = s
        .strip_prefix('−')
        .or_else(|| s.strip_prefix('-'))
        .or_else(|| s.strip_prefix('+'))
        .unwrap_or(s);
    s.chars().next().is_some_and(|c| c.is_ascii_digit())
}

/// RMS of `a − b` over the samples where both are finite; `None` when there are none.
fn rms_difference(a: &[f64], b: &[f64]) -> Option<f64> {
    let (sum, n) = a
        .iter()
        .zip(b)
        .map(|(x, y)| x - y)
        .filter(|d| d.is_finite())
        .fold((0.0, 0usize), |(s, n), d| (s + d * d, n + 1));
    (n > 0).then(|| (sum / n as f64).sqrt())
}

/// RMS of the finite values; `None` when there are none.
fn rms_finite(values: &[f64]) -> Option<f64> {
    rms_difference(values, &vec![0.0; values.len()])
}

/// "0.12 A before, 0.011 A after (9 % of it)".
fn before_after_text(before: Option<f64>, after: Option<f64>, unit: &str) -> String {
    match (before, after) {
        (Some(b), Some(a)) if b > 0.0 => format!(
            "RMS error {} before, <b>{} after</b> ({} % of it)",
            escape(&with_unit(b, unit)),
            escape(&with_unit(a, unit)),
            format_number(100.0 * a / b)
        ),
        (Some(b), Some(a)) => format!(
            "RMS error {} before, {} after",
            escape(&with_unit(b, unit)),
            escape(&with_unit(a, unit))
        ),
        (Some(b), None) => format!("RMS error {}", escape(&with_unit(b, unit))),
        _ => "no finite values to compare".to_owned(),
    }
}

fn series_caption(p: &SeriesPlot) -> String {
    let title = escape(&p.title);
    if super::validate_series(p).is_err() {
        return format!("<b>{title}</b>: this plot could not be drawn (see the notice).");
    }
    let before = rms_difference(&p.measured, &p.before);
    let after = p
        .after
        .as_ref()
        .and_then(|a| rms_difference(&p.measured, a));
    let how = if p.after.is_some() {
        "Dark grey is the measurement, red the model as it was, blue the model after adding \
         the effect: blue should follow grey where red does not."
    } else {
        "Dark grey is the measurement, red the model: look for stretches where they part."
    };
    let mut text = format!(
        "<b>{title}</b>: {how} {}.",
        before_after_text(before, after, &p.unit)
    );
    let strip = if p.band > 0.0 {
        format!(
            " The strip beneath shows measured − model; the grey band (±{}) is what noise \
             alone would leave.",
            escape(&with_unit(p.band, &p.unit))
        )
    } else {
        " The strip beneath shows measured − model.".to_owned()
    };
    text.push_str(&strip);
    if !p.windows.is_empty() {
        text.push_str(" Shaded red and numbered: where the model fails.");
    }
    text.push_str(&windows_text(&p.windows, &p.unit, p.band > 0.0));
    if let Some((a, b)) = zoom_window(p) {
        let _ = write!(
            text,
            " The bottom panel zooms into {}–{} s, where the model's error is largest.",
            format_number(a),
            format_number(b)
        );
    }
    text
}

/// " 2 failure windows: (1) 0.1–0.5 s, peak 0.3 A at 0.2 s, measured above the model; …."
/// (with `with_band`) or " The residual before never leaves the band." when there are none.
fn windows_text(windows: &[FailureWindow], unit: &str, with_band: bool) -> String {
    let mut text = String::new();
    match windows.len() {
        0 if with_band => text.push_str(" The residual before never leaves the band."),
        0 => {}
        n => {
            let _ = write!(
                text,
                " {n} failure window{}: ",
                if n == 1 { "" } else { "s" }
            );
            // Each listed window by its number on the chart (windows in time order).
            let listed: Vec<String> = crate::residual::largest_windows(windows, MAX_LISTED_WINDOWS)
                .into_iter()
                .map(|w| {
                    let k = windows.iter().position(|x| std::ptr::eq(x, w)).unwrap_or(0);
                    let side = match w.sign {
                        1 => ", measured above the model",
                        -1 => ", measured below the model",
                        _ => "",
                    };
                    format!(
                        "({}) {}–{} s, peak {} at {} s{side}",
                        k + 1,
                        format_number(w.start),
                        format_number(w.end),
                        escape(&with_unit(w.peak, unit)),
                        format_number(w.peak_time)
                    )
                })
                .collect();
            text.push_str(&listed.join("; "));
            if n > MAX_LISTED_WINDOWS {
                let _ = write!(text, "; and {} with smaller peaks", n - MAX_LISTED_WINDOWS);
            }
            text.push('.');
        }
    }
    text
}

fn residual_caption(p: &ResidualPlot) -> String {
    let title = escape(&p.title);
    if super::validate_residual(p).is_err() {
        return format!("<b>{title}</b>: this plot could not be drawn (see the notice).");
    }
    let mut text = format!(
        "<b>{title}</b>: the grey band (±{}) is what noise alone would leave; shaded red \
         windows are where the model fails.",
        escape(&with_unit(p.band, &p.unit))
    );
    text.push_str(&windows_text(&p.windows, &p.unit, true));
    let before = rms_finite(&p.before);
    let after = p.after.as_deref().and_then(rms_finite);
    let _ = write!(text, " {}", before_after_text(before, after, &p.unit));
    if p.after.is_some() {
        text.push_str("; the blue residual after adding the effect should stay inside the band.");
    } else {
        text.push('.');
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Of many windows the caption lists the largest, each by its number on the chart.
    #[test]
    fn listed_windows_keep_their_chart_numbers() {
        let windows: Vec<FailureWindow> = (0..8)
            .map(|k| FailureWindow {
                start: f64::from(k),
                end: f64::from(k) + 0.5,
                peak: if k == 6 {
                    9.0
                } else {
                    1.0 + 0.1 * f64::from(k)
                },
                peak_time: f64::from(k) + 0.2,
                sign: 1,
            })
            .collect();
        let text = windows_text(&windows, "V", true);
        // The smallest two (windows 1 and 2) are left out; window 7's peak is named as 7th.
        assert!(!text.contains("(1)") && !text.contains("(2)"), "{text}");
        assert!(text.contains("(7) 6–6.5 s, peak 9 V"), "{text}");
        assert!(text.contains("and 2 with smaller peaks"), "{text}");
    }
}

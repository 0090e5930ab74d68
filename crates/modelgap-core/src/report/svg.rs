//! The report's time plots, drawn with plotters' SVG backend (text as `<text>` elements, no
//! font files): measured against model (with the residual beneath on the same time axis and
//! a zoom where the error is largest) and residuals with band and failure windows. The
//! ranking bar chart is in [`ranking`](super::ranking).

use std::error::Error;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::decimate::{self, Decimated};
use super::format::{escape, format_tick, with_unit};
use super::{ResidualPlot, SeriesPlot, validate_residual, validate_series};
use crate::explain::estimate::{MissingSignal, SignalRole};
use crate::explain::screen::Law;
use crate::residual::FailureWindow;

/// Width of every plot (px); the page scales it to the column width.
pub(super) const WIDTH: u32 = 960;
/// Height of a measured-against-model or residual plot (px).
const HEIGHT: u32 = 380;
/// Height of the strip above a plot that holds its title and legend (px).
const HEADER: u32 = 58;
/// Space left of the plot area for y tick labels and the unit (px).
const Y_LABEL_AREA: u32 = 78;
/// Space below the plot area for x tick labels and "time (s)" (px).
const X_LABEL_AREA: u32 = 46;
/// Right margin of the plot area (px).
const RIGHT_MARGIN: u32 = 24;
/// Decimation columns: about one per pixel of the plot area, so at most ~1 700 points per
/// line whatever the length of the series.
const COLUMNS: usize = (WIDTH - Y_LABEL_AREA - RIGHT_MARGIN) as usize;
/// Series up to this many samples draw the measurement as dots as well as a line.
const MAX_DOTS: usize = 300;

pub(super) const FONT: &str = "sans-serif";
pub(super) const INK: RGBColor = RGBColor(33, 37, 41);
pub(super) const MUTED: RGBColor = RGBColor(100, 106, 115);
const MEASURED: RGBColor = RGBColor(64, 64, 64);
const BEFORE: RGBColor = RGBColor(214, 39, 40);
pub(super) const AFTER: RGBColor = RGBColor(31, 95, 191);
const BAND: RGBColor = RGBColor(221, 221, 221);
const WINDOW: RGBColor = RGBColor(239, 68, 68);
/// Opacity of the failure-window shading.
const WINDOW_ALPHA: f64 = 0.16;
const GRID_BOLD: RGBColor = RGBColor(222, 225, 230);
pub(super) const BAR: RGBColor = RGBColor(176, 183, 195);

/// plotters' SVG backend writes `font-size` as the requested size divided by 1.24 (its
/// estimate of a font's line height over its size); [`px`] undoes that.
const PLOTTERS_FONT_SCALE: f64 = 1.24;

/// The size to ask plotters for so the SVG text is `size` px.
pub(super) fn px(size: f64) -> f64 {
    size * PLOTTERS_FONT_SCALE
}

pub(super) type DrawResult = std::result::Result<(), Box<dyn Error>>;
pub(super) type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// The measured signal (dark grey) against the model before (red) and after (blue) adding
/// the effect, over time, with axes, ticks and a legend; beneath it, on the same time axis,
/// the residual `measured − model` before and after with the noise band
/// ([`SeriesPlot::band`]) and the failure windows shaded and numbered; and at the bottom a
/// zoom on the stretch where the model's error is largest (`zoom_window`), so an error
/// smaller than a line width in the full view still shows.
///
/// Long series are decimated (minimum and maximum per pixel column); non-finite values are
/// gaps. A plot whose series lengths do not match its time axis (see
/// [`Report::validate`](super::Report::validate)) becomes a notice saying so.
pub fn series_svg(p: &SeriesPlot) -> String {
    if let Err(e) = validate_series(p) {
        return notice_svg(&p.title, &format!("cannot draw this plot: {e}"));
    }
    let zoom = zoom_window(p);
    let height = HEADER + SERIES_MAIN + SERIES_STRIP + zoom.map_or(0, |_| SERIES_ZOOM);
    render(height, |root| draw_series(root, p, zoom))
}

/// Height of the main panel of a measured-against-model figure (px).
const SERIES_MAIN: u32 = 270;
/// Height of the residual strip beneath it (px).
const SERIES_STRIP: u32 = 180;
/// Height of the zoom panel at the bottom, with its title line (px).
const SERIES_ZOOM: u32 = 270;
/// Height of the zoom panel's title line (px).
const ZOOM_TITLE: u32 = 34;
/// The zoom shows this fraction of the whole time span.
const ZOOM_FRACTION: f64 = 0.12;

/// The stretch `(start, end)` in seconds a measured-against-model figure zooms into: a
/// [`ZOOM_FRACTION`] of the time span centred where the running mean of
/// `measured − before` (over 1/200 of the samples, so noise spikes do not win) is largest in
/// size. `None` for fewer than 20 samples, a zero time span, or no finite non-zero error.
pub(crate) fn zoom_window(p: &SeriesPlot) -> Option<(f64, f64)> {
    let n = p.t.len();
    if n < 20 || p.measured.len() != n || p.before.len() != n {
        return None;
    }
    let (t0, t1) = (p.t[0], p.t[n - 1]);
    // Finite times are checked by the caller; a zero span has nothing to zoom into.
    if t1 <= t0 {
        return None;
    }
    // Prefix sums over finite residuals, and their counts.
    let mut sum = vec![0.0; n + 1];
    let mut count = vec![0usize; n + 1];
    for k in 0..n {
        let r = p.measured[k] - p.before[k];
        let (v, c) = if r.is_finite() { (r, 1) } else { (0.0, 0) };
        sum[k + 1] = sum[k] + v;
        count[k + 1] = count[k] + c;
    }
    let w = (n / 200).max(1);
    let mut best: Option<(f64, usize)> = None;
    for k in 0..=(n - w) {
        let c = count[k + w] - count[k];
        if c == 0 {
            continue;
        }
        let mean = ((sum[k + w] - sum[k]) / c as f64).abs();
        if mean > best.map_or(0.0, |b| b.0) {
            best = Some((mean, k + w / 2));
        }
    }
    let centre = p.t[best?.1];
    let half = 0.5 * ZOOM_FRACTION * (t1 - t0);
    let (mut a, mut b) = (centre - half, centre + half);
    if a < t0 {
        b += t0 - a;
        a = t0;
    }
    if b > t1 {
        a = (a - (b - t1)).max(t0);
        b = t1;
    }
    Some((a, b))
}

/// The residual before (red) and after (blue) adding the effect, with the grey band `±band`
/// that noise alone would fill and the failure windows of the residual before shaded light
/// red and numbered.
///
/// Long series are decimated as in [`series_svg`]; invalid input becomes a notice.
pub fn residual_svg(p: &ResidualPlot) -> String {
    if let Err(e) = validate_residual(p) {
        return notice_svg(&p.title, &format!("cannot draw this plot: {e}"));
    }
    render(HEIGHT, |root| draw_residual(root, p))
}

/// Runs `draw` on a fresh SVG canvas `WIDTH × height` and returns the SVG text; a drawing
/// error (none is expected from the SVG backend) becomes a notice.
pub(super) fn render(height: u32, draw: impl FnOnce(&Area<'_>) -> DrawResult) -> String {
    let mut out = String::new();
    let result = {
        let root = SVGBackend::with_string(&mut out, (WIDTH, height)).into_drawing_area();
        let drawn = draw(&root);
        drawn.and_then(|()| root.present().map_err(Into::into))
    };
    match result {
        Ok(()) => out,
        Err(e) => notice_svg("plot", &format!("drawing failed: {e}")),
    }
}

/// A small SVG that shows a title and a message in place of a plot, written by hand so it
/// cannot fail.
pub(super) fn notice_svg(title: &str, message: &str) -> String {
    format!(
        "<svg width=\"{WIDTH}\" height=\"90\" viewBox=\"0 0 {WIDTH} 90\" \
         xmlns=\"http://www.w3.org/2000/svg\">\n\
         <rect x=\"0.5\" y=\"0.5\" width=\"{w}\" height=\"89\" fill=\"#fff7f7\" \
         stroke=\"#e5a0a0\"/>\n\
         <text x=\"16\" y=\"32\" font-family=\"{FONT}\" font-size=\"17\" font-weight=\"bold\" \
         fill=\"#212529\">{title}</text>\n\
         <text x=\"16\" y=\"62\" font-family=\"{FONT}\" font-size=\"14\" \
         fill=\"#b42318\">{message}</text>\n</svg>\n",
        w = WIDTH - 1,
        title = escape(title),
        message = escape(message),
    )
}

/// How a legend entry is drawn.
#[derive(Clone, Copy)]
enum Swatch {
    Line(RGBColor, u32),
    Fill(RGBColor, f64),
}

/// Draws the title and a one-line legend across the top strip.
fn draw_header(top: &Area<'_>, title: &str, legend: &[(Swatch, String)]) -> DrawResult {
    let title_style = (FONT, px(17.0), FontStyle::Bold)
        .into_font()
        .color(&INK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    top.draw(&Text::new(title.to_owned(), (16, 18), title_style))?;
    let label_style = (FONT, px(13.0))
        .into_font()
        .color(&MUTED)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let y = 44;
    let mut x = 16;
    for (swatch, label) in legend {
        match *swatch {
            Swatch::Line(color, width) => {
                top.draw(&PathElement::new(
                    vec![(x, y), (x + 24, y)],
                    color.stroke_width(width + 1),
                ))?;
            }
            Swatch::Fill(color, alpha) => {
                top.draw(&Rectangle::new(
                    [(x, y - 6), (x + 24, y + 6)],
                    color.mix(alpha).filled(),
                ))?;
            }
        }
        top.draw(&Text::new(label.clone(), (x + 30, y), label_style.clone()))?;
        // The SVG backend cannot measure text; 7 px per character fits 13 px sans-serif.
        x += 30 + 7 * label.chars().count() as i32 + 22;
    }
    Ok(())
}

/// Axis limits `(t0, t1, y0, y1)` for lines over `t`, with 5 % headroom in y and a span
/// that is never zero.
fn limits(t: &[f64], lines: &[&Decimated], extra_y: &[f64]) -> (f64, f64, f64, f64) {
    let (mut t0, mut t1) = match (t.first(), t.last()) {
        (Some(&a), Some(&b)) => (a, b),
        _ => (0.0, 1.0),
    };
    if t1 <= t0 {
        t0 -= 0.5;
        t1 += 0.5;
    }
    let mut range: Option<(f64, f64)> = None;
    for (lo, hi) in lines
        .iter()
        .filter_map(|d| d.value_range())
        .chain(extra_y.iter().map(|&v| (v, v)))
    {
        range = Some(match range {
            None => (lo, hi),
            Some((a, b)) => (a.min(lo), b.max(hi)),
        });
    }
    let (mut y0, mut y1) = range.unwrap_or((-1.0, 1.0));
    if y1 - y0 <= f64::EPSILON * y0.abs().max(y1.abs()) {
        let pad = if y0 == 0.0 { 1.0 } else { 0.1 * y0.abs() };
        y0 -= pad;
        y1 += pad;
    }
    let pad = 0.05 * (y1 - y0);
    (t0, t1, y0 - pad, y1 + pad)
}

type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Builds a chart on `body` with its grid, ticks and axis names; `x_desc` names the time
/// axis (`None`: tick labels only, for a panel with another beneath it).
fn chart<'a, 'b>(
    body: &'a Area<'b>,
    (t0, t1, y0, y1): (f64, f64, f64, f64),
    y_desc: &str,
    x_desc: Option<&str>,
) -> std::result::Result<Chart<'a, 'b>, Box<dyn Error>> {
    let mut chart = ChartBuilder::on(body)
        .margin_right(RIGHT_MARGIN)
        .margin_top(6)
        .x_label_area_size(if x_desc.is_some() { X_LABEL_AREA } else { 24 })
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d(t0..t1, y0..y1)?;
    let t_span = t1 - t0;
    let y_span = y1 - y0;
    let x_fmt = move |v: &f64| format_tick(*v, t_span);
    let y_fmt = move |v: &f64| format_tick(*v, y_span);
    let mut mesh = chart.configure_mesh();
    mesh.x_labels(10)
        .y_labels(if y1 - y0 > 0.0 && body.dim_in_pixel().1 < 200 {
            5
        } else {
            7
        })
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .y_desc(y_desc)
        .label_style((FONT, px(12.0)).into_font().color(&MUTED))
        .axis_desc_style((FONT, px(13.0)).into_font().color(&INK))
        .max_light_lines(0)
        .bold_line_style(GRID_BOLD)
        .axis_style(MUTED);
    if let Some(x) = x_desc {
        mesh.x_desc(x);
    }
    mesh.draw()?;
    Ok(chart)
}

fn y_description(kind: &str, unit: &str) -> String {
    if unit.is_empty() {
        kind.to_owned()
    } else {
        format!("{kind} ({unit})")
    }
}

/// Draws a decimated line, one polyline per run of finite values.
fn draw_line(chart: &mut Chart<'_, '_>, line: &Decimated, style: ShapeStyle) -> DrawResult {
    for segment in &line.segments {
        chart.draw_series(LineSeries::new(segment.iter().copied(), style))?;
    }
    Ok(())
}

/// A note for the legend when some values could not be drawn.
fn gaps_note(lines: &[(&str, &Decimated)]) -> Option<String> {
    let parts: Vec<String> = lines
        .iter()
        .filter(|(_, d)| d.n_non_finite > 0)
        .map(|(name, d)| format!("{} non-finite values of {name} not drawn", d.n_non_finite))
        .collect();
    (!parts.is_empty()).then(|| parts.join("; "))
}

fn draw_series(root: &Area<'_>, p: &SeriesPlot, zoom: Option<(f64, f64)>) -> DrawResult {
    root.fill(&WHITE)?;
    let (top, rest) = root.split_vertically(HEADER);
    let (main, rest) = rest.split_vertically(SERIES_MAIN);
    let (strip, zoom_area) = rest.split_vertically(SERIES_STRIP);
    let measured = decimate::min_max(&p.t, &p.measured, COLUMNS);
    let before = decimate::min_max(&p.t, &p.before, COLUMNS);
    let after = p
        .after
        .as_ref()
        .map(|a| decimate::min_max(&p.t, a, COLUMNS));

    let mut legend = vec![
        (Swatch::Line(MEASURED, 1), "measured".to_owned()),
        (Swatch::Line(BEFORE, 2), "model before".to_owned()),
    ];
    if after.is_some() {
        legend.push((
            Swatch::Line(AFTER, 2),
            "model after adding the effect".to_owned(),
        ));
    }
    legend.extend(band_legend(p.band, &p.windows, &p.unit));
    let mut named = vec![("measured", &measured), ("model before", &before)];
    if let Some(a) = &after {
        named.push(("model after", a));
    }
    draw_header(&top, &p.title, &legend)?;

    let (extra_y, off_plot) = model_extent(&measured, &named[1..], &p.unit);
    let lim = if measured.value_range().is_some() {
        limits(&p.t, &[&measured], &extra_y)
    } else {
        let mut lines = vec![&before];
        lines.extend(after.as_ref());
        limits(&p.t, &lines, &[])
    };
    let mut main_chart = chart(&main, lim, &y_description("value", &p.unit), None)?;
    draw_signal_lines(
        &mut main_chart,
        &measured,
        &before,
        after.as_ref(),
        p.t.len(),
    )?;
    if let Some((a, b)) = zoom {
        // Where the zoom at the bottom looks, outlined and labelled.
        let (_, _, y0, y1) = lim;
        main_chart.draw_series(std::iter::once(Rectangle::new(
            [(a, y0), (b, y1)],
            INK.mix(0.55).stroke_width(1),
        )))?;
        let style = (FONT, px(11.0))
            .into_font()
            .color(&INK)
            .pos(Pos::new(HPos::Center, VPos::Bottom));
        // At the box's foot: the top right corner holds the notes of lines off the plot.
        main_chart.draw_series(std::iter::once(Text::new(
            "zoom below".to_owned(),
            ((a + b) / 2.0, y0 + 0.01 * (y1 - y0)),
            style,
        )))?;
    }
    let notes: Vec<String> = gaps_note(&named).into_iter().chain(off_plot).collect();
    if !notes.is_empty() {
        draw_corner_note(&main, &notes.join("; "))?;
    }

    // The residual beneath, on the same time axis (same margins, so times line up).
    let residual_before: Vec<f64> = residual(&p.measured, &p.before);
    let residual_after: Option<Vec<f64>> = p.after.as_ref().map(|a| residual(&p.measured, a));
    let rb = decimate::min_max(&p.t, &residual_before, COLUMNS);
    let ra = residual_after
        .as_ref()
        .map(|r| decimate::min_max(&p.t, r, COLUMNS));
    let mut lines = vec![&rb];
    lines.extend(ra.as_ref());
    let (t0, t1, y0, mut y1) = limits(&p.t, &lines, &[0.0, 1.25 * p.band, -1.25 * p.band]);
    if !p.windows.is_empty() {
        y1 += 0.12 * (y1 - y0);
    }
    let lim = (t0, t1, y0, y1);
    let mut strip_chart = chart(
        &strip,
        lim,
        &y_description("measured − model", &p.unit),
        Some("time (s)"),
    )?;
    draw_band_and_windows(&mut strip_chart, lim, p.band, &p.windows)?;
    draw_line(&mut strip_chart, &rb, BEFORE.stroke_width(1))?;
    if let Some(a) = &ra {
        draw_line(&mut strip_chart, a, AFTER.stroke_width(1))?;
    }

    if let Some(window) = zoom {
        draw_zoom(&zoom_area, p, window)?;
    }
    Ok(())
}

/// `measured − model`, sample by sample.
fn residual(measured: &[f64], model: &[f64]) -> Vec<f64> {
    measured.iter().zip(model).map(|(m, p)| m - p).collect()
}

/// The measurement (with dots when there are few samples) and the model lines.
fn draw_signal_lines(
    chart: &mut Chart<'_, '_>,
    measured: &Decimated,
    before: &Decimated,
    after: Option<&Decimated>,
    n_samples: usize,
) -> DrawResult {
    draw_line(chart, measured, MEASURED.stroke_width(1))?;
    if n_samples <= MAX_DOTS {
        for segment in &measured.segments {
            chart.draw_series(
                segment
                    .iter()
                    .map(|&(t, v)| Circle::new((t, v), 2, MEASURED.filled())),
            )?;
        }
    }
    draw_line(chart, before, BEFORE.stroke_width(2))?;
    if let Some(a) = after {
        draw_line(chart, a, AFTER.stroke_width(2))?;
    }
    Ok(())
}

/// The zoom panel: measured against the model over `[a, b]` only, its y axis fitted to the
/// values there.
fn draw_zoom(area: &Area<'_>, p: &SeriesPlot, (a, b): (f64, f64)) -> DrawResult {
    let (title_area, body) = area.split_vertically(ZOOM_TITLE);
    let lo = p.t.partition_point(|&t| t < a);
    let hi = p.t.partition_point(|&t| t <= b).max(lo);
    let t = &p.t[lo..hi];
    let measured = decimate::min_max(t, &p.measured[lo..hi], COLUMNS);
    let before = decimate::min_max(t, &p.before[lo..hi], COLUMNS);
    let after = p
        .after
        .as_ref()
        .map(|x| decimate::min_max(t, &x[lo..hi], COLUMNS));
    let mean_gap = |model: &[f64]| {
        let (s, n) = p.measured[lo..hi]
            .iter()
            .zip(&model[lo..hi])
            .map(|(m, x)| m - x)
            .filter(|d| d.is_finite())
            .fold((0.0, 0usize), |(s, n), d| (s + d, n + 1));
        (n > 0).then(|| s / n as f64)
    };
    let mut title = format!(
        "zoom on {}–{} s, where the model's error is largest",
        format_tick(a, b - a),
        format_tick(b, b - a)
    );
    if let Some(g) = mean_gap(&p.before) {
        title.push_str(&format!(
            ": measured − model averages {} before",
            with_unit(g, &p.unit)
        ));
        if let Some(g) = p.after.as_deref().and_then(mean_gap) {
            title.push_str(&format!(", {} after", with_unit(g, &p.unit)));
        }
    }
    let style = (FONT, px(13.0))
        .into_font()
        .color(&INK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    title_area.draw(&Text::new(title, (16, (ZOOM_TITLE / 2 + 2) as i32), style))?;
    let mut lines = vec![&measured, &before];
    lines.extend(after.as_ref());
    let (_, _, y0, y1) = limits(t, &lines, &[]);
    let mut zoom_chart = chart(
        &body,
        (a, b, y0, y1),
        &y_description("value", &p.unit),
        Some("time (s)"),
    )?;
    draw_signal_lines(&mut zoom_chart, &measured, &before, after.as_ref(), t.len())
}

/// Legend entries for a noise band (when there is one) and failure windows (when any).
fn band_legend(band: f64, windows: &[FailureWindow], unit: &str) -> Vec<(Swatch, String)> {
    let mut legend = Vec::new();
    if band > 0.0 {
        legend.push((
            Swatch::Fill(BAND, 1.0),
            format!("noise band ±{}", with_unit(band, unit)),
        ));
    }
    if !windows.is_empty() {
        legend.push((
            Swatch::Fill(WINDOW, WINDOW_ALPHA * 1.6),
            "model fails".to_owned(),
        ));
    }
    legend
}

/// The grey band `±band`, the failure windows shaded and numbered at the top, and the zero
/// line, under a residual.
fn draw_band_and_windows(
    chart: &mut Chart<'_, '_>,
    (t0, t1, y0, y1): (f64, f64, f64, f64),
    band: f64,
    windows: &[FailureWindow],
) -> DrawResult {
    if band > 0.0 {
        chart.draw_series(std::iter::once(Rectangle::new(
            [(t0, -band), (t1, band)],
            BAND.filled(),
        )))?;
    }
    // At least 2 px wide, so a one-sample window still shows.
    let min_width = 2.0 * (t1 - t0) / COLUMNS as f64;
    let label_style = (FONT, px(11.0))
        .into_font()
        .color(&BEFORE)
        .pos(Pos::new(HPos::Center, VPos::Top));
    for (k, w) in windows.iter().enumerate() {
        let pad = ((min_width - (w.end - w.start)) / 2.0).max(0.0);
        let (a, b) = ((w.start - pad).max(t0), (w.end + pad).min(t1));
        chart.draw_series(std::iter::once(Rectangle::new(
            [(a, y0), (b, y1)],
            WINDOW.mix(WINDOW_ALPHA).filled(),
        )))?;
        if windows.len() <= 30 {
            chart.draw_series(std::iter::once(Text::new(
                format!("{}", k + 1),
                ((a + b) / 2.0, y1),
                label_style.clone(),
            )))?;
        }
    }
    chart.draw_series(LineSeries::new(
        [(t0, 0.0), (t1, 0.0)],
        MUTED.stroke_width(1),
    ))?;
    Ok(())
}

/// How far a model line may run beyond the measured range, in measured spans, before the
/// plot stops following it: a diverged model then leaves the plot instead of flattening the
/// measurement into a line.
const MAX_OVERSHOOT: f64 = 1.0;

/// The y values the plot must show for the model lines (their extremes, clamped to
/// `MAX_OVERSHOOT` measured spans beyond the measurement) and a note for each line that runs
/// off the plot.
fn model_extent(
    measured: &Decimated,
    models: &[(&str, &Decimated)],
    unit: &str,
) -> (Vec<f64>, Option<String>) {
    let Some((m_lo, m_hi)) = measured.value_range() else {
        return (Vec::new(), None);
    };
    let span = (m_hi - m_lo)
        .max(m_lo.abs().max(m_hi.abs()) * 0.1)
        .max(f64::MIN_POSITIVE);
    let (lo_limit, hi_limit) = (m_lo - MAX_OVERSHOOT * span, m_hi + MAX_OVERSHOOT * span);
    let mut extra = Vec::new();
    let mut notes = Vec::new();
    for (name, line) in models {
        let Some((lo, hi)) = line.value_range() else {
            continue;
        };
        extra.push(lo.max(lo_limit));
        extra.push(hi.min(hi_limit));
        if hi > hi_limit {
            notes.push(format!(
                "{name} runs off the top (up to {})",
                with_unit(hi, unit)
            ));
        }
        if lo < lo_limit {
            notes.push(format!(
                "{name} runs off the bottom (down to {})",
                with_unit(lo, unit)
            ));
        }
    }
    let note = (!notes.is_empty()).then(|| notes.join("; "));
    (extra, note)
}

/// A warning in the top right corner of the plot area (non-finite values, for example).
fn draw_corner_note(body: &Area<'_>, note: &str) -> DrawResult {
    let style = (FONT, px(12.0))
        .into_font()
        .color(&BEFORE)
        .pos(Pos::new(HPos::Right, VPos::Top));
    body.draw(&Text::new(
        note.to_owned(),
        ((WIDTH - RIGHT_MARGIN - 6) as i32, 12),
        style,
    ))?;
    Ok(())
}

fn draw_residual(root: &Area<'_>, p: &ResidualPlot) -> DrawResult {
    root.fill(&WHITE)?;
    let (top, body) = root.split_vertically(HEADER);
    let before = decimate::min_max(&p.t, &p.before, COLUMNS);
    let after = p
        .after
        .as_ref()
        .map(|a| decimate::min_max(&p.t, a, COLUMNS));

    let mut legend = band_legend(p.band, &p.windows, &p.unit);
    legend.push((Swatch::Line(BEFORE, 2), "residual before".to_owned()));
    if after.is_some() {
        legend.push((Swatch::Line(AFTER, 2), "residual after".to_owned()));
    }
    draw_header(&top, &p.title, &legend)?;

    let mut lines = vec![&before];
    lines.extend(after.as_ref());
    // Show the band whole, with room above it, and zero.
    let (t0, t1, y0, mut y1) = limits(&p.t, &lines, &[0.0, 1.25 * p.band, -1.25 * p.band]);
    if !p.windows.is_empty() {
        // Room above the data for the windows' numbers.
        y1 += 0.08 * (y1 - y0);
    }
    let lim = (t0, t1, y0, y1);
    let mut residual_chart = chart(
        &body,
        lim,
        &y_description("residual", &p.unit),
        Some("time (s)"),
    )?;
    draw_band_and_windows(&mut residual_chart, lim, p.band, &p.windows)?;
    draw_line(&mut residual_chart, &before, BEFORE.stroke_width(1))?;
    if let Some(a) = &after {
        draw_line(&mut residual_chart, a, AFTER.stroke_width(1))?;
    }
    let mut named = vec![("residual before", &before)];
    if let Some(a) = &after {
        named.push(("residual after", a));
    }
    if let Some(note) = gaps_note(&named) {
        draw_corner_note(&body, &note)?;
    }
    Ok(())
}

/// Height of each panel of a missing-effort figure (px).
const MISSING_PANEL: u32 = 300;
/// At most this many dots in the missing effort against its place's flow.
const MAX_SCATTER: usize = 2500;

/// The missing effort (or flow) estimated at one place ([`MissingSignal`]): over time with
/// its one-sigma band (grey) and the law the screen found (blue), and beneath it against the
/// place's flow (or effort, on a node), one dot per sample (decimated), the law's value
/// beside each: the shape of what is missing, where it acts — a Stribeck dip, a parabola, a
/// step, a ripple.
pub fn missing_svg(m: &MissingSignal, law: Option<&Law>) -> String {
    let n = m.t.len();
    if n < 2 || m.value.len() != n || m.band.len() != n {
        return notice_svg(&m.place, "cannot draw this plot: the estimate is empty");
    }
    render(HEADER + 2 * MISSING_PANEL, |root| {
        draw_missing(root, m, law)
    })
}

fn draw_missing(root: &Area<'_>, m: &MissingSignal, law: Option<&Law>) -> DrawResult {
    root.fill(&WHITE)?;
    let (top, body) = root.split_vertically(HEADER);
    let (upper, lower) = body.split_vertically(MISSING_PANEL);
    let quantity = format!("missing {}", m.quantity.word());
    let mut legend = vec![
        (Swatch::Fill(BAND, 1.0), "±1σ band".to_owned()),
        (Swatch::Line(BEFORE, 2), format!("{quantity} (estimated)")),
    ];
    if let Some(l) = law {
        let what = if l.has_formula() {
            "law found (with a formula of the symbolic search)"
        } else {
            "law found"
        };
        legend.push((Swatch::Line(AFTER, 2), what.to_owned()));
    }
    draw_header(&top, &format!("{quantity} at {}", m.place), &legend)?;
    // Over time.
    let finite = |v: f64| if v.is_finite() { v } else { f64::NAN };
    let hi: Vec<f64> = (0..m.t.len())
        .map(|k| finite(m.value[k] + m.band[k]))
        .collect();
    let lo: Vec<f64> = (0..m.t.len())
        .map(|k| finite(m.value[k] - m.band[k]))
        .collect();
    let value = decimate::min_max(&m.t, &m.value, COLUMNS);
    let (hi_d, lo_d) = (
        decimate::min_max(&m.t, &hi, COLUMNS),
        decimate::min_max(&m.t, &lo, COLUMNS),
    );
    let law_t: Vec<f64> = law.map_or(Vec::new(), |l| {
        l.fitted.iter().map(|(k, _)| m.t[*k]).collect()
    });
    let law_v: Vec<f64> = law.map_or(Vec::new(), |l| l.fitted.iter().map(|(_, v)| *v).collect());
    let law_d = (!law_t.is_empty()).then(|| decimate::min_max(&law_t, &law_v, COLUMNS));
    // The band may be wide at the start (the smoother's prior): the limits follow the value.
    let mut lines = vec![&value];
    lines.extend(law_d.as_ref());
    let lim = limits(&m.t, &lines, &[0.0]);
    let mut chart = chart(
        &upper,
        lim,
        &y_description(&quantity, &m.unit),
        Some("time (s)"),
    )?;
    draw_line(&mut chart, &hi_d, BAND.stroke_width(1))?;
    draw_line(&mut chart, &lo_d, BAND.stroke_width(1))?;
    draw_line(&mut chart, &value, BEFORE.stroke_width(1))?;
    if let Some(d) = &law_d {
        draw_line(&mut chart, d, AFTER.stroke_width(1))?;
    }
    // Against the place's own flow (or effort).
    let Some(x) = m
        .acting
        .iter()
        .find(|a| matches!(a.role, SignalRole::Flow | SignalRole::Effort))
    else {
        return Ok(());
    };
    let step = m.t.len().div_ceil(MAX_SCATTER).max(1);
    let pts: Vec<(f64, f64)> = (0..m.t.len())
        .step_by(step)
        .map(|k| (x.values[k], m.value[k]))
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .collect();
    let law_pts: Vec<(f64, f64)> = law.map_or(Vec::new(), |l| {
        let s = l.fitted.len().div_ceil(MAX_SCATTER).max(1);
        l.fitted
            .iter()
            .step_by(s)
            .map(|(k, v)| (x.values[*k], *v))
            .collect()
    });
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, lim.2, lim.3);
    for (a, _) in pts.iter().chain(&law_pts) {
        x0 = x0.min(*a);
        x1 = x1.max(*a);
    }
    if !(x0.is_finite() && x1 > x0) {
        return Ok(());
    }
    let pad = 0.03 * (x1 - x0);
    (x0, x1) = (x0 - pad, x1 + pad);
    if y1 <= y0 {
        (y0, y1) = (y0 - 1.0, y1 + 1.0);
    }
    let mut scatter = ChartBuilder::on(&lower)
        .margin_right(RIGHT_MARGIN)
        .margin_top(6)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    let (xs, ys) = (x1 - x0, y1 - y0);
    let x_fmt = move |v: &f64| format_tick(*v, xs);
    let y_fmt = move |v: &f64| format_tick(*v, ys);
    scatter
        .configure_mesh()
        .x_labels(10)
        .y_labels(7)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .x_desc(y_description(&x.label, &x.unit))
        .y_desc(y_description(&quantity, &m.unit))
        .label_style((FONT, px(12.0)).into_font().color(&MUTED))
        .axis_desc_style((FONT, px(13.0)).into_font().color(&INK))
        .max_light_lines(0)
        .bold_line_style(GRID_BOLD)
        .axis_style(MUTED)
        .draw()?;
    scatter.draw_series(
        pts.iter()
            .map(|&(a, b)| Circle::new((a, b), 1, BEFORE.mix(0.5).filled())),
    )?;
    scatter.draw_series(
        law_pts
            .iter()
            .map(|&(a, b)| Circle::new((a, b), 1, AFTER.filled())),
    )?;
    Ok(())
}

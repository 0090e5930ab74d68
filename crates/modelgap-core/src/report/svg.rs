//! The report's SVG plots, drawn with plotters' SVG backend (text as `<text>` elements, no
//! font files): measured against model, residuals with band and failure windows, and the
//! ranking bar chart.

use std::error::Error;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::decimate::{self, Decimated};
use super::format::{escape, format_tick, with_unit};
use super::{
    RankingBar, ResidualPlot, SeriesPlot, validate_ranking, validate_residual, validate_series,
};

/// Width of every plot (px); the page scales it to the column width.
const WIDTH: u32 = 960;
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

const FONT: &str = "sans-serif";
const INK: RGBColor = RGBColor(33, 37, 41);
const MUTED: RGBColor = RGBColor(100, 106, 115);
const MEASURED: RGBColor = RGBColor(64, 64, 64);
const BEFORE: RGBColor = RGBColor(214, 39, 40);
const AFTER: RGBColor = RGBColor(31, 95, 191);
const BAND: RGBColor = RGBColor(221, 221, 221);
const WINDOW: RGBColor = RGBColor(239, 68, 68);
/// Opacity of the failure-window shading.
const WINDOW_ALPHA: f64 = 0.16;
const GRID_BOLD: RGBColor = RGBColor(222, 225, 230);
const BAR: RGBColor = RGBColor(176, 183, 195);

/// plotters' SVG backend writes `font-size` as the requested size divided by 1.24 (its
/// estimate of a font's line height over its size); [`px`] undoes that.
const PLOTTERS_FONT_SCALE: f64 = 1.24;

/// The size to ask plotters for so the SVG text is `size` px.
fn px(size: f64) -> f64 {
    size * PLOTTERS_FONT_SCALE
}

type DrawResult = std::result::Result<(), Box<dyn Error>>;
type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// The measured signal (dark grey) against the model before (red) and after (blue) adding
/// the effect, over time, with axes, ticks and a legend.
///
/// Long series are decimated (minimum and maximum per pixel column); non-finite values are
/// gaps. A plot whose series lengths do not match its time axis (see
/// [`Report::validate`](super::Report::validate)) becomes a notice saying so.
pub fn series_svg(p: &SeriesPlot) -> String {
    if let Err(e) = validate_series(p) {
        return notice_svg(&p.title, &format!("cannot draw this plot: {e}"));
    }
    render(HEIGHT, |root| draw_series(root, p))
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

/// The candidate effects as horizontal bars, one row each in the given order, the value
/// (in `unit`) at the end of each bar, the highlighted (chosen) one in blue.
///
/// Bars start at zero, so negative values (an effect that makes the error worse) point left.
/// Non-finite values become a notice.
pub fn ranking_svg(bars: &[RankingBar], unit: &str) -> String {
    let title = "Candidate effects, ranked by the error they remove";
    if let Err(e) = validate_ranking(bars) {
        return notice_svg(title, &format!("cannot draw this plot: {e}"));
    }
    if bars.is_empty() {
        return notice_svg(title, "no candidate effects were ranked");
    }
    let height = RANK_TOP + RANK_ROW * bars.len() as u32 + RANK_BOTTOM;
    render(height, |root| draw_ranking(root, bars, unit, title))
}

/// Runs `draw` on a fresh SVG canvas `WIDTH × height` and returns the SVG text; a drawing
/// error (none is expected from the SVG backend) becomes a notice.
fn render(height: u32, draw: impl FnOnce(&Area<'_>) -> DrawResult) -> String {
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
pub(crate) fn notice_svg(title: &str, message: &str) -> String {
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

/// Splits off the header and builds the chart with its grid, ticks and axis names.
fn chart<'a, 'b>(
    body: &'a Area<'b>,
    (t0, t1, y0, y1): (f64, f64, f64, f64),
    y_desc: &str,
) -> std::result::Result<Chart<'a, 'b>, Box<dyn Error>> {
    let mut chart = ChartBuilder::on(body)
        .margin_right(RIGHT_MARGIN)
        .margin_top(6)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d(t0..t1, y0..y1)?;
    let t_span = t1 - t0;
    let y_span = y1 - y0;
    let x_fmt = move |v: &f64| format_tick(*v, t_span);
    let y_fmt = move |v: &f64| format_tick(*v, y_span);
    chart
        .configure_mesh()
        .x_labels(10)
        .y_labels(7)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .x_desc("time (s)")
        .y_desc(y_desc)
        .label_style((FONT, px(12.0)).into_font().color(&MUTED))
        .axis_desc_style((FONT, px(13.0)).into_font().color(&INK))
        .max_light_lines(0)
        .bold_line_style(GRID_BOLD)
        .axis_style(MUTED)
        .draw()?;
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

fn draw_series(root: &Area<'_>, p: &SeriesPlot) -> DrawResult {
    root.fill(&WHITE)?;
    let (top, body) = root.split_vertically(HEADER);
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
    let mut chart = chart(&body, lim, &y_description("value", &p.unit))?;

    draw_line(&mut chart, &measured, MEASURED.stroke_width(1))?;
    if p.t.len() <= MAX_DOTS {
        for segment in &measured.segments {
            chart.draw_series(
                segment
                    .iter()
                    .map(|&(t, v)| Circle::new((t, v), 2, MEASURED.filled())),
            )?;
        }
    }
    draw_line(&mut chart, &before, BEFORE.stroke_width(2))?;
    if let Some(a) = &after {
        draw_line(&mut chart, a, AFTER.stroke_width(2))?;
    }
    let notes: Vec<String> = gaps_note(&named).into_iter().chain(off_plot).collect();
    if !notes.is_empty() {
        draw_corner_note(&body, &notes.join("; "))?;
    }
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

    let mut legend = vec![(
        Swatch::Fill(BAND, 1.0),
        format!("noise band ±{}", with_unit(p.band, &p.unit)),
    )];
    if !p.windows.is_empty() {
        legend.push((
            Swatch::Fill(WINDOW, WINDOW_ALPHA * 1.6),
            "model fails".to_owned(),
        ));
    }
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
    let mut chart = chart(&body, lim, &y_description("residual", &p.unit))?;

    if p.band > 0.0 {
        chart.draw_series(std::iter::once(Rectangle::new(
            [(t0, -p.band), (t1, p.band)],
            BAND.filled(),
        )))?;
    }
    // At least 2 px wide, so a one-sample window still shows.
    let min_width = 2.0 * (t1 - t0) / COLUMNS as f64;
    let label_style = (FONT, px(11.0))
        .into_font()
        .color(&BEFORE)
        .pos(Pos::new(HPos::Center, VPos::Top));
    for (k, w) in p.windows.iter().enumerate() {
        let pad = ((min_width - (w.end - w.start)) / 2.0).max(0.0);
        let (a, b) = ((w.start - pad).max(t0), (w.end + pad).min(t1));
        chart.draw_series(std::iter::once(Rectangle::new(
            [(a, y0), (b, y1)],
            WINDOW.mix(WINDOW_ALPHA).filled(),
        )))?;
        if p.windows.len() <= 30 {
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
    draw_line(&mut chart, &before, BEFORE.stroke_width(1))?;
    if let Some(a) = &after {
        draw_line(&mut chart, a, AFTER.stroke_width(1))?;
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

/// Height of the ranking chart's title strip (px).
const RANK_TOP: u32 = 56;
/// Height of one ranking row: label, bar, note (px).
const RANK_ROW: u32 = 62;
/// Space below the last ranking row (px).
const RANK_BOTTOM: u32 = 16;
/// Left edge of the ranking bars and labels (px).
const RANK_LEFT: i32 = 16;
/// Room right of the longest bar for its value label (px).
const RANK_VALUE_ROOM: i32 = 150;

fn draw_ranking(root: &Area<'_>, bars: &[RankingBar], unit: &str, title: &str) -> DrawResult {
    root.fill(&WHITE)?;
    let subtitle = if unit.is_empty() {
        "bar length: error removed".to_owned()
    } else {
        format!("bar length: error removed ({unit})")
    };
    let title_style = (FONT, px(17.0), FontStyle::Bold)
        .into_font()
        .color(&INK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    root.draw(&Text::new(title.to_owned(), (RANK_LEFT, 18), title_style))?;
    let sub_style = (FONT, px(13.0))
        .into_font()
        .color(&MUTED)
        .pos(Pos::new(HPos::Left, VPos::Center));
    root.draw(&Text::new(subtitle, (RANK_LEFT, 42), sub_style))?;

    let lo = bars.iter().map(|b| b.value).fold(0.0, f64::min);
    let hi = bars.iter().map(|b| b.value).fold(0.0, f64::max);
    let left = RANK_LEFT + if lo < 0.0 { RANK_VALUE_ROOM } else { 0 };
    let right = WIDTH as i32 - RANK_VALUE_ROOM;
    let span = if hi > lo { hi - lo } else { 1.0 };
    let x_of = |v: f64| left + ((v - lo) / span * f64::from(right - left)).round() as i32;
    let zero = x_of(0.0);

    let label_style = |chosen: bool| {
        let font = if chosen {
            (FONT, px(14.0), FontStyle::Bold).into_font()
        } else {
            (FONT, px(14.0)).into_font()
        };
        font.color(&INK).pos(Pos::new(HPos::Left, VPos::Center))
    };
    let note_style = (FONT, px(12.0))
        .into_font()
        .color(&MUTED)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let value_style = |chosen: bool, h: HPos| {
        let font = if chosen {
            (FONT, px(13.0), FontStyle::Bold).into_font()
        } else {
            (FONT, px(13.0)).into_font()
        };
        font.color(&INK).pos(Pos::new(h, VPos::Center))
    };
    for (i, bar) in bars.iter().enumerate() {
        let y = (RANK_TOP + RANK_ROW * i as u32) as i32;
        if bar.highlight {
            root.draw(&Rectangle::new(
                [(4, y - 2), (WIDTH as i32 - 4, y + RANK_ROW as i32 - 6)],
                AFTER.mix(0.07).filled(),
            ))?;
        }
        let label = if bar.highlight {
            format!("{}. {}  (chosen)", i + 1, bar.label)
        } else {
            format!("{}. {}", i + 1, bar.label)
        };
        root.draw(&Text::new(
            label,
            (RANK_LEFT, y + 10),
            label_style(bar.highlight),
        ))?;
        let x = x_of(bar.value);
        let (a, b) = if x >= zero {
            (zero, x.max(zero + 1))
        } else {
            (x, zero)
        };
        let color = if bar.highlight { AFTER } else { BAR };
        root.draw(&Rectangle::new([(a, y + 20), (b, y + 36)], color.filled()))?;
        if lo < 0.0 {
            // The zero line, only beside the bar, so it never crosses a label.
            root.draw(&PathElement::new(
                vec![(zero, y + 17), (zero, y + 39)],
                MUTED.stroke_width(1),
            ))?;
        }
        let value = with_unit(bar.value, short_unit(unit));
        if bar.value >= 0.0 {
            root.draw(&Text::new(
                value,
                (b + 8, y + 28),
                value_style(bar.highlight, HPos::Left),
            ))?;
        } else {
            root.draw(&Text::new(
                value,
                (a - 8, y + 28),
                value_style(bar.highlight, HPos::Right),
            ))?;
        }
        if !bar.note.is_empty() {
            root.draw(&Text::new(
                bar.note.clone(),
                (RANK_LEFT, y + 48),
                note_style.clone(),
            ))?;
        }
    }
    Ok(())
}

/// The unit written after each bar's value: short units only ("%", "dB"); a long one is
/// said once in the subtitle.
fn short_unit(unit: &str) -> &str {
    if unit.chars().count() <= 4 { unit } else { "" }
}

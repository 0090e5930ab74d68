//! The ranking of candidate effects as a horizontal bar chart, drawn with plotters' SVG
//! backend like the time plots in [`svg`](super::svg).

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::format::with_unit;
use super::svg::{AFTER, Area, BAR, DrawResult, FONT, INK, MUTED, WIDTH, notice_svg, px, render};
use super::{RankingBar, validate_ranking};

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
    let rows: u32 = bars.iter().map(row_height).sum();
    let height = RANK_TOP + rows + RANK_BOTTOM;
    render(height, |root| draw_ranking(root, bars, unit, title))
}

/// Height of the ranking chart's title strip (px).
const RANK_TOP: u32 = 56;
/// Height of one ranking row: label, bar, one line of note (px).
const RANK_ROW: u32 = 62;
/// Height of each further line of a long note (px).
const NOTE_LINE: u32 = 15;
/// The most characters of a note on one line: 12 px sans-serif averages under 6 px a
/// character (5.3 px measured in Chromium on the demo's notes), so 150 fit the 928 px between
/// the margins.
const NOTE_CHARS: usize = 150;

/// A bar's note broken into lines that fit the chart's width (SVG text does not wrap).
fn note_lines(bar: &RankingBar) -> Vec<String> {
    crate::story::wrap_text(&bar.note, NOTE_CHARS)
        .lines()
        .map(str::to_owned)
        .collect()
}

/// The height of a bar's row: label, bar and every line of its note.
fn row_height(bar: &RankingBar) -> u32 {
    RANK_ROW + NOTE_LINE * (note_lines(bar).len().max(1) as u32 - 1)
}
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
    let mut next_y = RANK_TOP as i32;
    for (i, bar) in bars.iter().enumerate() {
        let y = next_y;
        let row = row_height(bar) as i32;
        next_y += row;
        if bar.highlight {
            root.draw(&Rectangle::new(
                [(4, y - 2), (WIDTH as i32 - 4, y + row - 6)],
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
        for (k, line) in note_lines(bar).into_iter().enumerate() {
            root.draw(&Text::new(
                line,
                (RANK_LEFT, y + 48 + (NOTE_LINE as i32) * k as i32),
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

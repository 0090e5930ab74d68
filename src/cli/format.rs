//! Number and matrix formatting for the command line's text output.

use std::fmt::Write as _;

use modelgap::math::DMatrix;

/// Significant digits of numbers printed for people.
const SIGNIFICANT: i32 = 6;

/// A number with [`SIGNIFICANT`] significant digits, like C's `%g`: fixed notation from
/// 1e-4 to 1e6, exponent notation outside, trailing zeros removed (`-200`, `0.0478`,
/// `1.5e-7`).
pub fn num(v: f64) -> String {
    if v == 0.0 {
        return "0".to_owned();
    }
    if !v.is_finite() {
        return v.to_string();
    }
    // Round first, so that 999999.7 is seen as 1e6 when choosing the notation.
    let rounded: f64 = format!("{v:.*e}", (SIGNIFICANT - 1) as usize)
        .parse()
        .unwrap_or(v);
    let exp = rounded.abs().log10().floor() as i32;
    if (-4..SIGNIFICANT).contains(&exp) {
        let decimals = (SIGNIFICANT - 1 - exp).max(0) as usize;
        trim_zeros(&format!("{rounded:.decimals$}"))
    } else {
        let text = format!("{rounded:.*e}", (SIGNIFICANT - 1) as usize);
        match text.split_once('e') {
            Some((mantissa, exponent)) => format!("{}e{exponent}", trim_zeros(mantissa)),
            None => text,
        }
    }
}

/// A unit to print after a value: as given, but nothing for `1` (dimensionless, such as a
/// duty cycle).
pub fn unit(text: &str) -> &str {
    if text == "1" { "" } else { text }
}

/// Removes trailing zeros after a decimal point, and the point if nothing follows it.
fn trim_zeros(text: &str) -> String {
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        text.to_owned()
    }
}

/// How a column of [`aligned`] is aligned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    /// Text: padded on the right.
    Left,
    /// Numbers: padded on the left.
    Right,
}

/// Rows of cells as an aligned table: the first column left-aligned, the others right-aligned,
/// each line indented by `indent` spaces.
pub fn table(rows: &[Vec<String>], indent: usize) -> String {
    aligned(rows, indent, &[Align::Left], Align::Right)
}

/// Rows of cells as an aligned table, column `j` aligned as `align[j]` (columns past the
/// end of `align` as `rest`), two spaces between columns, each line indented by `indent`.
pub fn aligned(rows: &[Vec<String>], indent: usize, align: &[Align], rest: Align) -> String {
    let n_cols = rows.iter().map(Vec::len).max().unwrap_or(0);
    let widths: Vec<usize> = (0..n_cols)
        .map(|j| {
            rows.iter()
                .filter_map(|r| r.get(j))
                .map(|c| c.chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut out = String::new();
    for row in rows {
        let mut line = " ".repeat(indent);
        for (j, cell) in row.iter().enumerate() {
            if j > 0 {
                line.push_str("  ");
            }
            let w = widths[j];
            match align.get(j).copied().unwrap_or(rest) {
                Align::Left => {
                    let _ = write!(line, "{cell:<w$}");
                }
                Align::Right => {
                    let _ = write!(line, "{cell:>w$}");
                }
            }
        }
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

/// A matrix with its row and column names, titled `name`, as an aligned table.
pub fn matrix(name: &str, m: &DMatrix, rows: &[String], cols: &[String]) -> String {
    let mut cells = vec![
        std::iter::once(name.to_owned())
            .chain(cols.iter().cloned())
            .collect::<Vec<_>>(),
    ];
    for (i, row) in rows.iter().enumerate().take(m.nrows()) {
        let mut line = vec![row.clone()];
        line.extend((0..m.ncols()).map(|j| num(m[(i, j)])));
        cells.push(line);
    }
    table(&cells, 2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_print_like_percent_g() {
        assert_eq!(num(0.0), "0");
        assert_eq!(num(-200.0), "-200");
        assert_eq!(num(0.047_809_6), "0.0478096");
        assert_eq!(num(239.043_824_7), "239.044");
        assert_eq!(num(1.5e-7), "1.5e-7");
        assert_eq!(num(2.0e7), "2e7");
        assert_eq!(num(999_999.7), "1e6");
        assert_eq!(num(f64::INFINITY), "inf");
    }

    #[test]
    fn table_aligns_columns() {
        let rows = vec![
            vec!["A".to_owned(), "p3".to_owned()],
            vec!["dp3".to_owned(), "-200".to_owned()],
        ];
        assert_eq!(table(&rows, 2), "  A      p3\n  dp3  -200\n");
    }
}

//! Text for the report: HTML/SVG escaping and number formatting.

/// Escapes plain text for HTML and SVG text and attribute values (`& < > " '`).
///
/// # Example
///
/// ```
/// # use modelgap_core::report::escape;
/// assert_eq!(escape("R < 2 & \"L\""), "R &lt; 2 &amp; &quot;L&quot;");
/// ```
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// Formats a number for people: four significant digits, trailing zeros dropped, plain
/// decimals from 0.001 to below 100 000 and `1.23e-5`-style exponents outside; `n/a` for
/// NaN and infinities, so no `NaN` or `inf` text reaches a page.
///
/// # Example
///
/// ```
/// # use modelgap_core::report::format_number;
/// assert_eq!(format_number(0.123456), "0.1235");
/// assert_eq!(format_number(2.0), "2");
/// assert_eq!(format_number(-1234.56), "-1235");
/// assert_eq!(format_number(1.5e-5), "1.5e-5");
/// assert_eq!(format_number(f64::NAN), "n/a");
/// ```
pub fn format_number(v: f64) -> String {
    format_significant(v, 4)
}

/// Formats `v` with `digits` significant digits (see [`format_number`]).
pub(crate) fn format_significant(v: f64, digits: i32) -> String {
    if !v.is_finite() {
        return "n/a".to_owned();
    }
    if v == 0.0 {
        return "0".to_owned();
    }
    let magnitude = v.abs().log10().floor() as i32;
    if (-3..5).contains(&magnitude) {
        let decimals = (digits - 1 - magnitude).max(0) as usize;
        let text = trim_zeros(&format!("{v:.decimals$}"));
        // Rounding may carry into the next power of ten (99 999.9 → "100000"); still fine.
        if text == "-0" { "0".to_owned() } else { text }
    } else {
        let decimals = (digits - 1).max(0) as usize;
        let text = format!("{v:.decimals$e}");
        match text.split_once('e') {
            Some((mantissa, exponent)) => format!("{}e{exponent}", trim_zeros(mantissa)),
            None => text,
        }
    }
}

/// Formats an axis tick at `v` on an axis spanning `span`: rounds away floating-point noise
/// (`0.30000000000000004`, `1e-17` for zero) before formatting.
pub(crate) fn format_tick(v: f64, span: f64) -> String {
    let span = span.abs();
    if span > 0.0 && v.abs() < span * 1e-9 {
        return "0".to_owned();
    }
    // Enough digits to tell ticks a thousandth of the span apart.
    let digits = if span > 0.0 && v != 0.0 {
        ((v.abs().log10() - (span / 1000.0).log10()).ceil() as i32).clamp(1, 6)
    } else {
        4
    };
    format_significant(v, digits)
}

/// A value for an error message: the number in full, or "not a number", "+∞", "−∞", so that
/// messages shown on a page carry no `NaN` or `inf` text.
pub(crate) fn describe(v: f64) -> String {
    if v.is_nan() {
        "not a number".to_owned()
    } else if v == f64::INFINITY {
        "+∞".to_owned()
    } else if v == f64::NEG_INFINITY {
        "−∞".to_owned()
    } else {
        v.to_string()
    }
}

/// A number with its unit ("0.25 A"), or the number alone when the unit is empty.
pub(crate) fn with_unit(v: f64, unit: &str) -> String {
    if unit.is_empty() {
        format_number(v)
    } else {
        format!("{} {unit}", format_number(v))
    }
}

fn trim_zeros(text: &str) -> String {
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        text.to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_have_four_significant_digits() {
        assert_eq!(format_number(3.45678), "3.457");
        assert_eq!(format_number(0.001234567), "0.001235");
        assert_eq!(format_number(12345.6), "12346");
        assert_eq!(format_number(123456.0), "1.235e5");
        assert_eq!(format_number(-2.5e-7), "-2.5e-7");
        assert_eq!(format_number(1e6), "1e6");
        assert_eq!(format_number(-0.00001), "-1e-5");
        assert_eq!(format_number(f64::INFINITY), "n/a");
    }

    #[test]
    fn ticks_lose_floating_point_noise() {
        assert_eq!(format_tick(0.1 + 0.2, 1.0), "0.3");
        assert_eq!(format_tick(1e-17, 1.0), "0");
        assert_eq!(format_tick(1000.5, 2.0), "1000.5");
        assert_eq!(format_tick(0.25, 1.0), "0.25");
    }

    #[test]
    fn escape_covers_markup_and_quotes() {
        assert_eq!(escape("<b>'x'</b>"), "&lt;b&gt;&#39;x&#39;&lt;/b&gt;");
    }
}

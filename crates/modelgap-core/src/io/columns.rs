//! What the readers of table files (CSV, Parquet) share about their columns: the time column
//! found by name, a unit in a column's name, the time units converted to seconds, a row-index
//! column recognised, the signal names checked and values held within range.

use crate::error::{CoreError, Location, Result};
use crate::recording::{MAX_MAGNITUDE, TIME_NAME, check_name};

/// A column name split into a name and a unit: `u [V]`, `u[V]` and `u (V)` give `u` and `V`.
pub(crate) fn split_unit(cell: &str) -> (&str, Option<&str>) {
    for (open, close, needs_space) in [('[', ']', false), ('(', ')', true)] {
        if let Some(body) = cell.strip_suffix(close)
            && let Some(at) = body.rfind(open)
        {
            let before = &body[..at];
            let name = before.trim_end();
            let unit = body[at + 1..].trim();
            let spaced = before.len() > name.len();
            if !name.is_empty()
                && !unit.is_empty()
                && !unit.contains(open)
                && (spaced || !needs_space)
            {
                return (name, Some(unit));
            }
        }
    }
    (cell, None)
}

/// How many of a time unit make a second, for the units the readers convert.
pub(crate) fn per_second(unit: &str) -> Option<f64> {
    match unit {
        "s" | "sec" => Some(1.0),
        "ms" => Some(1e3),
        "us" | "\u{b5}s" | "\u{3bc}s" => Some(1e6),
        "ns" => Some(1e9),
        _ => None,
    }
}

/// True for a column name that names a row index: empty, `index` or `Unnamed: 0` (pandas'
/// name for the unnamed first column of a CSV file it read).
pub(crate) fn is_index_name(cell: &str) -> bool {
    cell.is_empty() || cell.eq_ignore_ascii_case("index") || cell == "Unnamed: 0"
}

/// True when `value` continues a count of rows whose last number was `last`: a whole number,
/// one more than `last` (any whole number to start).
pub(crate) fn next_row_number(last: Option<f64>, value: f64) -> bool {
    // Whole numbers beyond 2^53 no longer step by one in f64.
    const LARGEST: f64 = 9_007_199_254_740_992.0;
    value.fract() == 0.0 && value.abs() < LARGEST && last.is_none_or(|last| value == last + 1.0)
}

/// The note for a first column of row numbers left out: `column` as written, `None` when it
/// is unnamed.
pub(crate) fn row_index_note(column: Option<&str>, first: f64, last: f64) -> String {
    let which = match column {
        Some(name) => format!(" `{name}`"),
        None => " (unnamed)".to_owned(),
    };
    format!(
        "the first column{which} holds the row numbers {first} to {last}: read as a row index \
         and left out"
    )
}

/// The time column among `columns` (names as written): the asked one (as written or without
/// its unit), else the column `t`, else the one column named `t` with a unit (`t [s]`), else
/// the one column named `t` or `time` (any case, any unit; of several, a unit that is no time
/// unit, as in `T [degC]`, rules one out). `line` is the CSV header's, `None` for a Parquet
/// file.
pub(crate) fn find_time(
    columns: &[&str],
    line: Option<usize>,
    asked: Option<&str>,
) -> Result<usize> {
    let matching: Vec<usize> = match asked {
        Some(name) => (0..columns.len())
            .filter(|&i| columns[i] == name || split_unit(columns[i]).0 == name)
            .collect(),
        None => {
            if let Some(i) = columns.iter().position(|c| *c == TIME_NAME) {
                return Ok(i);
            }
            let named_t: Vec<usize> = (0..columns.len())
                .filter(|&i| split_unit(columns[i]).0 == TIME_NAME)
                .collect();
            if let [i] = named_t[..] {
                return Ok(i);
            }
            let mut like: Vec<usize> = (0..columns.len())
                .filter(|&i| is_time_name(columns[i]))
                .collect();
            let timed = |i: &usize| split_unit(columns[*i]).1.is_none_or(is_time_unit);
            if like.len() > 1 && like.iter().filter(|i| timed(i)).count() == 1 {
                like.retain(timed);
            }
            like
        }
    };
    match matching[..] {
        [i] => Ok(i),
        [] => Err(CoreError::MissingTimeColumn {
            line,
            asked: asked.map(str::to_owned),
            columns: columns.iter().map(|c| (*c).to_owned()).collect(),
            path: None,
        }),
        _ => Err(CoreError::AmbiguousTimeColumn {
            line,
            columns: matching.iter().map(|&i| columns[i].to_owned()).collect(),
            path: None,
        }),
    }
}

/// True for a unit of time, converted ([`per_second`]) or not (`min`, `h`, `d`).
fn is_time_unit(unit: &str) -> bool {
    per_second(unit).is_some() || matches!(unit, "min" | "h" | "hr" | "d" | "day")
}

/// True for a column named `t` or `time` in any case, with or without a unit.
fn is_time_name(column: &str) -> bool {
    let name = split_unit(column).0;
    name.eq_ignore_ascii_case(TIME_NAME) || name.eq_ignore_ascii_case("time")
}

/// Checks the names of the signals a table gives, in column order: each a valid name
/// ([`check_name`]) and none repeated. `at` is where the names are (a CSV header's line).
pub(crate) fn check_signal_names<'a>(
    names: impl IntoIterator<Item = &'a str>,
    at: Option<Location>,
) -> Result<()> {
    let mut seen: Vec<&str> = Vec::new();
    for name in names {
        check_name(name).map_err(|e| match e {
            CoreError::InvalidSignalName { name, reason, .. } => CoreError::InvalidSignalName {
                name,
                reason,
                at,
                path: None,
            },
            other => other,
        })?;
        if seen.contains(&name) {
            return Err(CoreError::DuplicateSignal {
                name: name.to_owned(),
                at,
                path: None,
            });
        }
        seen.push(name);
    }
    Ok(())
}

/// Refuses a value beyond [`MAX_MAGNITUDE`]; `t` is the sample's time.
pub(crate) fn check_magnitude(value: f64, t: f64, column: &str, at: Location) -> Result<()> {
    if value.abs() > MAX_MAGNITUDE {
        return Err(CoreError::OutOfRange {
            at,
            t,
            column: column.to_owned(),
            value,
            limit: MAX_MAGNITUDE,
            path: None,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_split_from_names_in_brackets_or_spaced_parentheses() {
        assert_eq!(split_unit("u [V]"), ("u", Some("V")));
        assert_eq!(split_unit("u[V]"), ("u", Some("V")));
        assert_eq!(split_unit("omega (rad/s)"), ("omega", Some("rad/s")));
        assert_eq!(split_unit("f(x)"), ("f(x)", None));
        assert_eq!(split_unit("[V]"), ("[V]", None));
    }

    #[test]
    fn time_is_t_first_then_the_one_time_like_column() {
        assert_eq!(find_time(&["x", "Time [ms]", "t"], None, None).unwrap(), 2);
        assert_eq!(find_time(&["x", "Time [ms]"], None, None).unwrap(), 1);
        assert_eq!(find_time(&["x", "when"], None, Some("when")).unwrap(), 1);
        // A temperature `T` beside the time: the one named `t`, or the one with a time unit.
        assert_eq!(find_time(&["t [s]", "T [degC]"], None, None).unwrap(), 0);
        assert_eq!(find_time(&["Time [s]", "T [K]"], None, None).unwrap(), 0);
        assert!(find_time(&["Time [s]", "T [ms]"], None, None).is_err());
        let e = find_time(&["T", "time"], None, None).unwrap_err();
        assert_eq!(
            e.to_string(),
            "columns `T`, `time` could each be time: choose one with the time option (`--time COL`)"
        );
        let e = find_time(&["x"], None, None).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("missing column `t`: the file has no column")
        );
    }

    #[test]
    fn row_numbers_step_by_one_from_any_whole_number() {
        assert!(next_row_number(None, 1000.0));
        assert!(next_row_number(Some(1000.0), 1001.0));
        assert!(!next_row_number(Some(1000.0), 1002.0));
        assert!(!next_row_number(None, 0.5));
    }

    #[test]
    fn signal_names_are_checked_in_order() {
        assert!(check_signal_names(["a", "b"], None).is_ok());
        let e = check_signal_names(["a", "b", "a"], Some(Location::Line(3))).unwrap_err();
        assert!(matches!(
            e,
            CoreError::DuplicateSignal {
                at: Some(Location::Line(3)),
                ..
            }
        ));
        let e = check_signal_names(["a", ""], None).unwrap_err();
        assert!(matches!(e, CoreError::InvalidSignalName { .. }));
    }
}

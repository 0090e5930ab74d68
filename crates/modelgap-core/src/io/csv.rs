//! Signals as CSV text: a header `t,<name>,<name>,…`, then one row per sample.
//!
//! Reading: lines whose first non-blank character is `#` are comments and blank lines are
//! skipped (both still count for line numbers); whitespace around cells is trimmed; a
//! trailing `\r` (Windows line ends) and a leading UTF-8 byte-order mark are ignored. Cells
//! are not quoted, so names cannot contain commas. Time must be finite and strictly
//! increasing, values finite; errors name the line (from 1) and the column.
//!
//! Writing uses Rust's shortest round-trip `Display` of `f64` (never exponent notation), so
//! write → read gives back an identical recording, bit for bit.

use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Read, Write};
use std::path::Path;

use crate::error::{CoreError, Location, Result};
use crate::recording::{Recording, Signal, TIME_NAME, check_name};

/// Reads a recording from CSV text.
///
/// # Errors
///
/// [`CoreError::MissingHeader`], [`CoreError::MissingTimeColumn`],
/// [`CoreError::InvalidSignalName`] or [`CoreError::DuplicateSignal`] for a bad header;
/// [`CoreError::RowLength`], [`CoreError::NotANumber`], [`CoreError::NonFinite`] or
/// [`CoreError::NonIncreasingTime`] for a bad row (all with the line number);
/// [`CoreError::EmptyRecording`] when there are no rows; [`CoreError::NotUtf8`] and
/// [`CoreError::Io`] when the text cannot be read.
///
/// # Example
///
/// ```
/// # use modelgap_core::io::csv;
/// let text = "# motor run 1\nt, i, omega\n0.0, 1.0, 0.0\n0.1, 0.9, 12.5\n";
/// let rec = csv::read_signals(text.as_bytes())?;
/// assert_eq!(rec.names(), vec!["i", "omega"]);
/// assert_eq!(rec.values("omega")?, &[0.0, 12.5]);
/// # Ok::<(), modelgap_core::CoreError>(())
/// ```
pub fn read_signals(reader: impl Read) -> Result<Recording> {
    let mut reader = BufReader::new(reader);
    let mut buf = Vec::new();
    let mut line_no = 0usize;
    let mut header: Option<Vec<String>> = None;
    let mut t: Vec<f64> = Vec::new();
    let mut columns: Vec<Vec<f64>> = Vec::new();

    loop {
        buf.clear();
        let n = reader
            .read_until(b'\n', &mut buf)
            .map_err(|e| CoreError::io(e, None))?;
        if n == 0 {
            break;
        }
        line_no += 1;
        let line = std::str::from_utf8(&buf).map_err(|_| CoreError::NotUtf8 {
            line: line_no,
            path: None,
        })?;
        let line = if line_no == 1 {
            line.strip_prefix('\u{feff}').unwrap_or(line)
        } else {
            line
        };
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        match &header {
            None => {
                let names = parse_header(line, line_no)?;
                columns = vec![Vec::new(); names.len()];
                header = Some(names);
            }
            Some(names) => parse_row(line, line_no, names, &mut t, &mut columns)?,
        }
    }

    let Some(names) = header else {
        return Err(CoreError::MissingHeader { path: None });
    };
    if t.is_empty() {
        return Err(CoreError::EmptyRecording { path: None });
    }
    let signals = names
        .into_iter()
        .zip(columns)
        .map(|(name, values)| Signal::new(name, values))
        .collect();
    Recording::new(t, signals)
}

/// Reads a recording from a CSV file; like [`read_signals`], with the path in every error.
///
/// # Errors
///
/// As [`read_signals`], plus [`CoreError::Io`] when the file cannot be opened.
pub fn read_signals_path(path: &Path) -> Result<Recording> {
    let file = File::open(path).map_err(|e| CoreError::io(e, Some(path)))?;
    read_signals(file).map_err(|e| e.with_path(path))
}

/// Writes a recording as CSV text: the header `t,<names>`, then one row per sample.
///
/// # Errors
///
/// [`CoreError::InvalidSignalName`] for a name that CSV cannot hold (a comma, a line break,
/// or whitespace at either end, which reading would trim); [`CoreError::Io`] when writing fails.
pub fn write_signals(recording: &Recording, writer: impl Write) -> Result<()> {
    for name in recording.names() {
        check_csv_name(name)?;
    }
    let io = |e| CoreError::io(e, None);
    let mut w = BufWriter::new(writer);
    write!(w, "{TIME_NAME}").map_err(io)?;
    for name in recording.names() {
        write!(w, ",{name}").map_err(io)?;
    }
    writeln!(w).map_err(io)?;
    let signals = recording.signals();
    for (i, t) in recording.t().iter().enumerate() {
        // `{}` on f64 prints the shortest decimal that parses back to the same bits.
        write!(w, "{t}").map_err(io)?;
        for s in signals {
            write!(w, ",{}", s.values[i]).map_err(io)?;
        }
        writeln!(w).map_err(io)?;
    }
    w.flush().map_err(io)
}

/// Writes a recording to a CSV file (created or truncated); like [`write_signals`], with the
/// path in every error.
///
/// # Errors
///
/// As [`write_signals`], plus [`CoreError::Io`] when the file cannot be created.
pub fn write_signals_path(recording: &Recording, path: &Path) -> Result<()> {
    let file = super::atomic::AtomicFile::create(path)?;
    let mut w = BufWriter::new(file);
    write_signals(recording, &mut w).map_err(|e| e.with_path(path))?;
    super::atomic::commit_buffered(w)
}

fn parse_header(line: &str, line_no: usize) -> Result<Vec<String>> {
    let mut cells = line.split(',').map(str::trim);
    let first = cells.next().unwrap_or_default();
    if first != TIME_NAME {
        return Err(CoreError::MissingTimeColumn {
            line: line_no,
            found: first.to_owned(),
            path: None,
        });
    }
    let mut names: Vec<String> = Vec::new();
    for cell in cells {
        let at = Some(Location::Line(line_no));
        check_name(cell).map_err(|e| match e {
            CoreError::InvalidSignalName { name, reason, .. } => CoreError::InvalidSignalName {
                name,
                reason,
                at,
                path: None,
            },
            other => other,
        })?;
        if names.iter().any(|n| n == cell) {
            return Err(CoreError::DuplicateSignal {
                name: cell.to_owned(),
                at,
                path: None,
            });
        }
        names.push(cell.to_owned());
    }
    Ok(names)
}

fn parse_row(
    line: &str,
    line_no: usize,
    names: &[String],
    t: &mut Vec<f64>,
    columns: &mut [Vec<f64>],
) -> Result<()> {
    let found = line.split(',').count();
    if found != names.len() + 1 {
        return Err(CoreError::RowLength {
            line: line_no,
            expected: names.len() + 1,
            found,
            path: None,
        });
    }
    for (col, cell) in line.split(',').map(str::trim).enumerate() {
        let column = if col == 0 {
            TIME_NAME
        } else {
            names[col - 1].as_str()
        };
        let value: f64 = cell.parse().map_err(|_| CoreError::NotANumber {
            line: line_no,
            column: column.to_owned(),
            text: cell.to_owned(),
            path: None,
        })?;
        if !value.is_finite() {
            return Err(CoreError::NonFinite {
                at: Location::Line(line_no),
                column: column.to_owned(),
                value,
                path: None,
            });
        }
        if value.abs() > crate::recording::MAX_MAGNITUDE {
            return Err(CoreError::OutOfRange {
                at: Location::Line(line_no),
                t: if col == 0 {
                    value
                } else {
                    t.last().copied().unwrap_or(f64::NAN)
                },
                column: column.to_owned(),
                value,
                limit: crate::recording::MAX_MAGNITUDE,
                path: None,
            });
        }
        if col == 0 {
            if let Some(&t_prev) = t.last()
                && value <= t_prev
            {
                return Err(CoreError::NonIncreasingTime {
                    at: Location::Line(line_no),
                    t_prev,
                    t: value,
                    path: None,
                });
            }
            t.push(value);
        } else {
            columns[col - 1].push(value);
        }
    }
    Ok(())
}

/// Checks that a name survives a CSV round trip.
fn check_csv_name(name: &str) -> Result<()> {
    let reason = if name.contains([',', '\n', '\r']) {
        "a csv column name cannot contain a comma or a line break"
    } else if name.trim() != name {
        "a csv column name cannot start or end with whitespace"
    } else {
        return Ok(());
    };
    Err(CoreError::InvalidSignalName {
        name: name.to_owned(),
        reason,
        at: None,
        path: None,
    })
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;

    fn read(text: &str) -> Result<Recording> {
        read_signals(text.as_bytes())
    }

    fn bits(rec: &Recording) -> Vec<u64> {
        rec.t()
            .iter()
            .chain(rec.signals().iter().flat_map(|s| s.values.iter()))
            .map(|v| v.to_bits())
            .collect()
    }

    #[test]
    fn reads_header_rows_comments_blank_lines_and_crlf() {
        let text =
            "\u{feff}# a comment\r\n\r\n t , i ,omega\r\n0,1,2\r\n  # another\r\n0.5, 3 ,4\r\n";
        let rec = read(text).unwrap();
        assert_eq!(rec.t(), &[0.0, 0.5]);
        assert_eq!(rec.names(), vec!["i", "omega"]);
        assert_eq!(rec.values("i").unwrap(), &[1.0, 3.0]);
        assert_eq!(rec.values("omega").unwrap(), &[2.0, 4.0]);
    }

    #[test]
    fn reads_last_line_without_newline() {
        let rec = read("t,x\n0,1\n1,2").unwrap();
        assert_eq!(rec.values("x").unwrap(), &[1.0, 2.0]);
    }

    #[test]
    fn non_increasing_time_names_the_file_line_counting_comments() {
        let text = "# c\nt,x\n0.0,1\n\n# c\n0.6,2\n0.5,3\n";
        let e = read(text).unwrap_err();
        assert_eq!(
            e.to_string(),
            "time is not strictly increasing at line 7: 0.5 s after 0.6 s"
        );
    }

    #[test]
    fn non_numeric_cell_names_line_column_and_text() {
        let e = read("t,i,omega\n0,1,2\n1,2,fast\n").unwrap_err();
        assert!(matches!(
            e,
            CoreError::NotANumber { line: 3, ref column, ref text, .. }
                if column == "omega" && text == "fast"
        ));
    }

    #[test]
    fn nan_and_infinite_cells_are_rejected_with_line_and_column() {
        for cell in ["NaN", "inf", "-infinity"] {
            let e = read(&format!("t,i\n0,1\n1,{cell}\n")).unwrap_err();
            assert!(
                matches!(e, CoreError::NonFinite { at: Location::Line(3), ref column, .. } if column == "i"),
                "{cell}: {e}"
            );
        }
        let e = read("t,i\nnan,1\n").unwrap_err();
        assert!(matches!(e, CoreError::NonFinite { ref column, .. } if column == "t"));
    }

    #[test]
    fn header_must_start_with_t() {
        let e = read("# c\ntime,i\n0,1\n").unwrap_err();
        assert!(matches!(
            e,
            CoreError::MissingTimeColumn { line: 2, ref found, .. } if found == "time"
        ));
    }

    #[test]
    fn duplicate_and_reserved_columns_are_rejected_with_line() {
        let e = read("t,i,i\n0,1,2\n").unwrap_err();
        assert!(matches!(
            e,
            CoreError::DuplicateSignal { at: Some(Location::Line(1)), ref name, .. } if name == "i"
        ));
        let e = read("t,i,t\n0,1,2\n").unwrap_err();
        assert!(matches!(e, CoreError::InvalidSignalName { .. }));
        let e = read("t,i,\n0,1,2\n").unwrap_err();
        assert!(matches!(e, CoreError::InvalidSignalName { ref name, .. } if name.is_empty()));
    }

    #[test]
    fn wrong_row_length_names_line_and_counts() {
        let e = read("t,i,omega\n0,1,2\n1,2\n").unwrap_err();
        assert!(matches!(
            e,
            CoreError::RowLength {
                line: 3,
                expected: 3,
                found: 2,
                ..
            }
        ));
    }

    #[test]
    fn empty_inputs_are_typed_errors() {
        assert!(matches!(read(""), Err(CoreError::MissingHeader { .. })));
        assert!(matches!(
            read("# only\n\n"),
            Err(CoreError::MissingHeader { .. })
        ));
        assert!(matches!(
            read("t,i\n# no rows\n"),
            Err(CoreError::EmptyRecording { .. })
        ));
    }

    #[test]
    fn invalid_utf8_names_the_line() {
        let e = read_signals(&b"t,i\n0,\xff\n"[..]).unwrap_err();
        assert!(matches!(e, CoreError::NotUtf8 { line: 2, .. }));
    }

    #[test]
    fn time_only_recording_reads() {
        let rec = read("t\n0\n1\n").unwrap();
        assert_eq!(rec.t(), &[0.0, 1.0]);
        assert!(rec.signals().is_empty());
    }

    #[test]
    fn write_then_read_is_identical_bit_for_bit() {
        let n = 200;
        let t: Vec<f64> = (0..n).map(|k| -1.0 + f64::from(k) * 0.1 / 3.0).collect();
        let a: Vec<f64> = (0..n)
            .map(|k| (f64::from(k) * 0.7).sin() * 1e-7 + 1.0 / 3.0)
            .collect();
        let mut b: Vec<f64> = (0..n).map(|k| f64::from(k).exp() * 1e-300).collect();
        b[0] = -0.0;
        b[1] = crate::recording::MAX_MAGNITUDE;
        b[2] = f64::MIN_POSITIVE;
        b[3] = 5e-324;
        let rec = Recording::new(t, vec![Signal::new("a", a), Signal::new("b", b)]).unwrap();
        let mut out = Vec::new();
        write_signals(&rec, &mut out).unwrap();
        let text = String::from_utf8(out.clone()).unwrap();
        assert!(text.starts_with("t,a,b\n"));
        assert!(!text.contains('e'), "no exponent notation expected");
        let back = read_signals(out.as_slice()).unwrap();
        assert_eq!(back, rec);
        assert_eq!(bits(&back), bits(&rec));
    }

    #[test]
    fn write_rejects_names_csv_cannot_hold() {
        for name in ["a,b", " a", "a\nb"] {
            let rec = Recording::new(vec![0.0], vec![Signal::new(name, vec![1.0])]).unwrap();
            let e = write_signals(&rec, Vec::new()).unwrap_err();
            assert!(matches!(e, CoreError::InvalidSignalName { .. }), "{name:?}");
        }
    }

    #[test]
    fn path_functions_round_trip_and_put_the_path_in_errors() {
        let dir = std::env::temp_dir().join(format!("modelgap-core-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("rec.csv");
        let rec = Recording::new(vec![0.0, 0.25], vec![Signal::new("x", vec![1.5, -2.0])]).unwrap();
        write_signals_path(&rec, &path).unwrap();
        assert_eq!(read_signals_path(&path).unwrap(), rec);

        let bad = dir.join("bad.csv");
        std::fs::write(&bad, "t,x\n0,1\n0,2\n").unwrap();
        let e = read_signals_path(&bad).unwrap_err();
        assert_eq!(e.path(), Some(bad.as_path()));
        assert!(e.to_string().ends_with(&format!(" in {}", bad.display())));

        let missing: PathBuf = dir.join("missing.csv");
        let e = read_signals_path(&missing).unwrap_err();
        assert!(matches!(e, CoreError::Io { .. }));
        assert_eq!(e.path(), Some(missing.as_path()));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

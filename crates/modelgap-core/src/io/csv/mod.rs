//! Signals as CSV text: a header naming the columns, then one row per sample.
//!
//! Writing gives the header `t,<name>,…` and one row per sample, each number in Rust's
//! shortest round-trip `Display` of `f64` (never exponent notation), so write → read gives
//! back an identical recording, bit for bit.
//!
//! Reading takes that, and recordings as other tools export them (pandas `to_csv`, R
//! `write.csv`, a spreadsheet's "save as CSV"), parsed by the `csv` crate:
//!
//! - **Lines.** Lines whose first non-blank character is `#` are comments and blank lines
//!   are skipped (both still count for line numbers); a leading UTF-8 byte-order mark and
//!   `\r\n` line ends are accepted; whitespace around cells is trimmed.
//! - **Quotes.** A cell may be quoted (`"u"`, with `""` for a quote inside); a quote inside
//!   an unquoted cell, text after a closing quote and a quoted cell that spans lines are
//!   refused with [`CoreError::CsvQuoting`].
//! - **Time.** The time column is the column named `t`; failing one, the one column named
//!   `t` or `time` in any case, with or without a unit (`Time [s]`); anywhere in the header.
//!   [`CsvOptions::time`] names another. A time unit of `ms`, `us` or `ns` is converted to
//!   seconds; any unit other than those and `s` is refused.
//! - **Index column.** A first column that is unnamed (`,t,u` from pandas, `"","t","u"` from
//!   R), or named `index` or `Unnamed: 0`, whose values are consecutive whole numbers (`0, 1,
//!   2, …` or R's quoted `"1", "2", …`) is a row index: it is left out, and a note says so.
//!   Named, with other values, it is an ordinary signal; unnamed, it is refused.
//! - **Separators.** Cells are separated by `,`, or by `;` (or a tab) when the header has
//!   one and no `,` outside quotes, or by [`CsvOptions::delimiter`].
//! - **Decimal commas.** With `;` or tabs between cells, numbers may be written `1,5`: the
//!   first number with a decimal mark (`,` or `.`) decides for the file, and a later one with
//!   the other mark is refused. With `,` between cells, a decimal comma (only possible in a
//!   quoted cell) is refused unless declared by [`CsvOptions::decimal_comma`]. A number with
//!   both marks (`1.234,5`) is never read.
//! - **Units.** A header cell `name [unit]` (with or without the space) or `name (unit)`
//!   (with it) is the signal `name` with a unit; so is a second header row of units (every
//!   cell not a number, such as `s,V,A`). Units are kept in [`CsvRecording::units`]; signal
//!   values are not converted.
//!
//! Time must be finite and strictly increasing, values finite; errors name the line (from 1)
//! and the column.

use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::Path;

mod table;
mod text;

use table::Table;

use crate::error::{CoreError, Result};
use crate::io::columns::split_unit;
use crate::recording::{Recording, TIME_NAME};

/// How CSV text is read: the time column, the separator and the decimal mark, each
/// detected when not given (see the [module docs](self)).
///
/// # Example
///
/// ```
/// # use modelgap_core::io::csv::{CsvOptions, read_signals_with};
/// let text = "Zeit [s];U [V]\n0;1,5\n0,5;2,25\n";
/// let read = read_signals_with(text.as_bytes(), &CsvOptions::default().time("Zeit"))?;
/// assert_eq!(read.recording.values("U")?, &[1.5, 2.25]);
/// assert_eq!(read.unit("U"), Some("V"));
/// # Ok::<(), modelgap_core::CoreError>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CsvOptions {
    /// The time column, named as in the header (`time [s]`) or without its unit (`time`).
    /// Default `None`: the column named `t`, else the one column named `t` or `time` in any
    /// case, with or without a unit.
    pub time: Option<String>,
    /// The byte between cells. Default `None`: `,`, or `;` (else a tab) when the header has
    /// one and no `,` outside quotes.
    pub delimiter: Option<u8>,
    /// Whether numbers are written with a decimal comma (`1,5` for 1.5). Default `None`:
    /// never with `,` between cells; with `;` or tabs, the first number with a decimal mark
    /// decides.
    pub decimal_comma: Option<bool>,
}

impl CsvOptions {
    /// Reads time from the column `name` (as written, or without its unit).
    #[must_use]
    pub fn time(mut self, name: impl Into<String>) -> Self {
        self.time = Some(name.into());
        self
    }

    /// Separates cells by `delimiter` (`b';'`, `b'\t'`) instead of detecting it.
    #[must_use]
    pub fn delimiter(mut self, delimiter: u8) -> Self {
        self.delimiter = Some(delimiter);
        self
    }

    /// Declares whether numbers are written with a decimal comma.
    #[must_use]
    pub fn decimal_comma(mut self, decimal_comma: bool) -> Self {
        self.decimal_comma = Some(decimal_comma);
        self
    }

    /// True when every option is left to detection (as [`read_signals`] reads).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

/// A recording read from CSV text, with what the reader learned from the file.
#[derive(Clone, Debug, PartialEq)]
pub struct CsvRecording {
    /// The samples: time in seconds, the signals in header order.
    pub recording: Recording,
    /// The time column as written in the header (`t`, `Time [s]`).
    pub time_column: String,
    /// The time column's unit, when the header or a unit row gives one (`ms`: the values
    /// were divided by 1000).
    pub time_unit: Option<String>,
    /// Each signal's unit, in the recording's order; `None` where none is given.
    pub units: Vec<Option<String>>,
    /// The byte between cells.
    pub delimiter: u8,
    /// Whether numbers were read with a decimal comma.
    pub decimal_comma: bool,
    /// What the reader did that a user should know: an index column left out, a unit row
    /// read, a time unit converted, a separator or decimal mark detected.
    pub notes: Vec<String>,
}

impl CsvRecording {
    /// The unit of the signal `name`, when the file gives one.
    pub fn unit(&self, name: &str) -> Option<&str> {
        let i = self
            .recording
            .signals()
            .iter()
            .position(|s| s.name == name)?;
        self.units.get(i)?.as_deref()
    }
}

/// Reads a recording from CSV text with every option detected ([`read_signals_with`] with
/// [`CsvOptions::default`]), keeping the samples only.
///
/// # Errors
///
/// As [`read_signals_with`].
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
    Ok(read_signals_with(reader, &CsvOptions::default())?.recording)
}

/// Reads a recording from CSV text as exported by a logger, pandas, R or a spreadsheet (see
/// the [module docs](self)), with the units and notes the file gives.
///
/// # Errors
///
/// [`CoreError::MissingHeader`], [`CoreError::MissingTimeColumn`] (listing the columns),
/// [`CoreError::AmbiguousTimeColumn`], [`CoreError::TimeUnit`],
/// [`CoreError::InvalidSignalName`] or [`CoreError::DuplicateSignal`] for a bad header;
/// [`CoreError::CsvQuoting`], [`CoreError::RowLength`], [`CoreError::NotANumber`],
/// [`CoreError::DecimalMark`], [`CoreError::NonFinite`], [`CoreError::OutOfRange`] or
/// [`CoreError::NonIncreasingTime`] for a bad row (all with the line number);
/// [`CoreError::EmptyRecording`] when there are no rows; [`CoreError::InvalidArgument`] for
/// a delimiter that cannot separate cells; [`CoreError::NotUtf8`] and [`CoreError::Io`] when
/// the text cannot be read.
///
/// # Example
///
/// ```
/// # use modelgap_core::io::csv::{CsvOptions, read_signals_with};
/// // pandas' `df.to_csv()`: an unnamed index column first.
/// let text = ",t,u [V],y\n0,0.0,1.0,0.5\n1,0.1,1.0,0.75\n";
/// let read = read_signals_with(text.as_bytes(), &CsvOptions::default())?;
/// assert_eq!(read.recording.names(), vec!["u", "y"]);
/// assert_eq!(read.unit("u"), Some("V"));
/// assert!(read.notes[0].contains("row index"));
/// # Ok::<(), modelgap_core::CoreError>(())
/// ```
pub fn read_signals_with(reader: impl Read, options: &CsvOptions) -> Result<CsvRecording> {
    let text = text::clean_text(reader)?;
    let Some(header_text) = text.lines().find(|l| !l.is_empty()) else {
        return Err(CoreError::MissingHeader { path: None });
    };
    let delimiter = match options.delimiter {
        Some(d) => text::check_delimiter(d)?,
        None => text::detect_delimiter(header_text),
    };
    let mut parser = ::csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .delimiter(delimiter)
        .from_reader(text.as_bytes());
    let mut table: Option<Table> = None;
    for record in parser.records() {
        let record = record.map_err(|e| CoreError::io(e.into(), None))?;
        let line = text::check_record(&record, &text, delimiter)?;
        let cells: Vec<&str> = record.iter().map(str::trim).collect();
        match &mut table {
            None => table = Some(Table::new(&cells, line, options, delimiter)?),
            Some(table) => table.push_row(&cells, line)?,
        }
    }
    let Some(table) = table else {
        return Err(CoreError::MissingHeader { path: None });
    };
    table.finish(options)
}

/// Reads a recording from a CSV file; like [`read_signals`], with the path in every error.
///
/// # Errors
///
/// As [`read_signals`], plus [`CoreError::Io`] when the file cannot be opened.
pub fn read_signals_path(path: &Path) -> Result<Recording> {
    Ok(read_signals_path_with(path, &CsvOptions::default())?.recording)
}

/// Reads a recording from a CSV file; like [`read_signals_with`], with the path in every
/// error.
///
/// # Errors
///
/// As [`read_signals_with`], plus [`CoreError::Io`] when the file cannot be opened.
pub fn read_signals_path_with(path: &Path, options: &CsvOptions) -> Result<CsvRecording> {
    let file = File::open(path).map_err(|e| CoreError::io(e, Some(path)))?;
    read_signals_with(file, options).map_err(|e| e.with_path(path))
}

/// Writes a recording as CSV text: the header `t,<names>`, then one row per sample.
///
/// # Errors
///
/// [`CoreError::InvalidSignalName`] for a name that CSV cannot hold (a comma, a quote, a
/// line break, whitespace at either end, or a trailing `[…]` or ` (…)` that reading would
/// take for a unit); [`CoreError::Io`] when writing fails.
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
/// Checks that a name survives a CSV round trip.
fn check_csv_name(name: &str) -> Result<()> {
    let reason = if name.contains([',', '"', '\n', '\r']) {
        "a csv column name cannot contain a comma, a quote or a line break"
    } else if name.trim() != name {
        "a csv column name cannot start or end with whitespace"
    } else if split_unit(name).1.is_some() {
        "a csv column name ending in `[…]` or ` (…)` reads back as a name and a unit"
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
    use crate::error::Location;
    use crate::recording::Signal;

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
    fn header_without_a_time_column_lists_the_columns_and_the_option() {
        let e = read("# c\nwhen,i\n0,1\n").unwrap_err();
        assert!(matches!(
            e,
            CoreError::MissingTimeColumn { line: Some(2), asked: None, ref columns, .. }
                if columns == &["when", "i"]
        ));
        assert_eq!(
            e.to_string(),
            "missing column `t`: the header at line 2 has no column `t` or `time` (with or \
             without a unit); its columns are `when`, `i`: choose the time column with the time \
             option (`--time COL`)"
        );
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
        for name in ["a,b", " a", "a\nb", "a\"b", "u [V]", "u (V)"] {
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

//! The error type of modelgap-core and its `Result` alias.
//!
//! Every variant carries the facts a user needs to fix the input: where the problem is (a
//! [`Location`]: a CSV line, a sample index, an MCAP message index or a Parquet row), which
//! column or field,
//! what was found, and, last in the message, the file when it is known.

use std::fmt;
use std::path::{Path, PathBuf};

/// `Result` with [`CoreError`] as the default error type.
pub type Result<T, E = CoreError> = std::result::Result<T, E>;

/// Where in the input a problem sits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// A line of a text file, counted from 1 as editors do (comment and blank lines count).
    Line(usize),
    /// A sample of a recording, counted from 0 (an index into [`crate::Recording::t`]).
    Sample(usize),
    /// A message on the read topic of an MCAP file, counted from 0 in file order.
    Message(usize),
    /// A row of a Parquet file, counted from 0 as pandas and Polars count (across row
    /// groups).
    Row(usize),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Line(line) => write!(f, "line {line}"),
            Self::Sample(index) => write!(f, "sample {index}"),
            Self::Message(index) => write!(f, "message {index}"),
            Self::Row(index) => write!(f, "row {index}"),
        }
    }
}

/// Everything that can go wrong in modelgap-core.
///
/// Messages start lowercase, have no trailing period and end with ` in <path>` when the file
/// is known (see [`CoreError::with_path`]).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CoreError {
    /// Reading or writing a file failed.
    #[error("i/o error: {error}{}", in_path(.path))]
    Io {
        /// The operating system's error.
        error: std::io::Error,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A line of a text file is not valid UTF-8.
    #[error("line {line} is not valid utf-8{}", in_path(.path))]
    NotUtf8 {
        /// The line, counted from 1.
        line: usize,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// Time does not strictly increase from one sample to the next.
    #[error(
        "time is not strictly increasing at {at}: {t} s after {t_prev} s{}",
        in_path(.path)
    )]
    NonIncreasingTime {
        /// The sample that is not later than its predecessor.
        at: Location,
        /// The time of the previous sample (s).
        t_prev: f64,
        /// The time of the offending sample (s).
        t: f64,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A CSV cell does not hold a number.
    #[error("cannot read `{text}` as a number at line {line}, column `{column}`{}", in_path(.path))]
    NotANumber {
        /// The line, counted from 1.
        line: usize,
        /// The column name from the header.
        column: String,
        /// The cell's text, trimmed.
        text: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A value is NaN or infinite.
    #[error("value {value} is not finite at {at}, column `{column}`{}", in_path(.path))]
    NonFinite {
        /// Where the value sits.
        at: Location,
        /// The column or signal name (`t` for time).
        column: String,
        /// The offending value.
        value: f64,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A value is finite but beyond [`crate::recording::MAX_MAGNITUDE`] in magnitude: its
    /// square, and the sums of squares that every statistic takes, would overflow.
    #[error(
        "value {} at {at} (t = {} s), column `{column}`, is beyond the largest magnitude a recording may hold ({}: squares and their sums must stay finite){}",
        short(*.value),
        short(*.t),
        short(*.limit),
        in_path(.path)
    )]
    OutOfRange {
        /// Where the value sits.
        at: Location,
        /// The time of that sample (s); the value itself when it is the time.
        t: f64,
        /// The column or signal name (`t` for time).
        column: String,
        /// The offending value.
        value: f64,
        /// The largest magnitude allowed.
        limit: f64,
        /// The file, when known.
        path: Option<PathBuf>,
    },
    /// A CSV file has no header line.
    #[error("no header line `t,<name>,…` found{}", in_path(.path))]
    MissingHeader {
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A CSV header or a Parquet file has no time column: none named `t` or `time`, or none
    /// of the name asked for.
    #[error("{}{}", missing_time(*.line, .asked, .columns), in_path(.path))]
    MissingTimeColumn {
        /// The CSV header line, counted from 1; `None` for a Parquet file.
        line: Option<usize>,
        /// The time column asked for by name, if one was.
        asked: Option<String>,
        /// The header's columns as written.
        columns: Vec<String>,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// Several columns (of a CSV header or a Parquet file) could be the time column.
    #[error(
        "columns {}{} could each be time: choose one with the time option (`--time COL`){}",
        quoted(.columns),
        of_header(*.line),
        in_path(.path)
    )]
    AmbiguousTimeColumn {
        /// The CSV header line, counted from 1; `None` for a Parquet file.
        line: Option<usize>,
        /// The columns that could be time, as written.
        columns: Vec<String>,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// The time column has a unit that is not a unit of time modelgap reads.
    #[error(
        "time column `{column}`{} has unit `{unit}`: expected s, ms, us or ns{}",
        at_line(*.line),
        in_path(.path)
    )]
    TimeUnit {
        /// The CSV line that gives the unit (the header or the unit row), counted from 1;
        /// `None` for a Parquet column name.
        line: Option<usize>,
        /// The time column as written.
        column: String,
        /// The unit found.
        unit: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A CSV cell holds a number whose decimal mark cannot be read safely (a decimal comma
    /// with `,` between cells, or a file mixing `1.5` and `1,5`).
    #[error(
        "cannot read `{text}` as a number at line {line}, column `{column}`: {reason}{}",
        in_path(.path)
    )]
    DecimalMark {
        /// The line, counted from 1.
        line: usize,
        /// The column name from the header.
        column: String,
        /// The cell's text, trimmed.
        text: String,
        /// Why the mark is refused, and what to do.
        reason: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A CSV line is badly quoted (a quote inside an unquoted cell, text after a closing
    /// quote, a quoted cell that spans lines or never closes).
    #[error("bad quoting at line {line}, cell {cell}: {reason}{}", in_path(.path))]
    CsvQuoting {
        /// The line where the record starts, counted from 1.
        line: usize,
        /// The cell, counted from 1.
        cell: usize,
        /// What is wrong.
        reason: &'static str,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A signal name was asked for that the recording does not have.
    #[error("unknown signal `{name}`; available: {}", list(.available))]
    UnknownSignal {
        /// The name asked for.
        name: String,
        /// The names the recording has, in its order.
        available: Vec<String>,
    },

    /// Two signals (columns, fields) share a name.
    #[error("duplicate signal `{name}`{}{}", at_location(.at), in_path(.path))]
    DuplicateSignal {
        /// The repeated name.
        name: String,
        /// Where it repeats, when known.
        at: Option<Location>,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A signal name is empty, reserved or cannot be stored in the target format.
    #[error("invalid signal name `{name}`: {reason}{}{}", at_location(.at), in_path(.path))]
    InvalidSignalName {
        /// The name as given.
        name: String,
        /// Why it is rejected.
        reason: &'static str,
        /// Where it appears, when known.
        at: Option<Location>,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A recording would have no samples.
    #[error("recording has no samples{}", in_path(.path))]
    EmptyRecording {
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A CSV row has a different number of cells than the header.
    #[error(
        "line {line} has {found} cells, expected {expected} (one per header column){}",
        in_path(.path)
    )]
    RowLength {
        /// The line, counted from 1.
        line: usize,
        /// The number of header columns.
        expected: usize,
        /// The number of cells on the line.
        found: usize,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A signal's length differs from the number of time samples.
    #[error("signal `{name}` has {found} values, expected {expected} (one per time sample)")]
    LengthMismatch {
        /// The signal name.
        name: String,
        /// The number of time samples.
        expected: usize,
        /// The number of values of the signal.
        found: usize,
    },

    /// An argument is out of its domain (a NaN time, an empty interval).
    #[error("invalid argument `{name}`: {reason}")]
    InvalidArgument {
        /// The argument's name.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },

    /// An MCAP file cannot be read: it is truncated or corrupt.
    #[error("mcap data is truncated or corrupt: {reason}{}", in_path(.path))]
    McapCorrupt {
        /// The mcap crate's error text, with its causes.
        reason: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// Writing an MCAP file failed.
    #[error("cannot write mcap: {reason}{}", in_path(.path))]
    McapWrite {
        /// The mcap crate's error text, with its causes.
        reason: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// An MCAP file has no messages on the requested topic.
    #[error("no messages on topic `{topic}`; topics with messages: {}{}", list(.available), in_path(.path))]
    TopicNotFound {
        /// The requested topic.
        topic: String,
        /// The topics that do have messages, sorted.
        available: Vec<String>,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A topic's messages are not JSON.
    #[error("topic `{topic}` has message encoding `{encoding}`, expected `json`{}", in_path(.path))]
    McapEncoding {
        /// The topic.
        topic: String,
        /// The message encoding found.
        encoding: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// An MCAP message is not a flat JSON object.
    #[error("message {index} is not a flat json object of numbers: {reason}{}", in_path(.path))]
    McapJson {
        /// The message, counted from 0 in file order on the topic.
        index: usize,
        /// What the JSON parser said.
        reason: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// An MCAP message lacks a field that the first message has.
    #[error("message {index} lacks field `{field}` that the first message has{}", in_path(.path))]
    McapMissingField {
        /// The message, counted from 0 in file order on the topic.
        index: usize,
        /// The missing field.
        field: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// An MCAP message has a field that the first message lacks.
    #[error("message {index} has field `{field}` that the first message lacks{}", in_path(.path))]
    McapUnexpectedField {
        /// The message, counted from 0 in file order on the topic.
        index: usize,
        /// The extra field.
        field: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A field of an MCAP message is not a finite number.
    #[error("field `{field}` of message {index} is not a finite number: found `{found}`{}", in_path(.path))]
    McapBadField {
        /// The message, counted from 0 in file order on the topic.
        index: usize,
        /// The field.
        field: String,
        /// The JSON value found (shortened).
        found: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A time cannot be stored as an MCAP `log_time` (negative, not finite, too large, or
    /// two samples closer than the format's 1 ns resolution).
    #[error("cannot store time {t} s as an mcap log time at {at}: {reason}{}", in_path(.path))]
    McapTime {
        /// Where the time sits.
        at: Location,
        /// The time (s).
        t: f64,
        /// Why it cannot be stored.
        reason: &'static str,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A model (a bond graph, a cloth scene, a model written in Python) could not predict
    /// or be edited; the message is the domain crate's error, naming the element or
    /// parameter (with the effects it was tried with), and `domain` is that error itself,
    /// typed ([`CoreError::model_error`] reads it back).
    #[error("{message}")]
    Model {
        /// What went wrong, from the model's own error.
        message: String,
        /// The model's own error (a `BondError`, a `ClothError`), when there is one. Not
        /// the error's `source()`: its text is already in `message`.
        domain: Option<DomainError>,
    },

    /// A fit could not run (no parameters, a non-finite residual at the start).
    #[error("fit of {what}: {reason}")]
    Fit {
        /// What was being fitted (a candidate's name).
        what: String,
        /// Why it could not run.
        reason: String,
    },

    /// A file extension that names no supported format.
    #[error(
        "unknown file extension `{extension}`: expected `csv`, `mcap` or `parquet` (`pq`){}",
        in_path(.path)
    )]
    UnknownExtension {
        /// The extension found (empty when the file has none).
        extension: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A known format used for what it does not hold: a recording written as Parquet (read
    /// only), markers read from Parquet.
    #[error(
        "cannot {action} {format} ({reason}): expected a `csv` or `mcap` file{}",
        in_path(.path)
    )]
    FormatNotSupported {
        /// What was asked (`write a recording as`, `read markers from`).
        action: &'static str,
        /// The format (`parquet`).
        format: &'static str,
        /// Why not (`parquet is read, not written`).
        reason: &'static str,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A Parquet file cannot be read: it is truncated or corrupt.
    #[error("parquet data is truncated or corrupt: {reason}{}", in_path(.path))]
    ParquetCorrupt {
        /// The parquet crate's error text, or what does not add up.
        reason: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A Parquet column is compressed with a codec modelgap does not read.
    #[error(
        "column `{column}` is compressed with {codec}: expected snappy (pandas' default), zstd \
         (Polars') or none; write the file again with one of those{}",
        in_path(.path)
    )]
    ParquetCodec {
        /// The column as named in the file.
        column: String,
        /// The codec found (`GZIP`, `BROTLI`, …).
        codec: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A Parquet column that is not the index holds something other than numbers,
    /// timestamps or durations (text, booleans, lists).
    #[error(
        "column `{column}` holds {found}, not numbers: modelgap reads numbers, timestamps and \
         durations; drop the column or convert it before writing the file{}",
        in_path(.path)
    )]
    ColumnType {
        /// The column as named in the file.
        column: String,
        /// What it holds (`text (BYTE_ARRAY, String)`).
        found: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },

    /// A value is missing (a Parquet null; pandas writes NaN as null).
    #[error(
        "missing value (null) at {at}, column `{column}`: every sample needs a value{}",
        in_path(.path)
    )]
    MissingValue {
        /// Where the value is missing.
        at: Location,
        /// The column as named in the file.
        column: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },
}

/// A model's own error carried through the loop's seam ([`CoreError::Model`]).
pub type DomainError = Box<dyn std::error::Error + Send + Sync + 'static>;

impl CoreError {
    /// A model error with a message of its own (no typed error behind it).
    pub fn model(message: impl Into<String>) -> Self {
        Self::Model {
            message: message.into(),
            domain: None,
        }
    }

    /// A model's own error through the seam: its text after `context` (when there is one,
    /// e.g. the effects it was tried with), the error itself kept typed.
    pub fn from_model<E: std::error::Error + Send + Sync + 'static>(
        context: Option<String>,
        error: E,
    ) -> Self {
        let message = match context {
            Some(c) => format!("{c}: {error}"),
            None => error.to_string(),
        };
        Self::Model {
            message,
            domain: Some(Box::new(error)),
        }
    }

    /// The model's own error behind a [`CoreError::Model`], to downcast to its crate's type
    /// (`e.model_error().and_then(|d| d.downcast_ref::<BondError>())`).
    pub fn model_error(&self) -> Option<&(dyn std::error::Error + Send + Sync + 'static)> {
        match self {
            Self::Model {
                domain: Some(d), ..
            } => Some(d.as_ref()),
            _ => None,
        }
    }

    /// Wraps an I/O error with the file it concerns.
    pub fn io(error: std::io::Error, path: Option<&Path>) -> Self {
        Self::Io {
            error,
            path: path.map(Path::to_path_buf),
        }
    }

    /// Sets the file of a variant that names one, unless it already names one.
    ///
    /// Readers that work on in-memory data return errors without a path; the `*_path`
    /// functions add the path with this.
    #[must_use]
    pub fn with_path(mut self, file: &Path) -> Self {
        if let Some(slot) = self.path_slot()
            && slot.is_none()
        {
            *slot = Some(file.to_path_buf());
        }
        self
    }

    /// The file this error concerns, when known.
    pub fn path(&self) -> Option<&Path> {
        match self {
            Self::Io { path, .. }
            | Self::NotUtf8 { path, .. }
            | Self::NonIncreasingTime { path, .. }
            | Self::NotANumber { path, .. }
            | Self::NonFinite { path, .. }
            | Self::OutOfRange { path, .. }
            | Self::MissingHeader { path }
            | Self::MissingTimeColumn { path, .. }
            | Self::AmbiguousTimeColumn { path, .. }
            | Self::TimeUnit { path, .. }
            | Self::DecimalMark { path, .. }
            | Self::CsvQuoting { path, .. }
            | Self::DuplicateSignal { path, .. }
            | Self::InvalidSignalName { path, .. }
            | Self::EmptyRecording { path }
            | Self::RowLength { path, .. }
            | Self::McapCorrupt { path, .. }
            | Self::McapWrite { path, .. }
            | Self::TopicNotFound { path, .. }
            | Self::McapEncoding { path, .. }
            | Self::McapJson { path, .. }
            | Self::McapMissingField { path, .. }
            | Self::McapUnexpectedField { path, .. }
            | Self::McapBadField { path, .. }
            | Self::McapTime { path, .. }
            | Self::UnknownExtension { path, .. }
            | Self::FormatNotSupported { path, .. }
            | Self::ParquetCorrupt { path, .. }
            | Self::ParquetCodec { path, .. }
            | Self::ColumnType { path, .. }
            | Self::MissingValue { path, .. } => path.as_deref(),
            Self::UnknownSignal { .. }
            | Self::LengthMismatch { .. }
            | Self::InvalidArgument { .. }
            | Self::Model { .. }
            | Self::Fit { .. } => None,
        }
    }

    fn path_slot(&mut self) -> Option<&mut Option<PathBuf>> {
        match self {
            Self::Io { path, .. }
            | Self::NotUtf8 { path, .. }
            | Self::NonIncreasingTime { path, .. }
            | Self::NotANumber { path, .. }
            | Self::NonFinite { path, .. }
            | Self::OutOfRange { path, .. }
            | Self::MissingHeader { path }
            | Self::MissingTimeColumn { path, .. }
            | Self::AmbiguousTimeColumn { path, .. }
            | Self::TimeUnit { path, .. }
            | Self::DecimalMark { path, .. }
            | Self::CsvQuoting { path, .. }
            | Self::DuplicateSignal { path, .. }
            | Self::InvalidSignalName { path, .. }
            | Self::EmptyRecording { path }
            | Self::RowLength { path, .. }
            | Self::McapCorrupt { path, .. }
            | Self::McapWrite { path, .. }
            | Self::TopicNotFound { path, .. }
            | Self::McapEncoding { path, .. }
            | Self::McapJson { path, .. }
            | Self::McapMissingField { path, .. }
            | Self::McapUnexpectedField { path, .. }
            | Self::McapBadField { path, .. }
            | Self::McapTime { path, .. }
            | Self::UnknownExtension { path, .. }
            | Self::FormatNotSupported { path, .. }
            | Self::ParquetCorrupt { path, .. }
            | Self::ParquetCodec { path, .. }
            | Self::ColumnType { path, .. }
            | Self::MissingValue { path, .. } => Some(path),
            Self::UnknownSignal { .. }
            | Self::LengthMismatch { .. }
            | Self::InvalidArgument { .. }
            | Self::Model { .. }
            | Self::Fit { .. } => None,
        }
    }
}

/// ` in <path>` when the path is known, nothing otherwise.
fn in_path(path: &Option<PathBuf>) -> String {
    match path {
        Some(p) => format!(" in {}", p.display()),
        None => String::new(),
    }
}

/// A number as a person writes it: `1.5`, `-1.7e308` (not 309 digits).
fn short(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() || (1e-4..1e6).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// ` at <location>` when the location is known, nothing otherwise.
fn at_location(at: &Option<Location>) -> String {
    match at {
        Some(at) => format!(" at {at}"),
        None => String::new(),
    }
}

/// The message of [`CoreError::MissingTimeColumn`], without the path.
fn missing_time(line: Option<usize>, asked: &Option<String>, columns: &[String]) -> String {
    let (header, its) = match line {
        Some(line) => (format!("the header at line {line}"), "its"),
        None => ("the file".to_owned(), "the file's"),
    };
    match asked {
        Some(name) => format!(
            "missing column `{name}`: {header} has no column `{name}` (with or without a \
             unit); {its} columns are {}",
            quoted(columns)
        ),
        None => format!(
            "missing column `t`: {header} has no column `t` or `time` (with or without a unit); \
             {its} columns are {}: choose the time column with the time option (`--time COL`)",
            quoted(columns)
        ),
    }
}

/// ` of the header at line <line>` for a CSV header, nothing for a Parquet file.
fn of_header(line: Option<usize>) -> String {
    line.map(|l| format!(" of the header at line {l}"))
        .unwrap_or_default()
}

/// ` at line <line>` when the line is known, nothing otherwise.
fn at_line(line: Option<usize>) -> String {
    line.map(|l| format!(" at line {l}")).unwrap_or_default()
}

/// Names as `` `a`, `b` ``, or `(none)`.
fn quoted(items: &[String]) -> String {
    if items.is_empty() {
        "(none)".to_owned()
    } else {
        items
            .iter()
            .map(|i| format!("`{i}`"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// A comma-separated list, or `(none)`.
fn list(items: &[String]) -> String {
    if items.is_empty() {
        "(none)".to_owned()
    } else {
        items.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_increasing_time_message_names_line_times_and_path_last() {
        let e = CoreError::NonIncreasingTime {
            at: Location::Line(7),
            t_prev: 0.6,
            t: 0.5,
            path: None,
        }
        .with_path(Path::new("data.csv"));
        assert_eq!(
            e.to_string(),
            "time is not strictly increasing at line 7: 0.5 s after 0.6 s in data.csv"
        );
    }

    #[test]
    fn message_without_path_has_no_in_clause() {
        let e = CoreError::EmptyRecording { path: None };
        assert_eq!(e.to_string(), "recording has no samples");
        assert!(e.path().is_none());
    }

    #[test]
    fn with_path_keeps_an_existing_path() {
        let e = CoreError::MissingHeader {
            path: Some(PathBuf::from("first.csv")),
        }
        .with_path(Path::new("second.csv"));
        assert_eq!(e.path(), Some(Path::new("first.csv")));
    }

    #[test]
    fn with_path_leaves_pathless_variants_unchanged() {
        let e = CoreError::UnknownSignal {
            name: "x".into(),
            available: vec!["i".into(), "omega".into()],
        }
        .with_path(Path::new("data.csv"));
        assert_eq!(e.to_string(), "unknown signal `x`; available: i, omega");
    }

    #[test]
    fn empty_list_reads_none() {
        let e = CoreError::TopicNotFound {
            topic: "/signals".into(),
            available: vec![],
            path: None,
        };
        assert_eq!(
            e.to_string(),
            "no messages on topic `/signals`; topics with messages: (none)"
        );
    }

    #[test]
    fn messages_are_lowercase_without_trailing_period() {
        let errors = [
            CoreError::NotANumber {
                line: 4,
                column: "i".into(),
                text: "abc".into(),
                path: Some("a.csv".into()),
            },
            CoreError::DuplicateSignal {
                name: "i".into(),
                at: Some(Location::Line(1)),
                path: None,
            },
            CoreError::RowLength {
                line: 3,
                expected: 3,
                found: 2,
                path: None,
            },
            CoreError::io(std::io::Error::other("boom"), Some(Path::new("x.mcap"))),
        ];
        for e in errors {
            let text = e.to_string();
            let first = text.chars().next().unwrap_or('X');
            assert!(first.is_lowercase(), "{text}");
            assert!(!text.ends_with('.'), "{text}");
        }
    }
}

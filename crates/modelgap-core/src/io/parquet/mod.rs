//! Signals from Parquet files, as pandas (`DataFrame.to_parquet()`: pyarrow, Snappy) and
//! Polars (`write_parquet()`: zstd) export them. Read only: recordings are written as CSV or
//! MCAP.
//!
//! A column is a signal, one row a sample, read with the `parquet` crate's column readers
//! (no Arrow) over every row group. The columns mean what a CSV header's cells mean (see
//! [`super::csv`]):
//!
//! - **Time.** The column named `t`; failing one, the one column named `t` or `time` in any
//!   case, with or without a unit (`time [ms]`); the `time` argument (`--time COL`) names
//!   another. A numeric time column's unit of `ms`, `us` or `ns` is converted to seconds, as
//!   in CSV. Timestamps (and dates, INT96 timestamps) count in seconds from the first sample;
//!   durations (pandas' `timedelta64`, which its metadata names) and times of day are
//!   converted to seconds as they are. Failing a time column by name, a pandas index of
//!   timestamps or durations (a `DatetimeIndex` without a name) is time.
//! - **Index.** A pandas index stored as a column (`__index_level_0__`, or a named index the
//!   pandas metadata lists) is left out, and a note says so; so is a `RangeIndex` kept only in
//!   the metadata. As in CSV, a first column named `index` or `Unnamed: 0` whose values count
//!   rows one by one is a row index, left out with a note.
//! - **Values.** Every other column is a signal: doubles, floats, integers of any width
//!   (signed or not), decimals stored as integers; timestamps and durations in seconds. A
//!   `name [unit]` column gives the signal `name` with a unit. Text, booleans, byte arrays
//!   and nested columns are refused with [`CoreError::ColumnType`].
//!
//! Nulls (pandas writes NaN as null) are refused with [`CoreError::MissingValue`], NaN and
//! infinities with [`CoreError::NonFinite`], time that does not strictly increase with
//! [`CoreError::NonIncreasingTime`]; each names the row (counted from 0, as pandas and Polars
//! count) and the column. Columns compressed with Snappy, zstd or nothing are read; another
//! codec is refused with [`CoreError::ParquetCodec`]. A truncated or corrupt file is a
//! [`CoreError::ParquetCorrupt`].
//!
//! A Polars `Duration` column keeps its unit only in the Arrow schema the file carries, which
//! this reader does not decode: it reads as its integer count, and an integer time column
//! without a unit in such a file gets a note that says so.

use std::path::Path;

use ::parquet::errors::ParquetError;
use ::parquet::file::metadata::KeyValue;
use ::parquet::file::reader::{FileReader, SerializedFileReader};
use bytes::Bytes;

use crate::error::{CoreError, Location, Result};
use crate::io::columns::{
    check_magnitude, check_signal_names, find_time, is_index_name, next_row_number, per_second,
    row_index_note, split_unit,
};
use crate::recording::{Recording, Signal};

mod column;

use column::{Column, Kind, Stored, Unit, check_chunks};

/// A recording read from a Parquet file, with what the reader learned from it.
#[derive(Clone, Debug, PartialEq)]
pub struct ParquetRecording {
    /// The samples: time in seconds, the signals in column order.
    pub recording: Recording,
    /// The time column as named in the file (`t`, `time [ms]`, `__index_level_0__`).
    pub time_column: String,
    /// The time column's unit, from its type (`ns` for timestamps in nanoseconds) or its name
    /// (`ms` in `time [ms]`); `None` for seconds given by no unit.
    pub time_unit: Option<String>,
    /// Each signal's unit, in the recording's order: from a `name [unit]` column name, `s`
    /// for timestamps and durations; `None` where none is given.
    pub units: Vec<Option<String>>,
    /// What the reader did that a user should know: an index left out, a time unit
    /// converted, timestamps counted from the first.
    pub notes: Vec<String>,
}

impl ParquetRecording {
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

/// Reads a recording from Parquet data in memory, the time column found by name; keeps the
/// samples only.
///
/// # Errors
///
/// As [`read_signals_with`].
pub fn read_signals(bytes: &[u8]) -> Result<Recording> {
    Ok(read_signals_with(bytes, None)?.recording)
}

/// Reads a recording from Parquet data in memory (see the [module docs](self)), with the
/// units and notes the file gives; `time` names the time column (as written or without its
/// unit) instead of finding it.
///
/// # Errors
///
/// [`CoreError::ParquetCorrupt`] for truncated or corrupt data; [`CoreError::ParquetCodec`]
/// for a codec other than Snappy or zstd; [`CoreError::MissingTimeColumn`] (listing the
/// columns), [`CoreError::AmbiguousTimeColumn`], [`CoreError::TimeUnit`],
/// [`CoreError::ColumnType`], [`CoreError::InvalidSignalName`] or
/// [`CoreError::DuplicateSignal`] for the columns; [`CoreError::MissingValue`],
/// [`CoreError::NonFinite`], [`CoreError::OutOfRange`] or [`CoreError::NonIncreasingTime`]
/// for a value (with its row); [`CoreError::EmptyRecording`] when there are no rows.
pub fn read_signals_with(bytes: &[u8], time: Option<&str>) -> Result<ParquetRecording> {
    read_bytes(Bytes::copy_from_slice(bytes), time)
}

/// Reads a recording from a Parquet file; like [`read_signals`], with the path in every
/// error.
///
/// # Errors
///
/// As [`read_signals`], plus [`CoreError::Io`] when the file cannot be read.
///
/// # Example
///
/// ```no_run
/// # use std::path::Path;
/// let rec = modelgap_core::io::parquet::read_signals_path(Path::new("run.parquet"))?;
/// println!("{} samples of {:?}", rec.len(), rec.names());
/// # Ok::<(), modelgap_core::CoreError>(())
/// ```
pub fn read_signals_path(path: &Path) -> Result<Recording> {
    Ok(read_signals_path_with(path, None)?.recording)
}

/// Reads a recording from a Parquet file; like [`read_signals_with`], with the path in every
/// error.
///
/// # Errors
///
/// As [`read_signals_with`], plus [`CoreError::Io`] when the file cannot be read.
pub fn read_signals_path_with(path: &Path, time: Option<&str>) -> Result<ParquetRecording> {
    let bytes = std::fs::read(path).map_err(|e| CoreError::io(e, Some(path)))?;
    read_bytes(Bytes::from(bytes), time).map_err(|e| e.with_path(path))
}

/// What the pandas metadata of a file says: its index columns, a `RangeIndex` kept there
/// (first, last), and the unit of each `timedelta64` column; and whether the file's integer
/// columns may be durations it cannot see (an Arrow schema without pandas metadata).
#[derive(Debug, Default)]
struct Pandas {
    /// True for a file with an Arrow schema (Polars, pyarrow) and no pandas metadata: a
    /// duration's unit is only in that schema.
    arrow_only: bool,
    index_columns: Vec<String>,
    range: Option<(i128, i128)>,
    durations: Vec<(String, Unit)>,
}

impl Pandas {
    /// Parsed from the key `pandas`; a file without it (Polars) or with metadata that does
    /// not parse has none.
    fn from_metadata(key_values: Option<&Vec<KeyValue>>) -> Self {
        let mut pandas = Self::default();
        let has = |key: &str| key_values.into_iter().flatten().any(|kv| kv.key == key);
        pandas.arrow_only = has("ARROW:schema") && !has("pandas");
        let Some(json) = key_values
            .into_iter()
            .flatten()
            .find(|kv| kv.key == "pandas")
            .and_then(|kv| kv.value.as_deref())
            .and_then(|v| serde_json::from_str::<serde_json::Value>(v).ok())
        else {
            return pandas;
        };
        for index in json["index_columns"].as_array().into_iter().flatten() {
            if let Some(name) = index.as_str() {
                pandas.index_columns.push(name.to_owned());
            } else if index["kind"] == "range"
                && let (Some(start), Some(stop), Some(step)) = (
                    index["start"].as_i64().map(i128::from),
                    index["stop"].as_i64().map(i128::from),
                    index["step"].as_i64().map(i128::from),
                )
                && step != 0
            {
                // Python's range(start, stop, step): n values, the last start + (n - 1) step.
                let n = (stop - start + step - step.signum()) / step;
                if n > 0 {
                    pandas.range = Some((start, start + (n - 1) * step));
                }
            }
        }
        for column in json["columns"].as_array().into_iter().flatten() {
            let unit = match column["numpy_type"].as_str() {
                Some("timedelta64[ms]") => Unit::Millis,
                Some("timedelta64[us]") => Unit::Micros,
                Some("timedelta64[ns]") => Unit::Nanos,
                _ => continue,
            };
            if let Some(name) = column["field_name"].as_str() {
                pandas.durations.push((name.to_owned(), unit));
            }
        }
        pandas
    }

    /// True for a column that holds the pandas index.
    fn is_index(&self, column: &str) -> bool {
        self.index_columns.iter().any(|c| c == column)
            || (column.starts_with("__index_level_") && column.ends_with("__"))
    }
}

/// The parquet crate's error as [`CoreError::ParquetCorrupt`].
fn corrupt(e: ParquetError) -> CoreError {
    let text = e.to_string();
    CoreError::ParquetCorrupt {
        reason: text
            .strip_prefix("Parquet error: ")
            .unwrap_or(&text)
            .to_owned(),
        path: None,
    }
}

/// Runs `read`, a call into the parquet crate's decoders, a panic in it made an error.
///
/// The crate still panics on some damaged pages: flipping bytes of real exports found an
/// index out of bounds in its BYTE_STREAM_SPLIT decoder and a shift overflow in its bit
/// reader (a debug assertion). A damaged file must be a [`CoreError::ParquetCorrupt`] that
/// names it, never a crash, so a panic there is caught and reported as one. The usual damage
/// is refused before (negative offsets, a dictionary page missing), without a panic.
fn guarded<T>(read: impl FnOnce() -> Result<T>) -> Result<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(read)).unwrap_or_else(|panic| {
        let what = panic
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| panic.downcast_ref::<&str>().copied())
            .unwrap_or("a panic");
        Err(CoreError::ParquetCorrupt {
            reason: format!("the parquet decoder failed: {what}"),
            path: None,
        })
    })
}

fn read_bytes(bytes: Bytes, time: Option<&str>) -> Result<ParquetRecording> {
    let reader = guarded(|| SerializedFileReader::new(bytes).map_err(corrupt))?;
    let metadata = reader.metadata();
    let file = metadata.file_metadata();
    let pandas = Pandas::from_metadata(file.key_value_metadata());
    let columns: Vec<Column> = file
        .schema_descr()
        .columns()
        .iter()
        .enumerate()
        .map(|(index, descr)| Column::new(index, descr.clone(), &pandas))
        .collect();
    let names: Vec<&str> = columns.iter().map(|c| c.name.as_str()).collect();
    let mut notes = Vec::new();

    let time_index = match find_time(&names, None, time) {
        Ok(i) => i,
        Err(e @ CoreError::MissingTimeColumn { .. }) if time.is_none() => {
            // A DatetimeIndex (or TimedeltaIndex) without a name is time.
            let mut timed = (0..columns.len()).filter(|&i| {
                pandas.is_index(&columns[i].name)
                    && matches!(columns[i].kind, Ok(Kind::Time { .. }))
            });
            match (timed.next(), timed.next()) {
                (Some(i), None) => {
                    notes.push(format!(
                        "no column `t` or `time`: time read from the pandas index `{}`",
                        columns[i].name
                    ));
                    i
                }
                _ => return Err(e),
            }
        }
        Err(e) => return Err(e),
    };

    // Which columns are signals; the others are the time column and the index.
    let mut signal_columns = Vec::new();
    for (i, column) in columns.iter().enumerate() {
        if i == time_index {
            continue;
        }
        if pandas.is_index(&column.name) {
            notes.push(format!(
                "column `{}` holds the pandas index: left out",
                column.name
            ));
            continue;
        }
        signal_columns.push(i);
    }
    if let Some((first, last)) = pandas.range {
        notes.push(format!(
            "the pandas index (rows {first} to {last}) is kept in the file's metadata, not as a \
             column: left out"
        ));
    }
    for &i in signal_columns.iter().chain([&time_index]) {
        let column = &columns[i];
        if let Err(found) = &column.kind {
            return Err(CoreError::ColumnType {
                column: column.name.clone(),
                found: found.clone(),
                path: None,
            });
        }
    }
    check_chunks(
        metadata,
        &columns,
        signal_columns.iter().chain([&time_index]),
    )?;

    // Time, in seconds.
    let time_column = &columns[time_index];
    let stored = guarded(|| time_column.read(&reader))?;
    if stored.len() == 0 {
        return Err(CoreError::EmptyRecording { path: None });
    }
    let (t, time_unit) = time_seconds(time_column, stored, pandas.arrow_only, &mut notes)?;
    check_time(&t, &time_column.name)?;

    // A first column named as a row index, counting rows one by one, is left out.
    let mut signals = Vec::new();
    let mut units = Vec::new();
    for &i in &signal_columns {
        let column = &columns[i];
        let values = column.values(guarded(|| column.read(&reader))?);
        if i == 0
            && is_index_name(&column.name)
            && let Some(first) = values.first()
            && values.windows(2).all(|w| next_row_number(Some(w[0]), w[1]))
            && next_row_number(None, *first)
        {
            let name = (!column.name.is_empty()).then_some(column.name.as_str());
            notes.push(row_index_note(name, *first, values[values.len() - 1]));
            continue;
        }
        check_values(&values, &t, &column.name)?;
        let (name, unit) = split_unit(&column.name);
        let unit = match column.kind {
            Ok(Kind::Time { .. }) => Some("s"),
            _ => unit,
        };
        signals.push(Signal::new(name, values));
        units.push(unit.map(str::to_owned));
    }
    check_signal_names(signals.iter().map(|s| s.name.as_str()), None)?;
    Ok(ParquetRecording {
        recording: Recording::new(t, signals)?,
        time_column: time_column.name.clone(),
        time_unit,
        units,
        notes,
    })
}

/// The time column in seconds, with its unit; a note when it was converted.
fn time_seconds(
    column: &Column,
    stored: Stored,
    arrow_only: bool,
    notes: &mut Vec<String>,
) -> Result<(Vec<f64>, Option<String>)> {
    if let (
        Stored::Counts(counts),
        Ok(&Kind::Time {
            unit,
            instant,
            what,
        }),
    ) = (&stored, column.kind.as_ref())
    {
        let first = counts.first().copied().unwrap_or_default();
        let t = counts
            .iter()
            .map(|&c| {
                // Counted from the first in whole units, exactly, then in seconds.
                let c = if instant {
                    (i128::from(c) - i128::from(first)) as f64
                } else {
                    c as f64
                };
                unit.seconds(c)
            })
            .collect();
        let from = if instant {
            " from its first sample"
        } else {
            ""
        };
        notes.push(format!(
            "time column `{}` holds {what} in {}: read as seconds{from}",
            column.name,
            unit.name()
        ));
        return Ok((t, Some(unit.name().to_owned())));
    }
    let integers = matches!(stored, Stored::Counts(_));
    let t = column.values(stored);
    let Some(unit) = split_unit(&column.name).1 else {
        if integers && arrow_only {
            notes.push(format!(
                "time column `{}` holds integers without a unit: read as seconds (a Polars \
                 Duration's unit is not read: give time in seconds as floats, or its unit in \
                 the name, `{} [ms]`)",
                column.name, column.name
            ));
        }
        return Ok((t, None));
    };
    let per_second = per_second(unit).ok_or_else(|| CoreError::TimeUnit {
        line: None,
        column: column.name.clone(),
        unit: unit.to_owned(),
        path: None,
    })?;
    if per_second != 1.0 {
        notes.push(format!(
            "time column `{}` read in {unit} and converted to seconds",
            column.name
        ));
    }
    Ok((
        t.into_iter().map(|v| v / per_second).collect(),
        Some(unit.to_owned()),
    ))
}

/// Time finite, within range and strictly increasing, each refusal with its row.
fn check_time(t: &[f64], column: &str) -> Result<()> {
    for (i, &ti) in t.iter().enumerate() {
        let at = Location::Row(i);
        if !ti.is_finite() {
            return Err(CoreError::NonFinite {
                at,
                column: column.to_owned(),
                value: ti,
                path: None,
            });
        }
        check_magnitude(ti, ti, column, at)?;
        if i > 0 && ti <= t[i - 1] {
            return Err(CoreError::NonIncreasingTime {
                at,
                t_prev: t[i - 1],
                t: ti,
                path: None,
            });
        }
    }
    Ok(())
}

/// A signal's values finite and within range, each refusal with its row.
fn check_values(values: &[f64], t: &[f64], column: &str) -> Result<()> {
    for (i, (&v, &ti)) in values.iter().zip(t).enumerate() {
        let at = Location::Row(i);
        if !v.is_finite() {
            return Err(CoreError::NonFinite {
                at,
                column: column.to_owned(),
                value: v,
                path: None,
            });
        }
        check_magnitude(v, ti, column, at)?;
    }
    Ok(())
}

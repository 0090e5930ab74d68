//! Reading and writing recordings: CSV text and MCAP files, and reading Parquet files.
//!
//! Each format has a pair of functions per direction: one that works on in-memory data
//! (`read_signals`, `write_signals`) and one that opens the file and adds its path to errors
//! (`read_signals_path`, `write_signals_path`). [`read_recording_path`] and
//! [`write_recording_path`] pick the format from the file extension;
//! [`read_recording_path_with`] also takes [`csv::CsvOptions`] for CSV files as other tools
//! export them (its time column also applies to Parquet files). Parquet is read only (see
//! [`mod@parquet`]); what both table readers share about columns lives in `columns`.

pub mod atomic;
mod columns;
pub mod csv;
pub mod foxglove;
pub mod json_schema;
pub mod mcap;
pub mod parquet;

use std::path::Path;

use crate::error::{CoreError, Result};
use crate::recording::Recording;

/// The file formats a recording can be stored in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// CSV text, extension `.csv` (see [`csv`]).
    Csv,
    /// MCAP, extension `.mcap` (see [`mod@mcap`]).
    Mcap,
    /// Parquet, extension `.parquet` or `.pq` (see [`mod@parquet`]); read only.
    Parquet,
}

impl Format {
    /// The format named by a path's extension (case-insensitive).
    ///
    /// # Errors
    ///
    /// [`CoreError::UnknownExtension`] for any extension other than `csv`, `mcap`, `parquet`
    /// or `pq`, or none.
    pub fn from_path(path: &Path) -> Result<Self> {
        let extension = path
            .extension()
            .map(|e| e.to_string_lossy().into_owned())
            .unwrap_or_default();
        match extension.to_ascii_lowercase().as_str() {
            "csv" => Ok(Self::Csv),
            "mcap" => Ok(Self::Mcap),
            "parquet" | "pq" => Ok(Self::Parquet),
            _ => Err(CoreError::UnknownExtension {
                extension,
                path: Some(path.to_path_buf()),
            }),
        }
    }

    /// The format a recording is written to at `path`: as [`Format::from_path`], Parquet
    /// refused (it is read only). Check it before the work whose result is written.
    ///
    /// # Errors
    ///
    /// As [`Format::from_path`]; [`CoreError::FormatNotSupported`] for Parquet.
    pub fn for_writing(path: &Path) -> Result<Self> {
        match Self::from_path(path)? {
            Self::Parquet => Err(parquet_read_only(path)),
            format => Ok(format),
        }
    }
}

/// The refusal to write a recording (or markers) as Parquet at `path`: modelgap reads
/// Parquet files, it does not write them ([`CoreError::FormatNotSupported`]).
pub fn parquet_read_only(path: &Path) -> CoreError {
    CoreError::FormatNotSupported {
        action: "write a recording as",
        format: "parquet",
        reason: "parquet files are read, not written",
        path: Some(path.to_path_buf()),
    }
}

/// Reads a recording from a `.csv` file, from the [`mcap::DEFAULT_SIGNAL_TOPIC`] topic of a
/// `.mcap` file, or from a `.parquet` (`.pq`) file.
///
/// # Errors
///
/// [`CoreError::UnknownExtension`] for another extension; otherwise as
/// [`csv::read_signals_path`], [`mcap::read_signals_path`] or
/// [`parquet::read_signals_path`].
///
/// # Example
///
/// ```no_run
/// # use std::path::Path;
/// let rec = modelgap_core::io::read_recording_path(Path::new("run1.csv"))?;
/// println!("{} samples of {:?}", rec.len(), rec.names());
/// # Ok::<(), modelgap_core::CoreError>(())
/// ```
pub fn read_recording_path(path: &Path) -> Result<Recording> {
    match Format::from_path(path)? {
        Format::Csv => csv::read_signals_path(path),
        Format::Mcap => mcap::read_signals_path(path, mcap::DEFAULT_SIGNAL_TOPIC),
        Format::Parquet => parquet::read_signals_path(path),
    }
}

/// Reads a recording as [`read_recording_path`] does, a `.csv` file with `options` (see
/// [`csv::read_signals_with`]) and a Parquet file with its time column; returns it with the
/// reader's notes (an index column left out, a unit row read, a time unit converted, a
/// separator or decimal mark detected).
///
/// # Errors
///
/// As [`read_recording_path`]; [`CoreError::InvalidArgument`] for options other than the
/// defaults with an `.mcap` file, which has no columns to choose, and for a delimiter or a
/// decimal mark with a Parquet file, whose columns are typed.
pub fn read_recording_path_with(
    path: &Path,
    options: &csv::CsvOptions,
) -> Result<(Recording, Vec<String>)> {
    match Format::from_path(path)? {
        Format::Csv => {
            let read = csv::read_signals_path_with(path, options)?;
            Ok((read.recording, read.notes))
        }
        Format::Mcap if !options.is_default() => Err(CoreError::InvalidArgument {
            name: "csv options",
            reason: format!(
                "a time column, a delimiter or a decimal mark applies to CSV files; {} is MCAP, \
                 whose time is each message's log time",
                path.display()
            ),
        }),
        Format::Mcap => Ok((
            mcap::read_signals_path(path, mcap::DEFAULT_SIGNAL_TOPIC)?,
            Vec::new(),
        )),
        Format::Parquet if options.delimiter.is_some() || options.decimal_comma.is_some() => {
            Err(CoreError::InvalidArgument {
                name: "csv options",
                reason: format!(
                    "a delimiter or a decimal mark applies to CSV files; {} is Parquet, whose \
                     columns hold typed numbers (the time column may be chosen)",
                    path.display()
                ),
            })
        }
        Format::Parquet => {
            let read = parquet::read_signals_path_with(path, options.time.as_deref())?;
            Ok((read.recording, read.notes))
        }
    }
}

/// Writes a recording to a `.csv` file, or to the [`mcap::DEFAULT_SIGNAL_TOPIC`] topic of a
/// zstd-compressed `.mcap` file.
///
/// # Errors
///
/// [`CoreError::UnknownExtension`] for another extension and
/// [`CoreError::FormatNotSupported`] for Parquet (nothing is written); otherwise as
/// [`csv::write_signals_path`] or [`mcap::write_signals_path`].
pub fn write_recording_path(path: &Path, recording: &Recording) -> Result<()> {
    match Format::from_path(path)? {
        Format::Csv => csv::write_signals_path(recording, path),
        Format::Mcap => mcap::write_signals_path(
            recording,
            path,
            mcap::DEFAULT_SIGNAL_TOPIC,
            mcap::McapCompression::default(),
        ),
        Format::Parquet => Err(parquet_read_only(path)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::Signal;

    #[test]
    fn format_follows_extension_case_insensitively() {
        assert_eq!(
            Format::from_path(Path::new("a/b.CSV")).unwrap(),
            Format::Csv
        );
        assert_eq!(
            Format::from_path(Path::new("b.mcap")).unwrap(),
            Format::Mcap
        );
        for name in ["run.parquet", "run.PQ"] {
            assert_eq!(Format::from_path(Path::new(name)).unwrap(), Format::Parquet);
        }
    }

    #[test]
    fn parquet_is_read_only_and_refuses_csv_layout_options() {
        let rec = Recording::new(vec![0.0], vec![Signal::new("i", vec![0.1])]).unwrap();
        let path = std::env::temp_dir().join(format!("modelgap-core-io-{}.pq", std::process::id()));
        let e = write_recording_path(&path, &rec).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "cannot write a recording as parquet (parquet files are read, not written): \
                 expected a `csv` or `mcap` file in {}",
                path.display()
            )
        );
        assert!(!path.exists());
        let e = read_recording_path_with(&path, &csv::CsvOptions::default().delimiter(b';'))
            .unwrap_err();
        assert!(matches!(e, CoreError::InvalidArgument { .. }), "{e}");
    }

    #[test]
    fn unknown_extension_is_named_in_the_error() {
        let e = Format::from_path(Path::new("data.txt")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown file extension `txt`: expected `csv`, `mcap` or `parquet` (`pq`) in data.txt"
        );
        let e = read_recording_path(Path::new("noext")).unwrap_err();
        assert!(
            matches!(e, CoreError::UnknownExtension { ref extension, .. } if extension.is_empty())
        );
    }

    #[test]
    fn dispatch_round_trips_both_formats() {
        let dir = std::env::temp_dir().join(format!("modelgap-core-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let rec = Recording::new(
            vec![0.0, 0.001, 0.002],
            vec![Signal::new("i", vec![0.1, 0.2, 0.3])],
        )
        .unwrap();
        for name in ["rec.csv", "rec.mcap"] {
            let path = dir.join(name);
            write_recording_path(&path, &rec).unwrap();
            assert_eq!(read_recording_path(&path).unwrap(), rec, "{name}");
        }
        let csv_path = dir.join("rec.csv");
        let (back, notes) =
            read_recording_path_with(&csv_path, &csv::CsvOptions::default().time("t")).unwrap();
        assert_eq!((back, notes), (rec.clone(), Vec::new()));
        let e =
            read_recording_path_with(&dir.join("rec.mcap"), &csv::CsvOptions::default().time("t"))
                .unwrap_err();
        assert!(matches!(e, CoreError::InvalidArgument { .. }), "{e}");
        let bad = dir.join("rec.json");
        assert!(write_recording_path(&bad, &rec).is_err());
        assert!(!bad.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

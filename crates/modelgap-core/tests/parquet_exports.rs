//! Recordings as pandas and Polars write them to Parquet (issue 16, item 3): the committed
//! files in `tests/data/parquet/` (made by `make.py` there from the first 250 samples of the
//! bundled motor recording) read as the CSV's samples; each bad file is refused, typed, naming
//! the file, the column and the row; a damaged file never panics.

#![allow(clippy::unwrap_used)] // in test helpers, a panic is a test failure

use std::path::{Path, PathBuf};

use modelgap_core::error::Location;
use modelgap_core::io::csv::CsvOptions;
use modelgap_core::io::parquet::{ParquetRecording, read_signals, read_signals_path_with};
use modelgap_core::io::{read_recording_path, read_recording_path_with};
use modelgap_core::{CoreError, Recording};

/// The samples each fixture holds: the first 250 of the motor recording.
const ROWS: usize = 250;

/// Float64 values are written by pyarrow from Python's correctly rounded parse of the CSV's
/// text, as Rust parses it: they agree to the bit; 1e-12 leaves room for nothing else.
const EXACT: f64 = 1e-12;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/parquet")
        .join(name)
}

/// The first [`ROWS`] samples of the bundled motor recording, read from its CSV.
fn motor() -> Recording {
    let csv =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/data/motor_hidden_effect.csv");
    let full = read_recording_path(&csv).unwrap();
    Recording::new(
        full.t()[..ROWS].to_vec(),
        full.signals()
            .iter()
            .map(|s| modelgap_core::Signal::new(s.name.clone(), s.values[..ROWS].to_vec()))
            .collect(),
    )
    .unwrap()
}

fn read(name: &str) -> ParquetRecording {
    read_with(name, None)
}

fn read_with(name: &str, time: Option<&str>) -> ParquetRecording {
    match read_signals_path_with(&fixture(name), time) {
        Ok(read) => read,
        Err(e) => panic!("{name}: {e}"),
    }
}

fn refuse(name: &str) -> CoreError {
    match read_signals_path_with(&fixture(name), None) {
        Ok(read) => panic!(
            "{name}: expected an error, read {:?}",
            read.recording.names()
        ),
        Err(e) => e,
    }
}

fn assert_close(name: &str, what: &str, found: &[f64], expected: &[f64], tolerance: f64) {
    assert_eq!(found.len(), expected.len(), "{name}: {what}");
    for (k, (a, b)) in found.iter().zip(expected).enumerate() {
        assert!(
            (a - b).abs() <= tolerance,
            "{name}: {what}[{k}] = {a}, expected {b}"
        );
    }
}

/// `read` holds the motor's `t`, `V`, `i`, `omega` (in any order) to `tolerance`.
fn assert_motor(name: &str, read: &ParquetRecording, tolerance: f64) {
    let rec = &read.recording;
    let motor = motor();
    assert_close(name, "t", rec.t(), motor.t(), EXACT);
    let mut names = rec.names();
    names.sort_unstable();
    assert_eq!(names, vec!["V", "i", "omega"], "{name}");
    for signal in motor.signals() {
        let values = rec.values(&signal.name).unwrap();
        assert_close(name, &signal.name, values, &signal.values, tolerance);
    }
}

#[test]
fn pandas_default_reads_as_the_csv_and_notes_the_range_index() {
    // `df.to_parquet(path)`: pyarrow, Snappy, the RangeIndex in the pandas metadata only.
    let read = read("pandas_default.parquet");
    assert_motor("pandas_default", &read, EXACT);
    assert_eq!(read.recording.names(), vec!["V", "i", "omega"]);
    assert_eq!(read.time_column, "t");
    assert_eq!(read.time_unit, None);
    assert_eq!(
        read.notes,
        vec![
            "the pandas index (rows 0 to 249) is kept in the file's metadata, not as a column: \
             left out"
        ]
    );
}

#[test]
fn pandas_index_stored_as_a_column_is_left_out_with_a_note() {
    // `df.to_parquet(path, index=True)`: `__index_level_0__` holds 1000, 1001, …
    let read = read("pandas_index.parquet");
    assert_motor("pandas_index", &read, EXACT);
    assert_eq!(read.recording.names(), vec!["V", "i", "omega"]);
    assert_eq!(
        read.notes,
        vec!["column `__index_level_0__` holds the pandas index: left out"]
    );
}

#[test]
fn time_is_found_anywhere_and_units_come_from_the_names() {
    // Columns `V [V]`, `omega [rad/s]`, `t`, `i [A]`, `index=False`.
    let read = read("pandas_reordered.parquet");
    assert_motor("pandas_reordered", &read, EXACT);
    assert_eq!(read.recording.names(), vec!["V", "omega", "i"]);
    assert_eq!(read.unit("V"), Some("V"));
    assert_eq!(read.unit("omega"), Some("rad/s"));
    assert_eq!(read.unit("i"), Some("A"));
    assert!(read.notes.is_empty(), "{:?}", read.notes);
}

#[test]
fn polars_default_zstd_reads_as_the_csv() {
    let read = read("polars_default.parquet");
    assert_motor("polars_default", &read, EXACT);
    assert!(read.notes.is_empty(), "{:?}", read.notes);
}

#[test]
fn several_row_groups_read_as_one_recording() {
    // Five row groups of 50 rows, pages of 256 bytes.
    let read = read("row_groups.parquet");
    assert_motor("row_groups", &read, EXACT);
}

#[test]
fn integer_and_float32_columns_read_as_numbers() {
    // `V` int32, `i` float32, `count` int64 (3 k - 7), `code` uint16 (60000 + k % 7).
    let read = read("types.parquet");
    let rec = &read.recording;
    let motor = motor();
    assert_close("types", "t", rec.t(), motor.t(), EXACT);
    assert_close(
        "types",
        "V",
        rec.values("V").unwrap(),
        motor.values("V").unwrap(),
        0.0,
    );
    let i32: Vec<f64> = motor
        .values("i")
        .unwrap()
        .iter()
        .map(|&v| f64::from(v as f32))
        .collect();
    // float32 holds `i` to 2^-24 of its value; read back, it is that float32 exactly.
    assert_close("types", "i", rec.values("i").unwrap(), &i32, 0.0);
    let count: Vec<f64> = (0..ROWS).map(|k| 3.0 * k as f64 - 7.0).collect();
    assert_close("types", "count", rec.values("count").unwrap(), &count, 0.0);
    let code: Vec<f64> = (0..ROWS).map(|k| 60_000.0 + (k % 7) as f64).collect();
    assert_close("types", "code", rec.values("code").unwrap(), &code, 0.0);
}

#[test]
fn timestamps_count_in_seconds_from_the_first_sample() {
    // pandas: a DatetimeIndex named `time` (ns) from 2024-05-01 12:00, no `t`; Polars: a
    // Datetime("us") column `time`.
    for (name, unit) in [
        ("pandas_datetime_index.parquet", "ns"),
        ("polars_datetime.parquet", "us"),
    ] {
        let read = read(name);
        assert_motor(name, &read, EXACT);
        assert_eq!(read.time_column, "time", "{name}");
        assert_eq!(read.time_unit.as_deref(), Some(unit), "{name}");
        assert_eq!(
            read.notes,
            vec![format!(
                "time column `time` holds timestamps in {unit}: read as seconds from its first \
                 sample"
            )],
            "{name}"
        );
    }
}

#[test]
fn pandas_timedelta_time_is_converted_to_seconds() {
    // `t` as timedelta64[ns]: Parquet int64, the unit in pandas' metadata.
    let read = read("pandas_timedelta.parquet");
    assert_motor("pandas_timedelta", &read, EXACT);
    assert_eq!(read.time_unit.as_deref(), Some("ns"));
    assert_eq!(
        read.notes,
        vec!["time column `t` holds durations in ns: read as seconds"]
    );
}

#[test]
fn time_option_names_a_column_with_its_unit_converted() {
    // `Unnamed: 0` (0, 1, …) first, then `stamp [ms]`: no `t`, so time must be named.
    let e = read_signals_path_with(&fixture("stamp_ms.parquet"), None).unwrap_err();
    assert!(
        matches!(e, CoreError::MissingTimeColumn { line: None, asked: None, ref columns, .. }
            if columns == &["Unnamed: 0", "stamp [ms]", "V", "i", "omega"]),
        "{e}"
    );
    assert!(
        e.to_string().starts_with(
            "missing column `t`: the file has no column `t` or `time` (with or without a unit); \
             the file's columns are `Unnamed: 0`, `stamp [ms]`, `V`, `i`, `omega`: choose the \
             time column with the time option (`--time COL`) in "
        ),
        "{e}"
    );
    for asked in ["stamp", "stamp [ms]"] {
        let read = read_with("stamp_ms.parquet", Some(asked));
        assert_motor("stamp_ms", &read, EXACT);
        assert_eq!(read.time_unit.as_deref(), Some("ms"));
        assert_eq!(
            read.notes,
            vec![
                "time column `stamp [ms]` read in ms and converted to seconds",
                "the first column `Unnamed: 0` holds the row numbers 0 to 249: read as a row \
                 index and left out",
            ]
        );
    }
    let e = read_signals_path_with(&fixture("stamp_ms.parquet"), Some("when")).unwrap_err();
    assert!(
        matches!(e, CoreError::MissingTimeColumn { asked: Some(ref a), .. } if a == "when"),
        "{e}"
    );
}

#[test]
fn read_recording_path_dispatches_and_takes_the_time_option() {
    let path = fixture("stamp_ms.parquet");
    let (rec, notes) =
        read_recording_path_with(&path, &CsvOptions::default().time("stamp")).unwrap();
    assert_eq!(rec.len(), ROWS);
    assert_eq!(notes.len(), 2);
    let rec = read_recording_path(&fixture("polars_default.parquet")).unwrap();
    assert_eq!(rec, read("polars_default.parquet").recording);
    for options in [
        CsvOptions::default().delimiter(b';'),
        CsvOptions::default().decimal_comma(true),
    ] {
        let e = read_recording_path_with(&path, &options).unwrap_err();
        assert!(matches!(e, CoreError::InvalidArgument { .. }), "{e}");
        assert!(e.to_string().contains("is Parquet"), "{e}");
    }
}

/// The message ends with ` in <the fixture's path>`.
fn assert_in_file(e: &CoreError, name: &str) {
    let path = fixture(name);
    assert_eq!(e.path(), Some(path.as_path()), "{e}");
    assert!(
        e.to_string().ends_with(&format!(" in {}", path.display())),
        "{e}"
    );
}

#[test]
fn a_null_is_refused_with_its_row_and_column() {
    // pandas wrote NaN at row 7 of `i` as null.
    let e = refuse("null_value.parquet");
    assert!(
        matches!(e, CoreError::MissingValue { at: Location::Row(7), ref column, .. } if column == "i"),
        "{e}"
    );
    assert!(
        e.to_string()
            .starts_with("missing value (null) at row 7, column `i`"),
        "{e}"
    );
    assert_in_file(&e, "null_value.parquet");
}

#[test]
fn a_nan_is_refused_with_its_row_and_column() {
    // Polars keeps NaN: row 9 of `omega`.
    let e = refuse("nan_value.parquet");
    assert!(
        matches!(e, CoreError::NonFinite { at: Location::Row(9), ref column, .. } if column == "omega"),
        "{e}"
    );
    assert!(
        e.to_string()
            .starts_with("value NaN is not finite at row 9, column `omega`"),
        "{e}"
    );
    assert_in_file(&e, "nan_value.parquet");
}

#[test]
fn a_text_column_is_refused_by_name() {
    let e = refuse("string_column.parquet");
    assert!(
        matches!(e, CoreError::ColumnType { ref column, .. } if column == "mode"),
        "{e}"
    );
    assert!(
        e.to_string()
            .starts_with("column `mode` holds text (BYTE_ARRAY, String), not numbers"),
        "{e}"
    );
    assert_in_file(&e, "string_column.parquet");
}

#[test]
fn time_that_goes_back_is_refused_with_its_row() {
    // Rows 11 and 12 swapped.
    let e = refuse("time_not_increasing.parquet");
    assert!(
        matches!(e, CoreError::NonIncreasingTime { at: Location::Row(12), t, t_prev, .. }
            if t == 0.011 && t_prev == 0.012),
        "{e}"
    );
    assert!(
        e.to_string()
            .starts_with("time is not strictly increasing at row 12: 0.011 s after 0.012 s"),
        "{e}"
    );
    assert_in_file(&e, "time_not_increasing.parquet");
}

#[test]
fn a_codec_modelgap_does_not_read_is_named() {
    let e = refuse("gzip.parquet");
    assert!(
        matches!(e, CoreError::ParquetCodec { ref codec, .. } if codec == "gzip"),
        "{e}"
    );
    assert!(e.to_string().contains("compressed with gzip"), "{e}");
    assert_in_file(&e, "gzip.parquet");
}

#[test]
fn a_truncated_file_is_refused_naming_the_file() {
    let e = refuse("truncated.parquet");
    assert!(matches!(e, CoreError::ParquetCorrupt { .. }), "{e}");
    assert!(
        e.to_string()
            .starts_with("parquet data is truncated or corrupt: "),
        "{e}"
    );
    assert_in_file(&e, "truncated.parquet");
    let missing = fixture("missing.parquet");
    let e = read_signals_path_with(&missing, None).unwrap_err();
    assert!(matches!(e, CoreError::Io { .. }), "{e}");
    assert_eq!(e.path(), Some(missing.as_path()));
}

#[test]
fn damaged_files_are_errors_never_panics() {
    // Every cut of three exports, and every byte of them flipped: an error or (a flipped
    // value) a recording, never a panic.
    for name in [
        "pandas_default.parquet",
        "row_groups.parquet",
        "polars_default.parquet",
    ] {
        let bytes = std::fs::read(fixture(name)).unwrap();
        for cut in 0..bytes.len() {
            let e = read_signals(&bytes[..cut]).unwrap_err();
            assert!(
                matches!(e, CoreError::ParquetCorrupt { .. }),
                "{name} cut at {cut}: {e}"
            );
        }
        let mut flipped = bytes.clone();
        for (k, &byte) in bytes.iter().enumerate() {
            flipped[k] = byte ^ 0xA5;
            let _ = read_signals(&flipped);
            flipped[k] = byte;
        }
    }
    // One to four bytes set at random (xorshift, fixed seed) in pandas' default file: the
    // 2747th such file makes the parquet crate's BYTE_STREAM_SPLIT decoder index out of
    // bounds (a panic, in release builds too), which the reader reports as a corrupt file.
    let bytes = std::fs::read(fixture("pandas_default.parquet")).unwrap();
    let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let mut decoder_failures = 0;
    for _ in 0..3000 {
        let mut damaged = bytes.clone();
        for _ in 0..=next() % 4 {
            let k = (next() % bytes.len() as u64) as usize;
            damaged[k] = (next() & 0xFF) as u8;
        }
        if let Err(e) = read_signals(&damaged)
            && e.to_string().contains("the parquet decoder failed")
        {
            decoder_failures += 1;
        }
    }
    assert!(
        decoder_failures > 0,
        "no damage reached the decoder's panic"
    );
}

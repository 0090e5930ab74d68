//! Parquet recordings through the command line (issue 16, item 3): `modelgap compare` on
//! what pandas and Polars write (the committed files in
//! `crates/modelgap-core/tests/data/parquet/`, the first 250 samples of the bundled motor
//! recording) gives the numbers of the CSV of the same rows; `--time` applies, CSV-only
//! options and a bad file are refused naming the file, column and row; Parquet is not
//! written.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in test helpers, a panic is a test failure

use std::path::PathBuf;
use std::process::{Command, Output};

use serde_json::Value;

/// The bundled motor recording (`t,V,i,omega`, comment lines first).
const MOTOR_CSV: &str = include_str!("../examples/data/motor_hidden_effect.csv");

/// The samples each Parquet fixture holds.
const ROWS: usize = 250;

fn fixture(name: &str) -> String {
    format!(
        "{}/crates/modelgap-core/tests/data/parquet/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn modelgap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_modelgap"))
        .args(args)
        .output()
        .expect("the modelgap binary runs")
}

/// Runs `modelgap`, asserting success, and returns standard output.
fn ok(args: &[&str]) -> String {
    let out = modelgap(args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "modelgap {args:?} failed with {:?}\nstdout:\n{stdout}\nstderr:\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// Runs `modelgap`, asserting it refuses the input (exit code 2), and returns standard error.
fn refused(args: &[&str]) -> String {
    let out = modelgap(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "modelgap {args:?}\n{stderr}");
    stderr
}

/// A directory for one test, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(test: &str) -> Self {
        let dir = std::env::temp_dir().join(format!(
            "modelgap-cli-parquet-{}-{test}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// `compare --json` on `data`, without the fields that name the file and the reader's notes.
fn comparison(data: &str, extra: &[&str]) -> (Value, Value) {
    let mut args = vec!["compare", "--model", "dc-motor", "--data", data, "--json"];
    args.extend(extra);
    let mut value: Value = serde_json::from_str(&ok(&args)).unwrap();
    let object = value.as_object_mut().unwrap();
    object.remove("data");
    let notes = object.remove("notes").unwrap();
    (value, notes)
}

/// The first [`ROWS`] samples of the motor recording as CSV, written in `dir`.
fn motor_csv(dir: &TempDir) -> String {
    let mut lines = MOTOR_CSV.lines().filter(|l| !l.starts_with('#'));
    let mut text = String::new();
    for line in lines.by_ref().take(ROWS + 1) {
        text.push_str(line);
        text.push('\n');
    }
    let path = dir.0.join("motor.csv");
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn pandas_and_polars_exports_compare_as_the_csv_of_the_same_rows() {
    let dir = TempDir::new("exports");
    let (expected, notes) = comparison(&motor_csv(&dir), &[]);
    assert_eq!(notes, Value::Array(Vec::new()));
    for (name, note) in [
        (
            "pandas_default.parquet",
            Some(
                "the pandas index (rows 0 to 249) is kept in the file's metadata, not as a \
                 column: left out",
            ),
        ),
        ("polars_default.parquet", None),
        ("row_groups.parquet", None),
        (
            "pandas_index.parquet",
            Some("column `__index_level_0__` holds the pandas index: left out"),
        ),
    ] {
        let (value, notes) = comparison(&fixture(name), &[]);
        assert_eq!(value, expected, "{name}: the numbers differ from the CSV's");
        let notes: Vec<&str> = notes
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_str().unwrap())
            .collect();
        assert_eq!(notes, note.into_iter().collect::<Vec<_>>(), "{name}");
    }
    // Time in milliseconds, named by `--time`.
    let (value, _) = comparison(&fixture("stamp_ms.parquet"), &["--time", "stamp"]);
    assert_eq!(value, expected, "stamp_ms.parquet --time stamp");
}

#[test]
fn bad_files_and_csv_options_are_refused_naming_what_and_where() {
    let null = fixture("null_value.parquet");
    let stderr = refused(&["compare", "--model", "dc-motor", "--data", &null]);
    assert!(
        stderr.contains(&format!(
            "missing value (null) at row 7, column `i`: every sample needs a value in {null}"
        )),
        "{stderr}"
    );
    let text = fixture("string_column.parquet");
    let stderr = refused(&["explain", "--model", "dc-motor", "--data", &text]);
    assert!(
        stderr.contains("column `mode` holds text") && stderr.contains(&text),
        "{stderr}"
    );
    let truncated = fixture("truncated.parquet");
    let stderr = refused(&["compare", "--model", "dc-motor", "--data", &truncated]);
    assert!(
        stderr.contains("parquet data is truncated or corrupt") && stderr.contains(&truncated),
        "{stderr}"
    );
    let good = fixture("polars_default.parquet");
    for option in [&["--delimiter", ";"][..], &["--decimal-comma"]] {
        let mut args = vec!["compare", "--model", "dc-motor", "--data", &good];
        args.extend(option);
        let stderr = refused(&args);
        assert!(
            stderr.contains("applies to CSV files") && stderr.contains("is Parquet"),
            "{option:?}: {stderr}"
        );
    }
}

#[test]
fn parquet_is_not_written() {
    let dir = TempDir::new("write");
    let out = dir.0.join("run.parquet").to_string_lossy().into_owned();
    let stderr = refused(&[
        "bond",
        "simulate",
        "--model",
        "dc-motor",
        "--duration",
        "0.01",
        "--out",
        &out,
    ]);
    assert!(
        stderr.contains(&format!(
            "cannot write a recording as parquet (parquet files are read, not written): \
             expected a `csv` or `mcap` file in {out}"
        )),
        "{stderr}"
    );
    assert!(!PathBuf::from(&out).exists());
}

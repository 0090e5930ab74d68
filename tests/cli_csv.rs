//! The bundled motor recording as pandas, R and a spreadsheet would export it (issue 16,
//! item 3): `modelgap compare` reads each as it is and gives the numbers of the original;
//! `--time` names a time column that is not `t`; the reader's notes reach the user.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in test helpers, a panic is a test failure

use std::path::PathBuf;
use std::process::{Command, Output};

use serde_json::Value;

/// The bundled motor recording (`t,V,i,omega`, comment lines first).
const MOTOR_CSV: &str = include_str!("../examples/data/motor_hidden_effect.csv");

fn modelgap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_modelgap"))
        .args(args)
        .output()
        .expect("the modelgap binary runs")
}

/// Runs `modelgap` and returns standard output and standard error, asserting success.
fn ok(args: &[&str]) -> (String, String) {
    let out = modelgap(args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        out.status.success(),
        "modelgap {args:?} failed with {:?}\nstdout:\n{stdout}\nstderr:\n{stderr}",
        out.status.code()
    );
    (stdout, stderr)
}

/// A directory for one test, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(test: &str) -> Self {
        let dir =
            std::env::temp_dir().join(format!("modelgap-cli-csv-{}-{test}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }

    /// Writes `text` to `name` and returns its path.
    fn write(&self, name: &str, text: &str) -> String {
        let path = self.0.join(name);
        std::fs::write(&path, text).unwrap();
        path.to_string_lossy().into_owned()
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The motor recording's data rows (`t,V,i,omega` values as written).
fn rows() -> Vec<&'static str> {
    MOTOR_CSV
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .collect()
}

/// `compare --json` on `data`, without the fields that name the file and the reader's notes.
fn comparison(data: &str, extra: &[&str]) -> (Value, Value) {
    let mut args = vec!["compare", "--model", "dc-motor", "--data", data, "--json"];
    args.extend(extra);
    let (stdout, _) = ok(&args);
    let mut value: Value = serde_json::from_str(&stdout).unwrap();
    let object = value.as_object_mut().unwrap();
    object.remove("data");
    let notes = object.remove("notes").unwrap();
    (value, notes)
}

#[test]
fn pandas_r_and_spreadsheet_exports_compare_as_the_original() {
    let dir = TempDir::new("exports");
    let original = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/data/motor_hidden_effect.csv"
    );
    let (expected, notes) = comparison(original, &[]);
    assert_eq!(notes, Value::Array(Vec::new()));

    // pandas: `df.to_csv("run.csv")`, an unnamed index column of row numbers from 0.
    let mut pandas = String::from(",t,V,i,omega\n");
    // R: `write.csv(df, "run.csv")`, the header quoted, quoted row names from 1.
    let mut r = String::from("\"\",\"t\",\"V\",\"i\",\"omega\"\n");
    // A spreadsheet in a decimal-comma locale: BOM, units, `;`, CRLF.
    let mut sheet = String::from("\u{feff}Time [s];V [V];i [A];omega [rad/s]\r\n");
    for (k, row) in rows().iter().enumerate() {
        pandas.push_str(&format!("{k},{row}\n"));
        r.push_str(&format!("\"{}\",{row}\n", k + 1));
        sheet.push_str(&format!("{}\r\n", row.replace(',', ";").replace('.', ",")));
    }
    let n = rows().len();
    for (name, text, note) in [
        (
            "pandas.csv",
            pandas,
            format!(
                "the first column (unnamed) holds the row numbers 0 to {}: read as a row index \
                 and left out",
                n - 1
            ),
        ),
        (
            "r.csv",
            r,
            format!(
                "the first column (unnamed) holds the row numbers 1 to {n}: read as a row index \
                 and left out"
            ),
        ),
        (
            "sheet.csv",
            sheet,
            "read with `;` between cells and decimal commas".to_owned(),
        ),
    ] {
        let path = dir.write(name, &text);
        let (value, notes) = comparison(&path, &[]);
        assert_eq!(
            value, expected,
            "{name}: the numbers differ from the original's"
        );
        assert_eq!(notes, serde_json::json!([note]), "{name}");
    }
}

#[test]
fn time_option_names_the_time_column_and_is_carried_into_the_hint() {
    let dir = TempDir::new("time");
    let mut text = String::from("V,i,omega,stamp\n");
    for row in rows() {
        let (t, rest) = row.split_once(',').unwrap();
        text.push_str(&format!("{rest},{t}\n"));
    }
    let path = dir.write("stamp.csv", &text);

    let out = modelgap(&["compare", "--model", "dc-motor", "--data", &path]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("its columns are `V`, `i`, `omega`, `stamp`")
            && stderr.contains("--time COL"),
        "{stderr}"
    );

    let original = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/data/motor_hidden_effect.csv"
    );
    let (expected, _) = comparison(original, &[]);
    let (value, _) = comparison(&path, &["--time", "stamp"]);
    assert_eq!(value, expected);
    // The "next:" hint repeats the option, so the suggested command reads the file too.
    let (stdout, _) = ok(&[
        "compare", "--model", "dc-motor", "--data", &path, "--time", "stamp",
    ]);
    assert!(stdout.contains("--time stamp`"), "{stdout}");
}

#[test]
fn reader_notes_go_to_standard_error_in_text_mode() {
    let dir = TempDir::new("notes");
    let mut text = String::from("t;V;i;omega\ns;V;A;rad/s\n");
    for row in rows().iter().take(400) {
        text.push_str(&format!("{}\n", row.replace(',', ";")));
    }
    let path = dir.write("units.csv", &text);
    let (_, stderr) = ok(&[
        "compare",
        "--model",
        "dc-motor",
        "--data",
        &path,
        "--delimiter",
        ";",
    ]);
    assert!(
        stderr.contains("note: line 2 read as the columns' units"),
        "{stderr}"
    );
    // Declared, the separator is not reported as detected.
    assert!(!stderr.contains("between cells"), "{stderr}");
}

#[test]
fn csv_options_are_refused_for_a_cloth_scene_and_an_mcap_file() {
    let cloth = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/data/cloth_hidden_effect.csv"
    );
    let out = modelgap(&[
        "compare", "--model", "corner", "--data", cloth, "--time", "t",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("marker files"), "{stderr}");

    let dir = TempDir::new("mcap");
    let csv = dir.write("run.csv", MOTOR_CSV);
    let mcap = dir.0.join("run.mcap").to_string_lossy().into_owned();
    let rec = modelgap::io::read_recording_path(csv.as_ref()).unwrap();
    modelgap::io::write_recording_path(mcap.as_ref(), &rec).unwrap();
    let out = modelgap(&[
        "compare",
        "--model",
        "dc-motor",
        "--data",
        &mcap,
        "--decimal-comma",
    ]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("applies to CSV files"), "{stderr}");
}

//! End-to-end tests of the measurement loop on cloth through the command line: `compare`,
//! `explain` and `fix` with a scene file as `--model` and a marker recording as `--data`,
//! run as the built executable on a hidden-effect recording written to a temporary
//! directory; and the errors a bad scene or markers file gives (file, line, field, exit 2).

#![allow(clippy::unwrap_used, clippy::expect_used)] // in test helpers, a panic is a test failure

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use modelgap::cloth::hidden::{HiddenCase, RecordingOptions, cases, record};
use modelgap::cloth::markers::write_markers_csv_path;
use modelgap::cloth::model::recording_to_markers;
use modelgap::cloth::report::{CLOTH_ERROR_AFTER_TOPIC, CLOTH_ERROR_TOPIC};
use serde_json::Value;

/// Vertices per side of the test cloth: small, so the binary (built without full
/// optimisation for tests) explains it in seconds.
const GRID: usize = 7;

/// Runs `modelgap` with `args`.
fn modelgap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_modelgap"))
        .args(args)
        .output()
        .expect("the modelgap binary runs")
}

/// Runs `modelgap` with `args`, asserts success and returns its standard output.
fn ok(args: &[&str]) -> String {
    let out = modelgap(args);
    assert!(
        out.status.success(),
        "modelgap {args:?} failed with {:?}\nstdout:\n{}\nstderr:\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Runs `modelgap` with `args`, asserts it fails with exit code 2 without a panic and
/// returns its standard error.
fn bad_input(args: &[&str]) -> String {
    let out = modelgap(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(
        out.status.code(),
        Some(2),
        "modelgap {args:?}: expected exit code 2\nstdout:\n{}\nstderr:\n{stderr}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    stderr
}

/// Runs `modelgap` with `args` and parses its standard output as JSON.
fn json(args: &[&str]) -> Value {
    let text = ok(args);
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}: not JSON:\n{text}"))
}

/// A fresh directory for one test, unique per process and test name, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(test: &str) -> Self {
        let dir =
            std::env::temp_dir().join(format!("modelgap-cloth-loop-{}-{test}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }

    fn path(&self, name: &str) -> String {
        self.0.join(name).to_string_lossy().into_owned()
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn case(name: &str) -> HiddenCase {
    cases(GRID, GRID)
        .into_iter()
        .find(|c| c.name == name)
        .expect("a cloth hidden-effect case of that name")
}

/// Writes the nominal scene of a case and its marker recording (CSV) into `dir`; returns
/// (scene path, markers path).
fn scene_and_markers(dir: &TempDir, name: &str) -> (String, String) {
    let case = case(name);
    let rec = record(&case, &RecordingOptions::default()).unwrap();
    let markers = recording_to_markers(&rec).unwrap();
    let data = dir.path("markers.csv");
    write_markers_csv_path(&markers, Path::new(&data)).unwrap();
    let scene = dir.path("scene.toml");
    std::fs::write(&scene, case.scene.to_toml().unwrap()).unwrap();
    (scene, data)
}

fn number(v: &Value, key: &str) -> f64 {
    v.get(key)
        .and_then(Value::as_f64)
        .unwrap_or_else(|| panic!("no number `{key}` in {v}"))
}

#[test]
fn compare_explain_fix_find_the_hidden_drag_and_the_error_falls() {
    let dir = TempDir::new("drag");
    let (scene, data) = scene_and_markers(&dir, "drag");
    let report = dir.path("report");

    // compare: where and when the scene fails.
    let text = ok(&["compare", "--model", &scene, "--data", &data]);
    for needle in [
        "worst markers: m",
        "worst regions",
        "fails (",
        "next: `modelgap explain",
    ] {
        assert!(text.contains(needle), "`{needle}` not in:\n{text}");
    }
    let c = json(&[
        "compare", "--model", &scene, "--data", &data, "--json", "--report", &report,
    ]);
    let rms = number(&c, "rms");
    let floor = number(&c, "noise_floor");
    assert!(
        rms > 3.0 * floor,
        "drag must show: RMS {rms} m, floor {floor} m"
    );
    // 1 mm of noise per coordinate: a 3D floor near √3 mm.
    assert!(floor > 1e-3 && floor < 2.5e-3, "{floor}");
    assert_eq!(c["markers"].as_array().unwrap().len(), 9);
    assert!(!c["windows"].as_array().unwrap().is_empty(), "{c}");
    assert!(!c["regions"].as_array().unwrap().is_empty(), "{c}");
    assert_eq!(c["worst_markers"].as_array().unwrap().len(), 5);
    let html = std::fs::read_to_string(Path::new(&report).join("report.html")).unwrap();
    assert!(html.contains("RMS marker error per vertex"), "no error map");
    assert!(
        html.contains("marker error over time"),
        "no error over time"
    );
    let mcap = std::fs::read(Path::new(&report).join("comparison.mcap")).unwrap();
    let scenes = modelgap::io::mcap::read_topic_messages(&mcap, CLOTH_ERROR_TOPIC).unwrap();
    assert_eq!(scenes.len(), 201);
    assert_eq!(
        modelgap::io::mcap::read_topic_messages(&mcap, "/tf")
            .unwrap()
            .len(),
        1
    );
    let checked =
        modelgap::io::mcap::check_messages(&mcap, modelgap::io::json_schema::Strictness::Complete)
            .unwrap();
    assert_eq!(checked.len(), 5, "{checked:?}");

    // explain: drag first, the error falls to the floor.
    let ex = json(&["explain", "--model", &scene, "--data", &data, "--json"]);
    assert_eq!(ex["chosen"][0]["id"], "air-drag", "{}", ex["verdict_text"]);
    let before = number(&ex["marker_rms"], "before");
    let after = number(&ex["marker_rms"], "after");
    assert!(after < 0.5 * before, "{before} -> {after}");

    // fix: the scene file with the new term, whose error is lower.
    let fixed = dir.path("fixed.toml");
    let report_fixed = dir.path("report-fixed");
    let text = ok(&[
        "fix",
        "--model",
        &scene,
        "--data",
        &data,
        "--out",
        &fixed,
        "--report",
        &report_fixed,
    ]);
    assert!(
        text.contains("added: ") && text.contains("error before → after"),
        "{text}"
    );
    let written = std::fs::read_to_string(&fixed).unwrap();
    assert!(
        written.contains("[air]") && written.contains("drag_coefficient"),
        "{written}"
    );
    let mcap = std::fs::read(Path::new(&report_fixed).join("comparison.mcap")).unwrap();
    assert_eq!(
        modelgap::io::mcap::read_topic_messages(&mcap, CLOTH_ERROR_AFTER_TOPIC)
            .unwrap()
            .len(),
        201
    );
    let c_fixed = json(&["compare", "--model", &fixed, "--data", &data, "--json"]);
    let rms_fixed = number(&c_fixed, "rms");
    assert!(rms_fixed < 0.5 * rms, "{rms} -> {rms_fixed}");
    assert!(rms_fixed < 2.0 * floor, "{rms_fixed} vs floor {floor}");

    // fix refuses to overwrite its input scene.
    let err = bad_input(&["fix", "--model", &scene, "--data", &data, "--out", &scene]);
    assert!(err.contains("input model file"), "{err}");
}

#[test]
fn marker_outside_the_mesh_names_the_file_line_and_field() {
    let dir = TempDir::new("outside");
    let scene = dir.path("scene.toml");
    std::fs::write(&scene, case("nothing").scene.to_toml().unwrap()).unwrap();
    let data = dir.path("markers.csv");
    // The 7 × 7 grid has vertices 0 to 48; id 49 on line 4 is past it.
    std::fs::write(
        &data,
        "t,id,x,y,z\n0,0,0,0,0\n0,48,1,0,-1\n0,49,1,0,-1\n0.01,0,0,0,0\n0.01,48,1,0,-1\n0.01,49,1,0,-1\n",
    )
    .unwrap();
    for command in ["compare", "explain"] {
        let err = bad_input(&[command, "--model", &scene, "--data", &data]);
        for needle in ["marker id 49", "line 4", "`id`", "markers.csv", "0 to 48"] {
            assert!(err.contains(needle), "`{needle}` not in:\n{err}");
        }
    }
    let err = bad_input(&[
        "fix",
        "--model",
        &scene,
        "--data",
        &data,
        "--out",
        &dir.path("x.toml"),
    ]);
    assert!(err.contains("line 4"), "{err}");
}

#[test]
fn malformed_marker_line_names_the_file_line_and_field() {
    let dir = TempDir::new("malformed");
    let scene = dir.path("scene.toml");
    std::fs::write(&scene, case("nothing").scene.to_toml().unwrap()).unwrap();
    let data = dir.path("markers.csv");
    std::fs::write(&data, "t,id,x,y,z\n0,0,0,0,0\n0.01,0,zero,0,0\n").unwrap();
    let err = bad_input(&["compare", "--model", &scene, "--data", &data]);
    for needle in ["line 3", "`x`", "zero", "markers.csv"] {
        assert!(err.contains(needle), "`{needle}` not in:\n{err}");
    }
    let missing = dir.path("missing.csv");
    let err = bad_input(&["compare", "--model", &scene, "--data", &missing]);
    assert!(
        err.contains("missing.csv") && err.contains("not found"),
        "{err}"
    );
}

#[test]
fn bad_scene_and_bond_options_are_refused_with_the_reason() {
    let dir = TempDir::new("scene");
    let (scene, data) = scene_and_markers(&dir, "nothing");
    let broken = dir.path("broken.toml");
    std::fs::write(
        &broken,
        "name = 'x'\nduration = 1.0\ndt = -0.01\n[cloth]\nnx = 3\nnz = 3\nsize = 1.0\n",
    )
    .unwrap();
    let err = bad_input(&["compare", "--model", &broken, "--data", &data]);
    assert!(
        err.contains("broken.toml") && err.contains("dt must be positive"),
        "{err}"
    );
    let err = bad_input(&[
        "compare", "--model", &scene, "--data", &data, "--set", "R=1",
    ]);
    assert!(err.contains("--set") && err.contains("scene file"), "{err}");
    let err = bad_input(&[
        "compare",
        "--model",
        &scene,
        "--data",
        &data,
        "--noise",
        "m999.x=0.001",
    ]);
    assert!(err.contains("m999.x"), "{err}");
}

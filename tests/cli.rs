//! End-to-end tests of the `modelgap` binary: each runs the built executable and checks its
//! output, its files and its exit code.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in test helpers, a panic is a test failure

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use modelgap::io::read_recording_path;

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

/// Runs `modelgap` with `args`, asserts it fails with `code` and returns its standard error.
fn fails(args: &[&str], code: i32) -> String {
    let out = modelgap(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(
        out.status.code(),
        Some(code),
        "modelgap {args:?}: expected exit code {code}\nstderr:\n{stderr}"
    );
    stderr
}

/// A fresh directory for one test, unique per process and test name, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(test: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("modelgap-cli-{}-{test}", std::process::id()));
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

/// The closed-form steady-state speed of the DC motor at 12 V: ω = kV / (Rβ + k²).
const OMEGA_STEADY: f64 = 0.05 * 12.0 / (1.0 * 1e-5 + 0.05 * 0.05);

#[test]
fn equations_of_the_dc_motor_read_as_the_paper() {
    let text = ok(&["bond", "equations", "--model", "dc-motor"]);
    assert!(text.contains("dp3 = e1 - e2 - e4"), "{text}");
    assert!(text.contains("f1 = f2 = f3 = f4"), "{text}");
    assert!(text.contains("causality"), "{text}");
    assert!(text.contains("eigenvalues"), "{text}");
    // The slow mode of the motor: λ = −29.41 /s (time constant 34 ms).
    assert!(text.contains("-29.41"), "{text}");
}

#[test]
fn equations_print_latex() {
    let text = ok(&["bond", "equations", "--model", "dc-motor", "--latex"]);
    assert!(text.starts_with("\\begin{align*}"), "{text}");
    assert!(text.contains("\\dot{p}_{3}"), "{text}");
}

#[test]
fn simulate_writes_csv_that_reads_back_at_steady_state() {
    let dir = TempDir::new("simulate_csv");
    let out = dir.path("run.csv");
    let summary = ok(&[
        "bond",
        "simulate",
        "--model",
        "dc-motor",
        "--duration",
        "0.5",
        "--rate",
        "1000",
        "--out",
        &out,
    ]);
    assert!(summary.contains("501 samples"), "{summary}");
    let header = std::fs::read_to_string(&out).unwrap();
    assert!(header.starts_with("t,V,tau_L,i,omega\n"), "{header:.40}");
    let rec = read_recording_path(Path::new(&out)).unwrap();
    assert_eq!(rec.len(), 501);
    let omega = *rec.values("omega").unwrap().last().unwrap();
    // After 0.5 s (15 slow time constants) the speed is within 0.1 % of steady state.
    assert!(
        (omega - OMEGA_STEADY).abs() < 1e-3 * OMEGA_STEADY,
        "{omega}"
    );
}

#[test]
fn simulate_writes_mcap_with_states() {
    let dir = TempDir::new("simulate_mcap");
    let out = dir.path("run.mcap");
    ok(&[
        "bond",
        "simulate",
        "--model",
        "dc-motor",
        "--duration",
        "0.5",
        "--out",
        &out,
        "--states",
    ]);
    let rec = read_recording_path(Path::new(&out)).unwrap();
    assert_eq!(rec.names(), ["V", "tau_L", "i", "omega", "p3", "p8"]);
    let omega = *rec.values("omega").unwrap().last().unwrap();
    assert!(
        (omega - OMEGA_STEADY).abs() < 1e-3 * OMEGA_STEADY,
        "{omega}"
    );
}

#[test]
fn simulate_with_set_and_fault_slows_the_motor() {
    let dir = TempDir::new("simulate_fault");
    let out = dir.path("fault.csv");
    let summary = ok(&[
        "bond",
        "simulate",
        "--model",
        "dc-motor",
        "--set",
        "R=1.2",
        "--fault",
        "R=1.5@0.2",
        "--duration",
        "0.5",
        "--out",
        &out,
    ]);
    assert!(summary.contains("R = 1.5 from t = 0.2 s"), "{summary}");
    let rec = read_recording_path(Path::new(&out)).unwrap();
    let omega = *rec.values("omega").unwrap().last().unwrap();
    // Steady speed with R = 1.5: kV / (Rβ + k²) = 238.5 rad/s, below the nominal 239.0.
    let expected = 0.05 * 12.0 / (1.5 * 1e-5 + 0.05 * 0.05);
    assert!((omega - expected).abs() < 1e-3 * expected, "{omega}");
    assert!(omega < OMEGA_STEADY);
}

#[test]
fn simulate_noise_is_reproducible_with_its_seed() {
    let dir = TempDir::new("simulate_noise");
    let (a, b) = (dir.path("a.csv"), dir.path("b.csv"));
    for out in [&a, &b] {
        ok(&[
            "bond",
            "simulate",
            "--model",
            "dc-motor",
            "--duration",
            "0.1",
            "--noise",
            "1e-3,seed=7",
            "--out",
            out,
        ]);
    }
    assert_eq!(
        std::fs::read_to_string(&a).unwrap(),
        std::fs::read_to_string(&b).unwrap()
    );
}

#[test]
fn simulate_drives_inputs_from_a_recording() {
    let dir = TempDir::new("simulate_inputs");
    let inputs = dir.path("inputs.csv");
    std::fs::write(&inputs, "t,V\n0,0\n0.1,12\n0.3,12\n").unwrap();
    let out = dir.path("out.csv");
    let summary = ok(&[
        "bond", "simulate", "--model", "dc-motor", "--inputs", &inputs, "--out", &out,
    ]);
    assert!(summary.contains("V from"), "{summary}");
    let rec = read_recording_path(Path::new(&out)).unwrap();
    // The duration defaults to the recording's last time, 0.3 s at 1000 Hz.
    assert_eq!(rec.len(), 301);
    let v = rec.values("V").unwrap();
    assert!(
        (v[50] - 6.0).abs() < 1e-9,
        "linear hold halfway up the ramp"
    );
}

#[test]
fn diagnose_finds_an_increased_resistance() {
    let dir = TempDir::new("diagnose");
    let data = dir.path("r_fault.csv");
    ok(&[
        "bond",
        "simulate",
        "--model",
        "dc-motor",
        "--steady-start",
        "--fault",
        "R=1.2@0.1",
        "--duration",
        "1",
        "--out",
        &data,
    ]);
    let report = ok(&[
        "bond",
        "diagnose",
        "--model",
        "dc-motor",
        "--data",
        &data,
        "--steady-start",
    ]);
    let set = report
        .lines()
        .find_map(|l| l.strip_prefix("minimal hypothesis set: "))
        .unwrap_or_else(|| panic!("no hypothesis set in\n{report}"));
    assert!(set.contains("R+"), "{report}");

    let json = ok(&[
        "bond",
        "diagnose",
        "--model",
        "dc-motor",
        "--data",
        &data,
        "--steady-start",
        "--json",
    ]);
    let value: serde_json::Value = serde_json::from_str(&json).unwrap();
    let hypotheses: Vec<&str> = value["hypotheses"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|h| h.as_str())
        .collect();
    assert!(hypotheses.contains(&"R+"), "{json}");
    let detected = value["detected_at"].as_f64().unwrap();
    // The fault is at 0.1 s; the current leaves its 2 % band within a few samples.
    assert!((0.1..0.12).contains(&detected), "{detected}");
}

#[test]
fn diagnose_reads_the_bundled_example_recording() {
    // 200 Hz, 1 s, R = 1.2 Ω from 0.2 s, noise 1e-4 with seed 1 (see examples/data/README.md).
    let data = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/data/dc_motor_r_fault.csv"
    );
    let json = ok(&[
        "bond",
        "diagnose",
        "--model",
        "dc-motor",
        "--data",
        data,
        "--steady-start",
        "--json",
    ]);
    let value: serde_json::Value = serde_json::from_str(&json).unwrap();
    let detected = value["detected_at"].as_f64().unwrap();
    // The first sample after the fault (0.2 s) or the next one.
    assert!((0.2..0.215).contains(&detected), "{detected}");
    assert_eq!(value["residuals"][0]["first_deviation"], "-", "{json}");
    assert!(
        !value["hypotheses"].as_array().unwrap().is_empty(),
        "{json}"
    );
}

#[test]
fn graph_prints_dot_and_table() {
    let dot = ok(&["bond", "graph", "--model", "dc-motor"]);
    assert!(dot.starts_with("digraph causal {"), "{dot}");
    assert!(dot.contains("\"f3\" [label=\"f3\\n(i)\""), "{dot}");
    let table = ok(&["bond", "graph", "--model", "dc-motor", "--table"]);
    assert!(table.starts_with("consequent |"), "{table}");
}

#[test]
fn causality_shows_strokes_and_integral_storage() {
    let text = ok(&["bond", "causality", "--model", "buck-motor"]);
    // The supply imposes its effort on the switch; the output capacitor integrates.
    assert!(text.contains("Vs --->| switch"), "{text}");
    assert!(text.contains("Cf (C, bond 14): integral"), "{text}");
    assert!(!text.contains("warning"), "{text}");
}

#[test]
fn model_file_path_loads_like_the_builtin() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/crates/modelgap-bond/models/dc-motor.toml"
    );
    let from_file = ok(&["bond", "equations", "--model", path]);
    let builtin = ok(&["bond", "equations", "--model", "dc-motor"]);
    assert_eq!(from_file, builtin);
}

#[test]
fn unknown_model_exits_2_and_lists_the_builtins() {
    let stderr = fails(&["bond", "equations", "--model", "no-such-motor"], 2);
    assert!(stderr.starts_with("error: "), "{stderr}");
    assert!(stderr.contains("no-such-motor"), "{stderr}");
    assert!(
        stderr.contains("dc-motor") && stderr.contains("buck-motor"),
        "{stderr}"
    );
    let stderr = fails(&["bond", "equations", "--model", "missing/motor.toml"], 2);
    assert!(stderr.contains("missing/motor.toml"), "{stderr}");
    assert!(stderr.contains("dc-motor"), "{stderr}");
}

#[test]
fn bad_set_value_names_the_pair() {
    let stderr = fails(
        &["bond", "equations", "--model", "dc-motor", "--set", "X=abc"],
        2,
    );
    assert!(stderr.contains("X=abc"), "{stderr}");
    assert!(
        stderr.contains("`abc`") && stderr.contains("`X`"),
        "{stderr}"
    );
    // A well-formed pair with an unknown name lists the names the model has.
    let stderr = fails(
        &["bond", "equations", "--model", "dc-motor", "--set", "X=1"],
        2,
    );
    assert!(
        stderr.contains("caused by: unknown parameter 'X'"),
        "{stderr}"
    );
    assert!(stderr.contains("beta"), "{stderr}");
}

#[test]
fn missing_data_file_names_the_path() {
    let dir = TempDir::new("missing_data");
    let data = dir.path("nowhere.csv");
    let stderr = fails(
        &["bond", "diagnose", "--model", "dc-motor", "--data", &data],
        2,
    );
    assert!(stderr.contains(&data), "{stderr}");
}

#[test]
fn malformed_data_names_the_line_and_path() {
    let dir = TempDir::new("malformed_data");
    let data = dir.path("bad.csv");
    std::fs::write(&data, "t,i\n0,1\n0,2\n").unwrap();
    let stderr = fails(
        &["bond", "diagnose", "--model", "dc-motor", "--data", &data],
        2,
    );
    assert!(
        stderr.contains("line 3") && stderr.contains(&data),
        "{stderr}"
    );
}

#[test]
fn unknown_output_extension_fails_before_simulating() {
    let dir = TempDir::new("bad_extension");
    let out = dir.path("run.txt");
    let stderr = fails(
        &["bond", "simulate", "--model", "dc-motor", "--out", &out],
        2,
    );
    assert!(stderr.contains("`txt`"), "{stderr}");
    assert!(!Path::new(&out).exists());
}

#[test]
fn demo_runs() {
    ok(&["demo"]);
}

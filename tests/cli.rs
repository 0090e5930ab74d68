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

/// The built-in DC motor's model file with `from` replaced by `to`, written into `dir`.
fn motor_file_with(dir: &TempDir, name: &str, from: &str, to: &str) -> String {
    let src = include_str!("../crates/modelgap-bond/models/dc-motor.toml");
    assert!(src.contains(from), "{from}");
    let path = dir.path(name);
    std::fs::write(&path, src.replace(from, to)).unwrap();
    path
}

/// The bundled motor recording.
const MOTOR_CSV: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/examples/data/motor_hidden_effect.csv"
);

// Issue 11: a bad parameter used to end in "state 0 or its derivative is not finite",
// printed twice, exit 1 (2 through compare); `--set J=-1` was accepted.
#[test]
fn a_parameter_an_element_cannot_have_is_named_and_exits_2() {
    for (set, expected) in [
        (
            "k=1e300",
            "parameter 'k' must be finite and at most 1e100 in magnitude, found 1e300",
        ),
        (
            "L=0",
            "parameter L of element L (I: inductance, H) must be positive, found 0",
        ),
        (
            "J=-1",
            "parameter J of element J (I: inertia, kg m^2) must be positive, found -1",
        ),
        (
            "R=-1",
            "parameter R of element R (R: resistance, Ohm) must be zero or positive, found -1",
        ),
    ] {
        let stderr = fails(
            &["bond", "simulate", "--model", "dc-motor", "--set", set],
            2,
        );
        assert!(stderr.contains(expected), "{stderr}");
        let stderr = fails(
            &[
                "compare", "--model", "dc-motor", "--set", set, "--data", MOTOR_CSV,
            ],
            2,
        );
        assert!(stderr.contains(expected), "{stderr}");
    }
    // A model file with the bad value names the parameter and the line it is on.
    let dir = TempDir::new("unphysical_file");
    let model = motor_file_with(&dir, "m.toml", "L = { value = 5e-3", "L = { value = 0.0");
    let stderr = fails(&["bond", "simulate", "--model", &model], 2);
    assert!(
        stderr.contains("parameter L of element L") && stderr.contains("line 11"),
        "{stderr}"
    );
}

#[test]
fn a_law_that_is_nan_at_the_start_is_named_once_and_exits_2() {
    let dir = TempDir::new("nan_law");
    let model = motor_file_with(
        &dir,
        "m.toml",
        "name = \"R\"\nkind = \"R\"\nparameter = \"R\"",
        "name = \"R\"\nkind = \"R\"\neffort = \"f/0\"",
    );
    let expected = "the effort law of element R, `f/0`, is NaN at the start (f = 0)";
    let stderr = fails(&["bond", "simulate", "--model", &model], 2);
    assert_eq!(stderr.matches(expected).count(), 1, "{stderr}");
    let stderr = fails(&["compare", "--model", &model, "--data", MOTOR_CSV], 2);
    assert!(stderr.contains(expected), "{stderr}");
}

#[test]
fn a_state_that_runs_away_is_named_by_state_and_element_once() {
    let stderr = fails(
        &[
            "bond",
            "simulate",
            "--model",
            "dc-motor",
            "--set",
            "k=1e60",
            "--duration",
            "0.1",
        ],
        2,
    );
    assert_eq!(
        stderr.matches("not finite").count(),
        1,
        "printed once: {stderr}"
    );
    assert!(
        stderr.contains("state p3 (the momentum of I:L) or its derivative is not finite"),
        "{stderr}"
    );
}

// Issue 11: a PWM at 1 THz grew memory until the allocator aborted the process.
#[test]
fn runs_past_their_limits_are_refused_before_work_naming_the_option() {
    let stderr = fails(
        &[
            "bond",
            "simulate",
            "--model",
            "buck-motor",
            "--input",
            "m=pwm:0.5@1e12",
        ],
        2,
    );
    assert!(
        stderr.contains("input m") && stderr.contains("--max-events 10000000"),
        "{stderr}"
    );
    let stderr = fails(
        &["bond", "simulate", "--model", "dc-motor", "--rate", "1e12"],
        2,
    );
    assert!(
        stderr.contains("1e12 Hz") && stderr.contains("--max-samples"),
        "{stderr}"
    );
    // Raising the limit is what a user who means the run does.
    ok(&[
        "bond",
        "simulate",
        "--model",
        "buck-motor",
        "--input",
        "m=pwm:0.5@100",
        "--duration",
        "0.1",
        "--max-events",
        "100",
    ]);
    fails(
        &[
            "bond",
            "simulate",
            "--model",
            "buck-motor",
            "--input",
            "m=pwm:0.5@100",
            "--duration",
            "0.1",
            "--max-events",
            "10",
        ],
        2,
    );
}

// Issue 11: `--duration -1` got clap's "unexpected argument '-1'".
#[test]
fn negative_option_values_are_refused_naming_the_option() {
    for (args, option, found) in [
        (
            vec![
                "bond",
                "simulate",
                "--model",
                "dc-motor",
                "--duration",
                "-1",
            ],
            "--duration",
            "found -1 s",
        ),
        (
            vec!["bond", "simulate", "--model", "dc-motor", "--rate", "-5"],
            "--rate",
            "found -5 Hz",
        ),
        (
            vec!["bond", "simulate", "--model", "dc-motor", "--noise", "-0.1"],
            "--noise",
            "found -0.1",
        ),
        (
            vec![
                "compare",
                "--model",
                "dc-motor",
                "--data",
                MOTOR_CSV,
                "--band-sigmas",
                "-1",
            ],
            "--band-sigmas",
            "found -1",
        ),
        (
            vec![
                "explain", "--model", "dc-motor", "--data", MOTOR_CSV, "--top", "-1",
            ],
            "--top",
            "found -1",
        ),
        (
            vec![
                "bond",
                "diagnose",
                "--model",
                "dc-motor",
                "--data",
                MOTOR_CSV,
                "--persistence",
                "-2",
            ],
            "--persistence",
            "found -2",
        ),
        (
            vec!["bond", "table7", "--magnitude", "-0.2"],
            "--magnitude",
            "found -0.2",
        ),
        (
            vec!["bond", "bench", "--repeat", "0"],
            "--repeat",
            "found 0",
        ),
    ] {
        let stderr = fails(&args, 2);
        assert!(
            stderr.contains(option) && stderr.contains(found),
            "{args:?}: {stderr}"
        );
        assert!(!stderr.contains("unexpected argument"), "{stderr}");
    }
}

#[test]
fn a_directory_where_a_file_is_expected_is_named_with_its_option() {
    let dir = TempDir::new("directories");
    let d = dir.0.to_string_lossy().into_owned();
    let stderr = fails(&["compare", "--model", "dc-motor", "--data", &d], 2);
    assert!(
        stderr.contains(&format!("--data {d} is a directory: give a recording file")),
        "{stderr}"
    );
    let stderr = fails(
        &["bond", "simulate", "--model", "dc-motor", "--inputs", &d],
        2,
    );
    assert!(
        stderr.contains(&format!("--inputs {d} is a directory")),
        "{stderr}"
    );
    let stderr = fails(&["bond", "simulate", "--model", &d], 2);
    assert!(
        stderr.contains(&format!("--model {d} is a directory")),
        "{stderr}"
    );
    let stderr = fails(&["bond", "simulate", "--model", "dc-motor", "--out", &d], 2);
    assert!(
        stderr.contains(&format!("--out {d} is a directory")),
        "{stderr}"
    );
}

// Issue 11: values near f64::MAX made compare print `NaN× the noise floor`.
#[test]
fn a_recording_with_values_beyond_the_magnitude_limit_is_refused() {
    let dir = TempDir::new("huge_values");
    let data = dir.path("huge.csv");
    let mut text = String::from("t,V,i,omega\n");
    for k in 0..20 {
        let omega = if k == 7 { "1.7e308" } else { "1" };
        text.push_str(&format!("{},12,1,{omega}\n", f64::from(k) * 0.01));
    }
    std::fs::write(&data, text).unwrap();
    let stderr = fails(&["compare", "--model", "dc-motor", "--data", &data], 2);
    assert!(
        stderr.contains("line 9") && stderr.contains("`omega`") && stderr.contains("1e100"),
        "{stderr}"
    );
    assert!(!stderr.contains("NaN"), "{stderr}");
}

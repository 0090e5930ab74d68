//! Calibration (`modelgap fit`, [`modelgap::calibrate`]): a model's free parameters and
//! initial states fitted jointly by simulation error — on the real cascaded-tanks records,
//! on a recording of known truth with coloured noise, and from the command line.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in test helpers, a panic is a test failure

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use modelgap::bond::file::read_model_path;
use modelgap::bond::simulate::{Drive, Hold, Inputs, SimOptions, simulate};
use modelgap::{CalibrationOptions, LoadOptions, Recording, Signal, calibrate, load_model};
use serde_json::Value;

const TANKS_MODEL: &str = "examples/models/cascaded-tanks.toml";
const ESTIMATION: &str = "examples/data/realdata/cascaded_tanks/tanks_estimation.csv";
const VALIDATION: &str = "examples/data/realdata/cascaded_tanks/tanks_validation.csv";

fn root(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn rms_of(model: &dyn modelgap::Model, rec: &Recording, output: &str) -> f64 {
    let p = model.predict(rec).unwrap();
    let y = p.get(output).unwrap();
    let m = &rec.signal(output).unwrap().values;
    (m.iter().zip(y).map(|(a, b)| (a - b) * (a - b)).sum::<f64>() / m.len() as f64).sqrt()
}

/// The authors' model calibrated on the real estimation record reaches the error a plain
/// scipy least-squares fit of the same model reaches (0.603 V with the initial levels
/// fitted; the file also frees the sensor's offset), every value placed by the data, and
/// holds on the validation record.
#[test]
fn cascaded_tanks_calibrate_on_the_real_estimation_record() {
    let model_path = root(TANKS_MODEL);
    let model = load_model(model_path.to_str().unwrap(), &LoadOptions::default()).unwrap();
    let est = modelgap::load_recording(&root(ESTIMATION), model.as_ref()).unwrap();
    let cal = calibrate(model.as_ref(), &est, &CalibrationOptions::default()).unwrap();
    let names: Vec<&str> = cal.values.iter().map(|v| v.name.as_str()).collect();
    assert_eq!(names, ["k1", "k2", "k3", "offset", "Tank1(0)", "Tank2(0)"]);
    assert_eq!(cal.termination, modelgap::fit::Termination::Converged);
    let (before, after) = (cal.rms_before[0].1, cal.rms_after[0].1);
    assert!(after < 0.603, "RMS after {after} (scipy, no offset: 0.603)");
    assert!(after < 0.25 * before, "{before} -> {after}");
    for v in &cal.values {
        assert!(v.at_bound.is_none(), "{v:?}");
        let se = v
            .std_error
            .unwrap_or_else(|| panic!("{} not determined", v.name));
        assert!(se > 0.0 && se.is_finite(), "{v:?}");
    }
    // The calibrated model on the record it was not fitted to.
    let val = modelgap::load_recording(&root(VALIDATION), cal.model.as_ref()).unwrap();
    let validation = rms_of(cal.model.as_ref(), &val, "y");
    let nominal = rms_of(model.as_ref(), &val, "y");
    assert!(validation < 0.75, "validation RMS {validation}");
    assert!(validation < 0.3 * nominal, "{nominal} -> {validation}");
}

/// Exponentially correlated (AR(1)) noise, seeded.
fn coloured_noise(n: usize, sigma: f64, rho: f64, seed: u64) -> Vec<f64> {
    let mut state = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut uniform = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    let mut gauss = move || {
        let (u1, u2) = (uniform(), uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    };
    let mut x = 0.0;
    (0..n)
        .map(|_| {
            x = rho * x + (1.0 - rho * rho).sqrt() * sigma * gauss();
            x
        })
        .collect()
}

/// A recording of known truth (the tanks at other coefficients, other starting levels and a
/// sensor offset, a staircase pump input, AR(1) noise with ρ = 0.9): calibration from the
/// file's start values recovers every unknown within three of its standard errors.
#[test]
fn calibration_recovers_known_values_through_coloured_noise() {
    let g = read_model_path(&root(TANKS_MODEL)).unwrap();
    let mut truth = g.clone();
    let true_values = [
        ("k1", 0.041),
        ("k2", 0.062),
        ("k3", 0.058),
        ("offset", 0.35),
    ];
    for (name, v) in true_values {
        truth.set_param(name, v).unwrap();
    }
    let t: Vec<f64> = (0..1500).map(|k| 4.0 * k as f64).collect();
    let u: Vec<f64> = t
        .iter()
        .map(|&t| [2.0, 6.5, 3.5, 8.0, 1.0, 5.0][((t / 600.0) as usize) % 6])
        .collect();
    let inputs = Inputs::new().with(
        "u",
        Drive::Sampled {
            t: t.clone(),
            values: u.clone(),
            hold: Hold::Zero,
        },
    );
    let opts = SimOptions {
        initial_state: Some(vec![6.0, 2.5]),
        ..SimOptions::default()
    };
    let run = simulate(&truth, &inputs, &t, &opts).unwrap();
    let noise = coloured_noise(t.len(), 0.03, 0.9, 7);
    let y: Vec<f64> = run
        .output("y")
        .unwrap()
        .iter()
        .zip(&noise)
        .map(|(a, b)| a + b)
        .collect();
    let rec = Recording::new(t, vec![Signal::new("u", u), Signal::new("y", y)]).unwrap();
    let model = modelgap::bond::BondModel::new(g);
    let cal = calibrate(&model, &rec, &CalibrationOptions::default()).unwrap();
    let expected: Vec<(&str, f64)> = true_values
        .into_iter()
        .chain([("Tank1(0)", 6.0), ("Tank2(0)", 2.5)])
        .collect();
    for (name, truth) in expected {
        let v = cal.values.iter().find(|v| v.name == name).unwrap();
        let se = v
            .std_error
            .unwrap_or_else(|| panic!("{name} not determined: {v:?}"));
        assert!(
            (v.value - truth).abs() < 3.0 * se,
            "{name}: {} ± {se}, truth {truth}",
            v.value
        );
        assert!(
            se < 0.2 * truth.abs().max(0.1),
            "{name}: ± {se} is too wide to mean anything"
        );
    }
    assert!(cal.rms_after[0].1 < 0.05, "{:?}", cal.rms_after);
}

fn modelgap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_modelgap"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the modelgap binary runs")
}

#[test]
fn fit_on_the_command_line_writes_a_calibrated_model_that_compare_reads() {
    let dir = std::env::temp_dir().join(format!("modelgap-fit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("fitted.toml");
    let run = modelgap(&[
        "fit",
        "--model",
        TANKS_MODEL,
        "--data",
        ESTIMATION,
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let v: Value = serde_json::from_slice(&run.stdout).unwrap();
    let params = v["parameters"].as_array().unwrap();
    assert_eq!(params.len(), 6);
    for p in params {
        for field in ["name", "unit", "value", "std_error", "at_bound"] {
            assert!(p.get(field).is_some(), "{field} missing in {p}");
        }
    }
    let before = v["rms_before"][0]["rms"].as_f64().unwrap();
    let after = v["rms_after"][0]["rms"].as_f64().unwrap();
    assert!(after < 0.25 * before, "{before} -> {after}");
    // The written file holds the fitted values, still marked free, and compare reads it.
    let fitted = read_model_path(&out).unwrap();
    let k1 = params.iter().find(|p| p["name"] == "k1").unwrap()["value"]
        .as_f64()
        .unwrap();
    assert_eq!(fitted.param("k1").unwrap(), k1);
    assert!(fitted.params()["k1"].free.is_some());
    let tank1 = params.iter().find(|p| p["name"] == "Tank1(0)").unwrap()["value"]
        .as_f64()
        .unwrap();
    assert_eq!(fitted.initial()["Tank1"].value, tank1);
    let compare = modelgap(&[
        "compare",
        "--model",
        out.to_str().unwrap(),
        "--data",
        ESTIMATION,
        "--json",
    ]);
    assert!(compare.status.success());
    let c: Value = serde_json::from_slice(&compare.stdout).unwrap();
    let rms = c["outputs"][0]["rms"].as_f64().unwrap();
    assert!(
        (rms - after).abs() < 1e-6 * after,
        "compare {rms} vs fit {after}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn free_on_the_command_line_and_its_errors() {
    // A built-in with nothing free: a typed message saying what to do.
    let data = "examples/data/dc_motor_r_fault.csv";
    let run = modelgap(&["fit", "--model", "dc-motor", "--data", data]);
    assert_eq!(run.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&run.stderr).contains("nothing to calibrate"),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    // --free with bounds: the resistance fitted within them, the error falls.
    let run = modelgap(&[
        "fit", "--model", "dc-motor", "--data", data, "--free", "R=0.5:5", "--json",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let v: Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(v["parameters"][0]["name"], "R");
    assert_eq!(v["parameters"][0]["bounds"], serde_json::json!([0.5, 5.0]));
    let cases: [(&[&str], &str); 4] = [
        (&["--free", "nope"], "--free nope"),
        (&["--free", "R=5:1"], "LO must be below HI"),
        (&["--free", "R=2:5"], "outside its bounds"),
        (&["--free", "R=a:5"], "not a finite number"),
    ];
    for (extra, expected) in cases {
        let mut args = vec!["fit", "--model", "dc-motor", "--data", data];
        args.extend_from_slice(extra);
        let run = modelgap(&args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{extra:?}: {stderr}");
        assert!(
            stderr.contains(expected),
            "{extra:?}: expected '{expected}' in {stderr}"
        );
    }
}

/// A free parameter that starts wrong (R = 1.3 Ω, truth 1.0) on a recording with hidden
/// Coulomb friction: explain calibrates R first, then fits every candidate jointly with it,
/// so the friction is named with its true level and R comes back to its true value in the
/// fixed model, instead of R absorbing part of the friction.
#[test]
fn explain_fits_candidates_jointly_with_the_free_parameters() {
    let src = std::fs::read_to_string(root("crates/modelgap-bond/models/dc-motor.toml")).unwrap();
    let line = r#"R = { value = 1.0, unit = "Ohm", description = "armature resistance" }"#;
    assert!(src.contains(line));
    let src = src.replace(
        line,
        r#"R = { value = 1.3, unit = "Ohm", description = "armature resistance", free = true, min = 0.1, max = 10.0 }"#,
    );
    let g = modelgap::bond::file::read_model(&src).unwrap();
    let model = modelgap::bond::BondModel::new(g);
    let rec =
        modelgap::load_recording(&root("examples/data/motor_hidden_effect.csv"), &model).unwrap();
    let ex = modelgap::explain(&model, &rec, &modelgap::ExplainOptions::default()).unwrap();
    assert_eq!(ex.chosen.len(), 1, "{:?}", ex.verdict);
    let best = &ex.chosen[0];
    assert_eq!(best.candidate.id, "coulomb@1m");
    assert!(
        (best.params[0].value - 0.012).abs() < 0.0005,
        "{:?}",
        best.params
    );
    let cal = best
        .calibration
        .as_ref()
        .expect("R fitted with the friction");
    assert_eq!(cal.candidate.params[0].name, "R");
    assert!((cal.values[0] - 1.0).abs() < 0.02, "R = {}", cal.values[0]);
    // No "R is off" candidate: calibration fits R already.
    assert!(ex.ranked.iter().all(|r| r.candidate.id != "deviation:R"));
    assert!(
        ex.warnings
            .iter()
            .any(|w| w.contains("calibrated the model's free parameters"))
    );
    // The fixed model holds both.
    let fixed = modelgap::Model::with_effects(&model, &ex.effects()).unwrap();
    let text = fixed.to_file_text().unwrap();
    let back = modelgap::bond::file::read_model(&text).unwrap();
    assert!((back.param("R").unwrap() - 1.0).abs() < 0.02);
    assert!(text.contains("coulomb"), "{text}");
}

/// A first-order node: `C1 ė = b u − e / R1`, the effort measured. Only the time constant
/// `R1 C1` and the gain `b R1` show in the output: with all three free, one direction is
/// undetermined.
const NODE: &str = r#"name = "node"
[parameters]
b = { value = 1.0, unit = "A/V", free = true, min = 0.1, max = 10.0 }
R1 = { value = 1.0, unit = "Ohm", free = true, min = 0.1, max = 10.0 }
C1 = { value = 1.0, unit = "F", free = true, min = 0.1, max = 10.0 }
[inputs]
u = { default = 0.0, unit = "V" }
[[elements]]
name = "drive"
kind = "Sf"
flow = "b * u"
[[elements]]
name = "n"
kind = "0"
[[elements]]
name = "C"
kind = "C"
parameter = "C1"
[[elements]]
name = "R"
kind = "R"
parameter = "R1"
[[bonds]]
from = "drive"
to = "n"
[[bonds]]
from = "n"
to = "C"
[[bonds]]
from = "n"
to = "R"
[[outputs]]
name = "e"
effort = "n"
unit = "V"
"#;

/// The node at b = 0.5, R1 = 3, C1 = 2 (τ = 6 s, gain 1.5), driven by a staircase, with
/// AR(1) noise.
fn node_recording() -> Recording {
    let mut truth = modelgap::bond::file::read_model(NODE).unwrap();
    for (name, v) in [("b", 0.5), ("R1", 3.0), ("C1", 2.0)] {
        truth.set_param(name, v).unwrap();
    }
    let t: Vec<f64> = (0..1200).map(|k| 0.05 * k as f64).collect();
    let u: Vec<f64> = t
        .iter()
        .map(|&t| [1.0, 3.0, -1.0, 2.0, 0.5][((t / 12.0) as usize) % 5])
        .collect();
    let inputs = Inputs::new().with(
        "u",
        Drive::Sampled {
            t: t.clone(),
            values: u.clone(),
            hold: Hold::Zero,
        },
    );
    let run = simulate(&truth, &inputs, &t, &SimOptions::default()).unwrap();
    let noise = coloured_noise(t.len(), 0.01, 0.7, 3);
    let y: Vec<f64> = (run.output("e").unwrap().iter().zip(&noise))
        .map(|(a, b)| a + b)
        .collect();
    Recording::new(t, vec![Signal::new("u", u), Signal::new("e", y)]).unwrap()
}

/// A prior closes the direction the data cannot see: without one, the three values are not
/// all determined; with a datasheet's `C1 = 2 ± 0.05 F` every value is placed, near the
/// truth, with a finite ±, and C1's ± is no wider than its prior's.
#[test]
fn a_prior_places_what_the_data_cannot_see() {
    let rec = node_recording();
    let model = modelgap::bond::BondModel::new(modelgap::bond::file::read_model(NODE).unwrap());
    let cal = calibrate(&model, &rec, &CalibrationOptions::default()).unwrap();
    assert!(
        cal.values.iter().any(
            |v| v.std_error.is_none() || v.std_error.is_some_and(|se| se > 0.5 * v.value.abs())
        ),
        "without a prior one direction is undetermined: {:?}",
        cal.values
    );

    let with_prior = NODE.replace(
        "C1 = { value = 1.0, unit = \"F\", free = true, min = 0.1, max = 10.0 }",
        "C1 = { value = 1.0, unit = \"F\", free = true, min = 0.1, max = 10.0, prior = { mean = 2.0, std = 0.05 } }",
    );
    assert_ne!(with_prior, NODE);
    let g = modelgap::bond::file::read_model(&with_prior).unwrap();
    // The prior is part of the file: written and read back.
    let text = modelgap::bond::file::write_model(&g);
    assert!(text.contains("prior = { mean = 2"), "{text}");
    assert_eq!(modelgap::bond::file::read_model(&text).unwrap(), g);
    let model = modelgap::bond::BondModel::new(g);
    let cal = calibrate(&model, &rec, &CalibrationOptions::default()).unwrap();
    for (name, truth) in [("b", 0.5), ("R1", 3.0), ("C1", 2.0)] {
        let v = cal.values.iter().find(|v| v.name == name).unwrap();
        let se = v
            .std_error
            .unwrap_or_else(|| panic!("{name} not determined: {v:?}"));
        assert!(
            (v.value - truth).abs() < 0.1 * truth,
            "{name}: {} ± {se}, truth {truth}",
            v.value
        );
        assert!(se < 0.1 * truth, "{name}: ± {se}");
    }
    let c1 = cal.values.iter().find(|v| v.name == "C1").unwrap();
    assert!(c1.prior.is_some());
    assert!(c1.std_error.unwrap() <= 0.05 * 1.01, "{c1:?}");
    assert!(cal.rms_after[0].1 < 0.02, "{:?}", cal.rms_after);
    // explain calibrates the same way and keeps the prior in every joint fit.
    let ex = modelgap::explain(&model, &rec, &modelgap::ExplainOptions::default()).unwrap();
    let mut checked = 0;
    for r in ex.ranked.iter().filter(|r| r.error.is_none()) {
        let cal = r
            .calibration
            .as_ref()
            .expect("fitted jointly with the free values");
        let i = (cal.candidate.params.iter().position(|p| p.name == "C1")).unwrap();
        assert!(
            (cal.values[i] - 2.0).abs() < 0.2,
            "{}: C1 = {}",
            r.candidate.id,
            cal.values[i]
        );
        checked += 1;
    }
    assert!(checked > 0, "{:?}", ex.ranked);
}

/// A wrong but wide prior does not move what the data determine: with b and C1 held, R1's
/// fit is the data's whatever a loose prior says.
#[test]
fn a_loose_prior_yields_to_the_data() {
    let rec = node_recording();
    let held = NODE
        .replace(
            "b = { value = 1.0, unit = \"A/V\", free = true, min = 0.1, max = 10.0 }",
            "b = { value = 0.5, unit = \"A/V\" }",
        )
        .replace(
            "C1 = { value = 1.0, unit = \"F\", free = true, min = 0.1, max = 10.0 }",
            "C1 = { value = 2.0, unit = \"F\" }",
        );
    let loose = held.replace(
        "R1 = { value = 1.0, unit = \"Ohm\", free = true, min = 0.1, max = 10.0 }",
        "R1 = { value = 1.0, unit = \"Ohm\", free = true, min = 0.1, max = 10.0, prior = { mean = 6.0, std = 10.0 } }",
    );
    assert_ne!(loose, held);
    let fit_r1 = |text: &str| {
        let model = modelgap::bond::BondModel::new(modelgap::bond::file::read_model(text).unwrap());
        let cal = calibrate(&model, &rec, &CalibrationOptions::default()).unwrap();
        cal.values[0].value
    };
    let (alone, with_prior) = (fit_r1(&held), fit_r1(&loose));
    assert!((alone - 3.0).abs() < 0.05, "R1 = {alone}");
    assert!(
        (with_prior - alone).abs() < 0.01 * alone,
        "{alone} -> {with_prior}"
    );
}

#[test]
fn bad_priors_name_the_parameter_and_the_line() {
    for (from, to, expected) in [
        (
            "max = 10.0 }\nC1",
            "max = 10.0, prior = { mean = 1.0, std = 0.0 } }\nC1",
            "std",
        ),
        (
            "max = 10.0 }\nC1",
            "max = 10.0, prior = { mean = 1.0, sd = 0.1 } }\nC1",
            "sd",
        ),
        (
            "R1 = { value = 1.0, unit = \"Ohm\", free = true, min = 0.1, max = 10.0 }",
            "R1 = { value = 1.0, unit = \"Ohm\", prior = { mean = 1.0, std = 0.1 } }",
            "free = true",
        ),
    ] {
        assert!(NODE.contains(from), "{from}");
        let message = modelgap::bond::file::read_model(&NODE.replacen(from, to, 1))
            .expect_err(to)
            .to_string();
        assert!(message.contains(expected), "{to}: {message}");
        assert!(message.contains("line 4"), "{to}: {message}");
    }
}

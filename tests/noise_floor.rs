//! A floor that is the measurement's, not the model's error: the noise floor says how it was
//! found and whether its third differences are white noise. On the real records: Silverbox's
//! oversampled resonance leaks into them (the floor is likely too high), the buck converter's
//! output is quantised, the cascaded tanks' level and the bundled motor recording are white.
//! Correlated (AR) noise is recognised as such, and a right model of an oversampled resonance
//! is not told "nothing is missing" on the strength of a floor its own signal inflates.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in test helpers, a panic is a test failure

use std::collections::BTreeMap;
use std::path::Path;

use modelgap::bond::BondModel;
use modelgap::bond::file::read_model;
use modelgap::bond::simulate::{Drive, Hold, Inputs, SimOptions, simulate};
use modelgap::compare::{FloorKind, noise_floor};
use modelgap::noise::Gaussian;
use modelgap::{ExplainOptions, Recording, Signal, Verdict, explain};

fn column(path: &str, name: &str) -> Vec<f64> {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(path)).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let j = header.iter().position(|h| *h == name).unwrap();
    lines
        .map(|l| l.split(',').nth(j).unwrap().parse().unwrap())
        .collect()
}

fn kind(values: &[f64]) -> FloorKind {
    noise_floor("y", values, &BTreeMap::new()).kind
}

#[test]
fn real_records_say_how_their_floor_was_found() {
    let silverbox = column(
        "examples/data/realdata/silverbox/silverbox_estimation.csv",
        "y",
    );
    let floor = noise_floor("y", &silverbox, &BTreeMap::new());
    assert_eq!(floor.kind, FloorKind::SignalContent, "{floor:?}");
    let warning = floor.warning("y", "V").unwrap();
    assert!(
        warning.contains("too high") && warning.contains("--noise y="),
        "{warning}"
    );
    let buck = column(
        "examples/data/realdata/buck_converter/buck_estimation.csv",
        "Vo",
    );
    assert_eq!(kind(&buck), FloorKind::Quantised);
    let tanks = column(
        "examples/data/realdata/cascaded_tanks/tanks_estimation.csv",
        "y",
    );
    assert_eq!(kind(&tanks), FloorKind::White);
    for output in ["i", "omega"] {
        let motor = column("examples/data/motor_hidden_effect.csv", output);
        assert_eq!(kind(&motor), FloorKind::White, "{output}");
    }
    // Given, the user's value stands and is trusted.
    let given = BTreeMap::from([("y".to_string(), 2e-4)]);
    let floor = noise_floor("y", &silverbox, &given);
    assert_eq!((floor.kind, floor.sigma), (FloorKind::Given, 2e-4));
    assert!(floor.warning("y", "V").is_none());
}

#[test]
fn white_and_correlated_noise_are_told_apart() {
    let n = 4000;
    let slow: Vec<f64> = (0..n).map(|k| (k as f64 * 0.002).sin()).collect();
    let mut g = Gaussian::new(3);
    let white: Vec<f64> = slow.iter().map(|s| s + 0.01 * g.sample()).collect();
    assert_eq!(kind(&white), FloorKind::White);
    let mut x = 0.0;
    let coloured: Vec<f64> = (slow.iter())
        .map(|s| {
            x = 0.8 * x + 0.6 * 0.01 * g.sample();
            s + x
        })
        .collect();
    let floor = noise_floor("y", &coloured, &BTreeMap::new());
    assert_eq!(floor.kind, FloorKind::Coloured, "{floor:?}");
    // Its third differences see only the innovations: the floor is well below the noise.
    assert!(floor.sigma < 0.6 * 0.01, "{floor:?}");
    assert!(floor.warning("y", "V").unwrap().contains("too low"));
}

/// A lightly damped oscillator at 6 Hz sampled at 60 Hz (Silverbox's ten samples per period),
/// driven by a random force; its position measured with noise far below the signal.
const OSCILLATOR: &str = r#"name = "resonance"
[parameters]
m = { value = 1.0, unit = "kg" }
d = { value = 1.5, unit = "N s/m" }
k = { value = 1421.0, unit = "N/m" }
[inputs]
u = { default = 0.0, unit = "N" }
[[elements]]
name = "force"
kind = "Se"
effort = "u"
[[elements]]
name = "body"
kind = "1"
[[elements]]
name = "mass"
kind = "I"
parameter = "m"
[[elements]]
name = "damper"
kind = "R"
parameter = "d"
[[elements]]
name = "spring"
kind = "C"
effort = "k * q"
[[bonds]]
from = "force"
to = "body"
[[bonds]]
from = "body"
to = "mass"
[[bonds]]
from = "body"
to = "damper"
[[bonds]]
from = "body"
to = "spring"
[[outputs]]
name = "x"
state = "spring"
unit = "m"
"#;

/// The oscillator driven by a white random force (every frequency excited: no quiet band),
/// its position measured with white noise of 1e-5 m; `hidden` is a law added at the body
/// (none for the right model).
fn oversampled(hidden: Option<&str>, seed: u64) -> Recording {
    let mut g = read_model(OSCILLATOR).unwrap();
    if let Some(law) = hidden {
        g = read_model(&OSCILLATOR.replace(
            "[[bonds]]\nfrom = \"force\"",
            &format!(
                "[[elements]]\nname = \"extra\"\nkind = \"R\"\neffort = \"{law}\"\n\
                 [[bonds]]\nfrom = \"body\"\nto = \"extra\"\n[[bonds]]\nfrom = \"force\""
            ),
        ))
        .unwrap();
    }
    let n = 3000;
    let t: Vec<f64> = (0..n).map(|k| k as f64 / 60.0).collect();
    let mut gauss = Gaussian::new(seed);
    let u: Vec<f64> = (0..n).map(|_| 20.0 * gauss.sample()).collect();
    let inputs = Inputs::new().with(
        "u",
        Drive::Sampled {
            t: t.clone(),
            values: u.clone(),
            hold: Hold::Zero,
        },
    );
    let run = simulate(&g, &inputs, &t, &SimOptions::default()).unwrap();
    let x: Vec<f64> = (run.output("x").unwrap().iter())
        .map(|v| v + 1e-5 * gauss.sample())
        .collect();
    Recording::new(t, vec![Signal::new("u", u), Signal::new("x", x)]).unwrap()
}

#[test]
fn a_right_model_of_an_oversampled_resonance_is_judged_against_the_smoothers_floor() {
    let model = BondModel::new(read_model(OSCILLATOR).unwrap());
    let rec = oversampled(None, 11);
    let x = &rec.signal("x").unwrap().values;
    // The third differences read the resonance, not the noise; and the white force leaves no
    // quiet band to read it in.
    let floor = noise_floor("x", x, &BTreeMap::new());
    assert_eq!(floor.kind, FloorKind::SignalContent, "{floor:?}");
    assert!(floor.sigma > 10.0 * 1e-5, "{floor:?}");
    let u = &rec.signal("u").unwrap().values;
    assert_eq!(modelgap::residual::quiet_band_noise(x, &[u]), None);
    // explain takes the floor from what the model leaves beside a free force at the body:
    // the sensor's 1e-5 m, and the right model lacks nothing.
    let ex = explain(&model, &rec, &ExplainOptions::default()).unwrap();
    let out = &ex.outputs[0];
    assert_eq!(out.noise_method, FloorKind::Smoother, "{:?}", ex.warnings);
    assert!(
        (0.8e-5..1.25e-5).contains(&out.noise_floor),
        "floor {} (true noise 1e-5)",
        out.noise_floor
    );
    assert_eq!(ex.verdict, Verdict::NothingMissing, "{:?}", ex.reasons);
    // With the sensor's noise given, the same.
    let opts = ExplainOptions {
        noise: BTreeMap::from([("x".to_string(), 1e-5)]),
        ..ExplainOptions::default()
    };
    let ex = explain(&model, &rec, &opts).unwrap();
    assert_eq!(ex.verdict, Verdict::NothingMissing, "{:?}", ex.reasons);
}

/// The smoother's floor does not swallow what the model lacks: a quadratic damper the
/// model does not have (its force a few percent of the spring's) is found, not judged noise.
#[test]
fn a_wrong_model_of_an_oversampled_resonance_is_not_excused_by_the_smoothers_floor() {
    let model = BondModel::new(read_model(OSCILLATOR).unwrap());
    let rec = oversampled(Some("0.05 * f * abs(f)"), 12);
    let ex = explain(&model, &rec, &ExplainOptions::default()).unwrap();
    let out = &ex.outputs[0];
    assert_ne!(ex.verdict, Verdict::NothingMissing, "{:?}", ex.reasons);
    assert!(
        out.noise_floor < 2e-5,
        "floor {} ({:?})",
        out.noise_floor,
        out.noise_method
    );
    assert!(out.rms_before > 5.0 * out.noise_floor, "{out:?}");
}

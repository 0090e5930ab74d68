//! The loop on real measurements nobody here generated: the Silverbox benchmark
//! (Wigren & Schoukens 2013), an electronic mass–spring–damper whose spring hardens.
//!
//! A user writes the linear model (`examples/models/silverbox-linear.toml`), calibrates it
//! on a stretch of the multisine record, asks explain what is missing, builds the answer
//! in, and holds both models against the "arrow" record (amplitudes growing to 0.15 V, a
//! record neither fit saw). The cubic stiffness must be found both from the built-in menu
//! (`stiffness@k`) and as the user's own declared candidate (`declared:cubic`), and cut the
//! validation error at least threefold.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in tests, a panic is a failure

use std::path::{Path, PathBuf};

use modelgap::bond::simulate::Hold;
use modelgap::{
    CalibrationOptions, ExplainOptions, LoadOptions, Model, Recording, Verdict, calibrate, explain,
    load_model,
};

const MODEL: &str = "examples/models/silverbox-linear.toml";
const ESTIMATION: &str = "examples/data/realdata/silverbox/silverbox_estimation.csv";
const ARROW: &str = "examples/data/realdata/silverbox/silverbox_arrow.csv";

fn root(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn rms_of(model: &dyn Model, rec: &Recording) -> f64 {
    let p = model.predict(rec).unwrap();
    let y = p.get("y").unwrap();
    let m = &rec.signal("y").unwrap().values;
    (m.iter().zip(y).map(|(a, b)| (a - b) * (a - b)).sum::<f64>() / m.len() as f64).sqrt()
}

/// The linear model calibrated on the estimation record, and its error on the arrow.
fn calibrated_linear() -> (Box<dyn Model>, Recording, Recording, f64) {
    let opts = LoadOptions {
        hold: Some(Hold::Linear), // an analog input behind a reconstruction filter
        ..LoadOptions::default()
    };
    let model = load_model(root(MODEL).to_str().unwrap(), &opts).unwrap();
    let est = modelgap::load_recording(&root(ESTIMATION), model.as_ref()).unwrap();
    let arrow = modelgap::load_recording(&root(ARROW), model.as_ref()).unwrap();
    let cal = calibrate(model.as_ref(), &est, &CalibrationOptions::default()).unwrap();
    assert_eq!(cal.termination, modelgap::fit::Termination::Converged);
    // The record's output is not centred: an offset of about −5.5 mV.
    let offset = cal.values.iter().find(|v| v.name == "offset").unwrap();
    assert!((offset.value + 0.0055).abs() < 0.001, "{offset:?}");
    let linear = rms_of(cal.model.as_ref(), &arrow);
    (cal.model, est, arrow, linear)
}

/// Explains with `only` these candidates (the whole menu, with discovery, is the test after
/// this one), builds the choice in, and returns the arrow error and the cubic coefficient
/// found.
fn explained(model: &dyn Model, est: &Recording, arrow: &Recording, only: &[&str]) -> (f64, f64) {
    let opts = ExplainOptions {
        only: only.iter().map(|s| s.to_string()).collect(),
        ..ExplainOptions::default()
    };
    let ex = explain(model, est, &opts).unwrap();
    let first = &ex.ranked[0];
    assert!(
        first.candidate.id == "stiffness@k" || first.candidate.id == "declared:cubic",
        "ranked first: {} ({only:?})",
        first.candidate.id
    );
    assert!(
        matches!(ex.verdict, Verdict::EffectFound | Verdict::Partial),
        "{:?}",
        ex.verdict
    );
    let b = first.params[0].value;
    let fixed = model.with_effects(&ex.effects()).unwrap();
    (rms_of(fixed.as_ref(), arrow), b)
}

#[test]
fn silverbox_cubic_spring_is_found_and_cuts_the_validation_error_threefold() {
    let (linear, est, arrow, linear_rms) = calibrated_linear();
    // The built-in menu's cubic stiffness, against alternatives that also act at the mass.
    let (rms, k3) = explained(
        linear.as_ref(),
        &est,
        &arrow,
        &["stiffness@k", "coulomb@1m", "fault:a", "inertia@1m"],
    );
    assert!(
        (3.0..4.5).contains(&k3),
        "k3 = {k3} (scipy on the whole record: 3.95)"
    );
    assert!(
        rms <= linear_rms / 3.0,
        "arrow RMS: calibrated linear {linear_rms} → with the cubic stiffness {rms}"
    );
    // The user's own declared candidate gives the same answer.
    let (rms, b) = explained(
        linear.as_ref(),
        &est,
        &arrow,
        &["declared:cubic", "coulomb@1m"],
    );
    assert!((3.0..4.5).contains(&b), "b = {b}");
    assert!(
        rms <= linear_rms / 3.0,
        "arrow RMS: calibrated linear {linear_rms} → with the declared cubic {rms}"
    );
}

/// The whole menu with discovery, as a user runs it: the floor is read where the multisine
/// is quiet (its third differences carry the 62 Hz resonance), the cubic spring is found at
/// the mass (the built-in stiffness, the law discovery found, or the declared candidate,
/// which the record tells apart by less than its evidence), it halves the validation error
/// at least, and the verdict says the record holds more than that (a partial explanation:
/// the sensor's noise is about 2e-5 V, the cubic model leaves 1e-3 V).
#[test]
fn silverbox_whole_menu_finds_the_cubic_spring_against_the_quiet_band_floor() {
    let (linear, est, arrow, linear_rms) = calibrated_linear();
    let ex = explain(linear.as_ref(), &est, &ExplainOptions::default()).unwrap();
    let story = modelgap::story::explanation_text(&ex, 5);
    let y = &ex.outputs[0];
    assert_eq!(
        y.noise_method,
        modelgap::compare::FloorKind::QuietBand,
        "{story}"
    );
    assert!(y.noise_floor < 1e-4, "floor {}\n{story}", y.noise_floor);
    let first = &ex.chosen[0];
    let cubic = ["stiffness@k", "declared:cubic"].contains(&first.candidate.id.as_str())
        || first.candidate.id.starts_with("law@1m:") && first.candidate.id.contains("k.q^3");
    assert!(cubic, "chosen first: {}\n{story}", first.candidate.id);
    assert_eq!(ex.verdict, Verdict::Partial, "{story}");
    let fixed = linear.with_effects(&ex.effects()).unwrap();
    let rms = rms_of(fixed.as_ref(), &arrow);
    assert!(
        rms <= linear_rms / 2.0,
        "arrow RMS: calibrated linear {linear_rms} → explained {rms}\n{story}"
    );
}

const BUCK_MODEL: &str = "examples/models/buck-converter.toml";
const BUCK_ESTIMATION: &str = "examples/data/realdata/buck_converter/buck_estimation.csv";
const BUCK_VALIDATION: &str = "examples/data/realdata/buck_converter/buck_validation.csv";

/// The buck converter (SysIdentPy's records): the averaged model calibrates, the winding
/// resistance that would need to be negative is reported at its bound without an
/// uncertainty, the output's 0.2 V quantisation is recognised and sets the floor, and
/// explain does not call a model that leaves 5× the floor complete.
#[test]
fn buck_converter_calibrates_and_its_quantisation_is_recognised() {
    let model = load_model(root(BUCK_MODEL).to_str().unwrap(), &LoadOptions::default()).unwrap();
    let est = modelgap::load_recording(&root(BUCK_ESTIMATION), model.as_ref()).unwrap();
    let val = modelgap::load_recording(&root(BUCK_VALIDATION), model.as_ref()).unwrap();
    let cal = calibrate(model.as_ref(), &est, &CalibrationOptions::default()).unwrap();
    assert_eq!(cal.termination, modelgap::fit::Termination::Converged);
    let (before, after) = (cal.rms_before[0].1, cal.rms_after[0].1);
    assert!(after < 0.5 * before && after < 0.4, "{before} -> {after}");
    // The measured mean output lies above the ideal m·Vs: rL wants to be negative.
    let r = cal.values.iter().find(|v| v.name == "rL").unwrap();
    assert_eq!(r.at_bound, Some("lower"), "{r:?}");
    assert_eq!(r.std_error, None, "{r:?}");
    // The time constants land where the data put them (0.1–1 ms), not at a bound.
    for name in ["L", "C"] {
        let v = cal.values.iter().find(|v| v.name == name).unwrap();
        assert!(v.at_bound.is_none() && v.std_error.is_some(), "{v:?}");
    }
    for rec in [&est, &val] {
        let c = modelgap::compare(cal.model.as_ref(), rec, &Default::default()).unwrap();
        let vo = c.output("Vo").unwrap();
        let q = vo.quantum.expect("the 0.2 V steps are recognised");
        assert!((q - 0.2).abs() < 1e-9, "quantum {q}");
        assert!(
            vo.noise_floor >= 0.999 * 0.2 / 12f64.sqrt(),
            "{}",
            vo.noise_floor
        );
    }
    let ex = explain(cal.model.as_ref(), &est, &ExplainOptions::default()).unwrap();
    assert!(
        !matches!(ex.verdict, Verdict::NothingMissing),
        "{:?}: the calibrated model leaves {after} V against a floor near 0.06 V",
        ex.verdict
    );
}

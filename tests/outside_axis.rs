//! Hidden effects on a linear axis (`examples/models/linear-axis.toml`: a
//! carriage pushed by a force, a viscous guide, its velocity measured),
//! simulated by a generator that is not modelgap's: the equation of motion
//! written out by hand and integrated with classical Runge–Kutta. Each case
//! hides one effect in a form the menu does not have: Coulomb friction with
//! an offset (the published answer on a real ball-screw drive), a linear
//! motor's cogging locked to the position with a pitch nobody told the model,
//! Stribeck friction, white or coloured noise.
//!
//! `cargo test --release --test outside_axis -- --ignored --nocapture`
//! prints the table the docs quote; two cases also run in CI.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in tests, a panic is a failure

mod common;
use common::{Noise, print_row};

use std::path::Path;

use modelgap::bond::simulate::Hold;

use modelgap::{
    ExplainOptions, Explanation, LoadOptions, Model, Recording, Signal, explain, load_model,
};

const M: f64 = 5.0;
const C: f64 = 200.0;

type Law = fn(f64, f64, f64) -> f64;

fn drive(t: f64) -> f64 {
    use std::f64::consts::TAU;
    80.0 * (TAU * 0.5 * t).sin() + 25.0 * (TAU * 2.3 * t).sin() + 10.0 * (TAU * 7.0 * t).sin()
}

/// 6 s at 1 kHz of a carriage with the extra force `law(v, x, t)` opposing
/// it; velocity noise `white` × range plus AR(0.9) noise `coloured` × range.
fn record(law: Option<Law>, white: f64, coloured: f64, seed: u64) -> Recording {
    let f = |t: f64, s: [f64; 2]| {
        let extra = law.map_or(0.0, |l| l(s[0], s[1], t));
        [(drive(t) - C * s[0] - extra) / M, s[0]]
    };
    let (mut ts, mut fs, mut vs) = (vec![], vec![], vec![]);
    common::rk4([0.0; 2], f, 1e-3, 6001, 20, |t, s| {
        ts.push(t);
        fs.push(drive(t));
        vs.push(s[0]);
    });
    let mut rng = Noise(0x9E37_79B9_7F4A_7C15 ^ seed.wrapping_mul(0x2545_F491_4F6C_DD1D));
    let range = vs.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let gain = (1.0_f64 - 0.81).sqrt();
    let mut ar = 0.0;
    let vs = vs
        .iter()
        .map(|v| {
            ar = 0.9 * ar + gain * rng.gauss();
            v + white * range * rng.gauss() + coloured * range * ar
        })
        .collect();
    let signals = vec![
        Signal {
            name: "F".into(),
            values: fs,
        },
        Signal {
            name: "v".into(),
            values: vs,
        },
    ];
    Recording::new(ts, signals).unwrap()
}

fn explained(rec: &Recording) -> Explanation {
    explain(model().as_ref(), rec, &ExplainOptions::default()).unwrap()
}

fn model() -> Box<dyn Model> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("examples/models/linear-axis.toml");
    // The force is recorded at 1 kHz from a smooth drive: read between samples linearly.
    let opts = LoadOptions {
        hold: Some(Hold::Linear),
        ..LoadOptions::default()
    };
    load_model(path.to_str().unwrap(), &opts).unwrap()
}

fn cases() -> Vec<(&'static str, Option<Law>)> {
    vec![
        ("control", None),
        (
            "coulomb + offset",
            Some(|v, _, _| 20.0 * (v / 1e-3).tanh() - 3.0),
        ),
        (
            "cogging pitch 32 mm",
            Some(|_, x, _| 6.0 * (std::f64::consts::TAU * x / 0.032 + 0.5).sin()),
        ),
        (
            "stribeck",
            Some(|v, _, _| (12.0 + 15.0 * (-(v / 0.02).powi(2)).exp()) * (v / 1e-3).tanh()),
        ),
        (
            "asymmetric viscous",
            Some(|v, _, _| if v > 0.0 { 60.0 * v } else { 120.0 * v }),
        ),
    ]
}

fn params(ex: &Explanation) -> (Vec<(String, f64)>, String) {
    let params = (ex.chosen.iter())
        .flat_map(|c| c.params.iter().map(|p| (p.name.clone(), p.value)))
        .collect();
    (params, modelgap::story::explanation_text(ex, 6))
}

fn value(params: &[(String, f64)], name: &str, text: &str) -> f64 {
    (params.iter().find(|(n, _)| n.starts_with(name)))
        .unwrap_or_else(|| panic!("no {name}:\n{text}"))
        .1
}

fn case(name: &str) -> Option<Law> {
    cases().into_iter().find(|(n, _)| *n == name).unwrap().1
}

#[test]
fn a_linear_motors_cogging_is_named_with_its_pitch() {
    let ex = explained(&record(case("cogging pitch 32 mm"), 2e-3, 0.0, 21));
    let (p, text) = params(&ex);
    assert_eq!(ex.chosen.len(), 1, "{text}");
    assert!(ex.chosen[0].candidate.id.starts_with("law@1v:"), "{text}");
    let lambda = value(&p, "lam_sinx", &text);
    assert!((lambda - 0.032).abs() < 0.05 * 0.032, "{lambda}:\n{text}");
    let amplitude = value(&p, "c_sinx", &text).hypot(value(&p, "c_cosx", &text));
    assert!((amplitude - 6.0).abs() < 0.05 * 6.0, "{amplitude}:\n{text}");
    for o in &ex.outputs {
        assert!(o.rms_after <= 1.3 * o.noise_floor, "{text}");
    }
    // Built in, as `fix` does: the model file written reads back and predicts the same.
    let fixed = model().with_effects(&ex.effects()).unwrap();
    let file = fixed.to_file_text().unwrap();
    assert!(file.contains("lam_sinx"), "{file}");
    let back = modelgap::bond::BondModel::new(modelgap::bond::file::read_model(&file).unwrap())
        .with_hold(Hold::Linear);
    let rec = record(case("cogging pitch 32 mm"), 2e-3, 0.0, 21);
    let (a, b) = (fixed.predict(&rec).unwrap(), back.predict(&rec).unwrap());
    let (a, b) = (a.get("v").unwrap(), b.get("v").unwrap());
    assert!(a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9), "{file}");
}

#[test]
fn coulomb_friction_with_an_offset_is_found_with_the_drives_default_at_zero() {
    let ex = explained(&record(case("coulomb + offset"), 2e-3, 0.0, 22));
    let (p, text) = params(&ex);
    // As one law (a sign term and a constant) or as Coulomb friction and a load.
    let level = p
        .iter()
        .find(|(n, _)| n.starts_with("c_sign") || n.starts_with("F_c"))
        .unwrap_or_else(|| panic!("no friction level:\n{text}"))
        .1;
    let offset = p
        .iter()
        .find(|(n, _)| n.starts_with("c_const") || n.starts_with("F_0"))
        .unwrap_or_else(|| panic!("no offset:\n{text}"))
        .1;
    assert!((level - 20.0).abs() < 1.0, "{level}:\n{text}");
    assert!((offset + 3.0).abs() < 0.15, "{offset}:\n{text}");
    for o in &ex.outputs {
        assert!(o.rms_after <= 1.3 * o.noise_floor, "{text}");
    }
}

#[test]
#[ignore = "about a minute in release: the battery the docs quote"]
fn battery() {
    for (white, coloured) in [(2e-3, 0.0), (1e-3, 2e-3)] {
        println!("noise: white {white}, AR(0.9) {coloured} of range");
        for (name, law) in cases() {
            let rec = record(law, white, coloured, 7);
            print_row(name, || explained(&rec));
        }
    }
}

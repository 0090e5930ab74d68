//! Discovery (issue 14): the missing effort estimated where it acts, its law
//! screened from a typed library, confirmed by simulation — on hidden laws
//! unlike any menu candidate's shape, with noise, and on the real Silverbox.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in tests, a panic is a failure

mod common;
use common::Noise;

use modelgap::Signal;
use modelgap::bond::expr::parse;
use modelgap::bond::simulate::{Drive, Hold, Inputs, SimOptions, simulate};
use modelgap::bond::{BondModel, Element, ElementKind, library};
use modelgap::{ExplainOptions, Explanation, Recording, explain};

/// The DC motor with a hidden resistive law on its shaft, driven by a
/// multisine that reverses the shaft many times, 4 s at 1 kHz, with white
/// noise of `noise` × each output's range.
fn motor_with(hidden: Option<&str>, noise: f64, seed: u64) -> Recording {
    motor_driven(hidden, noise, seed, false)
}

/// [`motor_with`], or (`stepped`) driven by voltage steps held 0.4 s each, some of them 0 V,
/// where the shaft comes to rest and friction holds it.
fn motor_driven(hidden: Option<&str>, noise: f64, seed: u64, stepped: bool) -> Recording {
    let mut g = library::builtin("dc-motor").unwrap();
    let shaft = g.find("1m").unwrap();
    if let Some(law) = hidden {
        if law.contains("ang.q") {
            // The shaft's angle from the start, for a law that reads it.
            let zero = parse("0 * q").unwrap();
            let ang = g
                .add(Element::nonlinear("ang", ElementKind::C, Some(zero), None))
                .unwrap();
            g.bond(shaft, ang).unwrap();
        }
        let id = g
            .add(Element::nonlinear(
                "hidden",
                ElementKind::R,
                Some(parse(law).unwrap()),
                None,
            ))
            .unwrap();
        g.bond(shaft, id).unwrap();
    }
    let t: Vec<f64> = (0..=4000).map(|k| k as f64 * 1e-3).collect();
    let steps = [6.0, 12.0, 0.0, -12.0, -4.0, 0.0, 9.0, 0.0, 3.0, -8.0, 0.0];
    let v: Vec<f64> = t
        .iter()
        .map(|&t| {
            if stepped {
                steps[((t / 0.4) as usize).min(steps.len() - 1)]
            } else {
                6.0 * (std::f64::consts::TAU * 0.7 * t).sin()
                    + 2.0 * (std::f64::consts::TAU * 3.3 * t).sin()
            }
        })
        .collect();
    let inputs = Inputs::new().with(
        "V",
        Drive::Sampled {
            t: t.clone(),
            values: v.clone(),
            hold: if stepped { Hold::Zero } else { Hold::Linear },
        },
    );
    let run = simulate(
        &g,
        &inputs,
        &t,
        &SimOptions {
            rtol: 1e-9,
            atol: 1e-12,
            ..SimOptions::default()
        },
    )
    .unwrap();
    let mut rng = Noise(0x9E37_79B9_7F4A_7C15 ^ seed.wrapping_mul(0x2545_F491_4F6C_DD1D));
    let mut signals = vec![Signal {
        name: "V".into(),
        values: v,
    }];
    for (name, y) in run.output_names.iter().zip(&run.outputs) {
        let range = y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        signals.push(Signal {
            name: name.clone(),
            values: y.iter().map(|v| v + noise * range * rng.gauss()).collect(),
        });
    }
    Recording::new(t, signals).unwrap()
}

fn motor_model(v_default: f64) -> BondModel {
    let mut g = library::builtin("dc-motor").unwrap();
    g.add_input("V", v_default, "V", "armature voltage")
        .unwrap();
    BondModel::new(g).with_hold(Hold::Linear)
}

fn explained(rec: &Recording) -> Explanation {
    explain(&motor_model(12.0), rec, &ExplainOptions::default()).unwrap()
}

fn story(ex: &Explanation) -> String {
    modelgap::story::explanation_text(ex, 6)
}

/// The chosen law: its id, and each parameter's value by name.
fn chosen_law(ex: &Explanation) -> Vec<(String, f64)> {
    let first = ex
        .chosen
        .first()
        .unwrap_or_else(|| panic!("nothing chosen:\n{}", story(ex)));
    assert!(
        first.candidate.id.starts_with("law@1m:"),
        "a law at the shaft must be chosen, not {}:\n{}",
        first.candidate.id,
        story(ex)
    );
    first
        .params
        .iter()
        .map(|p| (p.name.clone(), p.value))
        .collect()
}

fn param(params: &[(String, f64)], name: &str) -> f64 {
    params
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, v)| *v)
        .unwrap_or_else(|| panic!("no parameter {name} in {params:?}"))
}

fn at_floor(ex: &Explanation, factor: f64) {
    for o in &ex.outputs {
        assert!(
            o.rms_after <= factor * o.noise_floor,
            "{} is left at {:.2}× its floor:\n{}",
            o.name,
            o.rms_after / o.noise_floor,
            story(ex)
        );
    }
}

#[test]
fn stribeck_friction_is_seen_at_the_shaft_and_named_with_its_shape() {
    // Coulomb 0.01 N m with a Stribeck excess of 0.02 N m below about 6 rad/s: no menu
    // candidate has this shape (the menu's Coulomb friction leaves 7x the floor).
    let rec = motor_with(
        Some("0.01 * tanh(f / 0.5) + 0.02 * tanh(f / 0.5) * exp(-(f / 6)^2)"),
        0.002,
        1,
    );
    let ex = explained(&rec);
    let place = &ex.places[0];
    assert_eq!(place.location, "1m", "{}", story(&ex));
    assert!(place.explained > 0.9, "{}", story(&ex));
    let law = chosen_law(&ex);
    let coulomb = param(&law, "c_sign");
    assert!(
        (coulomb - 0.01).abs() < 0.0005,
        "Coulomb {coulomb}\n{}",
        story(&ex)
    );
    let stribeck = param(&law, "c_stribeck");
    assert!(
        (stribeck - 0.02).abs() < 0.004,
        "Stribeck {stribeck}\n{}",
        story(&ex)
    );
    let vs = param(&law, "vs_stribeck");
    assert!(
        (4.5..8.0).contains(&vs),
        "Stribeck speed {vs}\n{}",
        story(&ex)
    );
    at_floor(&ex, 1.3);
}

/// Coulomb friction that differs by direction (0.015 N m forward, 0.006 N m backward, each
/// reached linearly within 0.1 rad/s: not the library's tanh): a sign term beside its
/// magnitude, `|tanh(v/ε)|`, names both levels;
/// a linear-in-speed `|v|` (viscous friction that differs by direction) was all the library
/// had, and a real geared drive's asymmetric friction was left partial with it.
#[test]
fn coulomb_friction_that_differs_by_direction_is_named_with_both_levels() {
    let rec = motor_driven(
        Some("0.015 * min(max(f / 0.1, 0), 1) + 0.006 * max(min(f / 0.1, 0), -1)"),
        0.002,
        4,
        true,
    );
    // Steps held: the shaft rests at 0 V, where a constant torque would turn it and
    // friction holds it.
    let mut g = library::builtin("dc-motor").unwrap();
    g.add_input("V", 12.0, "V", "armature voltage").unwrap();
    let model = BondModel::new(g).with_hold(Hold::Zero);
    let ex = explain(&model, &rec, &ExplainOptions::default()).unwrap();
    let law = chosen_law(&ex);
    let (sign, magnitude) = (param(&law, "c_sign"), param(&law, "c_smag"));
    let (forward, backward) = (sign + magnitude, sign - magnitude);
    assert!(
        (forward - 0.015).abs() < 0.00075 && (backward - 0.006).abs() < 0.0006,
        "forward {forward}, backward {backward}\n{}",
        story(&ex)
    );
    at_floor(&ex, 1.3);
}

#[test]
fn a_fan_load_is_named_as_quadratic_drag_within_five_percent() {
    let rec = motor_with(Some("2e-6 * f * abs(f)"), 0.002, 2);
    let ex = explained(&rec);
    let law = chosen_law(&ex);
    let c = param(&law, "c_drag");
    assert!((c / 2e-6 - 1.0).abs() < 0.05, "c_drag {c}\n{}", story(&ex));
    at_floor(&ex, 1.3);
    // The text says where it fails and the law; the JSON carries it; the report plots it.
    let text = story(&ex);
    assert!(text.contains("where the model fails"), "{text}");
    let json = modelgap::json::explanation_json(&ex);
    assert_eq!(json["places"][0]["location"], "1m", "{json}");
    assert_eq!(
        json["places"][0]["law"]["terms"][0]["family"], "quadratic-drag",
        "{json}"
    );
    let model = motor_model(12.0);
    let before = modelgap::compare(&model, &rec, &modelgap::CompareOptions::default()).unwrap();
    let report = modelgap::story::build_report(&before, Some(&ex), None);
    let (caption, svg) = &report.extra_svgs[0];
    assert!(caption.starts_with("Where the model fails: the missing effort at the shaft (1m)"));
    assert!(
        svg.contains("<svg") && svg.contains("law found"),
        "{caption}"
    );
    if let Ok(dir) = std::env::var("MODELGAP_SHOW") {
        std::fs::write(format!("{dir}/missing.svg"), svg).unwrap();
    }
}

#[test]
fn a_ripple_locked_to_the_angle_is_named_with_its_order() {
    // An order-6 ripple with a phase the menu's cogging (A sin Nθ) cannot take.
    let rec = motor_with(Some("0.008 * sin(6 * ang.q + 0.7)"), 0.002, 3);
    let ex = explained(&rec);
    let law = chosen_law(&ex);
    let (s6, c6) = (param(&law, "c_sin6"), param(&law, "c_cos6"));
    let amplitude = s6.hypot(c6);
    // Measured: 0.0073 (9 % low) and phase 0.65: the fit by simulation stops in a local
    // minimum (the exact law leaves 8 % less RMS); the estimate's random walk attenuates a
    // 95 Hz ripple threefold, so the regression's start is far. Still to do.
    assert!(
        (amplitude / 0.008 - 1.0).abs() < 0.12,
        "amplitude {amplitude}\n{}",
        story(&ex)
    );
    let phase = c6.atan2(s6);
    assert!((phase - 0.7).abs() < 0.1, "phase {phase}\n{}", story(&ex));
    at_floor(&ex, 1.3);
}

#[test]
fn a_load_that_steps_mid_run_is_named_with_its_time() {
    let rec = motor_with(Some("0.02 * max(sign(t - 2.1), 0)"), 0.002, 4);
    let ex = explained(&rec);
    let first = ex.chosen.first().expect("something chosen");
    let text = story(&ex);
    // The menu's abrupt changes cannot say it; the law's step can, with its time.
    assert!(first.candidate.id.starts_with("law@1m:"), "{text}");
    let law = chosen_law(&ex);
    let (c, t) = (param(&law, "c_step"), param(&law, "t_step"));
    assert!((c / 0.02 - 1.0).abs() < 0.05, "step {c}\n{text}");
    assert!((t - 2.1).abs() < 0.01, "at {t}\n{text}");
    at_floor(&ex, 1.3);
}

#[test]
fn the_right_model_gets_nothing_missing_and_no_law() {
    for seed in 10..14 {
        let rec = motor_with(None, 0.002, seed);
        let ex = explained(&rec);
        assert_eq!(
            ex.verdict,
            modelgap::Verdict::NothingMissing,
            "seed {seed}\n{}",
            story(&ex)
        );
    }
}

#[test]
fn the_answer_does_not_depend_on_an_input_default_the_recording_overrides() {
    let rec = motor_with(Some("2e-6 * f * abs(f)"), 0.002, 5);
    let a = explain(&motor_model(12.0), &rec, &ExplainOptions::default()).unwrap();
    let b = explain(&motor_model(0.0), &rec, &ExplainOptions::default()).unwrap();
    assert_eq!(a.chosen[0].candidate.id, b.chosen[0].candidate.id);
    let (ca, cb) = (a.chosen[0].params[0].value, b.chosen[0].params[0].value);
    assert!((ca / cb - 1.0).abs() < 1e-3, "{ca} vs {cb}");
    assert!((a.places[0].rms / b.places[0].rms - 1.0).abs() < 1e-6);
}

#[test]
fn silverbox_missing_effort_follows_the_cubic_spring() {
    use modelgap::{CalibrationOptions, LoadOptions, calibrate, load_model};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let opts = LoadOptions {
        hold: Some(Hold::Linear),
        ..LoadOptions::default()
    };
    let path = root.join("examples/models/silverbox-linear.toml");
    let model = load_model(path.to_str().unwrap(), &opts).unwrap();
    let est = modelgap::load_recording(
        &root.join("examples/data/realdata/silverbox/silverbox_estimation.csv"),
        model.as_ref(),
    )
    .unwrap();
    let cal = calibrate(model.as_ref(), &est, &CalibrationOptions::default()).unwrap();
    // The noise floor explain would use (the record's third differences).
    let y = &est.signal("y").unwrap().values;
    let sigma = modelgap::compare::noise_floor("y", y, &Default::default()).sigma;
    let m = cal
        .model
        .missing_signals(&est, &[], &["y".to_string()], &[sigma])
        .unwrap();
    let mass = m
        .iter()
        .find(|s| s.location == "1m")
        .expect("the mass is a place");
    for lin in [true, false] {
        let l = modelgap::explain::screen::screen_with(mass, lin);
        eprintln!(
            "{lin}: {:?}",
            l.map(|l| (l.describe(), l.explained, l.effective_samples))
        );
    }
    eprintln!("rms {} band {}", mass.rms(), mass.typical_band());
    assert!(mass.explained > 0.9, "{}", mass.explained);
    let law = modelgap::explain::screen::screen_with(mass, false).expect("a law");
    let first = &law.terms[0];
    assert_eq!(
        (first.family, first.expr.as_str()),
        (modelgap::explain::screen::Family::Cubic, "k.q^3"),
        "{}",
        law.describe()
    );
    // The whole record's least-squares cubic is 3.95 (scipy): the linear calibration has
    // taken part of it, and a quadratic term may share the rest.
    assert!(
        (2.0..5.0).contains(&first.coefficient),
        "{}",
        law.describe()
    );
}

#[test]
fn a_speed_sensor_that_reads_high_is_named_an_offset_of_its_sensor() {
    let rec = motor_with(None, 0.002, 7);
    let mut signals: Vec<modelgap::Signal> = Vec::new();
    for name in ["V", "i", "omega"] {
        let v = &rec.signal(name).unwrap().values;
        let shift = if name == "omega" { 2.0 } else { 0.0 };
        signals.push(modelgap::Signal {
            name: name.into(),
            values: v.iter().map(|x| x + shift).collect(),
        });
    }
    let rec = Recording::new(rec.t().to_vec(), signals).unwrap();
    let ex = explained(&rec);
    let first = ex
        .chosen
        .first()
        .unwrap_or_else(|| panic!("{}", story(&ex)));
    assert_eq!(first.candidate.id, "offset@omega", "{}", story(&ex));
    let b = first.params[0].value;
    assert!((b / 2.0 - 1.0).abs() < 0.05, "offset {b}\n{}", story(&ex));
    at_floor(&ex, 1.3);
}

/// A Duffing–van der Pol oscillator written out by hand (classical
/// Runge–Kutta, ten steps a sample): the Silverbox's linear mass, spring and
/// damper, with a damping that grows with the displacement squared,
/// `c·q²·v` — a law no menu effect has, a product of two signals acting at
/// the mass. Driven by a multisine over 10–120 Hz, 3 s at 2 kHz, white noise
/// of 2e-4 V on the output.
fn van_der_pol(c: f64, seed: u64) -> Recording {
    oscillator(|q, v| c * q * q * v, 0.0, seed)
}

/// Silverbox's linear oscillator with an `extra` restoring force `f(q, v)`
/// (V, as the model's units), integrated by hand (RK4, ten substeps a
/// sample), 3 s at 2 kHz under a 10–120 Hz multisine; the output carries
/// noise of RMS 2e-4 V, AR(1) with coefficient `rho` (0: white).
fn oscillator(extra: impl Fn(f64, f64) -> f64, rho: f64, seed: u64) -> Recording {
    let (m, d, a, offset) = (7.795e-6, 2.4696e-4, 1.2289, 0.01);
    let dt = 5e-4;
    let t: Vec<f64> = (0..6000).map(|k| k as f64 * dt).collect();
    let drive = |t: f64| -> f64 {
        (1..=12)
            .map(|k| {
                let f = 10.0 * k as f64;
                0.02 * (std::f64::consts::TAU * f * t + 0.7 * (k * k) as f64).sin()
            })
            .sum()
    };
    let u: Vec<f64> = t.iter().map(|&t| drive(t)).collect();
    let accel = |q: f64, v: f64, u: f64| (u - d * v - a * q - extra(q, v)) / m;
    let (mut q, mut v) = (0.0, 0.0);
    let mut rng = Noise(0x5DEE_CE66_D1CE_4E5B ^ seed.wrapping_mul(0x2545_F491_4F6C_DD1D));
    let innovation = 2e-4 * (1.0 - rho * rho).sqrt();
    let mut e = 2e-4 * rng.gauss();
    let mut y = Vec::with_capacity(t.len());
    for k in 0..t.len() {
        y.push(q + offset + e);
        e = rho * e + innovation * rng.gauss();
        if k + 1 == t.len() {
            break;
        }
        // The input held linearly between samples, as the model's `--hold linear`.
        let (u0, u1) = (u[k], u[k + 1]);
        let sub = 10;
        let h = dt / sub as f64;
        for s in 0..sub {
            let at = |x: f64| u0 + (u1 - u0) * x;
            let (x0, x1) = (s as f64 / sub as f64, (s + 1) as f64 / sub as f64);
            let xm = 0.5 * (x0 + x1);
            let k1 = (v, accel(q, v, at(x0)));
            let k2 = (
                v + 0.5 * h * k1.1,
                accel(q + 0.5 * h * k1.0, v + 0.5 * h * k1.1, at(xm)),
            );
            let k3 = (
                v + 0.5 * h * k2.1,
                accel(q + 0.5 * h * k2.0, v + 0.5 * h * k2.1, at(xm)),
            );
            let k4 = (v + h * k3.1, accel(q + h * k3.0, v + h * k3.1, at(x1)));
            q += h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
            v += h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
        }
    }
    Recording::new(t, vec![Signal::new("u", u), Signal::new("y", y)]).unwrap()
}

fn silverbox_linear() -> Box<dyn modelgap::Model> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let opts = modelgap::LoadOptions {
        hold: Some(Hold::Linear),
        ..modelgap::LoadOptions::default()
    };
    let path = root.join("examples/models/silverbox-linear.toml");
    modelgap::load_model(path.to_str().unwrap(), &opts).unwrap()
}

#[test]
fn a_damping_that_grows_with_the_displacement_is_named_as_a_product() {
    let c = 5e-3;
    let rec = van_der_pol(c, 3);
    let peak = (rec.signal("y").unwrap().values.iter()).fold(0.0_f64, |m, v| m.max(v.abs()));
    // The sensor's noise, as its maker states it: at 2 kHz the multisine's own fast content
    // is in the third differences, and the floor estimated from them is half again too high.
    let opts = ExplainOptions {
        noise: [("y".to_string(), 2e-4)].into(),
        ..ExplainOptions::default()
    };
    let ex = explain(silverbox_linear().as_ref(), &rec, &opts).unwrap();
    let text = story(&ex);
    eprintln!("peak {peak}\n{text}");
    let law = chosen_law(&ex);
    // One term, the product: the screen's extra terms (a cubic of the speed, a quadratic of
    // the position, mending the shape the calibration bent) are dropped once confirmed.
    assert_eq!(ex.chosen.len(), 1, "{text}");
    assert_eq!(
        ex.chosen[0].candidate.id, "law@1m:c_prod * '1m'.f * k.q^2",
        "{text}"
    );
    assert_eq!(law.len(), 1, "{text}");
    let coefficient = param(&law, "c_prod");
    assert!(
        (coefficient / c - 1.0).abs() < 0.05,
        "{coefficient} against {c}:\n{text}"
    );
    at_floor(&ex, 1.3);
}

#[test]
fn an_eddy_current_brake_no_typed_term_can_say_is_found_by_the_symbolic_search() {
    // An eddy-current brake's torque peaks at a critical speed and falls beyond it (2 T_m
    // (ω/ω_c)/(1 + (ω/ω_c)²), T_m 0.02 N m at ω_c 40 rad/s): no family of the library has
    // this shape. The typed library alone mimicked it with four terms (a sign 21 rad/s wide,
    // a negative drag, a negative Stribeck excess and a cubic), all reaching the floor.
    let rec = motor_with(Some("0.04 * (f / 40) / (1 + (f / 40)^2)"), 0.002, 5);
    let ex = explained(&rec);
    let text = story(&ex);
    let law = chosen_law(&ex);
    assert_eq!(law.len(), 2, "one term and its scale:\n{text}");
    let (c, a) = (param(&law, "c_sym"), param(&law, "a_sym"));
    assert!((c / 0.04 - 1.0).abs() < 0.05, "{c}\n{text}");
    assert!((a / 40.0 - 1.0).abs() < 0.05, "{a}\n{text}");
    let words = text.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        words.contains("a symbolic search built (the formula names no physical law)"),
        "{text}"
    );
    assert_eq!(
        modelgap::json::explanation_json(&ex)["places"][0]["law"]["terms"][0]["family"],
        "symbolic"
    );
    at_floor(&ex, 1.3);
    // The report's plot of the missing effort says the formula is the symbolic search's.
    let model = motor_model(12.0);
    let before = modelgap::compare(&model, &rec, &modelgap::CompareOptions::default()).unwrap();
    let report = modelgap::story::build_report(&before, Some(&ex), None);
    let (caption, svg) = &report.extra_svgs[0];
    assert!(
        caption.contains("a formula of the symbolic search, no named law"),
        "{caption}"
    );
    if let Ok(dir) = std::env::var("MODELGAP_SHOW") {
        std::fs::write(format!("{dir}/missing-symbolic.svg"), svg).unwrap();
    }
}

#[test]
fn a_spring_that_softens_like_an_arctangent_is_found_through_coloured_noise() {
    // A restoring force that saturates, f_s·atan(q/q_s) on top of the linear spring (a
    // magnetic spring, a rubber mount), under AR(0.9) sensor noise given by its maker.
    let (fs, qs) = (0.02, 0.05);
    let rec = oscillator(|q, _| fs * (q / qs).atan(), 0.9, 7);
    let opts = ExplainOptions {
        noise: [("y".to_string(), 2e-4)].into(),
        ..ExplainOptions::default()
    };
    let ex = explain(silverbox_linear().as_ref(), &rec, &opts).unwrap();
    let text = story(&ex);
    // The typed library's best, a one-sided spring `q·|q|`, leaves 2.7× the floor; a
    // formula of the symbolic search reaches it. Which saturating shape (measured: the peak
    // `u/(1 + u²)`, not the arctangent) the record cannot tell within its noise, so the
    // formula is reported as a shape, not a named law.
    let first = &ex.chosen[0];
    assert!(
        first.candidate.id.starts_with("law@1m:c_sym *"),
        "{}\n{text}",
        first.candidate.id
    );
    assert_eq!(ex.chosen.len(), 1, "{text}");
    at_floor(&ex, 1.3);
}

/// A driven pendulum (a user's model: the gravity torque written out as `mgl sin q`), its
/// inertia and pivot friction free.
const PENDULUM: &str = r#"name = "pendulum"
[parameters]
J = { value = 0.045, unit = "kg m^2", description = "inertia about the pivot", free = true, min = 0.01, max = 0.2 }
b = { value = 0.002, unit = "N m s/rad", description = "pivot viscous friction", free = true, min = 0.0, max = 1.0 }
mgl = { value = 1.47, unit = "N m", description = "gravity torque at 90 degrees" }
[inputs]
tau = { default = 0.0, unit = "N m", description = "motor torque" }
[[elements]]
name = "motor"
kind = "Se"
effort = "tau"
[[elements]]
name = "pivot"
kind = "1"
domain = "rotational"
[[elements]]
name = "J"
kind = "I"
parameter = "J"
[[elements]]
name = "b"
kind = "R"
parameter = "b"
[[elements]]
name = "gravity"
kind = "C"
effort = "mgl * sin(q)"
[[bonds]]
from = "motor"
to = "pivot"
[[bonds]]
from = "pivot"
to = "J"
[[bonds]]
from = "pivot"
to = "b"
[[bonds]]
from = "pivot"
to = "gravity"
[[outputs]]
name = "angle"
state = "gravity"
unit = "rad"
"#;

/// Where the model is far from the data (a pendulum the nominal model swings over the top
/// and on round and round, 135 rad away at worst, while the real one, slowed by air drag
/// `0.006 ω|ω|`, turns over a few times), the missing torque is still estimated where it
/// acts, and its law found: the smoother's random walk was sized from the nominal's error,
/// and the likeliest intensity lay below every one it tried (the estimate was noise, a band
/// of 0.22 N m about a torque of 0.06 N m, and no law was found).
#[test]
fn air_drag_on_a_pendulum_far_from_its_model_is_found_where_it_acts() {
    let truth = PENDULUM.replace(
        "parameter = \"b\"",
        "effort = \"b * f + 0.006 * f * abs(f)\"",
    );
    let g = modelgap::bond::file::read_model(&truth).unwrap();
    let (fs, duration) = (200.0, 30.0);
    let n = (fs * duration) as usize;
    let t: Vec<f64> = (0..n).map(|k| k as f64 / fs).collect();
    let mut noise = Noise(0x5eed_0f9e);
    // A staircase of torques, 1.5 s each, and a slow sine.
    let levels = [
        0.225, 0.715, 0.496, -0.495, -0.360, 0.672, -0.891, 0.578, 0.535, -0.058, -0.355, -0.399,
        -0.441, -0.099, 0.008, 0.096, 0.892, 0.527, 0.220, 0.880, -0.512,
    ];
    let tau: Vec<f64> = (t.iter())
        .map(|&t| levels[(t / 1.5) as usize] + 0.3 * (std::f64::consts::TAU * 0.37 * t).sin())
        .collect();
    let inputs = Inputs::new().with(
        "tau",
        Drive::Sampled {
            t: t.clone(),
            values: tau.clone(),
            hold: Hold::Zero,
        },
    );
    let run = simulate(&g, &inputs, &t, &SimOptions::default()).unwrap();
    // A 12-bit encoder over a turn, read with white noise.
    let step = std::f64::consts::TAU / 4096.0;
    let angle: Vec<f64> = (run.output("angle").unwrap().iter())
        .map(|a| ((a + 5e-4 * noise.gauss()) / step).round() * step)
        .collect();
    let turned = angle.iter().fold(0.0_f64, |m, a| m.max(a.abs()));
    assert!(turned > 4.0, "the pendulum must turn over: {turned} rad");
    let rec = Recording::new(
        t,
        vec![Signal::new("tau", tau), Signal::new("angle", angle)],
    )
    .unwrap();
    let model = BondModel::new(modelgap::bond::file::read_model(PENDULUM).unwrap());
    let ex = explain(&model, &rec, &ExplainOptions::default()).unwrap();
    let text = story(&ex);
    let pivot = (ex.places.iter())
        .find(|p| p.location == "pivot")
        .unwrap_or_else(|| panic!("no estimate at the pivot:\n{text}"));
    let law = (pivot.law.as_ref()).unwrap_or_else(|| panic!("no law at the pivot:\n{text}"));
    assert!(
        law.formula().contains("abs("),
        "the law at the pivot must be quadratic drag, not {}:\n{text}",
        law.formula()
    );
    assert!(
        pivot.band < 0.25 * pivot.rms,
        "the estimate must be pinned: band {} about {}:\n{text}",
        pivot.band,
        pivot.rms
    );
    let first = ex
        .chosen
        .first()
        .unwrap_or_else(|| panic!("nothing chosen:\n{text}"));
    assert!(
        first.candidate.id.starts_with("law@pivot:") && first.candidate.id.contains("abs("),
        "the drag law must be chosen first, not {}:\n{text}",
        first.candidate.id
    );
    let c = first.params[0].value;
    assert!((c - 0.006).abs() < 0.03 * 0.006, "c_drag {c}:\n{text}");
}

//! Signals in the model language: laws that read another element's variable,
//! modulated sources (`MSe`, `MSf`) and outputs given as expressions. Each
//! model is checked against an independent solution of the equations its
//! authors write, not against the bond-graph machinery itself.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in tests, a panic is a failure

use modelgap_bond::file::{read_model, write_model};
use modelgap_bond::simulate::{Drive, Hold, Inputs, SimOptions, simulate, time_grid};
use modelgap_bond::{BondError, Equations, assign_causality};

const TANKS: &str = include_str!("../../../examples/models/cascaded-tanks.toml");

/// The cascaded tanks as their authors write them, with the model file's
/// parameters changed to values that exercise both levels.
fn tanks() -> modelgap_bond::BondGraph {
    let mut g = read_model(TANKS).unwrap();
    for (name, value) in [
        ("k1", 0.06),
        ("k2", 0.045),
        ("k3", 0.035),
        ("k4", 0.04),
        ("gain", 1.3),
        ("offset", -0.4),
    ] {
        g.set_param(name, value).unwrap();
    }
    g
}

/// The authors' equations, integrated by classical RK4 with a small fixed
/// step: ẋ1 = −k1√x1 + k4 u, ẋ2 = k2√x1 − k3√x2, y = gain x2 + offset.
fn tanks_reference(t_out: &[f64], u: impl Fn(f64) -> f64, x0: [f64; 2]) -> Vec<f64> {
    let (k1, k2, k3, k4) = (0.06, 0.045, 0.035, 0.04);
    let f = |t: f64, x: [f64; 2]| {
        let s1 = x[0].max(0.0).sqrt();
        let s2 = x[1].max(0.0).sqrt();
        [-k1 * s1 + k4 * u(t), k2 * s1 - k3 * s2]
    };
    let h: f64 = 1e-3;
    let mut x = x0;
    let mut t = 0.0;
    let mut out = Vec::new();
    for &target in t_out {
        while t < target - 1e-12 {
            let step = h.min(target - t);
            let a = f(t, x);
            let b = f(
                t + step / 2.0,
                [x[0] + step / 2.0 * a[0], x[1] + step / 2.0 * a[1]],
            );
            let c = f(
                t + step / 2.0,
                [x[0] + step / 2.0 * b[0], x[1] + step / 2.0 * b[1]],
            );
            let d = f(t + step, [x[0] + step * c[0], x[1] + step * c[1]]);
            for i in 0..2 {
                x[i] += step / 6.0 * (a[i] + 2.0 * b[i] + 2.0 * c[i] + d[i]);
            }
            t += step;
        }
        out.push(1.3 * x[1] - 0.4);
    }
    out
}

#[test]
fn cascaded_tanks_print_the_authors_equations() {
    let g = tanks();
    let eqs = Equations::derive(&g, &assign_causality(&g).unwrap()).unwrap();
    let text: Vec<String> = eqs
        .states
        .iter()
        .map(|s| format!("{} = {}", s.derivative, eqs.substituted(s.derivative)))
        .collect();
    assert_eq!(
        text,
        [
            "dq2 = k4*u - k1*sqrt(max(q2, 0))",
            "dq5 = k2*sqrt(max(q2, 0)) - k3*sqrt(max(q5, 0))"
        ]
    );
    let y = &eqs.outputs[0];
    assert_eq!(eqs.substituted(y.var).to_string(), "gain*q5 + offset");
    // The one-way coupling is a signal from tank 1's state into the source.
    let source = eqs.defining(modelgap_bond::expr::Var::F(4)).unwrap();
    assert_eq!(source.rhs.to_string(), "k2*sqrt(max(q2, 0))");
}

#[test]
fn cascaded_tanks_simulate_as_the_authors_equations() {
    let g = tanks();
    let t = time_grid(600.0, 0.25);
    let u = |t: f64| 4.0 + 2.5 * (2.0 * std::f64::consts::PI * t / 300.0).sin();
    // The pump's voltage sampled finely enough that holding it linearly
    // between samples is the sine to 1e-7.
    let fine = time_grid(600.0, 20.0);
    let samples: Vec<f64> = fine.iter().map(|&t| u(t)).collect();
    let inputs = Inputs::new().with(
        "u",
        Drive::Sampled {
            t: fine,
            values: samples,
            hold: Hold::Linear,
        },
    );
    let opts = SimOptions {
        initial_state: Some(vec![3.0, 1.0]),
        ..SimOptions::default()
    };
    let run = simulate(&g, &inputs, &t, &opts).unwrap();
    let y = run.output("y").unwrap();
    let reference = tanks_reference(&t, u, [3.0, 1.0]);
    let worst = y
        .iter()
        .zip(&reference)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let span = reference.iter().copied().fold(f64::MIN, f64::max)
        - reference.iter().copied().fold(f64::MAX, f64::min);
    assert!(span > 1.0, "the levels move: span {span}");
    assert!(
        worst < 1e-5 * span,
        "worst difference {worst} of span {span}"
    );
}

const DRIVE: &str = r#"name = "position-loop"
description = "an inertia with viscous friction inside a PD position controller"

[parameters]
J = { value = 0.01, unit = "kg m^2" }
b = { value = 0.1, unit = "N m s/rad" }
kp = { value = 20.0, unit = "1/s" }
kv = { value = 0.5, unit = "N m s/rad" }

[inputs]
q_ref = { default = 1.0, unit = "rad", description = "position reference" }

[[elements]]
name = "drive"
kind = "MSe"
effort = "kp * kv * (q_ref - angle.q) - kv * shaft.f"

[[elements]]
name = "shaft"
kind = "1"

[[elements]]
name = "J"
kind = "I"
parameter = "J"

[[elements]]
name = "b"
kind = "R"
parameter = "b"

[[elements]]
name = "angle"
kind = "C"
effort = "0 * q"
description = "an integrator of the shaft's speed: its displacement is the angle"

[[bonds]]
from = "drive"
to = "shaft"
[[bonds]]
from = "shaft"
to = "J"
[[bonds]]
from = "shaft"
to = "b"
[[bonds]]
from = "shaft"
to = "angle"

[[outputs]]
name = "theta"
value = "angle.q"
unit = "rad"

[[outputs]]
name = "torque"
effort = "drive"
unit = "N m"
"#;

/// A plant inside its feedback loop: J θ'' + (b + kv) θ' + kp kv θ = kp kv r,
/// from rest, against the closed-form step response.
#[test]
fn closed_loop_drive_follows_the_closed_form_step_response() {
    let g = read_model(DRIVE).unwrap();
    let t = time_grid(0.5, 2000.0);
    let run = simulate(&g, &Inputs::new(), &t, &SimOptions::default()).unwrap();
    let theta = run.output("theta").unwrap();
    let (j, b, kp, kv) = (0.01_f64, 0.1, 20.0, 0.5);
    let wn = (kp * kv / j).sqrt();
    let zeta = (b + kv) / (2.0 * j * wn);
    assert!(zeta < 1.0, "underdamped case: zeta = {zeta}");
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    let worst = t
        .iter()
        .zip(theta)
        .map(|(&t, &y)| {
            let exact = 1.0
                - (-zeta * wn * t).exp()
                    * ((wd * t).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * t).sin());
            (y - exact).abs()
        })
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-6,
        "worst difference from the closed form: {worst}"
    );
    // The controller's torque at t = 0 is kp kv (r − 0) − kv·0.
    let torque = run.output("torque").unwrap();
    assert!((torque[0] - kp * kv).abs() < 1e-9, "{}", torque[0]);
}

#[test]
fn models_with_signals_round_trip() {
    for src in [TANKS, DRIVE] {
        let g = read_model(src).unwrap();
        let text = write_model(&g);
        let back = read_model(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_eq!(back, g);
        assert_eq!(write_model(&back), text);
        assert!(text.contains("kind = \"MS"), "{text}");
        assert!(text.contains("value = "), "{text}");
    }
}

#[test]
fn quoted_element_names_are_signals_too() {
    let src = TANKS.replace("Tank1.q", "'Tank1'.q");
    let g = read_model(&src).unwrap();
    assert_eq!(g, read_model(TANKS).unwrap());
}

/// `line N` of the first line of the tanks file holding `text`.
fn line_of(text: &str) -> String {
    let n = TANKS.lines().position(|l| l.contains(text)).expect(text) + 1;
    format!("line {n}")
}

/// Replaces `from` by `to` in the tanks file (which must contain it) and
/// returns the error.
fn tanks_error(from: &str, to: &str) -> String {
    assert!(TANKS.contains(from), "{from}");
    read_model(&TANKS.replace(from, to))
        .expect_err(to)
        .to_string()
}

#[test]
fn bad_signals_name_the_line_the_element_and_the_signal() {
    let name = line_of("name = \"Fall\"");
    let law = line_of("Tank1.q, 0");
    let value = line_of("gain * Tank2.q");
    let cases = [
        (
            "k2 * sqrt(max(Tank1.q, 0))",
            "k2 * sqrt(max(Tank9.q, 0))",
            &[name.as_str(), "Fall", "Tank9.q", "no element 'Tank9'"][..],
        ),
        (
            "k2 * sqrt(max(Tank1.q, 0))",
            "k2 * sqrt(max(Tank1.p, 0))",
            &[name.as_str(), "Fall", "Tank1.p", "only an I has a momentum"],
        ),
        (
            "k2 * sqrt(max(Tank1.q, 0))",
            "k2 * sqrt(max(top.f, 0))",
            &[name.as_str(), "0-junction has a common effort"],
        ),
        (
            "k2 * sqrt(max(Tank1.q, 0))",
            "k2 * sqrt(max(Tank1.x, 0))",
            &[law.as_str(), "expected e, f, p or q after 'Tank1.'"],
        ),
        (
            "k2 * sqrt(max(Tank1.q, 0))",
            "k2 * sqrt(max('Tank1, 0))",
            &[law.as_str(), "closing '"],
        ),
        (
            "gain * Tank2.q + offset",
            "gain * q + offset",
            &["output 'y'", "name the element"],
        ),
        (
            "gain * Tank2.q + offset",
            "gain * Tank2.q + offst",
            &["output 'y'", "'offst'"],
        ),
        (
            "gain * Tank2.q + offset",
            "gain * Tank2.q +",
            &[value.as_str(), "output 'y'", "cannot parse value"],
        ),
    ];
    for (from, to, expected) in cases {
        let message = tanks_error(from, to);
        for e in expected {
            assert!(message.contains(e), "{to}: expected '{e}' in: {message}");
        }
    }
}

#[test]
fn a_signal_loop_is_an_algebraic_loop_with_its_elements() {
    // The source reads the effort it imposes: no order computes it.
    let src = DRIVE.replace("- kv * shaft.f", "- kv * drive.e");
    let g = read_model(&src).unwrap();
    match modelgap_bond::CompiledModel::new(&g) {
        Err(BondError::AlgebraicLoop { elements, .. }) => {
            assert!(elements.contains("drive"), "{elements}")
        }
        other => panic!("expected an algebraic loop, got {other:?}"),
    }
}

#[test]
fn a_fixed_transformer_may_not_read_a_signal() {
    let src = r#"name = "tf"
[parameters]
R = { value = 1.0 }
[[elements]]
name = "src"
kind = "Se"
effort = "1"
[[elements]]
name = "x"
kind = "TF"
modulus = "1 + load.f"
[[elements]]
name = "load"
kind = "R"
parameter = "R"
[[bonds]]
from = "src"
to = "x"
[[bonds]]
from = "x"
to = "load"
"#;
    let message = read_model(src).unwrap_err().to_string();
    assert!(message.contains("use MTF"), "{message}");
}

#[test]
fn free_parameters_and_initial_states_round_trip() {
    let g = read_model(TANKS).unwrap();
    assert!(g.params()["k1"].free.is_some());
    assert!(g.params()["k4"].free.is_none());
    assert_eq!(g.initial()["Tank1"].value, 5.0);
    let text = write_model(&g);
    let back = read_model(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    assert_eq!(back, g);
    // A plain number starts a state without freeing it; the compiled model starts there.
    let src = TANKS.replace(
        "Tank2 = { value = 5.0, free = true, min = 0.0, max = 20.0 }",
        "Tank2 = 2.5",
    );
    let g = read_model(&src).unwrap();
    assert!(g.initial()["Tank2"].free.is_none());
    let m = modelgap_bond::CompiledModel::new(&g).unwrap();
    assert_eq!(m.initial_state, [5.0, 2.5]);
    assert_eq!(m.state_elements, ["Tank1", "Tank2"]);
    assert_eq!(read_model(&write_model(&g)).unwrap(), g);
}

#[test]
fn bad_free_marks_and_initial_states_name_the_line_and_what() {
    let cases = [
        (
            "offset = { value = 0.0, unit = \"V\", description = \"level sensor offset\", free = true, min = -10.0, max = 10.0 }",
            "offset = { value = 0.0, unit = \"V\", free = true }",
            &["'offset' is free with value 0", "give both `min` and `max`"][..],
        ),
        (
            "k3 = { value = 0.05, unit = \"V^0.5/s\", description = \"outflow of tank 2\", free = true, min = 0.001, max = 1.0 }",
            "k3 = { value = 0.05, min = 0.001 }",
            &["'k3'", "add `free = true`"],
        ),
        (
            "k3 = { value = 0.05, unit = \"V^0.5/s\", description = \"outflow of tank 2\", free = true, min = 0.001, max = 1.0 }",
            "k3 = { value = 0.05, free = true, min = 0.1, max = 1.0 }",
            &["'k3'", "outside its bounds [0.1, 1]"],
        ),
        (
            "Tank1 = { value = 5.0, free = true, min = 0.0, max = 20.0 }",
            "Outlet1 = 1.0",
            &["initial state", "Outlet1", "only C and I elements"],
        ),
        (
            "Tank1 = { value = 5.0, free = true, min = 0.0, max = 20.0 }",
            "Tank9 = 1.0",
            &["initial state", "Tank9"],
        ),
        (
            "Tank1 = { value = 5.0, free = true, min = 0.0, max = 20.0 }",
            "Tank1 = { value = 5.0, free = true, min = 9.0, max = 1.0 }",
            &["Tank1(0)", "min < max"],
        ),
    ];
    for (from, to, expected) in cases {
        assert!(TANKS.contains(from), "{from}");
        let message = read_model(&TANKS.replace(from, to))
            .expect_err(to)
            .to_string();
        for e in expected {
            assert!(message.contains(e), "{to}: expected '{e}' in: {message}");
        }
    }
}

#[test]
fn declared_domains_round_trip_and_bad_ones_are_named() {
    let g = read_model(TANKS).unwrap();
    let top = g.find("top").unwrap();
    assert_eq!(
        g.element(top).domain,
        Some(modelgap_bond::element::PhysicalDomain::Hydraulic)
    );
    let text = write_model(&g);
    assert!(text.contains("domain = \"hydraulic\""), "{text}");
    assert_eq!(read_model(&text).unwrap(), g);
    let first = "domain = \"hydraulic\"\ndescription = \"tank 1: common level\"";
    assert!(TANKS.contains(first));
    let cases = [
        (
            first.replace("hydraulic", "hydrolic"),
            &["element 'top'", "unknown domain 'hydrolic'", "thermal"][..],
        ),
        (
            "effort = \"q\"\ndescription = \"tank 1, level x1 = q\"".to_string(),
            &["element 'Tank1'", "only a junction"][..],
        ),
    ];
    for (i, (to, expected)) in cases.into_iter().enumerate() {
        let src = if i == 0 {
            TANKS.replace(first, &to)
        } else {
            TANKS.replace(&to, &format!("{to}\ndomain = \"hydraulic\""))
        };
        let message = read_model(&src).expect_err(&to).to_string();
        for e in expected {
            assert!(message.contains(e), "expected '{e}' in: {message}");
        }
        assert!(message.contains("line "), "{message}");
    }
}

//! Changes at given times (`[[changes]]`): an input that steps and a
//! parameter that changes are part of the model file, checked against the
//! hand-solved RC circuit, written back and read again, and refused with the
//! line when they are wrong.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in tests, a panic is a failure

use modelgap_bond::file::{read_model, write_model};
use modelgap_bond::simulate::{Drive, Inputs, ParamChange, SimOptions, simulate, time_grid};

/// An RC circuit (R = 1 kΩ, C = 100 µF: τ = 0.1 s) driven by V, which is 0
/// until it steps to 5 V at 0.1 s and to 2 V at 0.3 s; R doubles at 0.5 s.
const RC: &str = r#"
name = "rc-steps"

[parameters]
R = { value = 1000.0, unit = "Ohm" }
C = { value = 1e-4, unit = "F" }

[inputs]
V = { default = 0.0, unit = "V" }

[[elements]]
name = "V"
kind = "Se"
effort = "V"

[[elements]]
name = "loop"
kind = "1"

[[elements]]
name = "R"
kind = "R"
parameter = "R"

[[elements]]
name = "C"
kind = "C"
parameter = "C"

[[bonds]]
from = "V"
to = "loop"
[[bonds]]
from = "loop"
to = "R"
[[bonds]]
from = "loop"
to = "C"

[[outputs]]
name = "vC"
effort = "C"
unit = "V"

[[changes]]
at = 0.3
input = "V"
value = 2.0
description = "the supply is turned down"

[[changes]]
at = 0.1
input = "V"
value = 5.0

[[changes]]
at = 0.5
parameter = "R"
value = 2000.0
description = "a contact wears"
"#;

/// The capacitor's voltage solved by hand: first-order steps between the
/// changes, v → V with time constant R C.
fn by_hand(t: f64) -> f64 {
    let relax = |v0: f64, v_inf: f64, dt: f64, tau: f64| v_inf + (v0 - v_inf) * (-dt / tau).exp();
    if t < 0.1 {
        return 0.0;
    }
    let v1 = relax(0.0, 5.0, t.min(0.3) - 0.1, 0.1);
    if t < 0.3 {
        return v1;
    }
    let v2 = relax(relax(0.0, 5.0, 0.2, 0.1), 2.0, t.min(0.5) - 0.3, 0.1);
    if t < 0.5 {
        return v2;
    }
    let at_half = relax(relax(0.0, 5.0, 0.2, 0.1), 2.0, 0.2, 0.1);
    relax(at_half, 2.0, t - 0.5, 0.2)
}

#[test]
fn steps_and_changes_follow_the_hand_solution() {
    let g = read_model(RC).unwrap();
    // Kept in time order whatever the file's order.
    let times: Vec<f64> = g.schedule().iter().map(|c| c.at).collect();
    assert_eq!(times, [0.1, 0.3, 0.5]);
    let t = time_grid(0.8, 1000.0);
    let run = simulate(&g, &Inputs::new(), &t, &SimOptions::default()).unwrap();
    let v = run.output("vC").unwrap();
    let worst = t
        .iter()
        .zip(v)
        .map(|(&t, &v)| (v - by_hand(t)).abs())
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-6,
        "worst difference from the hand solution: {worst} V"
    );
}

#[test]
fn a_recorded_input_overrides_its_steps_and_a_scheduled_change_is_a_fault() {
    let g = read_model(RC).unwrap();
    let t = time_grid(0.8, 1000.0);
    let inputs = Inputs::new().with("V", Drive::Constant(3.0));
    let scheduled = simulate(&g, &inputs, &t, &SimOptions::default()).unwrap();
    // The same run without the file's schedule, R's change given as a fault.
    let plain = read_model(&RC[..RC.find("[[changes]]").unwrap()]).unwrap();
    assert!(plain.schedule().is_empty());
    let opts = SimOptions {
        changes: vec![ParamChange {
            at: 0.5,
            name: "R".into(),
            value: 2000.0,
        }],
        ..SimOptions::default()
    };
    let faulted = simulate(&plain, &inputs, &t, &opts).unwrap();
    assert_eq!(scheduled.output("vC"), faulted.output("vC"));
}

#[test]
fn changes_round_trip() {
    let g = read_model(RC).unwrap();
    let text = write_model(&g);
    assert!(text.contains("[[changes]]"), "{text}");
    let back = read_model(&text).unwrap();
    assert_eq!(back, g);
    assert_eq!(back.schedule()[1].description, "the supply is turned down");
}

#[test]
fn bad_changes_name_the_line_and_what() {
    let line_of = |text: &str, needle: &str| {
        let at = text.find(needle).expect(needle);
        format!("line {}", text[..at].matches('\n').count() + 1)
    };
    let cases = [
        // (replace, with, the line holds, the message says)
        (
            "parameter = \"R\"\nvalue = 2000.0",
            "parameter = \"Rx\"\nvalue = 2000.0",
            "\"Rx\"",
            "'Rx'",
        ),
        (
            "parameter = \"R\"\nvalue = 2000.0",
            "parameter = \"R\"\nvalue = -5.0",
            "-5.0",
            "R",
        ),
        ("at = 0.5", "at = -1.0", "at = -1.0", "not negative"),
        (
            "input = \"V\"\nvalue = 5.0",
            "input = \"W\"\nvalue = 5.0",
            "\"W\"",
            "'W'",
        ),
        (
            "input = \"V\"\nvalue = 5.0",
            "value = 5.0",
            "[[changes]]\nat = 0.1",
            "exactly one of `parameter` or `input`",
        ),
        (
            "input = \"V\"\nvalue = 5.0",
            "input = \"V\"\nparameter = \"R\"\nvalue = 5.0",
            "[[changes]]\nat = 0.1",
            "exactly one",
        ),
    ];
    for (from, to, line, says) in cases {
        assert!(RC.contains(from), "{from}");
        let text = RC.replacen(from, to, 1);
        let err = read_model(&text).expect_err(to).to_string();
        let at = line_of(&text, line);
        assert!(err.contains(&at), "{to}: {err} (expected {at})");
        assert!(err.contains(says), "{to}: {err}");
    }
}

//! The hard edges of the bond-graph side (issue 11): parameters an element cannot have,
//! laws that are NaN where a run starts, states that run away, and runs past their limits
//! all end in a typed error that names the parameter, element, law or limit — never a
//! panic, an allocation abort or a silent non-finite number.

#![allow(clippy::unwrap_used, clippy::expect_used)] // tests: a panic is a failure

use std::error::Error as _;

use modelgap_bond::element::ElementKind;
use modelgap_bond::file::read_model;
use modelgap_bond::ode::OdeError;
use modelgap_bond::simulate::{
    DEFAULT_MAX_SAMPLES, Drive, Inputs, ParamChange, SimOptions, checked_time_grid, simulate,
    time_grid,
};
use modelgap_bond::{BondError, CompiledModel, effects, library};

/// The built-in DC motor's model file with `from` replaced by `to`.
fn motor_file_with(from: &str, to: &str) -> String {
    let src = include_str!("../models/dc-motor.toml");
    assert!(src.contains(from), "{from}");
    src.replace(from, to)
}

/// The DC motor's file with element R given a nonlinear effort law.
fn motor_with_r_law(law: &str) -> String {
    motor_file_with(
        "name = \"R\"\nkind = \"R\"\nparameter = \"R\"",
        &format!("name = \"R\"\nkind = \"R\"\neffort = \"{law}\""),
    )
}

#[test]
fn zero_inductance_is_refused_naming_parameter_element_kind_and_unit() {
    let mut g = library::dc_motor();
    let e = g.set_param("L", 0.0).unwrap_err();
    assert!(
        matches!(
            &e,
            BondError::UnphysicalParameter { param, element, kind: ElementKind::I, value, .. }
                if param == "L" && element == "L" && *value == 0.0
        ),
        "{e:?}"
    );
    assert_eq!(
        e.to_string(),
        "parameter L of element L (I: inductance, H) must be positive, found 0"
    );
    // The graph is unchanged and still simulates.
    assert_eq!(g.param("L").unwrap(), 5e-3);
    assert!(CompiledModel::new(&g).is_ok());
}

#[test]
fn negative_inertia_and_resistance_are_refused_zero_resistance_is_not() {
    let mut g = library::dc_motor();
    let e = g.set_param("J", -1.0).unwrap_err();
    assert_eq!(
        e.to_string(),
        "parameter J of element J (I: inertia, kg m^2) must be positive, found -1"
    );
    let e = g.set_param("R", -1.0).unwrap_err();
    assert_eq!(
        e.to_string(),
        "parameter R of element R (R: resistance, Ohm) must be zero or positive, found -1"
    );
    g.set_param("beta", 0.0).unwrap();
    let mut buck = library::buck_motor();
    let e = buck.set_param("Cf", 0.0).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("parameter Cf of element Cf (C: capacitance, F) must be positive"),
        "{e}"
    );
}

#[test]
fn model_file_with_zero_inductance_names_the_parameter_line() {
    let src = motor_file_with("L = { value = 5e-3", "L = { value = 0.0");
    let e = read_model(&src).unwrap_err();
    let BondError::File { line, message, .. } = &e else {
        panic!("expected a file error, found {e:?}");
    };
    assert_eq!(*line, 11, "the line of `L = {{ value = 0.0 ... }}`: {e}");
    assert_eq!(
        message,
        "parameter L of element L (I: inductance, H) must be positive, found 0"
    );
}

#[test]
fn a_coefficient_that_is_infinite_is_refused_at_load() {
    let src = motor_file_with("parameter = \"R\"", "parameter = \"1/(R - 1)\"");
    let e = read_model(&src).unwrap_err();
    assert!(
        e.to_string()
            .contains("the parameter law of element R, `1/(R - 1)`, is inf"),
        "{e}"
    );
}

#[test]
fn a_law_that_is_nan_at_the_start_is_named_with_its_text_and_arguments() {
    let g = read_model(&motor_with_r_law("f/0")).unwrap();
    let e = simulate(
        &g,
        &Inputs::new(),
        &time_grid(0.1, 1000.0),
        &SimOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(&e, BondError::LawNotFinite { element, value, .. } if element == "R" && value.is_nan()),
        "{e:?}"
    );
    assert_eq!(
        e.to_string(),
        "the effort law of element R, `f/0`, is NaN at the start (f = 0)"
    );
    let g = read_model(&motor_with_r_law("sqrt(-1)")).unwrap();
    let e = simulate(
        &g,
        &Inputs::new(),
        &time_grid(0.1, 1000.0),
        &SimOptions::default(),
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "the effort law of element R, `sqrt(-1)`, is NaN at the start"
    );
}

#[test]
fn a_state_that_runs_away_is_named_by_state_and_element_and_printed_once() {
    let mut g = library::dc_motor();
    // Within the magnitude limit, but the motor's poles (~k²/(L J)) overflow any step; the
    // exact solver's matrix exponential used to loop (practically) forever here.
    g.set_param("k", 1e60).unwrap();
    let e = simulate(
        &g,
        &Inputs::new(),
        &time_grid(0.1, 1000.0),
        &SimOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(&e, BondError::NonFiniteState { state, what, .. }
            if state == "p3" && what == "the momentum of I:L"),
        "{e:?}"
    );
    assert!(
        e.to_string()
            .starts_with("state p3 (the momentum of I:L) or its derivative is not finite at t = "),
        "{e}"
    );
    assert!(e.source().is_none(), "the message is the whole story");
    // A solver error is part of the message, not a second cause printed again.
    let e = BondError::from(OdeError::StepSizeUnderflow { t: 1.5, h: 1e-20 });
    assert!(e.to_string().contains("step size underflow at t = 1.5 s"));
    assert!(e.source().is_none());
}

#[test]
fn a_value_beyond_the_magnitude_limit_is_refused_naming_the_parameter() {
    let mut g = library::dc_motor();
    let e = g.set_param("k", 1e300).unwrap_err();
    assert_eq!(
        e.to_string(),
        "parameter 'k' must be finite and at most 1e100 in magnitude, found 1e300"
    );
    assert_eq!(g.param("k").unwrap(), 0.05);
}

#[test]
fn a_fault_to_an_impossible_value_is_refused_before_the_run() {
    let g = library::dc_motor();
    let opts = SimOptions {
        changes: vec![ParamChange {
            at: 0.5,
            name: "L".into(),
            value: 0.0,
        }],
        ..SimOptions::default()
    };
    let e = simulate(&g, &Inputs::new(), &time_grid(1.0, 1000.0), &opts).unwrap_err();
    assert!(
        matches!(&e, BondError::UnphysicalParameter { param, .. } if param == "L"),
        "{e:?}"
    );
}

#[test]
fn a_terahertz_pwm_is_refused_before_any_edge_is_listed() {
    let g = library::buck_motor();
    let inputs = Inputs::new().with("m", Drive::pwm(0.5, 1e12));
    let e = simulate(&g, &inputs, &time_grid(1.0, 1000.0), &SimOptions::default()).unwrap_err();
    assert!(
        matches!(&e, BondError::TooLarge { option: "max_events", limit, count, .. }
            if *limit == 10_000_000 && *count >= 2e12),
        "{e:?}"
    );
    let text = e.to_string();
    assert!(
        text.contains("input m") && text.contains("1e12 Hz") && text.contains("max_events"),
        "{text}"
    );
    // Raising the limit is what a user who means it does.
    let opts = SimOptions {
        max_events: 4_000,
        ..SimOptions::default()
    };
    let inputs = Inputs::new().with("m", Drive::pwm(0.5, 1000.0));
    assert!(simulate(&g, &inputs, &time_grid(1.0, 1000.0), &opts).is_ok());
    let opts = SimOptions {
        max_events: 1_000,
        ..SimOptions::default()
    };
    assert!(matches!(
        simulate(&g, &inputs, &time_grid(1.0, 1000.0), &opts),
        Err(BondError::TooLarge { .. })
    ));
}

#[test]
fn a_time_grid_past_its_limit_is_refused_before_allocating() {
    let e = checked_time_grid(1.0, 1e12, DEFAULT_MAX_SAMPLES).unwrap_err();
    assert!(
        matches!(
            &e,
            BondError::TooLarge {
                option: "max_samples",
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().contains("1 s at 1e12 Hz"), "{e}");
    assert!(matches!(
        checked_time_grid(-1.0, 1000.0, DEFAULT_MAX_SAMPLES),
        Err(BondError::BadOptions(_))
    ));
    assert_eq!(checked_time_grid(2.0, 10.0, 21).unwrap().len(), 21);
}

#[test]
fn a_zero_resistance_keeps_its_deviation_bounds_physical() {
    let mut g = library::dc_motor();
    g.set_param("beta", 0.0).unwrap();
    let menu = effects::candidates(&g);
    for id in ["deviation:beta", "fault:beta"] {
        let c = menu.iter().find(|c| c.id == id).unwrap();
        assert_eq!(c.params[0].lower, 0.0, "{id}");
        assert!(c.params[0].upper > 0.0, "{id}");
    }
}

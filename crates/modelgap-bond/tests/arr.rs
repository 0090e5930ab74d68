//! Analytical redundancy relations of the built-in models: the DC motor's two
//! junction ARRs and their signature matrix, the buck-motor's ARRs at steady
//! state, and ARR residuals computed from simulated recordings.

use std::collections::{BTreeMap, BTreeSet};

use modelgap_bond::arr::{
    ArrAnalysis, arr_residuals, derive_arrs, evaluate, split_derivative_name,
};
use modelgap_bond::element::{Element, Law, Measured, Output};
use modelgap_bond::expr::parse;
use modelgap_bond::simulate::{Inputs, SimOptions, simulate, time_grid};
use modelgap_bond::{BondGraph, CompiledModel, Equations, StateSpace, assign_causality, library};
use nalgebra::DVector;

#[allow(clippy::unwrap_used)] // a test helper: a failure here is a test failure
fn analyse(g: &BondGraph) -> ArrAnalysis {
    let eqs = Equations::derive(g, &assign_causality(g).unwrap()).unwrap();
    derive_arrs(g, &eqs).unwrap()
}

fn set(names: &[&str]) -> BTreeSet<String> {
    names.iter().map(|s| s.to_string()).collect()
}

fn params_of(c: &BTreeSet<String>) -> BTreeSet<String> {
    c.iter()
        .filter(|f| !f.starts_with("sensor:"))
        .cloned()
        .collect()
}

/// Signal values for `evaluate`: `values` by name, every derivative 0.
fn at_steady_state(values: &BTreeMap<String, f64>) -> impl Fn(&str) -> Option<f64> + '_ {
    move |name| match split_derivative_name(name) {
        (_, 0) => values.get(name).copied(),
        _ => Some(0.0),
    }
}

/// Inputs (defaults) and outputs of a model at its steady state. The
/// models are affine in their states (the buck's `m*Vs` is bilinear in the
/// inputs only), so one Newton step from rest lands on it:
/// `x = -A⁻¹ f(0, u)`.
#[allow(clippy::unwrap_used)] // a test helper: a failure here is a test failure
fn steady_signals(g: &BondGraph) -> BTreeMap<String, f64> {
    let model = CompiledModel::new(g).unwrap();
    let u = model.input_defaults.clone();
    let n = model.n_states();
    let mut scratch = model.scratch();
    let f = |x: &[f64], scratch: &mut Vec<f64>| {
        model.eval(0.0, x, &u, scratch);
        let mut dx = vec![0.0; n];
        model.read_derivatives(scratch, &mut dx);
        dx
    };
    let f0 = f(&vec![0.0; n], &mut scratch);
    let ss = StateSpace::of_compiled(&model, None, Some(&u));
    let x: Vec<f64> = (ss.a.clone().lu())
        .solve(&-DVector::from_column_slice(&f0))
        .unwrap()
        .iter()
        .copied()
        .collect();
    let residual = f(&x, &mut scratch);
    assert!(
        residual.iter().all(|d| d.abs() < 1e-9),
        "not at rest: {residual:?}"
    );
    let mut y = vec![0.0; model.n_outputs()];
    model.read_outputs(&scratch, &mut y);
    let mut values: BTreeMap<String, f64> =
        model.input_names.iter().cloned().zip(u.clone()).collect();
    values.extend(model.output_names.iter().cloned().zip(y));
    values
}

#[test]
fn dc_motor_has_the_two_junction_arrs() {
    let g = library::dc_motor();
    let a = analyse(&g);
    println!("{}", a.to_text());
    assert_eq!(a.arrs.len(), 2);
    let (arr1, arr2) = (&a.arrs[0], &a.arrs[1]);
    assert_eq!((arr1.element.as_str(), arr2.element.as_str()), ("1e", "1m"));
    assert_eq!(params_of(&arr1.candidates), set(&["L", "R", "k"]));
    assert_eq!(params_of(&arr2.candidates), set(&["J", "beta", "k"]));
    for arr in [arr1, arr2] {
        assert!(arr.candidates.contains("sensor:i") && arr.candidates.contains("sensor:omega"));
    }
    // Equal, term by term, to the textbook forms at arbitrary signal values.
    let values: BTreeMap<&str, f64> = [
        ("V", 3.0),
        ("tau_L", 0.1),
        ("i", 0.7),
        ("omega", 11.0),
        ("d(i)/dt", 5.0),
        ("d(omega)/dt", -2.0),
    ]
    .into_iter()
    .collect();
    let signals = |n: &str| values.get(n).copied();
    let (r, l, k, j, beta) = (1.0, 5e-3, 0.05, 1e-4, 1e-5);
    let expected1 = 3.0 - r * 0.7 - l * 5.0 - k * 11.0;
    let expected2 = k * 0.7 - beta * 11.0 - j * -2.0 - 0.1;
    // Tolerance: a few roundings of terms of order 1.
    approx::assert_relative_eq!(
        evaluate(arr1, &signals).unwrap(),
        expected1,
        epsilon = 1e-12
    );
    approx::assert_relative_eq!(
        evaluate(arr2, &signals).unwrap(),
        expected2,
        epsilon = 1e-12
    );
}

#[test]
fn dc_motor_arrs_vanish_at_steady_state() {
    let g = library::dc_motor();
    let a = analyse(&g);
    let values = steady_signals(&g);
    for arr in &a.arrs {
        let r = evaluate(arr, &at_steady_state(&values)).unwrap();
        // Terms are of order V = 12 V; the steady state is solved to ~1e-12.
        assert!(r.abs() < 1e-9, "{} = {r} at steady state", arr.name);
    }
}

#[test]
fn dc_motor_arr_signatures_group_r_with_l_and_j_with_beta() {
    let a = analyse(&library::dc_motor());
    let row = |f: &str| {
        let i = a.faults.iter().position(|x| x == f).unwrap();
        a.signature_matrix[i].clone()
    };
    assert_eq!(row("R"), [true, false]);
    assert_eq!(row("L"), [true, false]);
    assert_eq!(row("J"), [false, true]);
    assert_eq!(row("beta"), [false, true]);
    assert_eq!(row("k"), [true, true]);
    assert!(a.undetectable.is_empty());
    assert_eq!(a.detectable.len(), a.faults.len());
    let group_of = |f: &str| a.groups.iter().find(|g| g.iter().any(|x| x == f)).cloned();
    assert_eq!(group_of("R"), Some(vec!["L".to_string(), "R".to_string()]));
    assert_eq!(
        group_of("J"),
        Some(vec!["J".to_string(), "beta".to_string()])
    );
    // k is told apart from both groups; only the sensors share its signature.
    let k_group = group_of("k").unwrap();
    assert!(k_group.iter().all(|f| f == "k" || f.starts_with("sensor:")));
}

#[test]
fn buck_motor_arrs_vanish_at_steady_state() {
    let g = library::buck_motor();
    let a = analyse(&g);
    println!("{}", a.to_text());
    assert!(a.arrs.len() >= 3);
    let values = steady_signals(&g);
    for arr in &a.arrs {
        let r = evaluate(arr, &at_steady_state(&values)).unwrap();
        // Terms are of order Vs = 24 V; the steady state is solved to ~1e-12.
        assert!(r.abs() < 1e-9, "{} = {r} at steady state", arr.name);
    }
    // The converter's loop: its filter parameters show up, the motor's do not.
    let conv = a.arrs.iter().find(|x| x.element == "1c").unwrap();
    assert_eq!(params_of(&conv.candidates), set(&["Cf", "Lf", "rf"]));
}

#[test]
fn model_without_sensors_has_no_arrs() {
    let mut g = BondGraph::new();
    g.add_param("R", 1.0, "Ohm", "").unwrap();
    g.add_param("L", 1e-3, "H", "").unwrap();
    g.add_input("V", 1.0, "V", "").unwrap();
    let v = g.add(Element::se("V", "V")).unwrap();
    let j = g.add(Element::one("1")).unwrap();
    let r = g.add(Element::r("R", "R")).unwrap();
    let l = g.add(Element::i("L", "L")).unwrap();
    g.bond(v, j).unwrap();
    g.bond(j, r).unwrap();
    g.bond(j, l).unwrap();
    let a = analyse(&g);
    assert!(a.arrs.is_empty());
    assert!(a.detectable.is_empty());
    assert_eq!(a.undetectable, ["L", "R"]);
    // With a current sensor, the loop closes into one ARR.
    g.add_output(Output {
        name: "i".to_string(),
        measured: Measured::Flow("1".to_string()),
        unit: "A".to_string(),
    })
    .unwrap();
    let a = analyse(&g);
    assert_eq!(a.arrs.len(), 1);
    assert_eq!(
        a.arrs[0].expr.as_ref().map(ToString::to_string).as_deref(),
        Some("V - R*i - L*d(i)/dt")
    );
}

/// Largest |value| after `skip` samples.
fn max_abs(x: &[f64], skip: usize) -> f64 {
    x[skip..].iter().fold(0.0, |m, v| m.max(v.abs()))
}

#[test]
fn arr_residuals_from_a_recording_react_to_r_only_in_arr1() {
    let nominal = library::dc_motor();
    let a = analyse(&nominal);
    // A step of V = 12 V from rest, sampled at 1 kHz.
    let t = time_grid(0.3, 1000.0);
    let run = |g: &BondGraph| {
        simulate(g, &Inputs::new(), &t, &SimOptions::default())
            .unwrap()
            .to_recording(false)
            .unwrap()
    };
    let healthy = arr_residuals(&a.arrs, &run(&nominal)).unwrap();
    let mut faulty_motor = nominal.clone();
    faulty_motor.set_param("R", 1.2).unwrap();
    let faulty = arr_residuals(&a.arrs, &run(&faulty_motor)).unwrap();
    // The fit's windows are one-sided at the ends, where the current bends
    // fastest (just after the step): leave out the first samples.
    let skip = 3;
    for k in 0..2 {
        println!(
            "ARR{}: healthy max {:.3e}, faulty max {:.3e}",
            k + 1,
            max_abs(&healthy[k], skip),
            max_abs(&faulty[k], skip)
        );
    }
    // Sizes of the terms: ARR1's V = 12 V, ARR2's k*i up to 0.05 * 9.75 A ≈ 0.49 N m.
    let (scale1, scale2) = (12.0, 0.49);
    assert!(max_abs(&healthy[0], skip) < 1e-3 * scale1);
    assert!(max_abs(&healthy[1], skip) < 1e-3 * scale2);
    // R + 20 % moves ARR1 by 0.2 R i (up to ~1.7 V in the transient), not ARR2.
    assert!(max_abs(&faulty[0], skip) > 0.1 * scale1);
    assert!(max_abs(&faulty[0], skip) > 100.0 * max_abs(&healthy[0], skip));
    assert!(max_abs(&faulty[1], skip) < 1e-3 * scale2);
}

#[test]
fn nonlinear_laws_enter_arrs_only_in_their_written_direction() {
    // Coulomb-like friction on the shaft: used as written (from omega to
    // torque), so ARR2 keeps its closed form and gains tau_c.
    let mut g = library::dc_motor();
    g.add_param("tau_c", 2e-3, "N m", "Coulomb friction")
        .unwrap();
    let beta = g.find("beta").unwrap();
    g.element_mut(beta).law = Law::Nonlinear {
        effort: Some(parse("beta*f + tau_c*tanh(f/0.01)").unwrap()),
        flow: None,
    };
    let a = analyse(&g);
    assert_eq!(a.arrs.len(), 2);
    let arr2 = &a.arrs[1];
    assert_eq!(
        params_of(&arr2.candidates),
        set(&["J", "beta", "k", "tau_c"])
    );
    let values: BTreeMap<&str, f64> = [
        ("tau_L", 0.1),
        ("i", 0.7),
        ("omega", 0.004),
        ("d(omega)/dt", -2.0),
    ]
    .into_iter()
    .collect();
    let r = evaluate(arr2, &|n: &str| values.get(n).copied()).unwrap();
    let friction = 1e-5 * 0.004 + 2e-3 * (0.004f64 / 0.01).tanh();
    let expected = 0.05 * 0.7 - friction - 0.1 - 1e-4 * -2.0;
    approx::assert_relative_eq!(r, expected, epsilon = 1e-12); // a few roundings of terms below 1

    // A saturating inductor gives only i = φ(p): p cannot be had from the
    // measured current, so the electrical balance yields no ARR.
    let mut g = library::dc_motor();
    g.add_param("a", 1e3, "A/Wb^3", "saturation").unwrap();
    let l = g.find("L").unwrap();
    g.element_mut(l).law = Law::Nonlinear {
        effort: None,
        flow: Some(parse("p/L + a*p^3").unwrap()),
    };
    let a = analyse(&g);
    assert_eq!(a.arrs.len(), 1);
    assert_eq!(a.arrs[0].element, "1m");
    assert!(a.undetectable.contains(&"L".to_string()));
    assert!(a.undetectable.contains(&"R".to_string()));
}

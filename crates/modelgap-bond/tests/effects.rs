//! The bond-graph side of the measurement loop: every candidate effect of the
//! built-in models applies, keeps integral causality and simulates; added
//! elements of zero strength change nothing; edits survive the model file;
//! bad values are typed errors; and Coulomb friction slows the motor as the
//! steady-state equations say.

use modelgap_bond::causality::assign_causality;
use modelgap_bond::effects::{self, T_FAULT};
use modelgap_bond::file::read_model;
use modelgap_bond::model::Start;
use modelgap_bond::simulate::{Inputs, SimOptions, Solver, simulate, time_grid};
use modelgap_bond::{BondError, BondGraph, BondModel, CompiledModel, Equations, library};
use modelgap_core::{Candidate, Effect, EffectKind, Model as _, Recording, Signal};

/// The built-in models the loop is tried on.
fn models() -> Vec<BondGraph> {
    vec![library::dc_motor(), library::buck_motor()]
}

/// The nominal model's own run from rest under its default inputs, as a
/// recording (inputs and outputs).
fn nominal_recording(g: &BondGraph, duration: f64) -> Recording {
    let run = simulate(
        g,
        &Inputs::new(),
        &time_grid(duration, 1000.0),
        &SimOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{} does not simulate: {e}", g.name));
    run.to_recording(false)
        .unwrap_or_else(|e| panic!("{} gives no recording: {e}", g.name))
}

/// The middle of each parameter's bounds.
fn mid(c: &Candidate) -> Vec<f64> {
    c.params.iter().map(|p| 0.5 * (p.lower + p.upper)).collect()
}

/// Largest difference between two predictions, relative to each output's peak.
fn max_rel_diff(a: &modelgap_core::Prediction, b: &modelgap_core::Prediction) -> f64 {
    assert_eq!(a.names, b.names);
    let mut worst = 0.0_f64;
    for (x, y) in a.values.iter().zip(&b.values) {
        let peak = x.iter().fold(1e-300_f64, |m, v| m.max(v.abs()));
        for (u, v) in x.iter().zip(y) {
            worst = worst.max((u - v).abs() / peak);
        }
    }
    worst
}

#[test]
fn every_candidate_applies_keeps_integral_causality_and_simulates() {
    for g in models() {
        let n_states = CompiledModel::new(&g).unwrap().n_states();
        for c in effects::candidates(&g) {
            for values in [c.initial(), mid(&c)] {
                let (edited, changes) = effects::apply(&g, &c, &values)
                    .unwrap_or_else(|e| panic!("{} at {values:?}: {e}", c.id));
                assert_eq!(
                    changes.len(),
                    usize::from(c.kind == EffectKind::AbruptChange),
                    "{}",
                    c.id
                );
                // Append-only: every old element keeps its id and name.
                for id in g.element_ids() {
                    assert_eq!(edited.element(id).name, g.element(id).name, "{}", c.id);
                }
                let causality = assign_causality(&edited).unwrap();
                assert!(
                    causality.derivative.is_empty(),
                    "{}: derivative causality on {:?}",
                    c.id,
                    causality.derivative
                );
                Equations::derive(&edited, &causality).unwrap();
                let model = CompiledModel::new(&edited).unwrap();
                assert!(model.n_states() >= n_states, "{}", c.id);
                let opts = SimOptions {
                    changes,
                    ..SimOptions::default()
                };
                let run = simulate(&edited, &Inputs::new(), &time_grid(0.5, 1000.0), &opts)
                    .unwrap_or_else(|e| panic!("{} at {values:?}: {e}", c.id));
                assert!(
                    run.outputs.iter().flatten().all(|v| v.is_finite()),
                    "{}",
                    c.id
                );
            }
        }
    }
}

#[test]
fn candidates_have_finite_bounds_around_the_initial_value_and_a_positive_scale() {
    for g in models() {
        let menu = effects::candidates(&g);
        // A deviation and a fault per parameter, plus the elements.
        assert!(menu.len() > 2 * g.params().len(), "{}", g.name);
        let mut ids: Vec<&str> = menu.iter().map(|c| c.id.as_str()).collect();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), menu.len(), "ids must be unique");
        for c in &menu {
            assert!(!c.name.is_empty() && !c.params.is_empty(), "{}", c.id);
            for p in &c.params {
                assert!(
                    p.lower.is_finite() && p.upper.is_finite(),
                    "{} {}",
                    c.id,
                    p.name
                );
                assert!(p.lower < p.upper, "{} {}", c.id, p.name);
                assert!(
                    p.lower <= p.initial && p.initial <= p.upper,
                    "{} {}",
                    c.id,
                    p.name
                );
                assert!(p.scale.is_finite() && p.scale > 0.0, "{} {}", c.id, p.name);
                assert!(!p.unit.is_empty(), "{} {}", c.id, p.name);
            }
            if c.kind == EffectKind::AbruptChange {
                let t = c.params.last().unwrap();
                assert_eq!((t.name.as_str(), t.unit.as_str()), (T_FAULT, "s"));
            }
        }
    }
    let dc: Vec<String> = effects::candidates(&library::dc_motor())
        .into_iter()
        .map(|c| c.id)
        .collect();
    for id in [
        "deviation:R",
        "fault:R",
        "viscous@1m",
        "coulomb@1m",
        "load@1m",
        "inertia@1m",
        "coupling@1m",
        "cogging@1m",
        "brush@1e",
        "saturation@L",
        "flux-limit@L",
        "ripple@k",
    ] {
        assert!(dc.iter().any(|c| c == id), "dc-motor lacks {id}");
    }
    // The electrical junction gets no mechanical elements and vice versa.
    assert!(!dc.iter().any(|c| c == "coulomb@1e" || c == "brush@1m"));
    let buck: Vec<String> = effects::candidates(&library::buck_motor())
        .into_iter()
        .map(|c| c.id)
        .collect();
    for id in ["deviation:m", "fault:m", "brush@1c", "saturation@Lf"] {
        assert!(buck.iter().any(|c| c == id), "buck-motor lacks {id}");
    }
}

#[test]
fn added_elements_of_zero_strength_predict_the_nominal_outputs() {
    // Tight tolerances for the strict comparison: both runs on the same
    // adaptive solver, so only its error (~rtol) separates them.
    let tight = SimOptions {
        solver: Solver::Dopri5,
        rtol: 1e-12,
        atol: 1e-14,
        ..SimOptions::default()
    };
    let t = time_grid(0.5, 1000.0);
    for g in models() {
        let rec = nominal_recording(&g, 0.5);
        let model = BondModel::new(g.clone());
        let nominal = model.predict(&rec).unwrap();
        let strict_nominal = simulate(&g, &Inputs::new(), &t, &tight).unwrap();
        let mut tried = 0;
        for c in model.candidates() {
            let Some(zero) = effects::vanishing_values(&c) else {
                continue;
            };
            tried += 1;
            // Strict: an element of zero strength adds exact zeros to the
            // equations; at rtol 1e-12 the runs agree to 1e-9 of each peak.
            let (edited, _) = effects::apply(&g, &c, &zero).unwrap();
            let strict = simulate(&edited, &Inputs::new(), &t, &tight).unwrap();
            for (name, a) in strict_nominal
                .output_names
                .iter()
                .zip(&strict_nominal.outputs)
            {
                let b = strict.output(name).unwrap();
                let peak = a.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                for (x, y) in a.iter().zip(b) {
                    assert!((x - y).abs() <= 1e-9 * peak, "{} {name}: {x} vs {y}", c.id);
                }
            }
            // Through the loop's seam: a linear element keeps the exact LTI
            // discretisation and agrees to 1e-9; a nonlinear law moves the
            // model to the adaptive solver at rtol 1e-8, whose global error
            // stays well under 1e-6 of each output's peak.
            let with = model.predict_with(&rec, &[(&c, &zero)]).unwrap();
            let d = max_rel_diff(&nominal, &with);
            let linear = matches!(c.id.split('@').next(), Some("viscous" | "load" | "inertia"));
            let tol = if linear { 1e-9 } else { 1e-6 };
            assert!(d <= tol, "{}: relative difference {d:e} > {tol:e}", c.id);
        }
        assert!(tried >= 5, "{}", g.name);
    }
}

#[test]
fn coupling_adds_two_states() {
    for g in models() {
        let c = effects::candidates(&g)
            .into_iter()
            .find(|c| c.id == "coupling@1m")
            .unwrap();
        let (edited, _) = effects::apply(&g, &c, &c.initial()).unwrap();
        let before = CompiledModel::new(&g).unwrap().n_states();
        let after = CompiledModel::new(&edited).unwrap();
        assert_eq!(after.n_states(), before + 2, "{}", g.name);
        // The spring and the second inertia, as the paper names states.
        assert!(after.state_names.iter().any(|s| s.starts_with('q')));
    }
}

#[test]
fn an_edited_model_file_reads_back_and_predicts_the_same() {
    for g in models() {
        let rec = nominal_recording(&g, 0.3);
        let model = BondModel::new(g.clone());
        for c in model.candidates() {
            // A value away from the initial one, so the edit shows.
            let values: Vec<f64> = c
                .params
                .iter()
                .map(|p| p.initial + 0.1 * (p.upper - p.initial))
                .map(|v| v.min(1.0)) // keeps a fault time inside the run
                .zip(&c.params)
                .map(|(v, p)| v.clamp(p.lower, p.upper))
                .collect();
            let effect = Effect {
                candidate: c.clone(),
                values: values.clone(),
            };
            let fixed = model.with_effects(std::slice::from_ref(&effect)).unwrap();
            let text = fixed.to_file_text().unwrap();
            assert_eq!(fixed.file_extension(), "toml");
            assert!(text.starts_with("# added by explain: "), "{}", c.id);
            let read = read_model(&text).unwrap_or_else(|e| panic!("{}: {e}\n{text}", c.id));
            if c.kind == EffectKind::AbruptChange {
                // The file holds the fault as a change at its time.
                assert!(text.contains("[[changes]]"), "{}", c.id);
                assert!(text.contains("abrupt change found by explain"), "{}", c.id);
                assert_eq!(read.schedule().len(), 1, "{}", c.id);
            } else {
                let (edited, _) = effects::apply(&g, &c, &values).unwrap();
                assert_eq!(
                    read, edited,
                    "{}: the file does not read back to the edit",
                    c.id
                );
            }
            let direct = model.predict_with(&rec, &[(&c, &values)]).unwrap();
            let from_file = BondModel::new(read).predict(&rec).unwrap();
            let built_in = fixed.predict(&rec).unwrap();
            assert_eq!(direct, from_file, "{}", c.id);
            assert_eq!(direct, built_in, "{}", c.id);
        }
    }
}

#[test]
fn a_fault_built_into_a_model_happens_during_its_predictions() {
    let g = library::dc_motor();
    let rec = nominal_recording(&g, 0.4);
    let model = BondModel::new(g.clone());
    let c = model
        .candidates()
        .into_iter()
        .find(|c| c.id == "fault:R")
        .unwrap();
    let values = [1.5, 0.2];
    let direct = model.predict_with(&rec, &[(&c, &values)]).unwrap();
    let fixed = model
        .with_effects(&[Effect {
            candidate: c.clone(),
            values: values.to_vec(),
        }])
        .unwrap();
    assert_eq!(fixed.predict(&rec).unwrap(), direct);
    let text = fixed.to_file_text().unwrap();
    assert!(
        text.contains(
            "[[changes]]\nat = 0.2\nparameter = \"R\"\nvalue = 1.5\ndescription = \"abrupt change found by explain\""
        ),
        "{text}"
    );
    let read = BondModel::new(read_model(&text).unwrap());
    assert_eq!(read.predict(&rec).unwrap(), direct);
    // Before the fault the prediction is the nominal one, after it the current is lower.
    let nominal = model.predict(&rec).unwrap();
    let (i0, i1) = (nominal.get("i").unwrap(), direct.get("i").unwrap());
    assert_eq!(i0[..200], i1[..200]);
    assert!(i1[210] < i0[210]);
}

#[test]
fn bad_values_are_errors_naming_the_candidate_and_the_parameter() {
    let g = library::dc_motor();
    let menu = effects::candidates(&g);
    let coulomb = menu.iter().find(|c| c.id == "coulomb@1m").unwrap();
    let upper = coulomb.params[0].upper;
    for (values, param, says) in [
        (vec![f64::NAN], "tau_c", "finite"),
        (vec![f64::INFINITY], "tau_c", "finite"),
        (vec![-0.1], "tau_c", "outside its bounds"),
        (vec![2.0 * upper], "tau_c", "outside its bounds"),
        (vec![], "", "expected 1 value"),
        (vec![0.01, 0.02], "", "expected 1 value"),
    ] {
        let err = effects::apply(&g, coulomb, &values).unwrap_err();
        let text = err.to_string();
        match &err {
            BondError::BadEffect {
                candidate,
                param: p,
                ..
            } => {
                assert_eq!(candidate, "coulomb@1m");
                assert_eq!(p, param);
            }
            other => panic!("expected BadEffect, found {other:?}"),
        }
        assert!(
            text.contains("coulomb@1m") && text.contains("tau_c"),
            "{text}"
        );
        assert!(text.contains(says), "{text}");
    }
    // A fault time outside its bounds names t_fault.
    let fault = menu.iter().find(|c| c.id == "fault:R").unwrap();
    let err = effects::apply(&g, fault, &[1.0, -1.0]).unwrap_err();
    assert!(err.to_string().contains("fault:R") && err.to_string().contains(T_FAULT));
    // The loop sees the same message through the Model trait.
    let rec = nominal_recording(&g, 0.1);
    let err = BondModel::new(g.clone())
        .predict_with(&rec, &[(coulomb, &[f64::NAN])])
        .unwrap_err();
    assert!(matches!(err, modelgap_core::CoreError::Model { .. }));
    assert!(err.to_string().contains("coulomb@1m") && err.to_string().contains("tau_c"));
    // A candidate of another model is refused, naming it.
    let buck_only = effects::candidates(&library::buck_motor())
        .into_iter()
        .find(|c| c.id == "brush@1c")
        .unwrap();
    let err = effects::apply(&g, &buck_only, &buck_only.initial()).unwrap_err();
    assert!(err.to_string().contains("brush@1c"), "{err}");
}

#[test]
fn coulomb_friction_lowers_the_steady_speed_as_derived() {
    // Steady state with Coulomb friction tau_c (full strength at speed,
    // tanh(ω/ω_s) = 1 for ω ≫ ω_s = 1 rad/s):
    //   electrical loop  V = R i + k ω
    //   shaft            k i = β ω + tau_c
    // so i = (β ω + tau_c)/k and V = R (β ω + tau_c)/k + k ω, giving
    //   ω = (k V − R tau_c) / (R β + k²),
    // a drop of Δω = R tau_c / (R β + k²) from the nominal k V / (R β + k²).
    // DC motor: R = 1, k = 0.05, β = 1e-5, V = 12, tau_c = 0.01:
    // Δω = 0.01 / (1e-5 + 2.5e-3) = 3.984 rad/s.
    let g = library::dc_motor();
    let (r, k, beta, tau_c) = (1.0, 0.05, 1e-5, 0.01);
    let expected = r * tau_c / (r * beta + k * k);
    let t = time_grid(1.0, 1000.0);
    let rec = Recording::new(t.clone(), vec![Signal::new("V", vec![12.0; t.len()])]).unwrap();
    let model = BondModel::new(g);
    let coulomb = model
        .candidates()
        .into_iter()
        .find(|c| c.id == "coulomb@1m")
        .unwrap();
    let nominal = model.predict(&rec).unwrap();
    let with = model.predict_with(&rec, &[(&coulomb, &[tau_c])]).unwrap();
    // After 1 s (25 mechanical time constants) both runs are at steady state.
    let drop = nominal.get("omega").unwrap()[1000] - with.get("omega").unwrap()[1000];
    assert!(
        (drop - expected).abs() <= 0.02 * expected,
        "speed drop {drop} rad/s, expected {expected} rad/s"
    );
}

#[test]
fn a_steady_start_stays_at_the_steady_state() {
    let g = library::dc_motor();
    let t = time_grid(0.2, 1000.0);
    let rec = Recording::new(t.clone(), vec![Signal::new("V", vec![12.0; t.len()])]).unwrap();
    let model = BondModel::new(g).with_start(Start::SteadyState);
    let menu = model.candidates();
    let nominal = model.predict(&rec).unwrap();
    let omega = nominal.get("omega").unwrap();
    // ω_ss = k V / (R β + k²) = 0.6 / 0.00251.
    let expected = 0.6 / 0.00251;
    for w in omega {
        assert!((w - expected).abs() < 1e-6 * expected, "{w}");
    }
    // With Coulomb friction the steady start is the slower steady state.
    let coulomb = menu.iter().find(|c| c.id == "coulomb@1m").unwrap();
    let with = model.predict_with(&rec, &[(coulomb, &[0.01])]).unwrap();
    let w = with.get("omega").unwrap();
    assert!((w[0] - w[200]).abs() < 1e-6 * w[0]);
    assert!((expected - w[0] - 0.01 / 0.00251).abs() < 1e-3);
    // Cogging has no steady state of its own: its angle starts at 0.
    let cogging = menu.iter().find(|c| c.id == "cogging@1m").unwrap();
    let with = model
        .predict_with(&rec, &[(cogging, &cogging.initial())])
        .unwrap();
    assert!((with.get("omega").unwrap()[0] - expected).abs() < 1e-6 * expected);
}

/// A deterministic noise sequence (a linear congruential generator), uniform
/// in [−a, a].
fn noise(n: usize, a: f64, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            a * (2.0 * ((s >> 11) as f64 / (1u64 << 53) as f64) - 1.0)
        })
        .collect()
}

#[test]
fn qualitative_agreement_follows_the_fault_trees() {
    // The process: the DC motor at steady state whose R rises 20 % at 0.2 s,
    // measured with a little noise.
    let g = library::dc_motor();
    let x0 = CompiledModel::new(&g)
        .unwrap()
        .steady_state(&[12.0, 0.0], None)
        .unwrap();
    let opts = SimOptions {
        initial_state: Some(x0),
        changes: vec![modelgap_bond::simulate::ParamChange {
            at: 0.2,
            name: "R".into(),
            value: 1.2,
        }],
        ..SimOptions::default()
    };
    let run = simulate(&g, &Inputs::new(), &time_grid(1.0, 1000.0), &opts).unwrap();
    let n = run.t.len();
    let i: Vec<f64> = run
        .output("i")
        .unwrap()
        .iter()
        .zip(noise(n, 1e-4, 1))
        .map(|(a, b)| a + b)
        .collect();
    let w: Vec<f64> = run
        .output("omega")
        .unwrap()
        .iter()
        .zip(noise(n, 1e-2, 2))
        .map(|(a, b)| a + b)
        .collect();
    let rec = Recording::new(
        run.t.clone(),
        vec![
            Signal::new("V", vec![12.0; n]),
            Signal::new("i", i),
            Signal::new("omega", w),
        ],
    )
    .unwrap();
    let model = BondModel::new(g).with_start(Start::SteadyState);
    let menu = model.candidates();
    let agree = |id: &str| {
        let c = menu.iter().find(|c| c.id == id).unwrap();
        model.qualitative_agreement(&rec, c)
    };
    // The final stage's fault trees (i−, ω−) share {L+, R+, k+}; the
    // signatures would narrow it to {R+}, but agreement asks the trees only.
    assert_eq!(agree("deviation:R"), Some(true));
    assert_eq!(agree("fault:R"), Some(true));
    assert_eq!(agree("deviation:k"), Some(true));
    assert_eq!(agree("brush@1e"), Some(true));
    assert_eq!(agree("deviation:J"), Some(false));
    assert_eq!(agree("inertia@1m"), Some(false));
    assert_eq!(agree("viscous@1m"), Some(false));
    assert_eq!(agree("coulomb@1m"), Some(false));
    assert_eq!(agree("saturation@L"), None);
    assert_eq!(agree("coupling@1m"), None);
    // A recording the model matches shows nothing: no qualitative evidence.
    let clean = nominal_recording(&library::dc_motor(), 0.3);
    let c = menu.iter().find(|c| c.id == "deviation:R").unwrap();
    assert_eq!(
        BondModel::new(library::dc_motor()).qualitative_agreement(&clean, c),
        None
    );
}

#[test]
fn a_translational_body_gets_forces_in_newtons() {
    // A mass on a spring and damper (damping ratio 0.71, settled to 1e-6
    // within 3 s), pushed by a constant force.
    let g = read_model(
        r#"
name = "mass"
[parameters]
m = { value = 2.0, unit = "kg", description = "carriage mass" }
b = { value = 20.0, unit = "N s/m" }
C = { value = 0.01, unit = "m/N" }
[inputs]
F = { default = 10.0, unit = "N" }
[[elements]]
name = "F"
kind = "Se"
effort = "F"
[[elements]]
name = "1x"
kind = "1"
description = "carriage: common velocity"
[[elements]]
name = "m"
kind = "I"
parameter = "m"
[[elements]]
name = "b"
kind = "R"
parameter = "b"
[[elements]]
name = "C"
kind = "C"
parameter = "C"
[[bonds]]
from = "F"
to = "1x"
[[bonds]]
from = "1x"
to = "m"
[[bonds]]
from = "1x"
to = "b"
[[bonds]]
from = "1x"
to = "C"
[[outputs]]
name = "x"
state = "C"
unit = "m"
"#,
    )
    .unwrap();
    let menu = effects::candidates(&g);
    let unit_of = |id: &str| {
        let c = menu.iter().find(|c| c.id == id).unwrap();
        c.params.iter().map(|p| p.unit.clone()).collect::<Vec<_>>()
    };
    assert_eq!(unit_of("coulomb@1x"), ["N"]);
    assert_eq!(unit_of("viscous@1x"), ["N s/m"]);
    assert_eq!(unit_of("inertia@1x"), ["kg"]);
    assert_eq!(unit_of("coupling@1x"), ["N/m", "N s/m", "kg"]);
    assert!(!menu.iter().any(|c| c.id.starts_with("cogging@")));
    assert!(!menu.iter().any(|c| c.id.starts_with("brush@")));
    // A constant load of 2 N moves the spring's rest point by C·2 N = 2 cm.
    let rec = nominal_recording(&g, 3.0);
    let model = BondModel::new(g);
    let load = menu.iter().find(|c| c.id == "load@1x").unwrap();
    let x0 = model.predict(&rec).unwrap();
    let x1 = model.predict_with(&rec, &[(load, &[2.0])]).unwrap();
    let shift = x0.get("x").unwrap()[3000] - x1.get("x").unwrap()[3000];
    assert!((shift - 0.02).abs() < 1e-6, "{shift}");
    for c in &menu {
        let (edited, changes) = effects::apply(model.graph(), c, &mid(c)).unwrap();
        let opts = SimOptions {
            changes,
            ..SimOptions::default()
        };
        simulate(&edited, &Inputs::new(), &time_grid(0.5, 1000.0), &opts)
            .unwrap_or_else(|e| panic!("{}: {e}", c.id));
    }
}

/// The copy a fit simulates (`Model::for_fitting`): a fixed step, checked on the model as
/// given, that keeps every candidate's prediction within a small fraction of the adaptive
/// solver's, and moves smoothly with a candidate's parameter where the adaptive run's
/// finite differences are noise.
#[test]
fn the_copy_for_fitting_predicts_like_the_model_and_is_smooth_in_a_candidates_parameter() {
    let g = library::dc_motor();
    // A motor that reverses: Coulomb friction's switch is exercised.
    let t = time_grid(0.6, 1000.0);
    let v: Vec<f64> = t
        .iter()
        .map(|t| 6.0 * (2.0 * std::f64::consts::PI * 3.0 * t).sin())
        .collect();
    let model = BondModel::new(g);
    let driven = Recording::new(t.clone(), vec![Signal::new("V", v)]).unwrap();
    let fitting = model.for_fitting(&driven).expect("a fixed step is found");
    let coulomb = (model.candidates().into_iter())
        .find(|c| c.id == "coulomb@1m")
        .expect("the motor offers Coulomb friction");
    for value in [0.0, 0.004, 0.01] {
        let values = [value];
        let effects = [(&coulomb, &values[..])];
        let accurate = model.predict_with(&driven, &effects).unwrap();
        let smooth = fitting.predict_with(&driven, &effects).unwrap();
        assert!(
            max_rel_diff(&accurate, &smooth) < 1e-3,
            "tau_c = {value}: {}",
            max_rel_diff(&accurate, &smooth)
        );
    }
    // Central differences of the speed at two steps of tau_c agree on the copy.
    let omega_at = |m: &dyn modelgap_core::Model, tau: f64| -> f64 {
        let values = [tau];
        let p = m.predict_with(&driven, &[(&coulomb, &values[..])]).unwrap();
        p.get("omega").unwrap().iter().sum::<f64>()
    };
    let slope = |m: &dyn modelgap_core::Model, h: f64| {
        (omega_at(m, 0.005 + h) - omega_at(m, 0.005 - h)) / (2.0 * h)
    };
    let (a, b) = (slope(fitting.as_ref(), 1e-5), slope(fitting.as_ref(), 1e-7));
    assert!((a - b).abs() < 1e-4 * a.abs(), "{a} vs {b}");
}

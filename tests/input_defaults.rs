//! No number may depend on a value the recording overrides: the same recording explained
//! with the model's input defaults changed wildly (0, 50 and −7 for every input the
//! recording holds) gives the same verdict, the same chosen effects with the same values,
//! the same ranking and the same scores — on the DC motor, the buck converter feeding it,
//! and the real cascaded tanks (a model file with free parameters). A drive's default once
//! pinned Coulomb friction at its start value on a real recording (issue 14).

#![allow(clippy::unwrap_used, clippy::expect_used)] // in test helpers, a panic is a test failure

use modelgap::bond::BondModel;
use modelgap::bond::file::read_model_path;
use modelgap::bond::graph::BondGraph;
use modelgap::bond::hidden::{RecordingOptions, cases, record};
use modelgap::bond::library;
use modelgap::{ExplainOptions, Explanation, Recording, explain};

/// `g` with the default of every input `rec` holds set to `value`.
fn with_defaults(g: &BondGraph, rec: &Recording, value: f64) -> BondGraph {
    let mut g = g.clone();
    let held: Vec<(String, String, String)> = (g.inputs().iter())
        .filter(|(name, _)| rec.signal(name).is_some())
        .map(|(n, i)| (n.clone(), i.unit.clone(), i.description.clone()))
        .collect();
    assert!(!held.is_empty(), "the recording holds none of the inputs");
    for (name, unit, description) in held {
        g.add_input(&name, value, &unit, &description).unwrap();
    }
    g
}

fn close(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() <= 1e-6 * a.abs().max(b.abs()).max(1e-300)
}

fn assert_same(label: &str, a: &Explanation, b: &Explanation) {
    assert_eq!(a.verdict, b.verdict, "{label}: verdict");
    let ids = |e: &Explanation| -> Vec<String> {
        e.chosen.iter().map(|c| c.candidate.id.clone()).collect()
    };
    assert_eq!(ids(a), ids(b), "{label}: chosen");
    for (x, y) in a.chosen.iter().zip(&b.chosen) {
        for (p, q) in x.params.iter().zip(&y.params) {
            assert!(
                close(p.value, q.value),
                "{label}: {} {} vs {}",
                p.name,
                p.value,
                q.value
            );
        }
    }
    let top = |e: &Explanation| -> Vec<(String, f64)> {
        (e.ranked.iter().take(6))
            .map(|r| (r.candidate.id.clone(), r.score))
            .collect()
    };
    for ((ia, sa), (ib, sb)) in top(a).iter().zip(top(b).iter()) {
        assert_eq!(ia, ib, "{label}: ranking\n{:?}\n{:?}", top(a), top(b));
        assert!(
            close(*sa, *sb) || (sa - sb).abs() < 1e-3,
            "{label}: score of {ia}: {sa} vs {sb}"
        );
    }
}

#[test]
fn input_defaults_the_recording_overrides_change_nothing() {
    for name in ["coulomb", "buck-load"] {
        let case = cases().into_iter().find(|c| c.name == name).unwrap();
        let rec = record(&case, &RecordingOptions::default()).unwrap();
        let g = library::builtin(&case.model).unwrap();
        let reference =
            explain(&BondModel::new(g.clone()), &rec, &ExplainOptions::default()).unwrap();
        for value in [0.0, 50.0, -7.0] {
            let changed = BondModel::new(with_defaults(&g, &rec, value));
            let ex = explain(&changed, &rec, &ExplainOptions::default()).unwrap();
            assert_same(&format!("{name}, defaults {value}"), &reference, &ex);
        }
    }
}

#[test]
fn the_real_tanks_do_not_depend_on_the_pump_default() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let g = read_model_path(&root.join("examples/models/cascaded-tanks.toml")).unwrap();
    let model = BondModel::new(g.clone());
    let rec = modelgap::load_recording(
        &root.join("examples/data/realdata/cascaded_tanks/tanks_estimation.csv"),
        &model,
    )
    .unwrap();
    let opts = ExplainOptions {
        only: vec!["overflow@top".to_string(), "leak@top".to_string()],
        ..ExplainOptions::default()
    };
    let reference = explain(&model, &rec, &opts).unwrap();
    for value in [0.0, 50.0] {
        let changed = BondModel::new(with_defaults(&g, &rec, value));
        let ex = explain(&changed, &rec, &opts).unwrap();
        assert_same(&format!("tanks, pump default {value}"), &reference, &ex);
    }
}

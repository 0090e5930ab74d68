//! The qualitative check gives its reason in plain words (issue 16: the winning effect was
//! tagged "signature disagrees" with no reason): which outputs left their bands first and
//! which way, the parameter deviations their fault trees point at, and how the candidate
//! would show.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in tests, a panic is a test failure

use modelgap_bond::model::Start;
use modelgap_bond::simulate::{Inputs, ParamChange, SimOptions, simulate, time_grid};
use modelgap_bond::{BondModel, CompiledModel, library};
use modelgap_core::{Model as _, Recording, Signal};

/// Deterministic noise in [-a, a].
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

/// The DC motor at steady state whose R rises 20 % at 0.2 s, with a little noise: i and
/// omega both fall below the model, and the fault trees share {L+, R+, k+}.
fn r_fault() -> Recording {
    let g = library::dc_motor();
    let x0 = CompiledModel::new(&g)
        .unwrap()
        .steady_state(&[12.0, 0.0], None)
        .unwrap();
    let opts = SimOptions {
        initial_state: Some(x0),
        changes: vec![ParamChange {
            at: 0.2,
            name: "R".into(),
            value: 1.2,
        }],
        ..SimOptions::default()
    };
    let run = simulate(&g, &Inputs::new(), &time_grid(1.0, 1000.0), &opts).unwrap();
    let n = run.t.len();
    let with_noise = |name: &str, a: f64, seed: u64| -> Vec<f64> {
        let clean = run.output(name).unwrap();
        clean
            .iter()
            .zip(noise(n, a, seed))
            .map(|(x, e)| x + e)
            .collect()
    };
    Recording::new(
        run.t.clone(),
        vec![
            Signal::new("V", vec![12.0; n]),
            Signal::new("i", with_noise("i", 1e-4, 1)),
            Signal::new("omega", with_noise("omega", 1e-2, 2)),
        ],
    )
    .unwrap()
}

#[test]
fn the_check_says_why_it_agrees_or_disagrees() {
    let rec = r_fault();
    let model = BondModel::new(library::dc_motor()).with_start(Start::SteadyState);
    let menu = model.candidates();
    let check = |id: &str| {
        let c = menu.iter().find(|c| c.id == id).unwrap();
        model.qualitative_check(&rec, c).unwrap()
    };

    let viscous = check("viscous@1m");
    assert!(!viscous.agrees);
    let why = &viscous.reason;
    assert!(
        why.starts_with("measured i below the model and omega below it first (from 0.2"),
        "{why}"
    );
    assert!(
        why.contains("their fault trees point at L+, R+, k+"),
        "{why}"
    );
    assert!(
        why.contains("this effect would show as beta+, which is not among them"),
        "{why}"
    );

    let r = check("deviation:R");
    assert!(r.agrees);
    assert!(
        r.reason
            .ends_with("this effect would show as R+ or R-, which is among them"),
        "{}",
        r.reason
    );
    // The agreement alone is the check's.
    let c = menu.iter().find(|c| c.id == "viscous@1m").unwrap();
    assert_eq!(model.qualitative_agreement(&rec, c), Some(false));
}

//! The measurement loop on cloth, on the project's hidden-effect cloth
//! recordings (`modelgap::cloth::hidden`): a swing scene (a cloth hanging
//! from its top row, swung by kinematic pin paths), the true system with the
//! hidden effect and a 10× tighter solver tolerance, 1 mm marker noise,
//! 100 Hz for 2 s. The hidden effect ranks first with its parameters within
//! 15 %, the RMS after is within 1.3× of the noise floor, the control gets
//! "nothing is missing"; `fix` writes a scene file that reads back to the
//! fitted model. compare on a snapping scene blames the right model only
//! without its predictability band.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed setup should stop the test

use std::time::Instant;

use modelgap::cloth::MarkerRecording;
use modelgap::cloth::hidden::{HiddenCase, RecordingOptions, cases, record};
use modelgap::cloth::model::{
    ClothModel, PredictSettings, markers_to_recording, recording_to_markers, simulate_markers,
};
use modelgap::cloth::scenes::{self, Scene};
use modelgap::noise::Gaussian;
use modelgap::{
    CompareOptions, ExplainOptions, Explanation, Model as _, Verdict, compare, explain,
};

fn case(n: usize, name: &str) -> HiddenCase {
    cases(n, n)
        .into_iter()
        .find(|c| c.name == name)
        .expect("a case of that name")
}

/// The marker noise, known (1 mm per coordinate): a floor estimated from
/// 201 samples per coordinate scatters by ±25 %, which would judge "within
/// 1.3× of the floor" against a floor that is itself off by that much.
fn options(rec: &modelgap::Recording) -> ExplainOptions {
    let sigma = RecordingOptions::default().noise;
    ExplainOptions {
        noise: rec.names().iter().map(|n| (n.to_string(), sigma)).collect(),
        ..ExplainOptions::default()
    }
}

fn explained(c: &HiddenCase) -> (Explanation, modelgap::Recording, ClothModel) {
    let rec = record(c, &RecordingOptions::default()).unwrap();
    let model = ClothModel::new(c.scene.clone());
    let start = Instant::now();
    let ex = explain(&model, &rec, &options(&rec)).unwrap();
    println!(
        "{} ({} x {}): explain took {:.1} s",
        c.name,
        c.scene.cloth.nx,
        c.scene.cloth.nz,
        start.elapsed().as_secs_f64()
    );
    (ex, rec, model)
}

fn assert_found(n: usize, name: &str) {
    let c = case(n, name);
    let (ex, rec, model) = explained(&c);
    let story = modelgap::story::explanation_text(&ex, 8);
    println!("{story}");
    assert_eq!(ex.verdict, Verdict::EffectFound, "{name}:\n{story}");
    let h = &c.hidden[0];
    // Ranked first as itself or as an equivalent statement (a hanging
    // cloth's stretch depends on compliance × mass only): exactly equivalent
    // (the same cost to 1e-6), or named beside it as one this recording
    // cannot tell apart (the two fits, each to the cloth's fit tolerance,
    // land a shade apart).
    let first = &ex.ranked[0];
    let hidden_name = (ex.ranked.iter())
        .find(|r| r.candidate.id == h.id)
        .map(|r| r.candidate.name.clone());
    assert!(
        first.candidate.id == h.id
            || first.equivalent.contains(&h.id)
            || hidden_name.is_some_and(|n| first.indistinct.contains(&n)),
        "{name}: ranked first is {}\n{story}",
        first.candidate.id
    );
    let fitted = ex.ranked.iter().find(|r| r.candidate.id == h.id).unwrap();
    for (p, truth) in fitted.params.iter().zip(&h.values) {
        assert!(
            (p.value - truth).abs() <= 0.15 * truth.abs(),
            "{name}: {} = {} vs true {truth}\n{story}",
            p.name,
            p.value
        );
    }
    for o in &ex.outputs {
        assert!(
            o.rms_after <= 1.3 * o.noise_floor,
            "{name}: {} RMS after {} vs floor {}\n{story}",
            o.name,
            o.rms_after,
            o.noise_floor
        );
    }
    // fix: the scene file with the new term reads back to a model whose error fell.
    let fixed = model.with_effects(&ex.effects()).unwrap();
    let text = fixed.to_file_text().unwrap();
    let reread = ClothModel::new(Scene::from_toml(&text, "fixed.toml").unwrap());
    let opts = CompareOptions {
        predictability: false,
        ..CompareOptions::default()
    };
    let before = compare(&model, &rec, &opts).unwrap();
    let after = compare(&reread, &rec, &opts).unwrap();
    let total =
        |c: &modelgap::Comparison| c.outputs.iter().map(|o| o.stats.rms.powi(2)).sum::<f64>();
    assert!(
        total(&after) < 0.8 * total(&before),
        "{name}: the error must fall"
    );
}

#[test]
fn air_drag_is_found() {
    assert_found(10, "drag");
}

#[test]
fn stretch_compliance_is_found() {
    assert_found(10, "compliance");
}

#[test]
fn extra_point_mass_is_found() {
    assert_found(10, "point-mass");
}

#[test]
fn right_model_gets_nothing_missing() {
    let (ex, _, _) = explained(&case(10, "nothing"));
    assert_eq!(
        ex.verdict,
        Verdict::NothingMissing,
        "{}",
        modelgap::story::explanation_text(&ex, 5)
    );
}

/// A 30 × 30 swing with air drag: the size of the speed bar
/// (explain under 60 s). One simulation of it takes about 0.27 s (Newton,
/// 200 steps, release); explain found C_d = 0.8002 in 19 s (release) and
/// about 42 s in the test profile. Its time is printed with
/// `cargo test --release --test cloth_loop -- --nocapture`.
#[test]
fn air_drag_is_found_on_a_30_by_30_cloth() {
    assert_found(30, "drag");
}

/// The corner scene (8 × 8, 1 s): a cloth falling flat from one pinned
/// corner snaps taut and branches. The true run takes half the step and a
/// 100× tighter tolerance; the model, right but for its own step and
/// tolerance, misses it by centimetres. compare blames it without its
/// predictability band and not with it. (Against a truth at a quarter of
/// the step the band still leaves windows on 16 of 63 coordinates.)
#[test]
fn predictability_band_keeps_a_right_model_of_a_snapping_cloth_blameless() {
    let mut scene = scenes::corner().resized(8, 8).unwrap();
    scene.duration = 1.0;
    let ids: Vec<u32> = (0..64).step_by(3).collect();
    let t: Vec<f64> = (0..=100).map(|k| 0.01 * f64::from(k)).collect();
    let truth = PredictSettings {
        step_divisor: 2,
        stretch_tolerance: Some(1e-6),
        ..PredictSettings::default()
    };
    let clean = simulate_markers(&scene, &ids, &t, &truth, None).unwrap();
    let mut g = Gaussian::new(7);
    let noisy = clean
        .positions()
        .iter()
        .map(|f| f.iter().map(|p| p.map(|c| c + 1e-3 * g.sample())).collect())
        .collect();
    let markers = MarkerRecording::new(t, ids, noisy).unwrap();
    let rec = markers_to_recording(&markers).unwrap();
    assert_eq!(recording_to_markers(&rec).unwrap(), markers);
    let model = ClothModel::new(scene);
    let noise: std::collections::BTreeMap<String, f64> =
        rec.names().iter().map(|n| (n.to_string(), 1e-3)).collect();
    let failing = |predictability: bool| {
        let opts = CompareOptions {
            noise: noise.clone(),
            predictability,
            ..CompareOptions::default()
        };
        let c = compare(&model, &rec, &opts).unwrap();
        c.outputs.iter().filter(|o| !o.windows.is_empty()).count()
    };
    let without = failing(false);
    let with = failing(true);
    println!("outputs with failure windows: {without} without the band, {with} with it");
    assert!(without > 0, "the snapping scene must fail without the band");
    assert_eq!(with, 0, "the right model is blamed despite the band");
}

/// Prints the time of one prediction of the swing scene (10 × 10 and
/// 30 × 30, 2 s at 100 Hz): what each of explain's simulations costs.
/// Timing only (nothing to assert); run with `--ignored --nocapture`.
#[test]
#[ignore = "timing printout for the report"]
fn prediction_time_of_the_swing_scene() {
    for n in [10, 30] {
        let c = case(n, "nothing");
        let rec = record(&c, &RecordingOptions::default()).unwrap();
        let model = ClothModel::new(c.scene.clone());
        let start = Instant::now();
        model.predict(&rec).unwrap();
        println!(
            "{n} x {n}: one prediction {:.3} s",
            start.elapsed().as_secs_f64()
        );
    }
}

/// A recording of the real cloth is a truth converged in the step: here the swing scene
/// simulated at a quarter of its step and a stretch tolerance of 1e-6. The paper's step at
/// the scene's own step and tolerance moves its prediction by 14 times the noise (its
/// numerics alone: half the step, a tighter tolerance, a nudged start), so whatever
/// explain names on the control or the drag case, it warns that it may be the numerics
/// (measured: a point mass of 0 kg on the control, a wind for the drag, gains 0.6 and 1.9
/// times what the numerics cost). With `integrator = "bdf2"` this scene is no better
/// (21.7 times the noise: its compliant top row snaps between the pins, where BDF2 steps
/// fall back to impulse steps), unlike the curtain (docs/cloth.md, "Time integration").
#[test]
fn against_a_truth_converged_in_the_step_explain_warns_of_the_models_numerics() {
    for name in ["nothing", "drag"] {
        let c = case(10, name);
        let mut opts = RecordingOptions::default();
        opts.truth.step_divisor = 4;
        let rec = record(&c, &opts).unwrap();
        let ex = explain(&ClothModel::new(c.scene.clone()), &rec, &options(&rec)).unwrap();
        let story = modelgap::story::explanation_text(&ex, 5);
        assert_ne!(ex.verdict, Verdict::NothingMissing, "{name}:\n{story}");
        let warning = ex.warnings.iter().find(|w| w.contains("own numerics"));
        let warning = warning.unwrap_or_else(|| panic!("{name}: no warning:\n{story}"));
        assert!(warning.contains("may be the numerics"), "{name}: {warning}");
        let words = story.split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(
            words.contains("may be the numerics"),
            "{name}: not told:\n{story}"
        );
    }
}

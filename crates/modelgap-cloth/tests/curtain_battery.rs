//! The curtain battery of issue 15: the curtain of `examples/data/curtain.toml` (24 x 24,
//! 1 m, its whole top row on a rail) on a rail that sways both ways, 0.2 sin(2 pi 0.4 t) m
//! along the sheet (x) and 0.05 sin(2 pi 1.5 t) m across it (z), for 3 s, 64 markers at
//! 100 Hz with 1 mm noise. Each case hides one law in the truth, explain runs with the whole
//! menu and must name it with its parameters within 10 %, and the control must get "nothing
//! missing". Each case prints explain's wall and CPU time (its stages' sum): run with
//! `--release -- --ignored --test-threads=1` to read them; the CPU of the process is shared
//! by tests running side by side.
//!
//! The laws are the menu's own forms here (a cloth's air, mass and material laws have few
//! shapes a user would declare otherwise); drag hides its normal and tangential parts
//! together.
//!
//! **The truth is simulated at the model's own step** (a twin of the model's numerics), so
//! the battery measures discovery, not the model's step error. Against a truth converged in
//! the step this scene is out of reach: the paper's step at h = 0.01 s is 13–36 mm RMS from
//! it, and the scene branches (a micrometre's nudge of the start moves it by 15 mm RMS after
//! 1.5 s); explain now warns of it (the model's own error, `explain/own_error.rs`).
//! Environment knobs for runs against such truths: `TRUTH_DIVISOR=k` (the truth at 1/k of
//! the step), `BDF2=1` (model and truth with `Integrator::Bdf2`), `AX`, `AZ`, `FZ` (the
//! rail's sway along and across the sheet, m, and the frequency across, Hz);
//! `step_error_probe` prints the model's error against a truth at a quarter of the step.

#![allow(clippy::unwrap_used)] // in test helpers, a panic is a test failure

use std::path::PathBuf;

use modelgap_cloth::hidden::{Hidden, HiddenCase, RecordingOptions, record};
use modelgap_cloth::{ClothModel, Scene};
use modelgap_core::{ExplainOptions, Explanation, Verdict, explain};

fn curtain() -> Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/data/curtain.toml");
    let mut scene = Scene::from_path(&path).unwrap();
    let ax = std::env::var("AX").unwrap_or("0.2".into());
    let az = std::env::var("AZ").unwrap_or("0.05".into());
    let fz = std::env::var("FZ").unwrap_or("1.5".into());
    scene.rails[0].translation = modelgap_cloth::rail::Motion::expressions([
        format!("{ax} * sin(2 * pi * 0.4 * t)").as_str(),
        "0",
        format!("{az} * sin(2 * pi * {fz} * t)").as_str(),
    ])
    .unwrap();
    if std::env::var("BDF2").is_ok() {
        scene.params.integrator = modelgap_cloth::Integrator::Bdf2;
    }
    scene
}

fn markers() -> Vec<u32> {
    (0..8)
        .flat_map(|r| (0..8).map(move |c| (2 + 3 * r) * 24 + 2 + 3 * c))
        .collect()
}

/// The bending length of rigidity `b` (N m) on the curtain (m): `B = w c³`.
fn length(b: f64) -> f64 {
    let scene = curtain();
    let c = &scene.cloth;
    let w = c.particle_mass * scene.params.gravity.norm() / (c.spacing * c.spacing);
    (b / w).cbrt()
}

/// Explains the case hiding `hidden` (candidate ids and values); prints the verdict, the
/// chosen effects, and explain's wall and CPU time.
fn explain_case(name: &str, hidden: &[(&str, &[f64])]) -> Explanation {
    let scene = curtain();
    let case = HiddenCase {
        name: name.into(),
        scene: scene.clone(),
        hidden: hidden
            .iter()
            .map(|(id, values)| Hidden {
                id: (*id).into(),
                values: values.to_vec(),
            })
            .collect(),
        markers: markers(),
    };
    let mut opts = RecordingOptions::default();
    opts.truth.step_divisor = std::env::var("TRUTH_DIVISOR").map_or(1, |d| d.parse().unwrap());
    let rec = record(&case, &opts).unwrap();
    let ex = explain(&ClothModel::new(scene), &rec, &ExplainOptions::default()).unwrap();
    let wall: f64 = ex.timings.iter().map(|t| t.wall_s).sum();
    let cpu: f64 = ex.timings.iter().filter_map(|t| t.cpu_s).sum();
    println!(
        "{name}: {:?}, chosen {:?}, explain {wall:.1} s wall / {cpu:.1} s CPU",
        ex.verdict,
        ex.chosen
            .iter()
            .map(|c| (
                c.candidate.id.clone(),
                c.params.iter().map(|p| p.value).collect::<Vec<_>>()
            ))
            .collect::<Vec<_>>(),
    );
    for r in ex.ranked.iter().take(8) {
        println!(
            "  {:16} score {:10.1} cost {:10.1} (before {:10.1}){} {:?}",
            r.candidate.id,
            r.score,
            r.cost,
            ex.cost_before,
            if r.screened { " screened" } else { "" },
            r.params.iter().map(|p| p.value).collect::<Vec<_>>()
        );
    }
    for r in &ex.reasons {
        println!("  reason: {r}");
    }
    for w in ex.warnings.iter().filter(|w| w.contains("own numerics")) {
        println!("  warning: {w}");
    }
    for t in &ex.timings {
        println!(
            "  {:12} {:6.2} s wall {:6.2?} s CPU",
            t.stage, t.wall_s, t.cpu_s
        );
    }
    ex
}

/// The value of `param` of the chosen effect `id`.
fn found(ex: &Explanation, id: &str, param: &str) -> f64 {
    let effect = ex
        .chosen
        .iter()
        .find(|c| c.candidate.id == id)
        .unwrap_or_else(|| panic!("{id} not chosen: {:?}", ex.chosen));
    effect
        .params
        .iter()
        .find(|p| p.name == param)
        .unwrap_or_else(|| panic!("{id} has no {param}"))
        .value
}

fn within(found: f64, truth: f64, share: f64) -> bool {
    (found / truth - 1.0).abs() < share
}

#[test]
#[ignore = "minutes in debug: run with --release -- --ignored"]
fn drag_with_a_tangential_part() {
    let ex = explain_case("drag", &[("air-drag", &[1.2]), ("skin-friction", &[0.5])]);
    // Two laws of the menu, normal and tangential: each alone leaves most of the error (the
    // curtain sliding along its rail mostly feels the tangential part: 35.4 mm nominal,
    // 4.65 mm with the skin friction alone, 33.4 with the normal drag alone, 1.02 with both).
    assert_eq!(ex.verdict, Verdict::TwoEffects);
    let c_d = found(&ex, "air-drag", "drag_coefficient");
    let c_f = found(&ex, "skin-friction", "skin_friction");
    assert!(
        within(c_d, 1.2, 0.1) && within(c_f, 0.5, 0.1),
        "{c_d} {c_f}"
    );
}

#[test]
#[ignore = "minutes in debug: run with --release -- --ignored"]
fn wind() {
    let ex = explain_case("wind", &[("wind", &[1.0, 1.5, 0.0, -1.0])]);
    assert_eq!(ex.verdict, Verdict::EffectFound);
    for (axis, truth) in [("wind_x", 1.5), ("wind_z", -1.0)] {
        let w = found(&ex, "wind", axis);
        assert!(within(w, truth, 0.1), "{axis} {w}");
    }
}

#[test]
#[ignore = "minutes in debug: run with --release -- --ignored"]
fn stretch_compliance() {
    let ex = explain_case("compliance", &[("compliance", &[3e-3])]);
    assert_eq!(ex.verdict, Verdict::EffectFound);
    let c = found(&ex, "compliance", "compliance");
    assert!(within(c, 3e-3, 0.1), "{c}");
}

#[test]
#[ignore = "minutes in debug: run with --release -- --ignored"]
fn an_extra_point_mass() {
    let ex = explain_case("point mass", &[("point-mass", &[17.0, 15.0, 0.05])]);
    assert_eq!(ex.verdict, Verdict::EffectFound);
    let col = found(&ex, "point-mass", "col");
    let row = found(&ex, "point-mass", "row");
    let m = found(&ex, "point-mass", "mass");
    assert!(
        (col - 17.0).abs() < 0.6 && (row - 15.0).abs() < 0.6,
        "{col} {row}"
    );
    assert!(within(m, 0.05, 0.1), "{m}");
}

#[test]
#[ignore = "minutes in debug: run with --release -- --ignored"]
fn quadratic_bending() {
    let ex = explain_case("bending", &[("bending", &[length(1e-3)])]);
    assert_eq!(ex.verdict, Verdict::EffectFound);
    let c = found(&ex, "bending", "bending_length");
    let scene = curtain();
    let w = scene.cloth.particle_mass * 9.81 / (scene.cloth.spacing * scene.cloth.spacing);
    let b = w * c.powi(3);
    assert!(within(b, 1e-3, 0.1), "{b}");
}

#[test]
#[ignore = "minutes in debug: run with --release -- --ignored"]
fn velocity_damping() {
    let ex = explain_case("damping", &[("damping", &[0.5])]);
    assert_eq!(ex.verdict, Verdict::EffectFound);
    let c = found(&ex, "damping", "damping");
    assert!(within(c, 0.5, 0.1), "{c}");
}

#[test]
#[ignore = "minutes in debug: run with --release -- --ignored"]
fn control() {
    let ex = explain_case("control", &[]);
    assert_eq!(ex.verdict, Verdict::NothingMissing, "{:?}", ex.chosen);
}

/// Per-coordinate RMS (mm) of the nominal curtain with `effects` against the drag case's
/// recording: what each part of the hidden drag explains.
#[test]
#[ignore = "a probe: prints what each part of the drag explains"]
fn drag_parts() {
    use modelgap_core::Model as _;
    let scene = curtain();
    let case = HiddenCase {
        name: "drag".into(),
        scene: scene.clone(),
        hidden: vec![
            Hidden {
                id: "air-drag".into(),
                values: vec![1.2],
            },
            Hidden {
                id: "skin-friction".into(),
                values: vec![0.5],
            },
        ],
        markers: markers(),
    };
    let rec = record(&case, &RecordingOptions::default()).unwrap();
    let model = ClothModel::new(scene);
    let menu = model.candidates();
    let rms = |effects: &[(&str, f64)]| {
        let chosen: Vec<_> = effects
            .iter()
            .map(|(id, v)| {
                let c = menu.iter().find(|c| c.id == *id).unwrap();
                (c, vec![*v])
            })
            .collect();
        let refs: Vec<_> = chosen.iter().map(|(c, v)| (*c, v.as_slice())).collect();
        let p = model.predict_with(&rec, &refs).unwrap();
        let (mut sum, mut n) = (0.0, 0usize);
        for (name, values) in p.names.iter().zip(&p.values) {
            for (a, b) in values.iter().zip(rec.values(name).unwrap()) {
                sum += (a - b) * (a - b);
                n += 1;
            }
        }
        1e3 * (sum / n as f64).sqrt()
    };
    for effects in [
        vec![],
        vec![("air-drag", 1.2)],
        vec![("skin-friction", 0.5)],
        vec![("skin-friction", 0.1)],
        vec![("air-drag", 1.2), ("skin-friction", 0.5)],
        vec![("damping", 0.5)],
    ] {
        println!("{effects:?}: {:.3} mm", rms(&effects));
    }
}

/// The nominal model's marker error (RMS and largest, per coordinate, and per 0.5 s) against
/// the control's truth at a quarter of the step and a stretch tolerance of 1e-6, at the
/// scene's step and half of it, with and without a micrometre's nudge of the start, at the
/// scene's tolerance and at 1e-6. A probe (nothing to assert): run with
/// `--release -- --ignored --nocapture step_error_probe`.
#[test]
#[ignore = "a probe: prints the model's step and tolerance error"]
fn step_error_probe() {
    use modelgap_cloth::PredictSettings;
    use modelgap_core::Model as _;
    let scene = curtain();
    let case = HiddenCase {
        name: "control".into(),
        scene: scene.clone(),
        hidden: vec![],
        markers: markers(),
    };
    let mut opts = RecordingOptions {
        noise: 0.0,
        ..RecordingOptions::default()
    };
    opts.truth.step_divisor = 4;
    let rec = record(&case, &opts).unwrap();
    for (d, pert) in [(1usize, 0.0), (1, 1e-6), (2, 0.0), (2, 1e-6)] {
        for tol in [1e-4, 1e-6] {
            let model = ClothModel::new(scene.clone()).with_settings(PredictSettings {
                step_divisor: d,
                perturbation: pert,
                stretch_tolerance: Some(tol),
                ..PredictSettings::default()
            });
            let t0 = std::time::Instant::now();
            let p = model.predict(&rec).unwrap();
            let mut win = [0.0f64; 6];
            for (name, values) in p.names.iter().zip(&p.values) {
                for (k, (a, b)) in values.iter().zip(rec.values(name).unwrap()).enumerate() {
                    win[(k / 50).min(5)] += (a - b) * (a - b) / 50.0 / p.names.len() as f64;
                }
            }
            println!(
                "windows (mm): {:?}",
                win.map(|w| (1e4 * w.sqrt()).round() / 10.0)
            );
            let (mut sum, mut n, mut worst) = (0.0, 0usize, 0.0f64);
            for (name, values) in p.names.iter().zip(&p.values) {
                for (a, b) in values.iter().zip(rec.values(name).unwrap()) {
                    sum += (a - b) * (a - b);
                    n += 1;
                    worst = worst.max((a - b).abs());
                }
            }
            println!(
                "divisor {d} pert {pert:e} tol {tol:e}: rms {:.3} mm, max {:.3} mm, {:.2} s",
                1e3 * (sum / n as f64).sqrt(),
                1e3 * worst,
                t0.elapsed().as_secs_f64()
            );
        }
    }
}

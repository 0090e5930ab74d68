//! Air drag with a tangential part (issue 15, item 3): a curtain whose rail moves in its own
//! plane feels skin friction, which the normal drag alone cannot give; the `skin-friction`
//! candidate with the true coefficient brings the error to the noise.

#![allow(clippy::unwrap_used)] // in test helpers, a panic is a test failure

use std::path::PathBuf;

use modelgap_cloth::hidden::{Hidden, HiddenCase, RecordingOptions, record};
use modelgap_cloth::{ClothModel, Scene};
use modelgap_core::{Model as _, Recording};

fn curtain() -> Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/data/curtain.toml");
    Scene::from_path(&path).unwrap()
}

/// Per-coordinate RMS of `model` with `effects` against `rec` (m).
fn rms(model: &ClothModel, rec: &Recording, effects: &[(&str, f64)]) -> f64 {
    let menu = model.candidates();
    let chosen: Vec<_> = effects
        .iter()
        .map(|(id, v)| (menu.iter().find(|c| c.id == *id).unwrap(), [*v]))
        .collect();
    let pairs: Vec<_> = chosen.iter().map(|(c, v)| (*c, &v[..])).collect();
    let p = model.predict_with(rec, &pairs).unwrap();
    let (mut sum, mut n) = (0.0, 0usize);
    for (name, values) in p.names.iter().zip(&p.values) {
        for (a, b) in values.iter().zip(rec.values(name).unwrap()) {
            sum += (a - b) * (a - b);
            n += 1;
        }
    }
    (sum / n as f64).sqrt()
}

#[test]
fn a_curtain_sliding_in_its_plane_feels_skin_friction() {
    let mut scene = curtain();
    // A faster rail (0.3 m at 0.4 Hz, 0.75 m/s peak) so that the air matters.
    scene.rails[0].translation =
        modelgap_cloth::rail::Motion::expressions(["0.3 * sin(2 * pi * 0.4 * t)", "0", "0"])
            .unwrap();
    scene.duration = 2.0;
    let markers: Vec<u32> = (0..8)
        .flat_map(|r| (0..8).map(move |c| (2 + 3 * r) * 24 + 2 + 3 * c))
        .collect();
    let c_f = 0.5;
    let case = HiddenCase {
        name: "skin-friction".into(),
        scene: scene.clone(),
        hidden: vec![Hidden {
            id: "skin-friction".into(),
            values: vec![c_f],
        }],
        markers,
    };
    let rec = record(&case, &RecordingOptions::default()).unwrap();
    let model = ClothModel::new(scene);
    let nominal = rms(&model, &rec, &[]);
    let truth = rms(&model, &rec, &[("skin-friction", c_f)]);
    // The normal drag alone cannot give it: the sheet moves in its own plane.
    let normal_only = rms(&model, &rec, &[("air-drag", 2.0)]);
    println!(
        "per-coordinate RMS (mm): nominal {:.3}, true skin friction {:.3}, normal drag C_d = 2 \
         instead {:.3}",
        1e3 * nominal,
        1e3 * truth,
        1e3 * normal_only
    );
    assert!(nominal > 2e-3, "the effect must show: {nominal}");
    assert!(truth < 1.1e-3, "{truth}");
    assert!(normal_only > 0.8 * nominal, "{normal_only} vs {nominal}");
}

#[test]
fn skin_friction_round_trips_through_the_scene_file() {
    let text = "name = 'x'\nduration = 1.0\ndt = 0.01\n[cloth]\nnx = 3\nnz = 3\nsize = 0.2\n\
                [air]\nskin_friction = 0.3\nwind = [1.0, 0.0, 0.0]\n";
    let scene = Scene::from_toml(text, "x").unwrap();
    let fx = &scene.effects.forces;
    assert_eq!((fx.drag_coefficient, fx.skin_friction), (0.0, 0.3));
    let back = Scene::from_toml(&scene.to_toml().unwrap(), "back").unwrap();
    assert_eq!(back.effects.forces, scene.effects.forces);
    let bad = Scene::from_toml(&text.replace("0.3", "-0.3"), "x").unwrap_err();
    assert!(bad.to_string().contains("air.skin_friction"), "{bad}");
}

/// explain with the whole menu names skin friction on an in-plane curtain (12 x 12, the
/// rail moving 0.3 sin(2 pi 0.4 t) m along it, 36 markers, 1 mm noise, hidden C_f = 0.5),
/// not velocity damping (which the in-plane drag was taken for before).
#[test]
fn explain_names_skin_friction_on_an_in_plane_curtain() {
    use modelgap_core::{ExplainOptions, Verdict, explain};
    let mut scene = curtain();
    scene.rails[0].translation =
        modelgap_cloth::rail::Motion::expressions(["0.3 * sin(2 * pi * 0.4 * t)", "0", "0"])
            .unwrap();
    scene.duration = 2.0;
    let scene = scene.resized(12, 12).unwrap();
    let markers: Vec<u32> = (0..6)
        .flat_map(|r| (0..6).map(move |c| (1 + 2 * r) * 12 + 1 + 2 * c))
        .collect();
    let case = HiddenCase {
        name: "skin-friction".into(),
        scene: scene.clone(),
        hidden: vec![Hidden {
            id: "skin-friction".into(),
            values: vec![0.5],
        }],
        markers,
    };
    let rec = record(&case, &RecordingOptions::default()).unwrap();
    let ex = explain(&ClothModel::new(scene), &rec, &ExplainOptions::default()).unwrap();
    assert_eq!(ex.verdict, Verdict::EffectFound, "{:?}", ex.verdict);
    assert_eq!(ex.chosen.len(), 1);
    let found = &ex.chosen[0];
    assert_eq!(found.candidate.id, "skin-friction");
    let c_f = found.params[0].value;
    assert!((c_f - 0.5).abs() < 0.025, "{c_f}");
}

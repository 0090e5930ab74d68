//! Materials per region and quadratic bending (issue 15, items 2 and 3): the curtain of
//! `examples/data/curtain.toml` (24 x 24, 1 m, its whole top row on a rail) with its rail
//! swinging it out of its plane, 0.05 sin(2 pi 1.5 t) m along z, for 3 s (a flat curtain
//! moved in its own plane never bends, so no bending law can be told from it), 64 markers
//! at 100 Hz with 1 mm noise (seeded). Its left half (columns 0-11) is declared a material
//! region, `left`. Each case hides one law in the truth; explain with the whole menu must
//! name it with its parameter within 10 %, and say "nothing missing" on the control.

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
fn rms(model: &ClothModel, rec: &Recording, effects: &[(&str, &[f64])]) -> f64 {
    let menu = model.candidates();
    let chosen: Vec<_> = effects
        .iter()
        .map(|(id, v)| (menu.iter().find(|c| c.id == *id).unwrap(), *v))
        .collect();
    let p = model.predict_with(rec, &chosen).unwrap();
    let (mut sum, mut n) = (0.0, 0usize);
    for (name, values) in p.names.iter().zip(&p.values) {
        for (a, b) in values.iter().zip(rec.values(name).unwrap()) {
            sum += (a - b) * (a - b);
            n += 1;
        }
    }
    (sum / n as f64).sqrt()
}

fn markers() -> Vec<u32> {
    (0..8)
        .flat_map(|r| (0..8).map(move |c| (2 + 3 * r) * 24 + 2 + 3 * c))
        .collect()
}

fn with_region(mut scene: Scene, name: &str, cols: Vec<u32>, rows: Vec<u32>) -> Scene {
    use modelgap_cloth::material::{Material, MaterialRegion};
    use modelgap_cloth::rail::VertexSet;
    scene.effects.materials.push(MaterialRegion {
        name: name.into(),
        vertices: VertexSet {
            cols,
            rows,
            ..VertexSet::default()
        },
        material: Material::default(),
    });
    scene
}

/// The nominal scene of the hidden cases.
fn swinging_curtain() -> Scene {
    let mut scene = curtain();
    scene.rails[0].translation =
        modelgap_cloth::rail::Motion::expressions(["0", "0", "0.05 * sin(2 * pi * 1.5 * t)"])
            .unwrap();
    with_region(scene, "left", (0..12).collect(), Vec::new())
}

/// Explains the case's recording with the whole menu; prints and returns the verdict, the
/// chosen effects and the CPU-ish (wall, single explain) time.
fn explain_case(id: &str, values: &[f64]) -> modelgap_core::Explanation {
    use modelgap_core::{ExplainOptions, explain};
    let scene = swinging_curtain();
    let hidden = if id.is_empty() {
        Vec::new()
    } else {
        vec![Hidden {
            id: id.into(),
            values: values.to_vec(),
        }]
    };
    let case = HiddenCase {
        name: id.into(),
        scene: scene.clone(),
        hidden,
        markers: markers(),
    };
    let rec = record(&case, &RecordingOptions::default()).unwrap();
    let model = ClothModel::new(scene);
    let t0 = std::time::Instant::now();
    let ex = explain(&model, &rec, &ExplainOptions::default()).unwrap();
    println!(
        "hidden {id:?} {values:?}: {:?}, chosen {:?}, nominal {:.3} mm, explain {:.1} s",
        ex.verdict,
        ex.chosen
            .iter()
            .map(|c| (
                c.candidate.id.clone(),
                c.params.iter().map(|p| p.value).collect::<Vec<_>>()
            ))
            .collect::<Vec<_>>(),
        1e3 * rms(&model, &rec, &[]),
        t0.elapsed().as_secs_f64()
    );
    ex
}

#[test]
fn explain_names_a_hidden_quadratic_bending() {
    use modelgap_core::Verdict;
    let b = 1e-3;
    let ex = explain_case("bending", &[b]);
    assert_eq!(ex.verdict, Verdict::EffectFound);
    assert_eq!(ex.chosen.len(), 1, "{:?}", ex.chosen);
    assert_eq!(ex.chosen[0].candidate.id, "bending");
    let found = ex.chosen[0].params[0].value;
    assert!((found / b - 1.0).abs() < 0.1, "{found}");
}

#[test]
fn explain_names_a_hidden_compliance_of_one_region() {
    use modelgap_core::Verdict;
    let c = 3.7e-3;
    let ex = explain_case("compliance@left", &[c]);
    assert_eq!(ex.verdict, Verdict::EffectFound);
    assert_eq!(ex.chosen.len(), 1, "{:?}", ex.chosen);
    assert_eq!(ex.chosen[0].candidate.id, "compliance@left");
    let found = ex.chosen[0].params[0].value;
    assert!((found / c - 1.0).abs() < 0.1, "{found}");
}

#[test]
fn explain_finds_nothing_missing_in_the_control() {
    let ex = explain_case("", &[]);
    assert_eq!(
        ex.verdict,
        modelgap_core::Verdict::NothingMissing,
        "{:?}",
        ex.chosen
    );
}

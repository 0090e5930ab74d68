//! Typed errors through the loop's seam (issue 12): a model's own error — a bond graph's,
//! a cloth scene's — crosses `Model::predict` as `CoreError::Model` and keeps its type
//! (`CoreError::model_error`), so the command line gives it its crate's exit code and Python
//! its documented exception class; each class is matched here by type.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed setup should stop the test

use modelgap::bond::model::Start;
use modelgap::bond::{BondError, BondModel, file::read_model};
use modelgap::cloth::model::ClothModel;
use modelgap::cloth::scenes::Scene;
use modelgap::cloth::{ClothError, scenes};
use modelgap::{CompareOptions, CoreError, Model, Recording, Signal, compare};

/// The model's own error behind a compare that failed.
fn seam_error(model: &dyn Model, rec: &Recording) -> CoreError {
    compare(model, rec, &CompareOptions::default()).expect_err("the model cannot predict")
}

fn motor_recording() -> Recording {
    let t: Vec<f64> = (0..100).map(|k| f64::from(k) * 1e-3).collect();
    let n = t.len();
    Recording::new(
        t,
        vec![
            Signal::new("V", vec![12.0; n]),
            Signal::new("i", vec![1.0; n]),
            Signal::new("omega", vec![1.0; n]),
        ],
    )
    .unwrap()
}

#[test]
fn a_law_that_is_nan_at_the_start_crosses_the_seam_as_a_bond_error() {
    let src = include_str!("../crates/modelgap-bond/models/dc-motor.toml").replacen(
        "parameter = \"R\"",
        "effort = \"f / 0\"",
        1,
    );
    let model = BondModel::new(read_model(&src).unwrap());
    let e = seam_error(&model, &motor_recording());
    let domain = e.model_error().expect("a typed model error");
    assert!(
        matches!(
            domain.downcast_ref::<BondError>(),
            Some(BondError::LawNotFinite { .. })
        ),
        "{e}"
    );
    assert!(e.to_string().contains("element R"), "{e}");
}

#[test]
fn a_missing_steady_state_crosses_the_seam_as_a_convergence_error() {
    // A mass pushed by a constant force: no steady state to start from.
    let src = r#"
name = "pushed-mass"
[parameters]
m = { value = 2.0, unit = "kg" }
[inputs]
F = { default = 1.0, unit = "N" }
[[elements]]
name = "F"
kind = "Se"
effort = "F"
[[elements]]
name = "m"
kind = "I"
parameter = "m"
[[elements]]
name = "1"
kind = "1"
[[bonds]]
number = 1
from = "F"
to = "1"
[[bonds]]
number = 2
from = "1"
to = "m"
[[outputs]]
name = "v"
flow = "1"
unit = "m/s"
"#;
    let model = BondModel::new(read_model(src).unwrap()).with_start(Start::SteadyState);
    let t: Vec<f64> = (0..50).map(|k| f64::from(k) * 1e-2).collect();
    let n = t.len();
    let rec = Recording::new(
        t,
        vec![
            Signal::new("F", vec![1.0; n]),
            Signal::new("v", vec![0.0; n]),
        ],
    )
    .unwrap();
    let e = seam_error(&model, &rec);
    assert!(
        matches!(
            e.model_error().and_then(|d| d.downcast_ref::<BondError>()),
            Some(BondError::NoSteadyState { .. })
        ),
        "{e}"
    );
}

#[test]
fn a_cloth_that_diverges_crosses_the_seam_as_a_cloth_error() {
    // A step of 1e99 s: the first step's fall overflows every squared length.
    let mut scene: Scene = scenes::corner().resized(3, 3).unwrap();
    scene.dt = 1e99;
    let model = ClothModel::new(scene);
    let t = vec![0.0, 1e99, 2e99];
    let rec = Recording::new(
        t,
        vec![
            Signal::new("m8.x", vec![0.0; 3]),
            Signal::new("m8.y", vec![0.0; 3]),
            Signal::new("m8.z", vec![0.0; 3]),
        ],
    )
    .unwrap();
    let e = model.predict(&rec).expect_err("it diverges");
    assert!(
        matches!(
            e.model_error().and_then(|d| d.downcast_ref::<ClothError>()),
            Some(ClothError::Diverged { .. })
        ),
        "{e}"
    );
}

#[test]
fn values_outside_an_effects_bounds_cross_the_seam_typed() {
    let motor = BondModel::new(modelgap::bond::library::dc_motor());
    let coulomb = motor
        .candidates()
        .into_iter()
        .find(|c| c.id == "coulomb@1m")
        .unwrap();
    let e = motor
        .with_effects(&[modelgap::Effect {
            candidate: coulomb,
            values: vec![f64::NAN],
        }])
        .err()
        .expect("NaN is refused");
    assert!(e.model_error().is_some(), "{e}");
    assert!(e.to_string().contains("coulomb@1m"), "{e}");
}

#[test]
fn a_bad_marker_file_crosses_the_seam_as_a_cloth_error() {
    let dir = std::env::temp_dir().join(format!("modelgap-seam-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("markers.csv");
    std::fs::write(&path, "t,id,x,y,z\n0,4000,0,0,0\n").unwrap();
    let model = ClothModel::new(scenes::corner().resized(3, 3).unwrap());
    let e = modelgap::load_recording(&path, &model).unwrap_err();
    let modelgap::Error::Core(core) = &e else {
        panic!("{e}");
    };
    assert!(
        matches!(
            core.model_error()
                .and_then(|d| d.downcast_ref::<ClothError>()),
            Some(ClothError::MarkerField { .. })
        ),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

//! Tolerances that cannot hang (issue 15, item 5): a stretch tolerance the solver cannot
//! reach is found by stagnation, reported once with the level reached, and the run goes on
//! at that level instead of running the iteration cap on every step.

#![allow(clippy::unwrap_used)] // in test helpers, a panic is a test failure

use std::path::PathBuf;

use modelgap_cloth::model::{ClothModel, PredictSettings, markers_to_recording, simulate_markers};
use modelgap_cloth::rail::VertexSet;
use modelgap_cloth::scene_world::SceneWorld;
use modelgap_cloth::{STALL_MARGIN, Scene};
use modelgap_core::Model as _;

/// The curtain: 24 x 24 on the moving rail, but held by every other top-row vertex
/// (the only way before whole rows could be pinned) and inextensible, so the top row is
/// straight between pins under a load: no configuration holds 1e-9 (Newton stalls near
/// 4e-7), and each step ran its 1000-iteration cap (compare ran past 300 s).
fn alternate_curtain(tolerance: f64) -> Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/data/curtain.toml");
    let mut scene = Scene::from_path(&path).unwrap();
    scene.rail_pins[0].vertices = VertexSet {
        vertices: (0..24).step_by(2).collect(),
        ..VertexSet::default()
    };
    scene.cloth.pinned = (0..24).step_by(2).collect();
    scene.params.stretch_tolerance = tolerance;
    scene.params.max_iterations = 1000;
    scene
}

#[test]
fn an_unreachable_tolerance_is_reported_once_and_the_run_goes_on() {
    let scene = alternate_curtain(1e-9);
    let mut sw = SceneWorld::new(&scene, None).unwrap();
    let (mut iterations, mut stagnated) = (0, 0);
    for step in 1..=scene.n_steps() {
        let r = sw.step(scene.dt).unwrap();
        iterations += r.iterations;
        stagnated += usize::from(r.stagnated);
        assert!(!r.converged, "step {step}: 1e-9 cannot hold here: {r:?}");
        if step > 1 {
            let floor = sw.world.stretch_floor().unwrap();
            assert_eq!(r.relaxed_tolerance, Some(floor), "step {step}");
            if !r.stagnated {
                assert!(r.max_stretch <= floor, "step {step}: {r:?}");
            }
        }
    }
    let s = *sw.world.stagnation().unwrap();
    println!("{iterations} iterations in {} steps; {s}", scene.n_steps());
    // The cap would be 300 000 iterations; the first step stops after the stall window.
    assert!(iterations < 10 * scene.n_steps(), "{iterations}");
    assert_eq!((s.step, s.steps), (1, stagnated));
    assert!(stagnated <= 3, "{stagnated}");
    assert!(s.reached > 1e-8 && s.reached < 1e-5, "{s:?}");
    assert_eq!(s.floor, STALL_MARGIN * s.reached);
    assert_eq!(s.requested, 1e-9);
    let text = s.to_string();
    assert!(
        text.starts_with("stretch tolerance 1.0e-9 cannot be reached: the solver stopped improving at a stretch of"),
        "{text}"
    );
}

#[test]
fn a_reachable_tolerance_never_stagnates() {
    // The same curtain held along its whole top row holds 1e-9 at every step.
    let mut scene = Scene::from_path(
        &PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/data/curtain.toml"),
    )
    .unwrap();
    scene.params.stretch_tolerance = 1e-9;
    let mut sw = SceneWorld::new(&scene, None).unwrap();
    for step in 1..=scene.n_steps() {
        let r = sw.step(scene.dt).unwrap();
        assert!(
            r.converged && !r.stagnated && r.relaxed_tolerance.is_none(),
            "step {step}: {r:?}"
        );
    }
    assert!(sw.world.stagnation().is_none());
    // And the alternate curtain at the default 1e-4 does not either.
    let scene = alternate_curtain(1e-4);
    let mut sw = SceneWorld::new(&scene, None).unwrap();
    for _ in 0..scene.n_steps() {
        let r = sw.step(scene.dt).unwrap();
        assert!(r.converged && !r.stagnated, "{r:?}");
    }
}

#[test]
fn the_model_notes_an_unreachable_tolerance_after_it_ran() {
    let mut scene = alternate_curtain(1e-9);
    scene.duration = 0.5;
    let t: Vec<f64> = (0..=50).map(|k| 0.01 * f64::from(k)).collect();
    let settings = PredictSettings {
        max_iterations: 1000,
        ..PredictSettings::default()
    };
    let frames = simulate_markers(&scene, &[575], &t, &settings, None).unwrap();
    let rec = markers_to_recording(&frames).unwrap();
    let model = ClothModel::new(scene).with_settings(settings);
    assert!(model.notes(&rec).is_empty());
    model.predict(&rec).unwrap();
    let notes = model.notes(&rec);
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert!(
        notes[0].starts_with("the cloth solver: stretch tolerance 1.0e-9 cannot be reached"),
        "{notes:?}"
    );
}

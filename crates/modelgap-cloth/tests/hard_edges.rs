//! Issue 11, the cloth side's hard edges: limits checked before anything is allocated,
//! scene fields checked where they enter, a diverged step or run ends in a typed error
//! (never `Ok` with NaN or infinity), and a run stops on its cancel flag.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in tests, a panic is a test failure

use std::sync::Arc;

use modelgap_cloth::scenes::{self, Scene};
use modelgap_cloth::trajectory::{MarkerSelection, RunLimits, RunOptions, run_scene};
use modelgap_cloth::{ClothError, ClothWorld, GridCloth, SolverParams};
use modelgap_core::fit::Cancel;
use nalgebra::Vector3;

/// A 3 × 3 scene file pinned at vertex 0, with `extra` lines before `[cloth]` and `cloth`
/// lines inside it.
fn scene_text(extra: &str, cloth: &str) -> String {
    format!(
        "name = 'small'\nduration = 0.02\ndt = 0.01\n{extra}\n[cloth]\nnx = 3\nnz = 3\n\
         size = 1.0\n{cloth}\n"
    )
}

fn scene(extra: &str, cloth: &str) -> Result<Scene, ClothError> {
    Scene::from_toml(&scene_text(extra, cloth), "small.toml")
}

#[test]
fn a_run_past_its_step_limit_is_refused_before_it_starts() {
    // dt = 1e-9 over 3 s: three billion steps, and a frame each.
    let mut scene = scenes::corner();
    scene.dt = 1e-9;
    let err = run_scene(&scene, &RunOptions::default()).unwrap_err();
    assert!(
        matches!(
            err,
            ClothError::TooManySteps {
                limit: 10_000_000,
                ..
            }
        ),
        "{err}"
    );
    assert_eq!(
        err.to_string(),
        "expected at most 10000000 steps (`max_steps`), found 3e9 (duration 3 s / dt 1e-9 s)"
    );
    // The limit is the caller's to move.
    let options = RunOptions {
        duration: Some(0.05),
        limits: RunLimits {
            max_steps: 4,
            ..RunLimits::default()
        },
        ..RunOptions::default()
    };
    let err = run_scene(&scenes::corner().resized(4, 4).unwrap(), &options).unwrap_err();
    assert!(
        matches!(err, ClothError::TooManySteps { limit: 4, .. }),
        "{err}"
    );
}

#[test]
fn recorded_frames_past_the_memory_limit_are_refused_before_the_run() {
    let scene = scenes::corner().resized(10, 10).unwrap();
    // 10 steps: 11 frames (12 counted) of 100 vertices and 100 markers.
    let options = RunOptions {
        duration: Some(0.1),
        limits: RunLimits {
            max_frame_bytes: 1000,
            ..RunLimits::default()
        },
        ..RunOptions::default()
    };
    let err = run_scene(&scene, &options).unwrap_err();
    assert!(
        matches!(
            err,
            ClothError::TooMuchFrameMemory {
                frames: 12,
                positions: 200,
                bytes: 57_600,
                limit: 1000
            }
        ),
        "{err}"
    );
    // Nothing recorded, nothing limited.
    let options = RunOptions {
        markers: MarkerSelection::None,
        ..options
    };
    assert_eq!(run_scene(&scene, &options).unwrap().stats.steps, 10);
}

#[test]
fn a_grid_past_its_particle_limit_is_refused_by_run_and_resize() {
    let scene = scenes::corner();
    let err = scene.resized(50_000, 50_000).unwrap_err();
    assert!(
        matches!(
            err,
            ClothError::TooManyParticles {
                nx: 50_000,
                nz: 50_000,
                ..
            }
        ),
        "{err}"
    );
    let mut big = scene.clone();
    big.cloth.nx = 100_000;
    big.cloth.nz = 100_000;
    let err = run_scene(&big, &RunOptions::default()).unwrap_err();
    assert!(matches!(err, ClothError::TooManyParticles { .. }), "{err}");
    // A scene file with an absurd grid reads (the limit can be raised), but cannot run.
    let absurd = scene_text("", "").replace("nx = 3", "nx = 99999999999");
    let absurd = Scene::from_toml(&absurd, "absurd.toml").unwrap();
    let err = run_scene(&absurd, &RunOptions::default()).unwrap_err();
    assert!(matches!(err, ClothError::TooManyParticles { .. }), "{err}");
}

#[test]
fn a_run_with_its_cancel_flag_set_stops_with_the_cancelled_error() {
    let cancel = Arc::new(Cancel::new());
    cancel.cancel();
    let options = RunOptions {
        duration: Some(0.1),
        cancel: Some(cancel),
        ..RunOptions::default()
    };
    let err = run_scene(&scenes::corner().resized(5, 5).unwrap(), &options).unwrap_err();
    assert!(
        matches!(err, ClothError::Cancelled { step: 0, steps: 10 }),
        "{err}"
    );
    assert_eq!(err.to_string(), "run cancelled after step 0 of 10");
    // An unset flag changes nothing.
    let options = RunOptions {
        duration: Some(0.1),
        cancel: Some(Arc::new(Cancel::new())),
        ..RunOptions::default()
    };
    let run = run_scene(&scenes::corner().resized(5, 5).unwrap(), &options).unwrap();
    assert_eq!(run.stats.steps, 10);
}

/// Gravity -1e200 used to print "worst stretch inf", exit 0 and write -2e201.
#[test]
fn a_run_that_goes_non_finite_returns_the_diverged_error() {
    // A step of 1e150 s: the first step's fall (5e300 m) overflows every length.
    let text = scene_text("", "pins = [0]")
        .replace("duration = 0.02", "duration = 1e150")
        .replace("dt = 0.01", "dt = 1e150");
    let scene = Scene::from_toml(&text, "overflow.toml").unwrap();
    let err = run_scene(&scene, &RunOptions::default()).unwrap_err();
    let ClothError::Diverged { step, quantity, .. } = &err else {
        panic!("expected Diverged, found {err}");
    };
    assert_eq!(*step, 1, "{err}");
    assert!(
        ["position", "velocity", "stretch"].contains(quantity),
        "{err}"
    );
    assert!(
        err.to_string()
            .starts_with("simulation diverged at step 1 (t = 1e150 s): expected a finite "),
        "{err}"
    );
}

#[test]
fn a_step_that_goes_non_finite_names_the_step_and_the_quantity() {
    let mut world = ClothWorld::new(SolverParams::default());
    let cloth = world.add_cloth(GridCloth::new(3, 3, 0.1).pin(0)).unwrap();
    world.step(0.01).unwrap();
    // A velocity that is finite, but whose step overflows.
    let i = world.particle(cloth, 8).unwrap().index();
    world.particles_mut().velocities[i] = Vector3::new(0.0, -1e308, 0.0);
    world.particles_mut().velocities[i - 1] = Vector3::new(0.0, 1e308, 0.0);
    let err = world.step(0.01).unwrap_err();
    assert!(matches!(err, ClothError::Diverged { step: 2, .. }), "{err}");
    assert_eq!(world.n_steps(), 2);
    let text = err.to_string();
    assert!(
        text.starts_with("simulation diverged at step 2 (t = 0.02 s): expected a finite ")
            && text.contains(", found "),
        "{text}"
    );
}

#[test]
fn gravity_past_its_bound_is_refused_by_the_step_and_the_scene() {
    let params = SolverParams {
        gravity: Vector3::new(0.0, -1e15, 0.0),
        ..SolverParams::default()
    };
    let mut world = ClothWorld::new(params);
    world.add_cloth(GridCloth::new(3, 3, 0.1).pin(0)).unwrap();
    let err = world.step(0.01).unwrap_err();
    assert!(
        matches!(
            err,
            ClothError::BadParameter {
                name: "gravity",
                ..
            }
        ),
        "{err}"
    );
    let err = scene("gravity = [0.0, -1e200, 0.0]", "").unwrap_err();
    assert!(
        matches!(&err, ClothError::SceneField { field, .. } if field == "gravity"),
        "{err}"
    );
    assert_eq!(
        err.to_string(),
        "scene 'small.toml': gravity must be finite and at most 1000 m/s^2 in magnitude, \
         found [0, -1e200, 0] (magnitude 1e200 m/s^2)"
    );
    let err = scene("gravity = [nan, 0.0, 0.0]", "").unwrap_err();
    assert!(err.to_string().contains("found [NaN, 0, 0]"), "{err}");
    // 100 g is still a scene.
    scene("gravity = [0.0, -981.0, 0.0]", "").unwrap();
}

#[test]
fn scene_fields_out_of_range_name_the_field_and_the_value() {
    let cases = [
        ("", "particle_mass = 0.0", "cloth.particle_mass", "0"),
        (
            "",
            "origin = [0.0, nan, 0.0]",
            "cloth.origin",
            "[0, NaN, 0]",
        ),
        (
            "",
            "origin = [1e300, 0.0, 0.0]",
            "cloth.origin",
            "[1e300, 0, 0]",
        ),
        (
            "",
            "rotation = [inf, 0.0, 0.0]",
            "cloth.rotation",
            "[inf, 0, 0]",
        ),
        ("", "pins = [0, 9]", "cloth.pins[1]", "9"),
        ("stretch_tolerance = -1.0", "", "stretch_tolerance", "-1"),
    ];
    for (extra, cloth, field, found) in cases {
        let err = scene(extra, cloth).unwrap_err();
        match &err {
            ClothError::SceneField {
                field: f, found: v, ..
            } => assert_eq!((f.as_str(), v.as_str()), (field, found), "{err}"),
            other => panic!("{cloth}: expected SceneField, found {other}"),
        }
        assert!(err.to_string().starts_with("scene 'small.toml': "), "{err}");
    }
    let text = scene_text("", "").replace("size = 1.0", "size = 1e300");
    let err = Scene::from_toml(&text, "small.toml").unwrap_err();
    assert_eq!(
        err.to_string(),
        "scene 'small.toml': cloth.size must be at most 1000000 m, found 1e300"
    );
}

/// Issue 11: the same vertex pinned twice was accepted silently.
#[test]
fn a_vertex_pinned_twice_is_refused_naming_both_places() {
    let err = scene("", "pins = [0, 2, 0]").unwrap_err();
    assert!(
        matches!(&err, ClothError::DuplicatePin { vertex: 0, first, second, .. }
            if first == "cloth.pins[0]" && second == "cloth.pins[2]"),
        "{err}"
    );
    assert_eq!(
        err.to_string(),
        "scene 'small.toml': vertex 0 is pinned twice, by cloth.pins[0] and by cloth.pins[2]; \
         expected each vertex pinned once"
    );
    let text = format!(
        "{}\n[[pins.paths]]\nvertex = 2\npath = [[0.0, 1.0, 0.0, 0.0]]\n",
        scene_text("", "pins = [0, 2]")
    );
    let err = Scene::from_toml(&text, "small.toml").unwrap_err();
    assert!(
        matches!(&err, ClothError::DuplicatePin { vertex: 2, first, second, .. }
            if first == "cloth.pins[1]" && second == "pins.paths[0].vertex"),
        "{err}"
    );
}

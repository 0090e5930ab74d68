//! Kinematic pins: a pinned corner moved along a path drags the cloth, from code, from a
//! scene file and from a marker recording.

use approx::assert_relative_eq;
use modelgap_cloth::markers::MarkerRecording;
use modelgap_cloth::{ClothError, ClothWorld, GridCloth, PinPath, Scene, SolverParams};
use nalgebra::Vector3;

fn centre_of_mass(xs: &[Vector3<f64>]) -> Vector3<f64> {
    xs.iter().sum::<Vector3<f64>>() / xs.len() as f64
}

#[test]
fn corner_moved_along_a_line_drags_the_cloth_and_stays_on_its_path() {
    let mut world = ClothWorld::new(SolverParams::default());
    let cloth = world.add_cloth(GridCloth::new(8, 8, 0.05).pin(0)).unwrap();
    // 1 m along +x in 1 s, then held.
    let path = PinPath::from_rows(&[[0.0, 0.0, 0.0, 0.0], [1.0, 1.0, 0.0, 0.0]]).unwrap();
    world.add_kinematic_pin(cloth, 0, path.clone()).unwrap();
    let com0 = centre_of_mass(world.positions(cloth));
    let mut n_converged = 0;
    for _ in 0..300 {
        // Gauss-Seidel may run out of sweeps while the dragged cloth pulls straight (a
        // nearly straight row is the paper's hard case); the state stays usable.
        n_converged += usize::from(world.step(0.01).unwrap().converged);
        let pin = world.positions(cloth)[0];
        // Exactly on the path: the pin's end-of-step position is the path's, bit for bit.
        assert_eq!(pin, path.at(world.time()));
    }
    // After 3 s the pin has been still at x = 1 for 2 s: the cloth swings under it (its
    // centre of mass started 0.175 m from the pin along x).
    let com = centre_of_mass(world.positions(cloth));
    assert!(
        com.x - com0.x > 0.5,
        "centre of mass moved {}",
        com.x - com0.x
    );
    // Gauss-Seidel converges in about half of these steps (a hanging 8 x 8 grid of
    // straight rows); what matters here is that the drag keeps the cloth together.
    assert!(n_converged > 100, "{n_converged} of 300 steps converged");
    assert!(
        world.max_stretch(cloth) <= 1e-3,
        "{}",
        world.max_stretch(cloth)
    );
    // The pin's velocity is the path's over the last step (0 once it stopped).
    assert_relative_eq!(world.velocities(cloth)[0].norm(), 0.0, epsilon = 1e-9);
}

#[test]
fn moving_pin_velocity_is_the_paths_over_the_step() {
    let mut world = ClothWorld::new(SolverParams::default());
    let cloth = world.add_cloth(GridCloth::new(4, 4, 0.1).pin(0)).unwrap();
    let path = PinPath::from_rows(&[[0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 2.0, 0.0]]).unwrap();
    world.add_kinematic_pin(cloth, 0, path).unwrap();
    world.step(0.01).unwrap();
    // 2 m/s along +y; epsilon: the difference of two positions near 0.02 m over 0.01 s.
    assert_relative_eq!(
        world.velocities(cloth)[0],
        Vector3::new(0.0, 2.0, 0.0),
        epsilon = 1e-12
    );
}

#[test]
fn only_pinned_vertices_can_follow_a_path() {
    let mut world = ClothWorld::new(SolverParams::default());
    let cloth = world.add_cloth(GridCloth::new(4, 4, 0.1).pin(0)).unwrap();
    let path = PinPath::from_rows(&[[0.0, 0.0, 0.0, 0.0]]).unwrap();
    let e = world.add_kinematic_pin(cloth, 5, path).unwrap_err();
    assert!(matches!(e, ClothError::NotPinned { vertex: 5 }), "{e}");
}

#[test]
fn scene_paths_and_marker_recordings_move_pins() {
    let scene = Scene::from_toml(
        r"
        name = 'moving'
        duration = 0.5
        dt = 0.01
        [cloth]
        nx = 5
        nz = 5
        size = 0.4
        pins = [0]
        [[pins.paths]]
        vertex = 4
        path = [[0.0, 0.4, 0.0, 0.0], [0.5, 0.4, 0.5, 0.0]]
        ",
        "moving",
    )
    .unwrap();
    assert!(scene.cloth.pinned.contains(&4));
    let (mut world, cloth) = scene.build().unwrap();
    world.step_n(scene.n_steps(), scene.dt).unwrap();
    assert_relative_eq!(world.positions(cloth)[4].y, 0.5, epsilon = 1e-12);
    assert_eq!(world.positions(cloth)[0], Vector3::zeros());

    // Vertex 0 follows a recording; marker 7 is on a dynamic vertex and is ignored.
    let rec = MarkerRecording::new(
        vec![0.0, 0.5],
        vec![0, 7],
        vec![
            vec![[0.0, 0.0, 0.0], [9.0, 9.0, 9.0]],
            vec![[0.0, 0.0, 0.25], [9.0, 9.0, 9.0]],
        ],
    )
    .unwrap();
    let (mut world, cloth) = scene.build_with_markers(Some(&rec)).unwrap();
    assert_eq!(world.kinematic_pins().len(), 2);
    world.step_n(scene.n_steps(), scene.dt).unwrap();
    assert_relative_eq!(world.positions(cloth)[0].z, 0.25, epsilon = 1e-12);

    let mut from_markers = scene.clone();
    from_markers.pins_from_markers = true;
    assert!(matches!(
        from_markers.build().unwrap_err(),
        ClothError::Scene { .. }
    ));
}

//! Behaviour of the cloth solver on small grids and the reference scenes:
//! tolerance, static particles, momentum, any-time stopping, repair of broken
//! states, the two-corners trap, contacts and typed errors.

use modelgap_cloth::{
    BuildMesh as _, ClothError, ClothMesh, ClothWorld, GridCloth, Method, SolverParams, scenes,
};
use nalgebra::Vector3;

/// Deterministic noise in [-1, 1) (a fixed linear congruential sequence).
fn noise(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

fn all_finite(world: &ClothWorld) -> bool {
    let p = world.particles();
    p.positions
        .iter()
        .chain(&p.velocities)
        .all(|x| x.iter().all(|c| c.is_finite()))
}

fn params(method: Method) -> SolverParams {
    SolverParams {
        method,
        ..SolverParams::default()
    }
}

#[test]
fn stretch_within_tolerance_after_converged_step() {
    for method in [Method::GaussSeidel, Method::Newton] {
        let mut world = ClothWorld::new(params(method));
        let cloth = world.add_cloth(GridCloth::new(8, 8, 0.05).pin(0)).unwrap();
        let mut converged = 0;
        for _ in 0..40 {
            let r = world.step(0.01).unwrap();
            if r.converged {
                converged += 1;
                assert!(r.max_stretch <= 1e-4, "{method:?}: {r:?}");
                assert!(world.max_stretch(cloth) <= 1e-4);
            }
        }
        // A corner-hung grid with structural edges only pulls its chains
        // nearly straight, where Gauss–Seidel converges slowly: a few steps
        // may run out of sweeps (reported, not an error).
        assert!(converged >= 35, "{method:?}: {converged} of 40 converged");
    }
}

#[test]
fn static_particles_never_move() {
    let mut world = ClothWorld::new(SolverParams::default());
    let cloth = world
        .add_cloth(GridCloth::new(8, 8, 0.05).pin(0).pin(7))
        .unwrap();
    let before = [world.positions(cloth)[0], world.positions(cloth)[7]];
    for _ in 0..30 {
        world.step(0.01).unwrap();
        assert_eq!(
            [world.positions(cloth)[0], world.positions(cloth)[7]],
            before
        );
        assert_eq!(world.velocities(cloth)[0], Vector3::zeros());
    }
}

#[test]
fn impulses_conserve_momentum() {
    // No gravity, no pins, random velocities: only constraint impulses act.
    for method in [Method::GaussSeidel, Method::Newton] {
        let mut world = ClothWorld::new(SolverParams {
            gravity: Vector3::zeros(),
            ..params(method)
        });
        world.add_cloth(GridCloth::new(6, 6, 0.05)).unwrap();
        let mut seed = 7;
        for v in &mut world.particles_mut().velocities {
            *v = Vector3::new(noise(&mut seed), noise(&mut seed), noise(&mut seed)) * 0.2;
        }
        let before = world.particles().momentum();
        for _ in 0..20 {
            world.step(0.01).unwrap();
        }
        // Sums of 36 terms of order 1e-3 kg m/s: rounding is near 1e-17.
        approx::assert_relative_eq!(world.particles().momentum(), before, epsilon = 1e-13);
    }
}

#[test]
fn stopped_after_one_iteration_stays_finite_and_recovers() {
    let mut world = ClothWorld::new(SolverParams {
        max_iterations: 1,
        ..SolverParams::default()
    });
    let cloth = world
        .add_cloth(GridCloth::new(10, 10, 0.05).pin(0))
        .unwrap();
    for _ in 0..20 {
        let r = world.step(0.01).unwrap();
        assert!(r.max_stretch.is_finite() && r.iterations <= 1);
        assert!(all_finite(&world));
    }
    let broken = world.max_stretch(cloth);
    assert!(
        broken > 1e-2,
        "one sweep per step cannot hold 30 constraints: {broken}"
    );
    world.params_mut().max_iterations = 1000;
    let last = world.step_n(10, 0.01).unwrap();
    assert!(all_finite(&world));
    assert!(world.max_stretch(cloth) <= 1e-3, "{broken} -> {last:?}");
    // The global solve finishes the repair.
    world.params_mut().method = Method::Newton;
    let last = world.step(0.01).unwrap();
    assert!(
        last.converged && world.max_stretch(cloth) <= 1e-4,
        "{last:?}"
    );
}

#[test]
fn scrambled_positions_are_pulled_back() {
    let mut world = ClothWorld::new(SolverParams::default());
    let cloth = world.add_cloth(GridCloth::new(8, 8, 0.05).pin(0)).unwrap();
    world.step_n(5, 0.01).unwrap();
    let mut seed = 42;
    for (i, x) in world.particles_mut().positions.iter_mut().enumerate() {
        if i != 0 {
            *x += Vector3::new(noise(&mut seed), noise(&mut seed), noise(&mut seed)) * 0.01;
        }
    }
    let broken = world.max_stretch(cloth);
    assert!(broken > 0.1);
    let r = world.step_n(3, 0.01).unwrap();
    assert!(all_finite(&world));
    assert!(world.max_stretch(cloth) <= 1e-4, "{broken} -> {r:?}");
}

#[test]
fn two_corners_stays_finite_and_holds_the_tolerance() {
    // The trap: a straight row held at both ends under a transverse load. A
    // 12 x 12 grid keeps the test fast; the 30 x 30 scene is timed by the
    // `scene_timing` example and the bench.
    let mut world = ClothWorld::new(SolverParams::default());
    let cloth = world
        .add_cloth(GridCloth::new(12, 12, 1.0 / 11.0).pin(0).pin(11))
        .unwrap();
    for _ in 0..50 {
        let r = world.step(0.01).unwrap();
        assert!(all_finite(&world), "{r:?}");
        assert!(r.max_stretch.is_finite());
    }
    assert!(world.max_stretch(cloth) < 1e-2);
    // The scene itself: finite over its first steps.
    let scene = scenes::two_corners();
    let (mut world, _) = scene.build().unwrap();
    world.params_mut().max_iterations = 100;
    for _ in 0..20 {
        world.step(scene.dt).unwrap();
        assert!(all_finite(&world));
    }
}

#[test]
fn drape_never_penetrates_the_ball_by_more_than_a_millimetre() {
    let scene = scenes::drape();
    let (mut world, cloth) = scene.build().unwrap();
    world.params_mut().max_iterations = 200;
    let mut touched = 0;
    for _ in 0..50 {
        let r = world.step(scene.dt).unwrap();
        assert!(r.max_penetration <= 1e-3, "{r:?}");
        touched = touched.max(r.n_contacts);
    }
    assert!(touched > 0, "the cloth reached the ball");
    let top = world.positions(cloth)[15 * 30 + 15];
    assert!(top.y > 0.29, "the centre rests on the ball: {top}");
}

#[test]
fn bad_input_gives_typed_errors() {
    let mut world = ClothWorld::new(SolverParams::default());
    assert!(matches!(
        world.step(0.0),
        Err(ClothError::BadTimeStep { .. })
    ));
    assert!(matches!(
        world.step(f64::NAN),
        Err(ClothError::BadTimeStep { .. })
    ));
    let cloth = world.add_cloth(GridCloth::new(3, 3, 0.1).pin(0)).unwrap();
    let p = world.particle(cloth, 4).unwrap();
    world.particles_mut().positions[p.index()].x = f64::NAN;
    assert!(matches!(
        world.step(0.01),
        Err(ClothError::NonFinite {
            particle: 4,
            what: "position",
            ..
        })
    ));

    let mut mesh: ClothMesh = GridCloth::new(2, 2, 0.1).build_mesh().unwrap();
    mesh.pin(0).unwrap();
    mesh.pin(1).unwrap();
    // Two neighbouring pins: the edge between them is not a constraint.
    let mut both = ClothWorld::new(SolverParams::default());
    let square = both.add_cloth(mesh).unwrap();
    assert_eq!(both.constraints().len(), 3);
    assert!(both.step(0.01).unwrap().converged);
    assert_eq!(both.positions(square)[1], Vector3::new(0.1, 0.0, 0.0));

    let mut mesh = GridCloth::new(2, 2, 0.1).build_mesh().unwrap();
    mesh.positions[1] = mesh.positions[0];
    let err = ClothWorld::new(SolverParams::default())
        .add_cloth(mesh)
        .unwrap_err();
    assert!(
        matches!(err, ClothError::ZeroLengthEdge { a: 0, b: 1 }),
        "{err}"
    );

    let err = ClothWorld::new(SolverParams::default())
        .add_cloth(ClothMesh::default())
        .unwrap_err();
    assert!(matches!(
        err,
        ClothError::EmptyMesh {
            n_particles: 0,
            n_edges: 0
        }
    ));
    assert!(err.to_string().starts_with("mesh is empty"));
}

/// Every step of a reference scene with the global Newton solve converges:
/// max stretch ≤ 1e-4, finite, and (for `drape`) at most 1 mm into the ball.
fn newton_holds_the_scene(scene: &modelgap_cloth::Scene) -> Result<(), ClothError> {
    let (mut world, _) = scene.build()?;
    world.params_mut().method = Method::Newton;
    for step in 0..scene.n_steps() {
        let r = world.step(scene.dt)?;
        assert!(
            r.converged && r.max_stretch <= 1e-4 && all_finite(&world),
            "{} step {step}: {r:?}",
            scene.name
        );
        assert!(
            r.max_penetration <= 1e-3,
            "{} step {step}: {r:?}",
            scene.name
        );
    }
    Ok(())
}

#[test]
fn newton_holds_two_corners_at_every_step() -> Result<(), ClothError> {
    newton_holds_the_scene(&scenes::two_corners())
}

#[test]
fn newton_holds_corner_at_every_step() -> Result<(), ClothError> {
    newton_holds_the_scene(&scenes::corner())
}

#[test]
fn newton_holds_drape_at_every_step() -> Result<(), ClothError> {
    newton_holds_the_scene(&scenes::drape())
}

#[test]
fn newton_holds_an_over_constrained_mesh_without_iterating_long() -> Result<(), ClothError> {
    // Shear edges (both diagonals of every quad): more constraints than
    // degrees of freedom, so the impulses are not unique and can carry
    // self-stress. Started from last step's correction, Newton once needed
    // hundreds of iterations per step here.
    let mut world = ClothWorld::new(SolverParams::default());
    world.add_cloth(GridCloth::new(16, 16, 1.0 / 15.0).shear(true).pin(0))?;
    let (mut iterations, steps) = (0, 50);
    for step in 0..steps {
        let r = world.step(0.01)?;
        let stretch = world
            .constraints()
            .max_stretch(&world.particles().positions);
        assert!(
            r.converged && r.max_stretch <= 1e-4 && stretch <= 1e-4 && all_finite(&world),
            "step {step}: {r:?}, geometric stretch {stretch:e}"
        );
        iterations += r.iterations;
    }
    let mean = iterations as f64 / f64::from(steps);
    eprintln!("over-constrained 16 x 16: {mean} Newton iterations per step");
    assert!(mean <= 10.0, "{mean} iterations per step");
    Ok(())
}

#[test]
fn compliant_chain_stretches_by_compliance_times_tension() {
    // A vertical chain of 5 links, 0.1 m each, 10 g per particle, hanging
    // from a pin: at rest the top link carries the weight of the 5 particles
    // below it, and a compliance α stretches it by α T.
    for method in [Method::GaussSeidel, Method::Newton] {
        let mut world = ClothWorld::new(SolverParams {
            method,
            ..SolverParams::default()
        });
        let positions: Vec<_> = (0..6)
            .map(|i| nalgebra::Vector3::new(0.0, -0.1 * f64::from(i), 0.0))
            .collect();
        let mesh = modelgap_cloth::ClothMesh {
            positions,
            masses: vec![0.01; 6],
            edges: (0..5).map(|i| [i, i + 1]).collect(),
            triangles: Vec::new(),
            pinned: vec![0],
        };
        let chain = world.add_cloth(mesh).unwrap();
        let alpha = 1e-3; // m/N
        world.set_compliance(chain, alpha).unwrap();
        // Averaged over the last 2 s: the chain still swings a little.
        let (mut top, mut bottom) = (0.0, 0.0);
        for step in 0..600 {
            let r = world.step(0.01).unwrap();
            assert!(r.converged, "{method:?}: {r:?}");
            if step >= 400 {
                let x = world.positions(chain);
                top += ((x[0] - x[1]).norm() - 0.1) / 200.0;
                bottom += ((x[4] - x[5]).norm() - 0.1) / 200.0;
            }
        }
        let tension = 5.0 * 0.01 * 9.81;
        approx::assert_relative_eq!(top, alpha * tension, max_relative = 0.02);
        approx::assert_relative_eq!(bottom, alpha * 0.01 * 9.81, max_relative = 0.05);
    }
}

//! The coloured Gauss–Seidel sweep in a world (issue 4): the same bits with one
//! and two threads on a grid large enough to run in parallel, and convergence on
//! the 30 × 30 `corner` scene like the serial sweep.

#![allow(clippy::unwrap_used)] // in test helpers, a panic is a test failure

use modelgap_cloth::colouring::{ConstraintColouring, PARALLEL_MIN_CONSTRAINTS};
use modelgap_cloth::{ClothWorld, StepReport, scenes};
use nalgebra::Vector3;

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

fn bits(xs: &[Vector3<f64>]) -> Vec<u64> {
    xs.iter()
        .flat_map(|x| x.iter().map(|c| c.to_bits()))
        .collect()
}

/// Runs `steps` steps of the scene's `dt` in a pool of `threads` threads.
fn run(world: &mut ClothWorld, steps: usize, dt: f64, threads: usize) -> Vec<StepReport> {
    pool(threads).install(|| (0..steps).map(|_| world.step(dt).unwrap()).collect())
}

#[test]
fn coloured_world_gives_the_same_bits_with_one_and_two_threads() {
    // 100 x 100 corner: 19 800 constraints, colours above the parallel threshold.
    let scene = scenes::corner().resized(100, 100).unwrap();
    let build = || {
        let (mut world, _) = scene.build().unwrap();
        world.params_mut().coloured_sweep = true;
        world.params_mut().max_iterations = 40;
        world
    };
    let mut one = build();
    let mut two = build();
    let colouring = ConstraintColouring::new(one.constraints(), &one.particles().inv_mass).unwrap();
    let largest = (0..colouring.n_colours())
        .map(|c| colouring.colour(c).len())
        .max()
        .unwrap();
    assert!(
        largest >= PARALLEL_MIN_CONSTRAINTS,
        "largest colour {largest} would not run in parallel"
    );
    let reports_one = run(&mut one, 4, scene.dt, 1);
    let reports_two = run(&mut two, 4, scene.dt, 2);
    assert_eq!(reports_one, reports_two);
    assert!(reports_one.iter().all(|r| r.iterations > 0));
    assert_eq!(
        bits(&one.particles().positions),
        bits(&two.particles().positions)
    );
    assert_eq!(
        bits(&one.particles().velocities),
        bits(&two.particles().velocities)
    );
}

#[test]
fn coloured_sweep_converges_on_the_corner_scene_like_the_serial_sweep() {
    // A loose tolerance (0.1 %) and the first 0.2 s: both sweeps converge
    // within the 1000-sweep cap (in index order, 640 sweeps at step 20;
    // later, as the cloth swings through, both run into the cap).
    const TOLERANCE: f64 = 1e-3;
    const STEPS: usize = 20;
    let scene = scenes::corner();
    let mut worlds = [false, true].map(|coloured| {
        let (mut world, _) = scene.build().unwrap();
        world.params_mut().coloured_sweep = coloured;
        world.params_mut().stretch_tolerance = TOLERANCE;
        world
    });
    let [serial, coloured] = worlds
        .each_mut()
        .map(|world| run(world, STEPS, scene.dt, 2));
    for (name, reports) in [("serial", &serial), ("coloured", &coloured)] {
        for (step, r) in reports.iter().enumerate() {
            assert!(r.converged, "{name} step {step}: {r:?}");
            assert!(r.max_stretch <= TOLERANCE, "{name} step {step}: {r:?}");
        }
    }
    let iterations = |reports: &[StepReport]| reports.iter().map(|r| r.iterations).sum::<usize>();
    let (n_serial, n_coloured) = (iterations(&serial), iterations(&coloured));
    // Another order, about the same work: within a factor 2 either way.
    assert!(
        n_coloured <= 2 * n_serial && n_serial <= 2 * n_coloured,
        "iterations: serial {n_serial}, coloured {n_coloured}"
    );
    // The same motion: particles agree to a fraction of the 3.4 cm spacing.
    let [a, b] = worlds.each_ref().map(|w| &w.particles().positions);
    let gap = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max);
    println!("serial {n_serial} iterations, coloured {n_coloured}, largest gap {gap:.3e} m");
    assert!(gap < 2e-3, "largest gap {gap} m");
}

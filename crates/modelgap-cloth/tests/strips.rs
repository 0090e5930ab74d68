//! The strip sweep ([`Method::Strips`], the paper's acceleration): a chain is
//! solved exactly by one linear-time strip solve, momentum is conserved,
//! pins stay put, every edge of a grid or an OBJ triangle mesh lies in
//! exactly one strip, a grid converges in fewer sweeps than Gauss–Seidel,
//! and a step stopped after one sweep stays finite.

#![allow(clippy::unwrap_used)] // in test helpers, a panic is a test failure

use modelgap_cloth::strips::StripDecomposition;
use modelgap_cloth::{ClothMesh, ClothWorld, GridCloth, Method, SolverParams, StepReport, scenes};
use nalgebra::Vector3;

/// A rope of `n` particles of 10 g, 5 cm apart, from the origin along
/// `direction`, pinned at the origin.
fn rope(n: usize, direction: Vector3<f64>) -> ClothMesh {
    let step = direction.normalize() * 0.05;
    ClothMesh {
        positions: (0..n).map(|i| step * i as f64).collect(),
        masses: vec![0.01; n],
        edges: (0..n as u32 - 1).map(|i| [i, i + 1]).collect(),
        triangles: Vec::new(),
        pinned: vec![0],
    }
}

fn params(method: Method, tolerance: f64, max_iterations: usize) -> SolverParams {
    SolverParams {
        method,
        stretch_tolerance: tolerance,
        max_iterations,
        ..SolverParams::default()
    }
}

/// A world with the rope, every position moved away from the pin by 10 %.
fn stretched_rope(method: Method, tolerance: f64, direction: Vector3<f64>) -> ClothWorld {
    let mut world = ClothWorld::new(params(method, tolerance, 1000));
    world.add_cloth(rope(20, direction)).unwrap();
    for x in &mut world.particles_mut().positions {
        *x *= 1.1;
    }
    world
}

fn finite(xs: &[Vector3<f64>]) -> bool {
    xs.iter().all(|x| x.iter().all(|c| c.is_finite()))
}

#[test]
fn a_straight_hanging_rope_is_solved_exactly_by_one_strip_solve() {
    // Hanging straight down, stretched by 10 %: the rope is one strip, all
    // its directions stay vertical, so the linear-time solve is exact.
    let down = Vector3::new(0.0, -1.0, 0.0);
    let mut world = stretched_rope(Method::Strips, 1e-13, down);
    let report = world.step(0.01).unwrap();
    assert!(report.converged, "{report:?}");
    assert_eq!(report.iterations, 1, "{report:?}");
    assert!(report.max_stretch <= 1e-13);
    // Gauss–Seidel needs many sweeps for the same.
    let mut gs = stretched_rope(Method::GaussSeidel, 1e-13, down);
    let gs_report = gs.step(0.01).unwrap();
    assert!(gs_report.iterations > 50, "{gs_report:?}");
}

#[test]
fn a_swinging_rope_converges_to_machine_precision_in_a_few_sweeps() {
    // At 45° with a sideways push: the directions turn as the rope moves,
    // one strip solve is one Gauss–Newton step, and a few reach 1e-13.
    let slant = Vector3::new(1.0, -1.0, 0.3);
    let mut world = stretched_rope(Method::Strips, 1e-13, slant);
    for (i, v) in world.particles_mut().velocities.iter_mut().enumerate() {
        *v = Vector3::new(0.0, 0.0, 0.1 * i as f64);
    }
    for _ in 0..5 {
        let report = world.step(0.01).unwrap();
        assert!(report.converged, "{report:?}");
        assert!(report.iterations <= 6, "{report:?}");
    }
}

#[test]
fn momentum_is_conserved() {
    // A free cloth (no pins), stretched and spinning: the impulses cancel,
    // the momentum changes by gravity's impulse only.
    let mut world = ClothWorld::new(params(Method::Strips, 1e-4, 20));
    world.add_cloth(GridCloth::new(8, 8, 0.05)).unwrap();
    let ps = world.particles_mut();
    for (i, (x, v)) in ps.positions.iter_mut().zip(&mut ps.velocities).enumerate() {
        *x *= 1.05;
        *v = Vector3::new(-x.z, 0.1 * (i % 3) as f64, x.x);
    }
    let momentum = |w: &ClothWorld| -> Vector3<f64> {
        let ps = w.particles();
        ps.velocities
            .iter()
            .zip(&ps.inv_mass)
            .map(|(v, k)| v / *k)
            .sum()
    };
    let mass: f64 = world.particles().inv_mass.iter().map(|k| 1.0 / k).sum();
    let h = 0.01;
    let before = momentum(&world);
    let report = world.step(h).unwrap();
    assert!(report.iterations > 1, "{report:?}");
    let gained = momentum(&world) - before;
    let gravity = world.params().gravity * mass * h;
    assert!(
        (gained - gravity).norm() <= 1e-12 * before.norm().max(gravity.norm()),
        "gained {gained:?}, gravity {gravity:?}"
    );
}

#[test]
fn static_particles_never_move() {
    let scene = scenes::corner().resized(12, 12).unwrap();
    let (mut world, _) = scene.build().unwrap();
    world.params_mut().method = Method::Strips;
    let ps = world.particles();
    let pins: Vec<(usize, Vector3<f64>)> = (0..ps.len())
        .filter(|&i| ps.inv_mass[i] == 0.0)
        .map(|i| (i, ps.positions[i]))
        .collect();
    assert!(!pins.is_empty());
    world.step_n(20, scene.dt).unwrap();
    for (i, x) in pins {
        assert_eq!(world.particles().positions[i], x);
    }
}

/// Sum of sweeps over `steps` steps of the 12 × 12 corner scene, and whether all converged.
fn corner_sweeps(method: Method, steps: usize) -> StepReport {
    let scene = scenes::corner().resized(12, 12).unwrap();
    let (mut world, _) = scene.build().unwrap();
    world.params_mut().method = method;
    world.params_mut().max_iterations = 5000;
    world.step_n(steps, scene.dt).unwrap()
}

#[test]
fn a_small_grid_converges_in_fewer_sweeps_than_gauss_seidel() {
    let strips = corner_sweeps(Method::Strips, 40);
    let gs = corner_sweeps(Method::GaussSeidel, 40);
    assert!(strips.converged, "{strips:?}");
    assert!(strips.max_stretch <= 1e-4);
    assert!(
        strips.iterations * 2 < gs.iterations,
        "strips {} sweeps, Gauss–Seidel {}",
        strips.iterations,
        gs.iterations
    );
}

/// Every constraint in exactly one strip; each strip a chain: consecutive
/// constraints join consecutive strip particles, which are distinct, static
/// ones only at the ends.
fn assert_strip_cover(world: &ClothWorld) -> StripDecomposition {
    let ps = world.particles();
    let cs = world.constraints();
    let strips = StripDecomposition::new(cs, &ps.inv_mass, &ps.positions).unwrap();
    let mut count = vec![0_usize; cs.len()];
    for s in 0..strips.n_strips() {
        let edges = strips.strip(s);
        let nodes = strips.strip_particles(s);
        assert!(!edges.is_empty());
        assert_eq!(nodes.len(), edges.len() + 1);
        for (t, &i) in edges.iter().enumerate() {
            count[i as usize] += 1;
            let mut ends = [cs.a[i as usize], cs.b[i as usize]];
            let mut pair = [nodes[t], nodes[t + 1]];
            ends.sort_unstable();
            pair.sort_unstable();
            assert_eq!(ends, pair, "strip {s} constraint {t}");
        }
        let mut distinct = nodes.to_vec();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(distinct.len(), nodes.len(), "strip {s} revisits a particle");
        for &p in &nodes[1..nodes.len() - 1] {
            assert!(ps.inv_mass[p as usize] > 0.0, "strip {s} passes a pin");
        }
    }
    assert!(
        count.iter().all(|&c| c == 1),
        "an edge is in 0 or 2+ strips"
    );
    strips
}

#[test]
fn every_grid_edge_is_in_exactly_one_strip() {
    let mut world = ClothWorld::new(SolverParams::default());
    world
        .add_cloth(GridCloth::new(30, 30, 0.05).pin(0).pin(29))
        .unwrap();
    let strips = assert_strip_cover(&world);
    // Rows and columns: 60 strips of 29.
    assert_eq!(strips.n_strips(), 60);
    assert_eq!(strips.longest(), 29);
    // With shear and bend edges too.
    let mut world = ClothWorld::new(SolverParams::default());
    world
        .add_cloth(GridCloth::new(9, 7, 0.05).shear(true).bend(true).pin(0))
        .unwrap();
    assert_strip_cover(&world);
}

/// An irregular triangulated disc: a ring of 7 around a centre, a ring of
/// 14 around that (jittered), fanned into triangles.
fn disc_obj() -> String {
    let mut obj = String::from("v 0 0 0\n");
    for i in 0..7 {
        let a = f64::from(i) * std::f64::consts::TAU / 7.0;
        obj += &format!("v {} 0 {}\n", 0.1 * a.cos(), 0.1 * a.sin());
    }
    for i in 0..14 {
        let a = f64::from(i) * std::f64::consts::TAU / 14.0 + 0.05 * f64::from(i % 3);
        obj += &format!("v {} 0.01 {}\n", 0.2 * a.cos(), 0.2 * a.sin());
    }
    for i in 0..7 {
        obj += &format!("f 1 {} {}\n", 2 + i, 2 + (i + 1) % 7);
    }
    for i in 0..7 {
        let (inner, next_inner) = (2 + i, 2 + (i + 1) % 7);
        let (o0, o1, o2) = (9 + 2 * i, 9 + 2 * i + 1, 9 + (2 * i + 2) % 14);
        obj += &format!(
            "f {inner} {o0} {o1}\nf {inner} {o1} {next_inner}\nf {next_inner} {o1} {o2}\n"
        );
    }
    obj
}

#[test]
fn every_obj_edge_is_in_exactly_one_strip() {
    let run = |method| {
        let mut mesh = ClothMesh::from_obj(disc_obj().as_bytes(), 0.01).unwrap();
        mesh.pin(0).unwrap();
        let mut world = ClothWorld::new(params(method, 1e-4, 500));
        world.add_cloth(mesh).unwrap();
        let report = world.step_n(20, 0.01).unwrap();
        (world, report)
    };
    let (world, strips_report) = run(Method::Strips);
    let strips = assert_strip_cover(&world);
    assert!(strips.n_strips() < world.constraints().len());
    // An umbrella held at its centre: hard for both sweeps (neither holds
    // 1e-4 in 500 sweeps a step); the strips stay finite and near.
    let (_, gs_report) = run(Method::GaussSeidel);
    assert!(finite(&world.particles().positions));
    assert!(
        strips_report.max_stretch < 2.0 * gs_report.max_stretch,
        "strips {strips_report:?}, Gauss–Seidel {gs_report:?}"
    );
}

#[test]
fn a_step_stopped_after_one_sweep_stays_finite() {
    // The 30 x 30 corner scene, one sweep a step, then a scrambled state.
    let scene = scenes::corner();
    let (mut world, _) = scene.build().unwrap();
    world.params_mut().method = Method::Strips;
    world.params_mut().max_iterations = 1;
    for _ in 0..30 {
        let report = world.step(scene.dt).unwrap();
        assert_eq!(report.iterations, 1);
        assert!(report.max_stretch.is_finite());
    }
    let ps = world.particles_mut();
    for (i, x) in ps.positions.iter_mut().enumerate() {
        if ps.inv_mass[i] > 0.0 {
            *x += Vector3::new(
                ((i * 7919) % 13) as f64 * 0.01,
                ((i * 104_729) % 17) as f64 * -0.01,
                ((i * 31) % 11) as f64 * 0.01,
            );
        }
    }
    let report = world.step_n(10, scene.dt).unwrap();
    assert!(report.max_stretch.is_finite());
    assert!(finite(&world.particles().positions));
    assert!(finite(&world.particles().velocities));
    // Given sweeps again, the broken state is pulled back.
    world.params_mut().max_iterations = 5000;
    world.step_n(5, scene.dt).unwrap();
    let report = world.step(scene.dt).unwrap();
    assert!(report.converged && report.max_stretch <= 1e-4, "{report:?}");
}

#[test]
fn compliant_constraints_reach_their_compliant_length() {
    // A compliant rope: converged means every link at `rest + α μ / h²`
    // (the world's check); the strips reach the same state as Gauss–Seidel.
    let run = |method| {
        let mut world = ClothWorld::new(params(method, 1e-11, 5000));
        let cloth = world
            .add_cloth(rope(15, Vector3::new(1.0, -0.5, 0.0)))
            .unwrap();
        world.set_compliance(cloth, 1e-3).unwrap();
        let report = world.step(0.01).unwrap();
        assert!(report.converged, "{method:?}: {report:?}");
        (
            world.positions(cloth).to_vec(),
            world.max_stretch(cloth),
            report,
        )
    };
    let (strips, stretch, report) = run(Method::Strips);
    let (gs, _, gs_report) = run(Method::GaussSeidel);
    // Compliant: the rope stretches under its weight, beyond the tolerance.
    assert!(stretch > 1e-4, "stretch {stretch}");
    assert!(report.iterations < gs_report.iterations);
    for (s, g) in strips.iter().zip(&gs) {
        // The impulses go along the directions at the time they are
        // applied: the converged state depends on the path, here by 1e-7 m
        // against a compliant stretch of 1e-4 m a link.
        assert!((s - g).norm() < 1e-6, "{s:?} vs {g:?}");
    }
}

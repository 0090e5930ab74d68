//! Benchmarks of the cloth solver: one step of each reference scene (30 × 30,
//! 900 particles, 1740 constraints) with the global Newton solve, one
//! Gauss–Seidel step (the any-time method, capped at 100 sweeps), and a step
//! of a 100 × 100 grid. Read a step's time against `h` = 10 ms of simulated
//! time: under 2 ms is five times real time.
#![allow(clippy::unwrap_used)] // benches: setup failures should abort

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use modelgap::cloth::{ClothWorld, GridCloth, Method, SolverParams, scenes};

/// The same allocator as the `modelgap` binary (see src/main.rs).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Steps run before timing, so the cloth is hanging or draping, not flat.
const SETTLE_STEPS: usize = 30;

fn scene_steps(c: &mut Criterion) {
    for (id, scene) in [
        ("corner", scenes::corner()),
        ("two_corners", scenes::two_corners()),
        ("drape", scenes::drape()),
    ] {
        let (mut world, _) = scene.build().unwrap();
        world.params_mut().method = Method::Newton;
        world.params_mut().max_iterations = 200;
        world.step_n(SETTLE_STEPS, scene.dt).unwrap();
        c.bench_function(&format!("cloth/step/30x30/{id}"), |b| {
            b.iter(|| black_box(world.step(black_box(scene.dt)).unwrap()));
        });
    }
}

fn sweep(c: &mut Criterion) {
    let scene = scenes::corner();
    let (mut world, _) = scene.build().unwrap();
    world.step_n(SETTLE_STEPS, scene.dt).unwrap();
    world.params_mut().method = Method::GaussSeidel;
    world.params_mut().max_iterations = 1;
    world.params_mut().warm_start = false;
    c.bench_function("cloth/sweep/30x30/corner", |b| {
        b.iter(|| black_box(world.step(black_box(scene.dt)).unwrap()));
    });
}

fn large(c: &mut Criterion) {
    let params = SolverParams {
        method: Method::Newton,
        max_iterations: 50,
        ..SolverParams::default()
    };
    let mut world = ClothWorld::new(params);
    world
        .add_cloth(GridCloth::new(100, 100, 0.01).pin(0).pin(99))
        .unwrap();
    world.step_n(5, 0.01).unwrap();
    c.bench_function("cloth/step/100x100/two_corners", |b| {
        b.iter(|| black_box(world.step(black_box(0.01)).unwrap()));
    });
}

criterion_group!(benches, scene_steps, sweep, large);
criterion_main!(benches);

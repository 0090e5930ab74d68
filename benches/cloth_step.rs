//! Benchmarks of the cloth solver: one step of each reference scene (30 × 30,
//! 900 particles, 1740 constraints) with the global Newton solve; one
//! Gauss–Seidel sweep, serial and coloured, on the 30 × 30 corner and a
//! 300 × 300 grid; a step of the corner scene resized to 100 × 100 and
//! 300 × 300 with Gauss–Seidel serial and coloured on one and two threads,
//! capped at [`LARGE_SWEEPS`] sweeps; and the constraint loop at scale, a
//! Newton step of the corner scene at 30 × 30, 100 × 100 and 300 × 300
//! (`cloth/step/{n}x{n}/corner/newton`, after [`NEWTON_SETTLE_STEPS`] steps,
//! before the corner's first snap). Read a step's time against `h` = 10 ms of
//! simulated time: under 2 ms is five times real time, under 10 ms real time.
//!
//! The coloured sweep runs inside a rayon pool of the thread count in the id
//! (`coloured/1t`, `coloured/2t`); its result is the same on any number of
//! threads, so the ids time the same work.
#![allow(clippy::unwrap_used)] // benches: setup failures should abort

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use modelgap::cloth::{ClothWorld, Method, scenes};

/// The same allocator as the `modelgap` binary (see src/main.rs).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Steps run before timing, so the cloth is hanging or draping, not flat.
const SETTLE_STEPS: usize = 30;

/// Sweeps per step on the 100 × 100 and 300 × 300 grids: Gauss–Seidel does
/// not reach 1e-4 there within a bench's patience, so a step is this many
/// sweeps (the time per sweep is what the ids compare).
const LARGE_SWEEPS: usize = 100;

/// Steps run before timing the large grids (short: setup runs in `cargo test` too).
const LARGE_SETTLE_STEPS: usize = 3;

/// Steps run before timing a Newton step of the corner at 30², 100² and 300²: the
/// cloth is falling, before its first snap (a 300 × 300 step takes 1.3 s CPU).
const NEWTON_SETTLE_STEPS: usize = 5;

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

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

/// The corner scene on an `n` × `n` grid after `settle` steps of `sweeps`
/// Gauss–Seidel sweeps at most, coloured or not.
fn corner_world(n: usize, coloured: bool, sweeps: usize, settle: usize) -> (ClothWorld, f64) {
    let scene = scenes::corner().resized(n, n).unwrap();
    let (mut world, _) = scene.build().unwrap();
    world.params_mut().method = Method::GaussSeidel;
    world.params_mut().coloured_sweep = coloured;
    world.params_mut().max_iterations = sweeps;
    world.step_n(settle, scene.dt).unwrap();
    (world, scene.dt)
}

/// One sweep: a step capped at one sweep without warm start (the preview,
/// two largest-error scans and the commit come with it).
fn sweeps(c: &mut Criterion) {
    let mut group = c.benchmark_group("cloth/sweep");
    for (n, settle) in [(30, SETTLE_STEPS), (300, LARGE_SETTLE_STEPS)] {
        if n > 100 {
            group.sample_size(10);
        }
        for (id, coloured, threads) in [
            ("serial", false, 1),
            ("coloured/1t", true, 1),
            ("coloured/2t", true, 2),
        ] {
            let (mut world, dt) = corner_world(n, coloured, LARGE_SWEEPS, settle);
            world.params_mut().max_iterations = 1;
            world.params_mut().warm_start = false;
            let pool = pool(threads);
            group.bench_function(format!("{n}x{n}/corner/{id}"), |b| {
                pool.install(|| b.iter(|| black_box(world.step(black_box(dt)).unwrap())));
            });
        }
    }
    group.finish();
}

/// One strip sweep ([`Method::Strips`]: every row and column solved by the
/// linear-time tridiagonal method) on the 30 × 30 corner: a step capped at
/// one sweep without warm start, as the sweeps above.
fn strip_sweep(c: &mut Criterion) {
    let scene = scenes::corner();
    let (mut world, _) = scene.build().unwrap();
    world.params_mut().method = Method::Strips;
    world.params_mut().max_iterations = LARGE_SWEEPS;
    world.step_n(SETTLE_STEPS, scene.dt).unwrap();
    world.params_mut().max_iterations = 1;
    world.params_mut().warm_start = false;
    c.bench_function("cloth/sweep/30x30/corner/strips", |b| {
        b.iter(|| black_box(world.step(black_box(scene.dt)).unwrap()));
    });
}

/// One step of the corner scene on 100 × 100 and 300 × 300 grids (Gauss–Seidel),
/// and on 30 × 30, 100 × 100 and 300 × 300 grids (Newton).
fn large_steps(c: &mut Criterion) {
    let mut group = c.benchmark_group("cloth/step");
    group.sample_size(10);
    for n in [100, 300] {
        for (id, coloured, threads) in [
            ("gauss_seidel", false, 1),
            ("coloured/1t", true, 1),
            ("coloured/2t", true, 2),
        ] {
            let (mut world, dt) = corner_world(n, coloured, LARGE_SWEEPS, LARGE_SETTLE_STEPS);
            let pool = pool(threads);
            group.bench_function(format!("{n}x{n}/corner/{id}"), |b| {
                pool.install(|| b.iter(|| black_box(world.step(black_box(dt)).unwrap())));
            });
        }
    }
    for n in [30, 100, 300] {
        let scene = scenes::corner().resized(n, n).unwrap();
        let (mut world, _) = scene.build().unwrap();
        world.params_mut().max_iterations = 50;
        world.step_n(NEWTON_SETTLE_STEPS, scene.dt).unwrap();
        group.bench_function(format!("{n}x{n}/corner/newton"), |b| {
            b.iter(|| black_box(world.step(black_box(scene.dt)).unwrap()));
        });
    }
    group.finish();
}

criterion_group!(benches, scene_steps, sweeps, strip_sweep, large_steps);
criterion_main!(benches);

//! Runs the reference scenes with each solver method and prints wall time,
//! multiple of real time, worst stretch and iterations:
//! `cargo run --release -p modelgap-cloth --example scene_timing [scene] [method]`.

use std::time::Instant;

use modelgap_cloth::{Method, StepReport, scenes};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let methods = [
        ("newton", Method::Newton),
        ("gauss-seidel", Method::GaussSeidel),
        ("strips", Method::Strips),
    ];
    println!(
        "scene        method        wall (s)  x real time  max stretch  iters/step  factors  fallbacks  converged  min y (m)"
    );
    for scene in scenes::all() {
        if args.first().is_some_and(|s| s != "all" && s != &scene.name) {
            continue;
        }
        for (label, method) in methods {
            if args.get(1).is_some_and(|m| m != "all" && m != label) {
                continue;
            }
            let (mut world, cloth) = scene.build()?;
            world.params_mut().method = method;
            let start = Instant::now();
            let mut total = StepReport {
                converged: true,
                ..StepReport::default()
            };
            let mut unconverged = 0;
            for _ in 0..scene.n_steps() {
                let r = world.step(scene.dt)?;
                if !r.converged {
                    unconverged += 1;
                }
                total = total.merge(r);
            }
            let wall = start.elapsed().as_secs_f64();
            let min_y = world
                .positions(cloth)
                .iter()
                .map(|x| x.y)
                .fold(f64::INFINITY, f64::min);
            println!(
                "{:<12} {:<12} {:>9.3} {:>12.1} {:>12.2e} {:>11.1} {:>8} {:>10} {:>10} {:>10.3}",
                scene.name,
                label,
                wall,
                scene.duration / wall,
                total.max_stretch,
                total.iterations as f64 / scene.n_steps() as f64,
                total.factorizations,
                total.fallback_sweeps,
                if unconverged == 0 {
                    "all".to_string()
                } else {
                    format!("{unconverged} not")
                },
                min_y
            );
        }
    }
    Ok(())
}

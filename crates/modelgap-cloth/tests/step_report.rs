//! Issue 12: every step reports the method that ran and, when it was not the
//! one asked for, why (`StepReport::method_used`, `StepReport::fallback`).
//!
//! The fallback for a Newton solver that cannot be built is provoked inside
//! the crate (`world.rs` and `trajectory.rs` unit tests): faer fails to build
//! it only on an index overflow or an allocation failure, which no input
//! within the crate's limits reaches. Here: normal steps of each method, and
//! the fallback that an input does provoke, a world without constraints.

use modelgap_cloth::{ClothError, ClothWorld, Fallback, GridCloth, Method, SolverParams};

/// A 5 × 5 cloth hanging from a corner.
fn world(method: Method, coloured_sweep: bool) -> Result<ClothWorld, ClothError> {
    let mut world = ClothWorld::new(SolverParams {
        method,
        coloured_sweep,
        ..SolverParams::default()
    });
    world.add_cloth(GridCloth::new(5, 5, 0.05).pin(0))?;
    Ok(world)
}

#[test]
fn each_step_reports_the_method_that_ran() {
    for (method, coloured) in [
        (Method::Newton, false),
        (Method::GaussSeidel, false),
        (Method::GaussSeidel, true),
        (Method::Strips, false),
    ] {
        let mut world = world(method, coloured).unwrap();
        for _ in 0..3 {
            let report = world.step(0.01).unwrap();
            assert_eq!(report.method_used, method, "{report:?}");
            assert_eq!(report.fallback, None, "{method:?}");
        }
    }
}

#[test]
fn a_world_without_constraints_reports_the_gauss_seidel_fallback() {
    let mut world = ClothWorld::new(SolverParams::default());
    let report = world.step(0.01).unwrap();
    assert_eq!(report.method_used, Method::GaussSeidel);
    assert_eq!(report.fallback, Some(Fallback::NoConstraints));
    assert!(report.converged && report.iterations == 0, "{report:?}");
    // Gauss–Seidel asked for: no fallback.
    world.params_mut().method = Method::GaussSeidel;
    assert_eq!(world.step(0.01).unwrap().fallback, None);
}

#[test]
fn merged_reports_keep_the_first_fallback_and_the_last_method() {
    let mut empty = ClothWorld::new(SolverParams::default());
    let fell_back = empty.step(0.01).unwrap();
    let mut cloth = world(Method::Newton, false).unwrap();
    let newton = cloth.step(0.01).unwrap();
    let merged = fell_back.merge(newton);
    assert_eq!(merged.method_used, Method::Newton);
    assert_eq!(merged.fallback, Some(Fallback::NoConstraints));
    assert_eq!(cloth.step_n(3, 0.01).unwrap().fallback, None);
}

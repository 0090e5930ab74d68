//! The DC motor of the paper: steady state, eigenvalues, printed equations.

use approx::assert_relative_eq;
use modelgap_bond::equations::Equations;
use modelgap_bond::notation::{equations_latex, equations_text};
use modelgap_bond::simulate::{Inputs, SimOptions, Solver, simulate, time_grid};
use modelgap_bond::{StateSpace, assign_causality, library};

#[test]
fn steady_state_at_12_volts_matches_closed_form() {
    let g = library::dc_motor();
    let ss = StateSpace::linearise(&g, None, None).unwrap();
    let x = ss.steady_state(&[12.0, 0.0]).unwrap();
    let y = ss.outputs_at(&x, &[12.0, 0.0]);
    // ω = kV/(Rβ + k²), i = βω/k (issue 2's reference values).
    assert_relative_eq!(y[1], 0.05 * 12.0 / (1e-5 + 0.0025), max_relative = 1e-9); // linearisation by central differences: exact up to rounding (~1e-11 here)
    assert_relative_eq!(y[1], 239.0438, max_relative = 1e-6);
    assert_relative_eq!(y[0], 0.04781, max_relative = 1e-4);
}

#[test]
fn eigenvalues_match_reference() {
    let ss = StateSpace::linearise(&library::dc_motor(), None, None).unwrap();
    let modes = ss.modes();
    assert_eq!(modes.len(), 2);
    assert_relative_eq!(modes[0].eigenvalue.re, -29.41, max_relative = 1e-3);
    assert_relative_eq!(modes[1].eigenvalue.re, -170.69, max_relative = 1e-3);
}

#[test]
fn simulated_run_reaches_steady_state_with_every_solver() {
    let g = library::dc_motor();
    for solver in [
        Solver::Exact,
        Solver::Dopri5,
        Solver::Rosenbrock,
        Solver::Auto,
    ] {
        let opts = SimOptions {
            solver,
            ..SimOptions::default()
        };
        let run = simulate(&g, &Inputs::new(), &time_grid(1.0, 1000.0), &opts).unwrap();
        let omega = *run.output("omega").unwrap().last().unwrap();
        assert_relative_eq!(omega, 239.0438, max_relative = 1e-5);
    }
}

#[test]
fn printed_equations_read_as_the_paper() {
    let g = library::dc_motor();
    let c = assign_causality(&g).unwrap();
    let eqs = Equations::derive(&g, &c).unwrap();
    let text = equations_text(&g, &eqs);
    // The paper's eq. 3-12 (dp3 is ṗ3; the paper writes eq. 5 as e8 = e5 − e6 − e7 = ṗ8).
    for line in [
        "dp3 = e1 - e2 - e4",
        "f1 = f2 = f3 = f4",
        "dp8 = e5 - e6 - e7",
        "f5 = f6 = f7 = f8",
        "e2 = R*f2",
        "f3 = p3/L",
        "f8 = p8/J",
        "e6 = beta*f6",
        "e4 = k*f5",
        "e5 = k*f4",
    ] {
        assert!(
            text.lines().any(|l| l.trim() == line),
            "missing `{line}` in\n{text}"
        );
    }
    // Eq. 13 and 14.
    assert!(
        text.contains(
            "[dp3; dp8] = [[-R/L, -k/J], [k/L, -beta/J]] [p3; p8] + [[1, 0], [0, -1]] [V; tau_L]"
        ),
        "{text}"
    );
    assert!(
        text.contains("[i; omega] = [[1/L, 0], [0, 1/J]] [p3; p8]"),
        "{text}"
    );
    let latex = equations_latex(&g, &eqs);
    assert!(
        latex.contains(r"\dot{p}_{3} &= e_{1} - e_{2} - e_{4}"),
        "{latex}"
    );
    assert!(latex.contains(r"-\frac{R}{L} & -\frac{k}{J}"), "{latex}");
    assert!(latex.contains(r"\frac{k}{L} & -\frac{\beta}{J}"), "{latex}");
}

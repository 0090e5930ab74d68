//! Causality assignment: every error class from a small bad model, naming the right bonds.

#![allow(clippy::unwrap_used)] // the graph-building helpers sit outside #[test] fns; a failed unwrap there is a failed test

use modelgap_bond::element::{Element, ElementKind};
use modelgap_bond::equations::Equations;
use modelgap_bond::expr::parse;
use modelgap_bond::file::read_model;
use modelgap_bond::graph::{BondGraph, BondId};
use modelgap_bond::{BondError, assign_causality, library};

/// Reads an inline model; the models here are structurally valid, so only
/// causality (not the reader) can object to them.
fn model(src: &str) -> BondGraph {
    read_model(src).unwrap_or_else(|e| panic!("test model does not read: {e}"))
}

fn bond(n: u32) -> BondId {
    BondId::from_number(n).unwrap()
}

// ---------------------------------------------------------------- conflicts

#[test]
fn two_effort_sources_on_one_0_junction_conflict_on_the_second_source_bond() {
    // Bond 1: V1 -> 0, bond 2: V2 -> 0, bond 3: 0 -> R.
    // V1 fixes the junction's effort through bond 1, so the 0-junction has to
    // impose its effort on V2 through bond 2, which V2 refuses.
    let g = model(
        r#"
        name = "two-se"
        elements = [
          { name = "V1", kind = "Se", effort = "V1" },
          { name = "V2", kind = "Se", effort = "V2" },
          { name = "0a", kind = "0" },
          { name = "R", kind = "R", parameter = "R" },
        ]
        bonds = [
          { from = "V1", to = "0a" },
          { from = "V2", to = "0a" },
          { from = "0a", to = "R" },
        ]
        [parameters]
        R = { value = 1.0 }
        [inputs]
        V1 = { default = 1.0 }
        V2 = { default = 2.0 }
        "#,
    );
    let err = assign_causality(&g).unwrap_err();
    let BondError::CausalConflict { bond, from, to, .. } = &err else {
        panic!("expected a causal conflict, got {err:?}");
    };
    assert_eq!((*bond, from.as_str(), to.as_str()), (2, "V2", "0a"));
    let msg = err.to_string();
    assert!(
        msg.starts_with("causal conflict on bond 2 (V2 -> 0a)"),
        "{msg}"
    );
    // Both sources are named: the one refused and the one already imposing the effort.
    assert!(msg.contains("Se 'V2'"), "{msg}");
    assert!(msg.contains("Se 'V1'"), "{msg}");
    assert!(msg.contains("bond 1"), "{msg}");
}

#[test]
fn two_flow_sources_on_one_1_junction_conflict_on_the_second_source_bond() {
    // Bond 1: I1 -> 1a, bond 2: I2 -> 1a, bond 3: 1a -> R. I1 fixes the common
    // flow; the 1-junction would have to impose it on I2 as well.
    let g = model(
        r#"
        name = "two-sf"
        elements = [
          { name = "I1", kind = "Sf", flow = "I1" },
          { name = "I2", kind = "Sf", flow = "I2" },
          { name = "1a", kind = "1" },
          { name = "R", kind = "R", parameter = "R" },
        ]
        bonds = [
          { from = "I1", to = "1a" },
          { from = "I2", to = "1a" },
          { from = "1a", to = "R" },
        ]
        [parameters]
        R = { value = 1.0 }
        [inputs]
        I1 = { default = 1.0 }
        I2 = { default = 2.0 }
        "#,
    );
    let err = assign_causality(&g).unwrap_err();
    let BondError::CausalConflict { bond, from, to, .. } = &err else {
        panic!("expected a causal conflict, got {err:?}");
    };
    assert_eq!((*bond, from.as_str(), to.as_str()), (2, "I2", "1a"));
    let msg = err.to_string();
    assert!(msg.contains("Sf 'I2'"), "{msg}");
    assert!(msg.contains("Sf 'I1'"), "{msg}");
    assert!(msg.contains("bond 1"), "{msg}");
}

#[test]
fn effort_source_bonded_to_effort_source_conflicts_on_that_bond() {
    // Se -> Se: each end wants to impose the effort of bond 1.
    let g = model(
        r#"
        name = "se-se"
        elements = [
          { name = "Va", kind = "Se", effort = "Va" },
          { name = "Vb", kind = "Se", effort = "Vb" },
        ]
        bonds = [{ from = "Va", to = "Vb" }]
        [inputs]
        Va = { default = 1.0 }
        Vb = { default = 2.0 }
        "#,
    );
    let err = assign_causality(&g).unwrap_err();
    let BondError::CausalConflict { bond, from, to, .. } = &err else {
        panic!("expected a causal conflict, got {err:?}");
    };
    assert_eq!((*bond, from.as_str(), to.as_str()), (1, "Va", "Vb"));
    let msg = err.to_string();
    assert!(msg.contains("Se 'Va'") && msg.contains("Se 'Vb'"), "{msg}");
}

#[test]
fn effort_source_driving_a_flow_source_is_causally_consistent() {
    // Se -> Sf is not a conflict: the Se imposes the effort of bond 1 and the
    // Sf its flow, which is exactly one stroke (at the Sf end). The equations
    // are e1 = V, f1 = Is with nothing left to solve.
    let g = model(
        r#"
        name = "se-sf"
        elements = [
          { name = "V", kind = "Se", effort = "V" },
          { name = "Is", kind = "Sf", flow = "Is" },
        ]
        bonds = [{ from = "V", to = "Is" }]
        [inputs]
        V = { default = 1.0 }
        Is = { default = 2.0 }
        "#,
    );
    let c = assign_causality(&g).unwrap();
    assert_eq!(c.effort_into(bond(1)), g.find("Is").unwrap());
    assert!(c.derivative.is_empty() && c.chosen_r.is_empty() && c.chosen_bonds.is_empty());
}

#[test]
fn flow_source_bonded_to_flow_source_conflicts_on_that_bond() {
    let g = model(
        r#"
        name = "sf-sf"
        elements = [
          { name = "Ia", kind = "Sf", flow = "Ia" },
          { name = "Ib", kind = "Sf", flow = "Ib" },
        ]
        bonds = [{ from = "Ia", to = "Ib" }]
        [inputs]
        Ia = { default = 1.0 }
        Ib = { default = 2.0 }
        "#,
    );
    let err = assign_causality(&g).unwrap_err();
    assert!(
        matches!(&err, BondError::CausalConflict { bond: 1, from, to, .. } if from == "Ia" && to == "Ib"),
        "{err:?}"
    );
    let msg = err.to_string();
    assert!(msg.contains("Sf 'Ia'") && msg.contains("Sf 'Ib'"), "{msg}");
}

// ------------------------------------------------------ derivative causality

/// Asserts that causality succeeds with exactly `element` (on bond `n`) in
/// derivative causality and that deriving equations refuses it, naming both.
fn assert_derivative(g: &BondGraph, element: &str, n: u32) {
    let c = assign_causality(g).unwrap();
    let id = g.find(element).unwrap();
    assert_eq!(c.derivative, vec![(id, bond(n))]);
    assert!(!c.is_integral(g, id));
    let err = Equations::derive(g, &c).unwrap_err();
    let BondError::DerivativeCausality {
        elements,
        bonds,
        hint,
    } = &err
    else {
        panic!("expected derivative causality, got {err:?}");
    };
    assert_eq!(
        (elements.as_str(), bonds.as_str()),
        (element, n.to_string().as_str())
    );
    let msg = err.to_string();
    assert!(
        msg.contains(&format!("{element} (bonds {n})")),
        "message names the element and its bond: {msg}"
    );
    // And says what to change.
    assert!(
        hint.contains("merge") && msg.contains(hint.as_str()),
        "{msg}"
    );
}

#[test]
fn flow_source_driving_an_inertia_forces_derivative_causality() {
    // Sf -> 1 -> I: the source fixes the junction's flow, so the I gets its
    // flow imposed (bond 2) instead of integrating its effort.
    let g = model(
        r#"
        name = "sf-i"
        elements = [
          { name = "Is", kind = "Sf", flow = "Is" },
          { name = "1a", kind = "1" },
          { name = "L", kind = "I", parameter = "L" },
        ]
        bonds = [{ from = "Is", to = "1a" }, { from = "1a", to = "L" }]
        [parameters]
        L = { value = 1e-3 }
        [inputs]
        Is = { default = 1.0 }
        "#,
    );
    assert_derivative(&g, "L", 2);
}

#[test]
fn two_inertias_in_series_leave_the_second_in_derivative_causality() {
    // Se -> 1 -> L1 (bond 2), 1 -> L2 (bond 3): one common flow, two momenta.
    let g = model(
        r#"
        name = "i-i"
        elements = [
          { name = "V", kind = "Se", effort = "V" },
          { name = "1a", kind = "1" },
          { name = "L1", kind = "I", parameter = "L1" },
          { name = "L2", kind = "I", parameter = "L2" },
        ]
        bonds = [
          { from = "V", to = "1a" },
          { from = "1a", to = "L1" },
          { from = "1a", to = "L2" },
        ]
        [parameters]
        L1 = { value = 1e-3 }
        L2 = { value = 2e-3 }
        [inputs]
        V = { default = 1.0 }
        "#,
    );
    assert_derivative(&g, "L2", 3);
    assert!(
        assign_causality(&g)
            .unwrap()
            .is_integral(&g, g.find("L1").unwrap())
    );
}

#[test]
fn two_capacitors_in_parallel_leave_the_second_in_derivative_causality() {
    // Sf -> 0 -> C1 (bond 2), 0 -> C2 (bond 3): one common effort, two charges.
    let g = model(
        r#"
        name = "c-c"
        elements = [
          { name = "Is", kind = "Sf", flow = "Is" },
          { name = "0a", kind = "0" },
          { name = "C1", kind = "C", parameter = "C1" },
          { name = "C2", kind = "C", parameter = "C2" },
        ]
        bonds = [
          { from = "Is", to = "0a" },
          { from = "0a", to = "C1" },
          { from = "0a", to = "C2" },
        ]
        [parameters]
        C1 = { value = 1e-6 }
        C2 = { value = 2e-6 }
        [inputs]
        Is = { default = 1.0 }
        "#,
    );
    assert_derivative(&g, "C2", 3);
}

// ------------------------------------------------------------ algebraic loop

#[test]
fn resistive_divider_is_an_algebraic_loop_through_its_resistor_bonds() {
    // V -> 1a (1); 1a -> R1 (2); 1a -> 0a (3); 0a -> R2 (4); 0a -> 1b (5);
    // 1b -> R3 (6); 1b -> L (7).
    //
    // L in integral causality fixes the flow of 1b, so R3 is forced into
    // resistance causality and bond 5 brings 1b's effort out of the 0a node.
    // Nothing fixes R1 or R2: SCAP chooses R1 (resistance causality), which
    // makes bond 3 bring 1a's flow into 0a and puts R2 in conductance
    // causality. The equations then need
    //   e3 = e1 - e2,  e2 = R1 f2,  f2 = f3,  f3 = f4 + f5,  f4 = e4 / R2,  e4 = e3:
    // a loop through bonds 2, 3, 4 only. Bond 1 (e1 = V) is known, and f1,
    // e5 and the state derivative of L (bond 7) wait on the loop without
    // being part of it.
    let g = model(
        r#"
        name = "divider"
        elements = [
          { name = "V", kind = "Se", effort = "V" },
          { name = "1a", kind = "1" },
          { name = "R1", kind = "R", parameter = "R1" },
          { name = "0a", kind = "0" },
          { name = "R2", kind = "R", parameter = "R2" },
          { name = "1b", kind = "1" },
          { name = "R3", kind = "R", parameter = "R3" },
          { name = "L", kind = "I", parameter = "L" },
        ]
        bonds = [
          { from = "V", to = "1a" },
          { from = "1a", to = "R1" },
          { from = "1a", to = "0a" },
          { from = "0a", to = "R2" },
          { from = "0a", to = "1b" },
          { from = "1b", to = "R3" },
          { from = "1b", to = "L" },
        ]
        [parameters]
        R1 = { value = 1.0 }
        R2 = { value = 2.0 }
        R3 = { value = 3.0 }
        L = { value = 1e-3 }
        [inputs]
        V = { default = 1.0 }
        "#,
    );
    let c = assign_causality(&g).unwrap();
    assert_eq!(c.chosen_r, vec![g.find("R1").unwrap()]);
    assert!(c.derivative.is_empty());
    let err = Equations::derive(&g, &c).unwrap_err();
    let BondError::AlgebraicLoop { bonds, elements } = &err else {
        panic!("expected an algebraic loop, got {err:?}");
    };
    assert_eq!(bonds, "2, 3, 4");
    assert_eq!(elements, "0a, 1a, R1, R2");
    assert!(
        err.to_string()
            .starts_with("algebraic loop through bonds 2, 3, 4 ")
    );
}

#[test]
fn forced_resistors_form_no_loop() {
    // The same divider with a capacitor on the 0a node: the C fixes the node's
    // effort, so every R is forced and the equations sort.
    let g = model(
        r#"
        name = "rc-divider"
        elements = [
          { name = "V", kind = "Se", effort = "V" },
          { name = "1a", kind = "1" },
          { name = "R1", kind = "R", parameter = "R1" },
          { name = "0a", kind = "0" },
          { name = "R2", kind = "R", parameter = "R2" },
          { name = "C", kind = "C", parameter = "C" },
        ]
        bonds = [
          { from = "V", to = "1a" },
          { from = "1a", to = "R1" },
          { from = "1a", to = "0a" },
          { from = "0a", to = "R2" },
          { from = "0a", to = "C" },
        ]
        [parameters]
        R1 = { value = 1.0 }
        R2 = { value = 2.0 }
        C = { value = 1e-3 }
        [inputs]
        V = { default = 1.0 }
        "#,
    );
    let c = assign_causality(&g).unwrap();
    assert!(c.chosen_r.is_empty() && c.derivative.is_empty());
    let eqs = Equations::derive(&g, &c).unwrap();
    assert_eq!(eqs.order.len(), eqs.equations.len());
}

// -------------------------------------------------------- structural errors

/// Asserts a `BadPorts` error on `element` whose detail contains `detail`.
fn assert_bad_ports(g: &BondGraph, element: &str, detail: &str) {
    let err = assign_causality(g).unwrap_err();
    match &err {
        BondError::BadPorts {
            element: e,
            detail: d,
            ..
        } => {
            assert_eq!(e, element);
            assert!(d.contains(detail), "{d}");
        }
        other => panic!("expected BadPorts on {element}, got {other:?}"),
    }
    assert!(
        err.to_string()
            .starts_with(&format!("element '{element}' "))
    );
}

/// V -> 1a: the start of every structural test graph.
fn source_and_junction() -> BondGraph {
    let mut g = BondGraph::new();
    g.add_param("R", 1.0, "Ohm", "").unwrap();
    g.add_param("n", 2.0, "1", "").unwrap();
    g.add_input("V", 1.0, "V", "").unwrap();
    g.add_input("m", 0.5, "1", "").unwrap();
    let v = g.add(Element::se("V", "V")).unwrap();
    let j = g.add(Element::one("1a")).unwrap();
    g.bond(v, j).unwrap();
    g
}

#[test]
fn resistor_with_two_bonds_is_bad_ports() {
    let mut g = source_and_junction();
    let j = g.find("1a").unwrap();
    let r = g.add(Element::r("R", "R")).unwrap();
    g.bond(j, r).unwrap();
    g.bond(j, r).unwrap();
    assert_bad_ports(&g, "R", "needs exactly 1 bond, has 2 (bonds 2, 3)");
}

#[test]
fn resistor_with_its_bond_pointing_out_is_bad_ports() {
    let mut g = source_and_junction();
    let j = g.find("1a").unwrap();
    let r = g.add(Element::r("R", "R")).unwrap();
    g.bond(r, j).unwrap();
    assert_bad_ports(&g, "R", "bond 2 points out");
}

#[test]
fn transformer_with_both_bonds_in_is_bad_ports() {
    // 1a -> T (2) and 1b -> T (3): no power comes out of the TF.
    let mut g = source_and_junction();
    let j = g.find("1a").unwrap();
    let t = g.add(Element::tf("T", "n")).unwrap();
    let j2 = g.add(Element::one("1b")).unwrap();
    let r = g.add(Element::r("R", "R")).unwrap();
    g.bond(j, t).unwrap();
    g.bond(j2, t).unwrap();
    g.bond(j2, r).unwrap();
    assert_bad_ports(&g, "T", "has 2 in (bonds 2, 3)");
}

#[test]
fn junction_without_bonds_is_bad_ports() {
    let mut g = source_and_junction();
    let j = g.find("1a").unwrap();
    let r = g.add(Element::r("R", "R")).unwrap();
    g.bond(j, r).unwrap();
    g.add(Element::zero("0lonely")).unwrap();
    assert_bad_ports(&g, "0lonely", "has no bonds");
}

/// V -> 1a -> X (2) -> 1b (3) -> R (4) with X the two-port under test.
fn with_two_port(x: Element) -> BondGraph {
    let mut g = source_and_junction();
    let j = g.find("1a").unwrap();
    let t = g.add(x).unwrap();
    let j2 = g.add(Element::one("1b")).unwrap();
    let r = g.add(Element::r("R", "R")).unwrap();
    g.bond(j, t).unwrap();
    g.bond(t, j2).unwrap();
    g.bond(j2, r).unwrap();
    g
}

#[test]
fn modulated_transformer_with_a_constant_modulus_is_bad_law() {
    // `n` is a parameter, not an input: nothing modulates this MTF.
    let g = with_two_port(Element::mtf("M", "n"));
    let err = assign_causality(&g).unwrap_err();
    assert!(
        matches!(&err, BondError::BadLaw { element, detail } if element == "M" && detail.contains("must follow an input")),
        "{err:?}"
    );
    // A modulus written as an expression without any input is refused the same way.
    let mut g = with_two_port(Element::mtf("M", "n"));
    let id = g.find("M").unwrap();
    g.element_mut(id).law = modelgap_bond::Law::Linear(parse("2 * n").unwrap());
    assert!(matches!(
        assign_causality(&g).unwrap_err(),
        BondError::BadLaw { element, .. } if element == "M"
    ));
}

#[test]
fn transformer_with_a_modulus_that_follows_an_input_is_bad_law() {
    let g = with_two_port(Element::tf("T", "m"));
    let err = assign_causality(&g).unwrap_err();
    assert!(
        matches!(&err, BondError::BadLaw { element, detail } if element == "T" && detail.contains("use MTF")),
        "{err:?}"
    );
    // Through an expression, and through time, too.
    for law in ["n * m", "n * (1 + 0.1 * sin(t))"] {
        let mut g = with_two_port(Element::tf("T", "n"));
        let id = g.find("T").unwrap();
        g.element_mut(id).law = modelgap_bond::Law::Linear(parse(law).unwrap());
        assert!(
            matches!(assign_causality(&g).unwrap_err(), BondError::BadLaw { element, .. } if element == "T"),
            "{law}"
        );
    }
    // The modulated forms are accepted.
    let g = with_two_port(Element::mtf("M", "m"));
    assert!(assign_causality(&g).is_ok());
    let g = with_two_port(Element::gy("G", "n"));
    assert!(assign_causality(&g).is_ok());
}

// ------------------------------------------------------------- the DC motor

#[test]
fn dc_motor_strokes_are_the_papers() {
    // Bonds 1..8: V->1e, 1e->R, 1e->L, 1e->k, k->1m, 1m->beta, 1m->tau_L, 1m->J.
    // Both inertias integrate (strokes at L and J); the junctions take their
    // flows from them, so every other bond has its stroke at the junction:
    // V and tau_L impose efforts, R and beta are in resistance causality, and
    // the GY imposes the efforts of both its bonds (e4 = k f5, e5 = k f4).
    let g = library::dc_motor();
    let c = assign_causality(&g).unwrap();
    let id = |n: &str| g.find(n).unwrap();
    let expected = [
        (1, "1e"),
        (2, "1e"),
        (3, "L"),
        (4, "1e"),
        (5, "1m"),
        (6, "1m"),
        (7, "1m"),
        (8, "J"),
    ];
    for (n, into) in expected {
        assert_eq!(
            g.element(c.effort_into(bond(n))).name,
            into,
            "stroke of bond {n}"
        );
    }
    assert!(c.is_integral(&g, id("L")) && c.is_integral(&g, id("J")));
    assert!(c.derivative.is_empty() && c.chosen_r.is_empty() && c.chosen_bonds.is_empty());
    // The GY receives the effort on neither bond.
    assert!(!c.receives_effort(bond(4), id("k")) && !c.receives_effort(bond(5), id("k")));
    assert_eq!(g.element(id("k")).kind, ElementKind::Gy);
}

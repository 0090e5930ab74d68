//! Model files: built-ins and nonlinear laws round-trip; bad files name the line, element and bond.

use modelgap_bond::element::{ElementKind, Law};
use modelgap_bond::file::{read_model, write_model};
use modelgap_bond::{BondError, BondGraph, library};

/// Reads, writes, reads again: the graphs are equal and a second write is
/// the same text as the first.
fn assert_round_trip(g: &BondGraph) {
    let text = write_model(g);
    let back = read_model(&text).unwrap_or_else(|e| panic!("{e}\n--- written text ---\n{text}"));
    assert_eq!(&back, g, "read(write(g)) differs from g");
    assert_eq!(write_model(&back), text, "write(read(write(g))) differs");
}

#[test]
fn builtin_models_round_trip() {
    for (name, _) in library::BUILTINS {
        let g = library::builtin(name).unwrap();
        assert!(!g.elements().is_empty(), "{name}");
        assert_round_trip(&g);
    }
}

#[test]
fn written_builtin_keeps_the_papers_bond_numbers() {
    let text = write_model(&library::dc_motor());
    let back = read_model(&text).unwrap();
    // Bond 4 is 1e -> k and bond 5 is k -> 1m, as in the paper's Fig. 3.
    let b4 = back.bonds()[3];
    let b5 = back.bonds()[4];
    assert_eq!(back.element(b4.from).name, "1e");
    assert_eq!(back.element(b4.to).name, "k");
    assert_eq!(back.element(b5.from).name, "k");
    assert_eq!(back.element(b5.to).name, "1m");
    assert!(text.contains("number = 8\n"), "{text}");
}

const NONLINEAR: &str = r#"name = "nonlinear"
description = "a coil with a saturating flux-current curve driving a mass with Coulomb friction"

[parameters]
tau_c = { value = 0.02, unit = "N m", description = "Coulomb friction torque" }
b = { value = 1e-4, unit = "N m s/rad" }
L0 = { value = 0.1, unit = "H", description = "unsaturated inductance" }
psi_s = { value = 0.05, unit = "Wb" }
R = { value = 10.0, unit = "Ohm" }
k = { value = 0.05, unit = "N m/A" }
J = { value = 1e-4, unit = "kg m^2" }

[inputs]
V = { default = 10.0, unit = "V" }

[[elements]]
name = "V"
kind = "Se"
effort = "V"

[[elements]]
name = "1e"
kind = "1"

[[elements]]
name = "R"
kind = "R"
parameter = "R"

[[elements]]
name = "L"
kind = "I"
flow = "p / L0 * (1 + (p / psi_s)^2)"
description = "saturating coil"

[[elements]]
name = "k"
kind = "GY"
modulus = "k"

[[elements]]
name = "1m"
kind = "1"

[[elements]]
name = "friction"
kind = "R"
effort = "tau_c * tanh(f / 0.01) + b * f"

[[elements]]
name = "J"
kind = "I"
parameter = "J"

[[bonds]]
from = "V"
to = "1e"
[[bonds]]
from = "1e"
to = "R"
[[bonds]]
from = "1e"
to = "L"
[[bonds]]
from = "1e"
to = "k"
[[bonds]]
from = "k"
to = "1m"
[[bonds]]
from = "1m"
to = "friction"
[[bonds]]
from = "1m"
to = "J"

[[outputs]]
name = "i"
flow = "1e"
unit = "A"

[[outputs]]
name = "psi"
state = "L"
unit = "Wb"
"#;

#[test]
fn nonlinear_laws_round_trip() {
    let g = read_model(NONLINEAR).unwrap();
    let friction = g.element(g.find("friction").unwrap());
    assert!(matches!(
        &friction.law,
        Law::Nonlinear {
            effort: Some(_),
            flow: None
        }
    ));
    let coil = g.element(g.find("L").unwrap());
    assert_eq!(coil.kind, ElementKind::I);
    assert!(matches!(
        &coil.law,
        Law::Nonlinear {
            effort: None,
            flow: Some(_)
        }
    ));
    assert_round_trip(&g);
    // The written laws are the same laws, in the printer's spelling.
    let text = write_model(&g);
    assert!(
        text.contains(r#"effort = "tau_c*tanh(f/0.01) + b*f""#),
        "{text}"
    );
    assert!(
        text.contains(r#"flow = "p/L0*(1 + (p/psi_s)^2)""#),
        "{text}"
    );
}

// ---------------------------------------------------------------- bad files

/// The 1-based line of the first line of `src` containing `needle`, and the
/// 1-based column where `needle` starts in it.
fn position_of(src: &str, needle: &str) -> (usize, usize) {
    for (i, line) in src.lines().enumerate() {
        if let Some(c) = line.find(needle) {
            return (i + 1, line[..c].chars().count() + 1);
        }
    }
    panic!("'{needle}' is not in the test text");
}

/// Reads `src`, which must fail with a located file error; returns line,
/// column and the full message.
fn file_error(src: &str) -> (usize, usize, String) {
    match read_model(src) {
        Err(e @ BondError::File { line, column, .. }) => (line, column, e.to_string()),
        Err(other) => panic!("expected a located file error, got {other:?}"),
        Ok(_) => panic!("the bad file was accepted"),
    }
}

/// An RC circuit with room for one mistake: `{param}` in `[parameters]`,
/// `{element}` lines in the R element, `{bond}` as the `to` of bond 2,
/// `{output}` lines in the output.
fn rc(param: &str, element: &str, bond: &str, output: &str) -> String {
    format!(
        r#"name = "rc"

[parameters]
R = {{ value = 1000.0, unit = "Ohm" }}
C = {{ value = 1e-6, unit = "F" }}
{param}
[inputs]
V = {{ default = 5.0, unit = "V" }}

[[elements]]
name = "V"
kind = "Se"
effort = "V"

[[elements]]
name = "1a"
kind = "1"

[[elements]]
name = "R"
{element}

[[elements]]
name = "C"
kind = "C"
parameter = "C"

[[bonds]]
from = "V"
to = "1a"
[[bonds]]
from = "1a"
to = "{bond}"
[[bonds]]
from = "1a"
to = "C"

[[outputs]]
name = "out"
{output}
unit = "A"
"#
    )
}

const R_OK: &str = "kind = \"R\"\nparameter = \"R\"";

#[test]
fn the_bad_file_template_is_good_as_given() {
    let g = read_model(&rc("", R_OK, "R", "flow = \"1a\"")).unwrap();
    assert_eq!(g.bonds().len(), 3);
}

#[test]
fn toml_syntax_error_names_line_and_column() {
    let src = rc("", "kind = \"R\"\nparameter = R", "R", "flow = \"1a\"");
    let (line, column, msg) = file_error(&src);
    // The bare `R` is not a TOML value; it starts after `parameter = `.
    let (l, c) = position_of(&src, "parameter = R");
    assert_eq!((line, column), (l, c + "parameter = ".len()));
    assert!(
        msg.ends_with(&format!("at line {line}, column {column}")),
        "{msg}"
    );
}

#[test]
fn unknown_field_names_the_field_and_its_line() {
    let src = rc("", "kind = \"R\"\nparamter = \"R\"", "R", "flow = \"1a\"");
    let (line, column, msg) = file_error(&src);
    assert_eq!((line, column), position_of(&src, "paramter"));
    assert!(msg.contains("unknown field `paramter`"), "{msg}");
}

#[test]
fn unknown_kind_names_the_element_and_line() {
    let src = rc("", "kind = \"Q\"\nparameter = \"R\"", "R", "flow = \"1a\"");
    let (line, column, msg) = file_error(&src);
    // The span is the quoted value: column of the opening quote.
    assert_eq!((line, column), position_of(&src, "\"Q\""));
    assert!(msg.contains("element 'R': unknown kind 'Q'"), "{msg}");
    assert!(
        msg.contains("Se, Sf, R, C, I, TF, GY, MTF, MGY, 0, 1"),
        "{msg}"
    );
}

#[test]
fn bond_to_an_unknown_element_names_the_bond_and_line() {
    let src = rc("", R_OK, "Rx", "flow = \"1a\"");
    let (line, column, msg) = file_error(&src);
    assert_eq!((line, column), position_of(&src, "\"Rx\""));
    assert!(msg.starts_with("bond 2: unknown element 'Rx'"), "{msg}");
    assert!(
        msg.ends_with(&format!("at line {line}, column {column}")),
        "{msg}"
    );
}

#[test]
fn law_that_does_not_parse_names_element_field_and_column() {
    let src = rc(
        "",
        "kind = \"R\"\neffort = \"R * (f\"",
        "R",
        "flow = \"1a\"",
    );
    let (line, column, msg) = file_error(&src);
    // The law is missing its ')': the parser stops one past its last character,
    // law column 7, which is 7 columns right of the opening quote.
    let (l, quote) = position_of(&src, "\"R * (f\"");
    assert_eq!((line, column), (l, quote + 7));
    assert!(
        msg.contains("element 'R': cannot parse effort law 'R * (f'"),
        "{msg}"
    );
    assert!(msg.contains("expected ')'"), "{msg}");
}

#[test]
fn non_finite_parameter_names_the_parameter_and_line() {
    for (text, shown) in [("inf", "inf"), ("nan", "NaN"), ("-inf", "-inf")] {
        let param = format!("Rbad = {{ value = {text} }}");
        let src = rc(&param, R_OK, "R", "flow = \"1a\"");
        let (line, column, msg) = file_error(&src);
        // Located at the parameter's table, which opens after `Rbad = `.
        let (l, c) = position_of(&src, "Rbad = {");
        assert_eq!((line, column), (l, c + "Rbad = ".len()), "{msg}");
        assert!(
            msg.contains(&format!(
                "parameter 'Rbad' must be finite and at most 1e100 in magnitude, found {shown}"
            )),
            "{msg}"
        );
    }
}

#[test]
fn unknown_name_in_a_law_names_element_and_name() {
    let src = rc("", "kind = \"R\"\nparameter = \"Rx\"", "R", "flow = \"1a\"");
    let (line, column, msg) = file_error(&src);
    // Located at the element's name (the quoted value after `name = `).
    let (l, c) = position_of(&src, "name = \"R\"");
    assert_eq!((line, column), (l, c + "name = ".len()));
    assert!(msg.contains("element 'R': unknown name 'Rx'"), "{msg}");
}

#[test]
fn output_reading_a_1_junction_effort_names_the_output() {
    let src = rc("", R_OK, "R", "effort = \"1a\"");
    let (line, column, msg) = file_error(&src);
    // A 1-junction has one flow but as many efforts as bonds.
    assert!(
        msg.starts_with("output 'out': element '1a' (1) has no single effort"),
        "{msg}"
    );
    // Located at the output's `[[outputs]]` header.
    assert_eq!((line, column), position_of(&src, "[[outputs]]"));
}

//! Errors of the bond-graph crate.

use std::path::PathBuf;

/// Everything that can go wrong while building, reading, deriving, simulating
/// or diagnosing a bond graph. Each variant names the element, bond, line or
/// signal a user has to look at.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BondError {
    /// An element name is used twice.
    #[error("element '{name}' is defined twice")]
    DuplicateElement {
        /// The repeated name.
        name: String,
    },
    /// A name refers to no element.
    #[error("unknown element '{name}'{context}")]
    UnknownElement {
        /// The name that was not found.
        name: String,
        /// Where it was used, e.g. " in bond 3".
        context: String,
    },
    /// A law refers to a name that is neither a parameter nor an input.
    #[error("element '{element}': unknown name '{name}' in its law (not a parameter or input)")]
    UnknownName {
        /// The element whose law mentions the name.
        element: String,
        /// The unknown name.
        name: String,
    },
    /// A parameter or input name is unknown.
    #[error("unknown parameter '{name}' (known: {known})")]
    UnknownParameter {
        /// The unknown name.
        name: String,
        /// The known names, comma-separated.
        known: String,
    },
    /// A parameter value is not finite.
    #[error("parameter '{name}' must be finite, found {value}")]
    BadParameter {
        /// The parameter.
        name: String,
        /// The value given.
        value: f64,
    },
    /// A name is both a parameter and an input, or otherwise clashes.
    #[error("name '{name}' is used twice: {detail}")]
    NameClash {
        /// The name.
        name: String,
        /// What it is used as.
        detail: String,
    },
    /// An element has the wrong number or direction of bonds.
    #[error("element '{element}' ({kind}) {detail}")]
    BadPorts {
        /// The element.
        element: String,
        /// Its kind, as in bond-graph notation.
        kind: String,
        /// What is wrong, e.g. "needs exactly 1 bond, has 2 (bonds 3, 4)".
        detail: String,
    },
    /// An element's law is missing, malformed or unusable.
    #[error("element '{element}': {detail}")]
    BadLaw {
        /// The element.
        element: String,
        /// What is wrong.
        detail: String,
    },
    /// A law expression does not parse.
    #[error(
        "element '{element}': cannot parse {field} law '{source_text}': {message} (column {column})"
    )]
    LawSyntax {
        /// The element.
        element: String,
        /// The field (`effort`, `flow`, `parameter`).
        field: String,
        /// The text of the law.
        source_text: String,
        /// What the parser expected and found.
        message: String,
        /// 1-based column in the law text.
        column: usize,
    },
    /// Two causal demands meet on one bond.
    #[error("causal conflict on bond {bond} ({from} -> {to}): {detail}")]
    CausalConflict {
        /// The bond number.
        bond: u32,
        /// The element the bond starts at.
        from: String,
        /// The element the bond ends at.
        to: String,
        /// Which elements impose what.
        detail: String,
    },
    /// Storage elements were forced into derivative causality; the derived
    /// equations would need differentiated inputs.
    #[error(
        "storage elements forced into derivative causality: {elements} (bonds {bonds}); simulation needs integral causality"
    )]
    DerivativeCausality {
        /// The storage elements, comma-separated.
        elements: String,
        /// Their bonds, comma-separated.
        bonds: String,
    },
    /// The causal equations contain an algebraic loop.
    #[error(
        "algebraic loop through bonds {bonds} (elements {elements}); the equations cannot be ordered explicitly"
    )]
    AlgebraicLoop {
        /// The bonds of the loop, comma-separated.
        bonds: String,
        /// The elements on the loop, comma-separated.
        elements: String,
    },
    /// A nonlinear law is given for the wrong causality and cannot be inverted.
    #[error(
        "element '{element}': causality needs its {needed} law, but only the {given} law is given; add `{needed} = \"...\"` to the element"
    )]
    NonInvertibleLaw {
        /// The element.
        element: String,
        /// The law the assigned causality needs (`effort` or `flow`).
        needed: String,
        /// The law that is given.
        given: String,
    },
    /// An output refers to something that has no such variable.
    #[error("output '{output}': {detail}")]
    BadOutput {
        /// The output name.
        output: String,
        /// What is wrong.
        detail: String,
    },
    /// An input signal is unknown or malformed.
    #[error("input '{input}': {detail}")]
    BadInput {
        /// The input name.
        input: String,
        /// What is wrong.
        detail: String,
    },
    /// A candidate effect cannot be applied: it is unknown to this model, or
    /// a parameter value is missing, not finite or outside its bounds.
    #[error("effect '{candidate}': {detail}")]
    BadEffect {
        /// The candidate's id (`coulomb@1m`).
        candidate: String,
        /// The parameter concerned; empty when it is the candidate as a whole.
        param: String,
        /// What is wrong, naming the parameter.
        detail: String,
    },
    /// A model file could not be read.
    #[error("{message} at line {line}, column {column}{}", path_suffix(path))]
    File {
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong.
        message: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },
    /// A built-in model name is unknown.
    #[error("unknown built-in model '{name}' (built-ins: {known})")]
    UnknownModel {
        /// The name asked for.
        name: String,
        /// The known built-ins.
        known: String,
    },
    /// Simulation options are invalid.
    #[error("bad simulation options: {0}")]
    BadOptions(String),
    /// The ODE solver failed.
    #[error("simulation failed: {0}")]
    Ode(#[from] crate::ode::OdeError),
    /// A recording could not be used.
    #[error(transparent)]
    Core(#[from] modelgap_core::CoreError),
    /// An I/O error.
    #[error("{message}: {source}")]
    Io {
        /// What was being done, with the path.
        message: String,
        /// The underlying error.
        source: std::io::Error,
    },
}

fn path_suffix(path: &Option<PathBuf>) -> String {
    match path {
        Some(p) => format!(" in {}", p.display()),
        None => String::new(),
    }
}

/// Result with [`BondError`] as the default error.
pub type Result<T, E = BondError> = std::result::Result<T, E>;

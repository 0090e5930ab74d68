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
    /// A parameter value (or an input's default) is not finite, or beyond
    /// [`MAX_MAGNITUDE`](modelgap_core::recording::MAX_MAGNITUDE), the limit
    /// recordings have too: a model value past it overflows the first product.
    #[error(
        "parameter '{name}' must be finite and at most {} in magnitude, found {}",
        num(modelgap_core::recording::MAX_MAGNITUDE),
        num(*value)
    )]
    BadParameter {
        /// The parameter.
        name: String,
        /// The value given.
        value: f64,
    },
    /// A prior that cannot be: on a parameter that is not free, or with a
    /// standard deviation that is not positive and finite.
    #[error("parameter '{name}': bad prior: {detail}")]
    BadPrior {
        /// The parameter.
        name: String,
        /// What is wrong.
        detail: String,
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
        "storage elements forced into derivative causality: {elements} (bonds {bonds}); simulation needs integral causality: {hint}"
    )]
    DerivativeCausality {
        /// The storage elements, comma-separated.
        elements: String,
        /// Their bonds, comma-separated.
        bonds: String,
        /// What to change in the model, by the kinds of storage.
        hint: String,
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
    /// The bounds of a free parameter or initial state are not finite and
    /// ordered, or leave out its value.
    #[error("'{name}': {detail}")]
    BadRange {
        /// The parameter (`k1`) or initial state (`Tank1(0)`).
        name: String,
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
    /// The coefficient of a linear R, C or I element has a value the element
    /// cannot physically have: an inductance, inertia, mass or capacitance
    /// that is not positive, a resistance that is negative.
    #[error(
        "{} of element {element} ({kind}: {quantity}) must be {expected}, found {}",
        coefficient(param, *expression),
        num(*value)
    )]
    UnphysicalParameter {
        /// The parameter (`L`), or the coefficient's law text when it is an
        /// expression of parameters (`(J) + dJ`).
        param: String,
        /// True when `param` is a law text rather than a parameter's name.
        expression: bool,
        /// The element.
        element: String,
        /// Its kind (R, C or I).
        kind: crate::element::ElementKind,
        /// What the coefficient is, with its unit when known (`inductance, H`).
        quantity: String,
        /// What it must be (`positive`, `zero or positive`).
        expected: &'static str,
        /// The value found.
        value: f64,
    },
    /// A law evaluates to NaN or an infinity where the model starts (or, for
    /// a constant coefficient, anywhere).
    #[error("the {field} law of element {element}, `{law}`, is {} {point}", num(*value))]
    LawNotFinite {
        /// The element.
        element: String,
        /// Which law (`effort`, `flow`, `parameter`, `modulus`, `value`).
        field: String,
        /// The law as written (`f/0`).
        law: String,
        /// What it evaluates to (NaN or ±inf).
        value: f64,
        /// Where: `at the start (t = 0 s, f = 0)`, or `whatever the state` for a constant.
        point: String,
    },
    /// A state or its derivative stopped being finite during a simulation.
    #[error("state {state} ({what}) or its derivative is not finite at t = {} s", num(*t))]
    NonFiniteState {
        /// The state's name (`p3`).
        state: String,
        /// What it is (`the momentum of I:L`).
        what: String,
        /// The time of the last finite state (s).
        t: f64,
    },
    /// An output is not finite although the states are.
    #[error("output {output} is not finite at t = {} s", num(*t))]
    NonFiniteOutput {
        /// The output's name.
        output: String,
        /// The time (s).
        t: f64,
    },
    /// A run would need more of something than a limit allows; checked
    /// before any work, so that a typo (a PWM at 1 THz) cannot exhaust memory.
    #[error("{what} would be {}, more than the limit of {limit} ({option})", num(*count))]
    TooLarge {
        /// What is counted, with where it comes from
        /// (`switching edges of the PWM on input m, 1e12 Hz over 1 s`).
        what: String,
        /// How many there would be.
        count: f64,
        /// The limit.
        limit: usize,
        /// The option that sets the limit (`max_events`, `max_samples`).
        option: &'static str,
    },
    /// Simulation options are invalid.
    #[error("bad simulation options: {0}")]
    BadOptions(String),
    /// No steady state was found to start from (Newton's method did not converge, or the
    /// Jacobian is singular: no unique one).
    #[error("no steady state to start from: {reason}")]
    NoSteadyState {
        /// Why not.
        reason: String,
    },
    /// The ODE solver failed. The solver's error is part of the message and
    /// not a separate cause, so that it is printed once.
    #[error("simulation failed: {0}")]
    Ode(crate::ode::OdeError),
    /// A recording could not be used.
    #[error(transparent)]
    Core(#[from] modelgap_core::CoreError),
    /// An I/O error. The operating system's error is part of the message and
    /// not a separate cause, so that it is printed once.
    #[error("{message}: {error}")]
    Io {
        /// What was being done, with the path.
        message: String,
        /// The underlying error.
        error: std::io::Error,
    },
}

impl From<crate::ode::OdeError> for BondError {
    fn from(e: crate::ode::OdeError) -> BondError {
        BondError::Ode(e)
    }
}

impl From<modelgap_core::effect::BadValues> for BondError {
    /// Values a candidate cannot take: [`BondError::BadEffect`] with the
    /// same candidate, parameter and detail.
    fn from(e: modelgap_core::effect::BadValues) -> BondError {
        BondError::BadEffect {
            candidate: e.candidate,
            param: e.param,
            detail: e.detail,
        }
    }
}

/// `parameter L`, or ``the coefficient `(J) + dJ` `` for an expression.
fn coefficient(param: &str, expression: bool) -> String {
    if expression {
        format!("the coefficient `{param}`")
    } else {
        format!("parameter {param}")
    }
}

/// A number as a person writes it: `0`, `-1`, `0.005`, `1e12`, `1e300` (not 301 digits).
pub(crate) fn num(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() || (1e-4..1e6).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

fn path_suffix(path: &Option<PathBuf>) -> String {
    match path {
        Some(p) => format!(" in {}", p.display()),
        None => String::new(),
    }
}

/// Result with [`BondError`] as the default error.
pub type Result<T, E = BondError> = std::result::Result<T, E>;

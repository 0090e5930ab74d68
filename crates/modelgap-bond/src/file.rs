//! Model files: a bond graph as TOML that a person can write and read.
//!
//! ```toml
//! name = "rc"
//! description = "an RC circuit"
//!
//! [parameters]
//! R = { value = 1000.0, unit = "Ohm", description = "resistor" }
//! C = { value = 1e-6, unit = "F", free = true, min = 1e-7, max = 1e-5 }  # unknown: `fit` calibrates it
//!
//! [inputs]
//! V = { default = 5.0, unit = "V" }
//!
//! [[elements]]
//! name = "V"
//! kind = "Se"
//! effort = "V"            # an input, a parameter or an expression of them and t
//!
//! [[elements]]
//! name = "1"
//! kind = "1"
//! domain = "electrical"   # optional, junctions only: what the menu attaches here
//!
//! [[elements]]
//! name = "R"
//! kind = "R"
//! parameter = "R"         # linear: e = R f; or `effort = "..."` in f / `flow = "..."` in e
//!
//! [[elements]]
//! name = "C"
//! kind = "C"
//! parameter = "C"         # linear: e = q / C; or `effort = "..."` in q
//!
//! [[bonds]]               # numbered 1, 2, ... in this order; power from -> to
//! from = "V"
//! to = "1"
//! [[bonds]]
//! from = "1"
//! to = "R"
//! [[bonds]]
//! from = "1"
//! to = "C"
//!
//! [initial]               # states at t = 0 (absent: 0); a table with `free = true` is unknown
//! C = { value = 0.0, free = true, min = -1e-5, max = 1e-5 }
//!
//! [[outputs]]
//! name = "i"
//! flow = "1"              # or effort = "<element>", state = "<storage element>",
//! unit = "A"              # or value = "<expression of signals>" (`2 * C.q + 0.1`)
//! ```
//!
//! `[[changes]]` are changes at given times, part of every run: `at` (s),
//! `parameter` or `input`, `value`, `description` — a load that steps, a
//! fault `fix` found. An input the recording holds follows the recording.
//!
//! `[[candidates]]` declares effects for explain to try: a one-port with
//! its law (as in `[[elements]]`), the junction `at` it is bonded from and
//! `[candidates.parameters]` with `value`, `min`, `max` (see
//! [`crate::effects::Declared`]).
//!
//! A parameter marked `free = true` takes bounds `min`/`max`; without them it
//! may range from 0 to 1000 times its value, its sign kept (a free value of 0
//! must give both). A free parameter may also carry what is known of it
//! before the data, `prior = { mean = 1.2e-3, std = 1e-4 }` (a datasheet's
//! tolerance): calibration weighs it against the recording.
//!
//! Kinds: `Se Sf MSe MSf R C I TF GY MTF MGY 0 1`. Laws may read another
//! element's variable as a signal, `Element.x` with `x` one of `e`, `f`,
//! `p`, `q` (`k2 * sqrt(Tank1.q)`): a modulated source (`MSe`, `MSf`) is a
//! source whose value reads signals, and an output may be an expression of
//! signals (`value = "gain * Tank2.q + offset"`). For TF/GY/MTF/MGY, `parameter`
//! (also spelt `modulus`) is the modulus; an MTF's modulus names an input.
//! Every error names the line and column, and the element or bond.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use serde::Deserialize;
use toml::Spanned;

use crate::element::{
    DeclaredCandidate, Element, ElementKind, InitialState, Law, Measured, Output, Parameter,
    PhysicalDomain, Range, Scheduled, ScheduledChange,
};
use crate::error::{BondError, Result};
use crate::expr::{Expr, parse};
use crate::graph::BondGraph;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelFile {
    name: String,
    #[serde(default)]
    description: String,
    #[serde(default)]
    parameters: BTreeMap<String, Spanned<ParamEntry>>,
    #[serde(default)]
    inputs: BTreeMap<String, Spanned<InputEntry>>,
    #[serde(default)]
    elements: Vec<Spanned<ElementEntry>>,
    #[serde(default)]
    bonds: Vec<Spanned<BondEntry>>,
    #[serde(default)]
    outputs: Vec<Spanned<OutputEntry>>,
    #[serde(default)]
    initial: BTreeMap<String, Spanned<InitialEntry>>,
    #[serde(default)]
    candidates: Vec<Spanned<CandidateEntry>>,
    #[serde(default)]
    changes: Vec<Spanned<ChangeEntry>>,
}

/// A change at a given time: a parameter or an input takes a new value.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ChangeEntry {
    at: Spanned<f64>,
    parameter: Option<Spanned<String>>,
    input: Option<Spanned<String>>,
    value: Spanned<f64>,
    #[serde(default)]
    description: String,
}

/// A declared candidate: an element (its law as in `[[elements]]`), the
/// junction it is bonded from, and its parameters with bounds.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CandidateEntry {
    name: Spanned<String>,
    kind: Spanned<String>,
    at: Spanned<String>,
    parameter: Option<Spanned<String>>,
    effort: Option<Spanned<String>>,
    flow: Option<Spanned<String>>,
    #[serde(default)]
    description: String,
    #[serde(default)]
    parameters: BTreeMap<String, Spanned<CandidateParam>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CandidateParam {
    value: f64,
    #[serde(default)]
    unit: String,
    #[serde(default)]
    description: String,
    min: f64,
    max: f64,
}

/// An initial state: a number, or a table with bounds when it is unknown.
#[derive(Deserialize)]
#[serde(untagged)]
enum InitialEntry {
    Value(f64),
    Table(InitialTable),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct InitialTable {
    value: f64,
    #[serde(default)]
    free: bool,
    min: Option<f64>,
    max: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ParamEntry {
    value: f64,
    #[serde(default)]
    unit: String,
    #[serde(default)]
    description: String,
    #[serde(default)]
    free: bool,
    min: Option<f64>,
    max: Option<f64>,
    prior: Option<PriorEntry>,
}

/// `prior = { mean = 1.2, std = 0.1 }`: a Gaussian prior on a free parameter.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PriorEntry {
    mean: f64,
    std: f64,
}

/// The bounds of a value marked `free`, or an error saying what to write.
fn free_range(
    name: &str,
    value: f64,
    free: bool,
    min: Option<f64>,
    max: Option<f64>,
) -> std::result::Result<Option<Range>, String> {
    if !free {
        if min.is_some() || max.is_some() {
            return Err(format!(
                "'{name}': `min`/`max` bound a free value; add `free = true`"
            ));
        }
        return Ok(None);
    }
    Range::around(value, min, max).map(Some).ok_or_else(|| {
        format!(
            "'{name}' is free with value 0: give both `min` and `max` (a zero has no sign or size to bound it by)"
        )
    })
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct InputEntry {
    default: f64,
    #[serde(default)]
    unit: String,
    #[serde(default)]
    description: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ElementEntry {
    name: Spanned<String>,
    kind: Spanned<String>,
    parameter: Option<Spanned<String>>,
    modulus: Option<Spanned<String>>,
    effort: Option<Spanned<String>>,
    flow: Option<Spanned<String>>,
    #[serde(default)]
    description: String,
    domain: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BondEntry {
    from: Spanned<String>,
    to: Spanned<String>,
    number: Option<Spanned<u32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OutputEntry {
    name: String,
    flow: Option<String>,
    effort: Option<String>,
    state: Option<String>,
    value: Option<Spanned<String>>,
    #[serde(default)]
    unit: String,
}

/// Line and column (1-based) of a byte offset in `src`.
fn line_col(src: &str, offset: usize) -> (usize, usize) {
    let before = &src[..offset.min(src.len())];
    let line = before.matches('\n').count() + 1;
    let col = before
        .rfind('\n')
        .map_or(before.chars().count(), |i| before[i + 1..].chars().count())
        + 1;
    (line, col)
}

struct Ctx<'a> {
    src: &'a str,
}

impl Ctx<'_> {
    fn err(&self, span: std::ops::Range<usize>, message: String) -> BondError {
        let (line, column) = line_col(self.src, span.start);
        BondError::File {
            line,
            column,
            message,
            path: None,
        }
    }

    fn law(&self, element: &str, field: &str, text: &Spanned<String>) -> Result<Expr> {
        parse(text.get_ref()).map_err(|e| {
            // The span covers the quoted string: the law starts one column after it.
            let (line, column) = line_col(self.src, text.span().start);
            BondError::File {
                line,
                column: column + e.column,
                message: format!(
                    "element '{element}': cannot parse {field} law '{}': {}",
                    text.get_ref(),
                    e.message
                ),
                path: None,
            }
        })
    }
}

impl Ctx<'_> {
    /// The element an `[[elements]]` entry (or a declared candidate's
    /// element) describes: its kind, its law checked against the kind, its
    /// declared domain.
    fn element(&self, e: &ElementEntry, span: std::ops::Range<usize>) -> Result<Element> {
        let ctx = self;
        let name = e.name.get_ref().clone();
        // 20-sim's modulated sources: a source whose value reads signals.
        let modulated = matches!(e.kind.get_ref().as_str(), "MSe" | "MSf");
        let symbol = e.kind.get_ref().trim_start_matches('M');
        let symbol = if modulated { symbol } else { e.kind.get_ref() };
        let kind = ElementKind::from_symbol(symbol).ok_or_else(|| {
            ctx.err(
                e.kind.span(),
                format!(
                    "element '{name}': unknown kind '{}' (expected one of {})",
                    e.kind.get_ref(),
                    (ElementKind::ALL.iter().map(|k| k.symbol()))
                        .chain(["MSe", "MSf"])
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
        })?;
        let parameter = match (&e.parameter, &e.modulus) {
            (Some(_), Some(m)) => {
                return Err(ctx.err(
                    m.span(),
                    format!("element '{name}': give `parameter` or `modulus`, not both"),
                ));
            }
            (Some(p), None) | (None, Some(p)) => Some(p),
            (None, None) => None,
        };
        let law = if kind.is_junction() {
            if let Some(x) = parameter.or(e.effort.as_ref()).or(e.flow.as_ref()) {
                return Err(ctx.err(
                    x.span(),
                    format!("element '{name}': a junction takes no law"),
                ));
            }
            Law::None
        } else if kind.is_source() {
            let (want, got, other) = match kind {
                ElementKind::Se => ("effort", &e.effort, &e.flow),
                _ => ("flow", &e.flow, &e.effort),
            };
            if let Some(x) = parameter.or(other.as_ref()) {
                return Err(ctx.err(
                    x.span(),
                    format!("element '{name}': a {kind} source takes only `{want}`"),
                ));
            }
            let text = got.as_ref().ok_or_else(|| {
                ctx.err(
                    span.clone(),
                    format!("element '{name}': a {kind} source needs `{want} = \"...\"`"),
                )
            })?;
            Law::Source(ctx.law(&name, want, text)?)
        } else if let Some(p) = parameter {
            if let Some(x) = e.effort.as_ref().or(e.flow.as_ref()) {
                return Err(ctx.err(
                x.span(),
                format!("element '{name}': give a linear `parameter` or nonlinear `effort`/`flow` laws, not both"),
            ));
            }
            Law::Linear(ctx.law(&name, "parameter", p)?)
        } else if kind.is_two_port() {
            return Err(ctx.err(
                span.clone(),
                format!("element '{name}': a {kind} needs `modulus = \"...\"`"),
            ));
        } else {
            let effort = e
                .effort
                .as_ref()
                .map(|t| ctx.law(&name, "effort", t))
                .transpose()?;
            let flow = e
                .flow
                .as_ref()
                .map(|t| ctx.law(&name, "flow", t))
                .transpose()?;
            if effort.is_none() && flow.is_none() {
                return Err(ctx.err(
                span.clone(),
                format!("element '{name}': a {kind} needs `parameter = \"...\"` or a nonlinear `effort`/`flow` law"),
            ));
            }
            Law::Nonlinear { effort, flow }
        };
        let domain = match &e.domain {
            None => None,
            Some(d) if !kind.is_junction() => {
                return Err(ctx.err(
                    d.span(),
                    format!("element '{name}': only a junction (0 or 1) declares a `domain`"),
                ));
            }
            Some(d) => Some(PhysicalDomain::from_name(d.get_ref()).ok_or_else(|| {
                ctx.err(
                    d.span(),
                    format!(
                        "element '{name}': unknown domain '{}' (expected one of {})",
                        d.get_ref(),
                        PhysicalDomain::ALL.map(PhysicalDomain::name).join(", ")
                    ),
                )
            })?),
        };
        let element = Element {
            name: name.clone(),
            kind,
            law,
            description: e.description.clone(),
            domain,
        };
        Ok(element)
    }
}

/// Reads a model from TOML text.
///
/// # Errors
/// [`BondError::File`] with the line and column of the problem: TOML
/// syntax, unknown fields, unknown element kinds, laws that do not parse,
/// bonds to unknown elements, wrong bond counts, unknown names in laws,
/// coefficients an element cannot physically have (a zero inductance, a
/// negative resistance: the line of the parameter's value) or that are not
/// finite (`1/0`).
pub fn read_model(src: &str) -> Result<BondGraph> {
    let file: ModelFile = toml::from_str(src).map_err(|e| {
        let (line, column) = e.span().map_or((1, 1), |s| line_col(src, s.start));
        BondError::File {
            line,
            column,
            message: e.message().trim().to_string(),
            path: None,
        }
    })?;
    let ctx = Ctx { src };
    let mut g = BondGraph::new();
    g.name = file.name;
    g.description = file.description;
    for (name, p) in &file.parameters {
        let span = p.span();
        let p = p.get_ref();
        g.add_param(name, p.value, &p.unit, &p.description)
            .map_err(|e| ctx.err(span.clone(), e.to_string()))?;
        let range = free_range(name, p.value, p.free, p.min, p.max)
            .map_err(|m| ctx.err(span.clone(), format!("parameter {m}")))?;
        g.set_free(name, range)
            .map_err(|e| ctx.err(span.clone(), format!("parameter {e}")))?;
        if let Some(pr) = &p.prior {
            let prior = modelgap_core::Prior::new(pr.mean, pr.std).ok_or_else(|| {
                ctx.err(
                    span.clone(),
                    format!(
                        "parameter '{name}': bad prior: `std` must be positive and finite and `mean` finite (found mean = {}, std = {})",
                        pr.mean, pr.std
                    ),
                )
            })?;
            g.set_prior(name, Some(prior))
                .map_err(|e| ctx.err(span, e.to_string()))?;
        }
    }
    for (name, i) in &file.inputs {
        let span = i.span();
        let i = i.get_ref();
        g.add_input(name, i.default, &i.unit, &i.description)
            .map_err(|e| ctx.err(span, e.to_string()))?;
    }
    let mut element_spans = Vec::new();
    for entry in &file.elements {
        let span = entry.span();
        let e = entry.get_ref();
        let element = ctx.element(e, span)?;
        g.add(element)
            .map_err(|err| ctx.err(e.name.span(), err.to_string()))?;
        element_spans.push(e.name.span());
    }
    for (i, entry) in file.bonds.iter().enumerate() {
        let b = entry.get_ref();
        if let Some(n) = &b.number
            && *n.get_ref() as usize != i + 1
        {
            return Err(ctx.err(
                n.span(),
                format!("bond number {} is out of order: bonds are numbered by position, this is bond {}", n.get_ref(), i + 1),
            ));
        }
        for end in [&b.from, &b.to] {
            if g.find(end.get_ref()).is_none() {
                return Err(ctx.err(
                    end.span(),
                    format!("bond {}: unknown element '{}'", i + 1, end.get_ref()),
                ));
            }
        }
        g.bond_names(b.from.get_ref(), b.to.get_ref())
            .map_err(|err| ctx.err(entry.span(), err.to_string()))?;
    }
    for entry in &file.outputs {
        let o = entry.get_ref();
        let measured = match (&o.flow, &o.effort, &o.state, &o.value) {
            (Some(f), None, None, None) => Measured::Flow(f.clone()),
            (None, Some(e), None, None) => Measured::Effort(e.clone()),
            (None, None, Some(s), None) => Measured::State(s.clone()),
            (None, None, None, Some(v)) => {
                Measured::Expression(parse(v.get_ref()).map_err(|e| {
                    let (line, column) = line_col(src, v.span().start);
                    BondError::File {
                        line,
                        column: column + e.column,
                        message: format!(
                            "output '{}': cannot parse value '{}': {}",
                            o.name,
                            v.get_ref(),
                            e.message
                        ),
                        path: None,
                    }
                })?)
            }
            _ => {
                return Err(ctx.err(
                    entry.span(),
                    format!("output '{}': give exactly one of `flow`, `effort`, `state` (an element name) or `value` (an expression of signals such as `gain * Tank2.q + offset`)", o.name),
                ));
            }
        };
        g.add_output(Output {
            name: o.name.clone(),
            measured,
            unit: o.unit.clone(),
        })
        .map_err(|err| ctx.err(entry.span(), err.to_string()))?;
    }
    for (element, entry) in &file.initial {
        let span = entry.span();
        let (value, range) = match entry.get_ref() {
            InitialEntry::Value(v) => (*v, None),
            InitialEntry::Table(t) => (
                t.value,
                free_range(&format!("{element}(0)"), t.value, t.free, t.min, t.max)
                    .map_err(|m| ctx.err(span.clone(), format!("initial state {m}")))?,
            ),
        };
        g.set_initial(element, InitialState { value, free: range })
            .map_err(|e| ctx.err(span, format!("initial state: {e}")))?;
    }
    // Structural checks, located at the element they concern.
    if let Err(err) = g.validate() {
        let span = match &err {
            // A value out of range is fixed where the value is written.
            BondError::UnphysicalParameter {
                param,
                expression: false,
                ..
            } if file.parameters.contains_key(param) => {
                file.parameters.get(param).map(Spanned::span)
            }
            BondError::BadPorts { element, .. }
            | BondError::BadLaw { element, .. }
            | BondError::UnknownName { element, .. }
            | BondError::UnphysicalParameter { element, .. }
            | BondError::LawNotFinite { element, .. } => g
                .find(element)
                .and_then(|id| element_spans.get(id.0 as usize).cloned()),
            BondError::BadOutput { output, .. } => file
                .outputs
                .iter()
                .find(|o| &o.get_ref().name == output)
                .map(|o| o.span()),
            _ => None,
        };
        return Err(match span {
            Some(s) => ctx.err(s, err.to_string()),
            None => err,
        });
    }
    for entry in &file.candidates {
        let c = entry.get_ref();
        let symbol = c.kind.get_ref().trim_start_matches('M');
        if !matches!(symbol, "R" | "C" | "I" | "Se" | "Sf") {
            return Err(ctx.err(
                c.kind.span(),
                format!(
                    "candidate '{}': a declared candidate is a one-port (R, C, I, Se, Sf), not a {}",
                    c.name.get_ref(),
                    c.kind.get_ref()
                ),
            ));
        }
        let element = ctx.element(
            &ElementEntry {
                name: c.name.clone(),
                kind: c.kind.clone(),
                parameter: c.parameter.clone(),
                modulus: None,
                effort: c.effort.clone(),
                flow: c.flow.clone(),
                description: c.description.clone(),
                domain: None,
            },
            entry.span(),
        )?;
        let mut params = Vec::new();
        for (name, p) in &c.parameters {
            let span = p.span();
            let p = p.get_ref();
            let range = Range {
                lower: p.min,
                upper: p.max,
            };
            if !(p.min.is_finite() && p.max.is_finite() && p.min < p.max && range.contains(p.value))
            {
                return Err(ctx.err(
                    span,
                    format!(
                        "candidate '{}': parameter '{name}' needs finite min < max around its value {} (found [{}, {}])",
                        c.name.get_ref(),
                        p.value,
                        p.min,
                        p.max
                    ),
                ));
            }
            params.push((
                name.clone(),
                Parameter {
                    value: p.value,
                    unit: p.unit.clone(),
                    description: p.description.clone(),
                    free: Some(range),
                    prior: None,
                },
            ));
        }
        g.add_declared(DeclaredCandidate {
            element,
            at: c.at.get_ref().clone(),
            params,
        })
        .map_err(|e| ctx.err(entry.span(), e.to_string()))?;
    }
    for entry in &file.changes {
        let c = entry.get_ref();
        let (what, name_span) = match (&c.parameter, &c.input) {
            (Some(p), None) => (Scheduled::Parameter(p.get_ref().clone()), p.span()),
            (None, Some(i)) => (Scheduled::Input(i.get_ref().clone()), i.span()),
            _ => {
                return Err(ctx.err(
                    entry.span(),
                    "change: give exactly one of `parameter` or `input` (what takes the new value)"
                        .to_string(),
                ));
            }
        };
        let (at, value) = (*c.at.get_ref(), *c.value.get_ref());
        // Located where the fault lies: the time, the name, or the value.
        let span = if !(at.is_finite() && at >= 0.0) {
            c.at.span()
        } else if g.params().contains_key(what.name()) || g.inputs().contains_key(what.name()) {
            c.value.span()
        } else {
            name_span
        };
        g.add_scheduled(ScheduledChange {
            at,
            what,
            value,
            description: c.description.clone(),
        })
        .map_err(|e| ctx.err(span, format!("change: {e}")))?;
    }
    Ok(g)
}

/// Reads a model file.
///
/// # Errors
/// As [`read_model`], with the path added; [`BondError::Io`] if it cannot be read.
pub fn read_model_path(path: &Path) -> Result<BondGraph> {
    let src = std::fs::read_to_string(path).map_err(|error| BondError::Io {
        message: format!("cannot read model file {}", path.display()),
        error,
    })?;
    read_model(&src).map_err(|e| match e {
        BondError::File {
            line,
            column,
            message,
            ..
        } => BondError::File {
            line,
            column,
            message,
            path: Some(path.to_path_buf()),
        },
        other => other,
    })
}

fn q(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

fn key(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        s.to_string()
    } else {
        q(s)
    }
}

fn num(v: f64) -> String {
    let s = format!("{v:?}");
    if s.contains('.') || s.contains('e') || s.contains("inf") || s.contains("NaN") {
        s
    } else {
        format!("{s}.0")
    }
}

/// The law fields of an element, as `[[elements]]` writes them.
fn write_law(s: &mut String, el: &Element) {
    match &el.law {
        Law::None => {}
        Law::Source(v) => {
            let field = if el.kind == ElementKind::Se {
                "effort"
            } else {
                "flow"
            };
            let _ = writeln!(s, "{field} = {}", q(&v.to_string()));
        }
        Law::Linear(p) => {
            let field = if el.kind.is_two_port() {
                "modulus"
            } else {
                "parameter"
            };
            let _ = writeln!(s, "{field} = {}", q(&p.to_string()));
        }
        Law::Nonlinear { effort, flow } => {
            if let Some(e) = effort {
                let _ = writeln!(s, "effort = {}", q(&e.to_string()));
            }
            if let Some(f) = flow {
                let _ = writeln!(s, "flow = {}", q(&f.to_string()));
            }
        }
    }
}

/// Writes a model as TOML that [`read_model`] reads back to an equal graph.
pub fn write_model(g: &BondGraph) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "name = {}", q(&g.name));
    if !g.description.is_empty() {
        let _ = writeln!(s, "description = {}", q(&g.description));
    }
    if !g.params().is_empty() {
        let _ = writeln!(s, "\n[parameters]");
        for (name, p) in g.params() {
            let _ = write!(
                s,
                "{} = {{ value = {}, unit = {}",
                key(name),
                num(p.value),
                q(&p.unit)
            );
            if !p.description.is_empty() {
                let _ = write!(s, ", description = {}", q(&p.description));
            }
            if let Some(r) = p.free {
                let _ = write!(
                    s,
                    ", free = true, min = {}, max = {}",
                    num(r.lower),
                    num(r.upper)
                );
            }
            if let Some(pr) = p.prior {
                let _ = write!(
                    s,
                    ", prior = {{ mean = {}, std = {} }}",
                    num(pr.mean),
                    num(pr.std)
                );
            }
            s.push_str(" }\n");
        }
    }
    if !g.inputs().is_empty() {
        let _ = writeln!(s, "\n[inputs]");
        for (name, i) in g.inputs() {
            let _ = write!(
                s,
                "{} = {{ default = {}, unit = {}",
                key(name),
                num(i.default),
                q(&i.unit)
            );
            if !i.description.is_empty() {
                let _ = write!(s, ", description = {}", q(&i.description));
            }
            s.push_str(" }\n");
        }
    }
    for el in g.elements() {
        let _ = writeln!(
            s,
            "\n[[elements]]\nname = {}\nkind = {}",
            q(&el.name),
            q(&el.symbol())
        );
        write_law(&mut s, el);
        if !el.description.is_empty() {
            let _ = writeln!(s, "description = {}", q(&el.description));
        }
        if let Some(d) = el.domain {
            let _ = writeln!(s, "domain = {}", q(d.name()));
        }
    }
    if !g.bonds().is_empty() {
        s.push('\n');
    }
    for (i, b) in g.bonds().iter().enumerate() {
        let _ = writeln!(
            s,
            "[[bonds]]\nnumber = {}\nfrom = {}\nto = {}",
            i + 1,
            q(&g.element(b.from).name),
            q(&g.element(b.to).name)
        );
    }
    if !g.initial().is_empty() {
        let _ = writeln!(s, "\n[initial]");
        for (element, i) in g.initial() {
            match i.free {
                None => {
                    let _ = writeln!(s, "{} = {}", key(element), num(i.value));
                }
                Some(r) => {
                    let _ = writeln!(
                        s,
                        "{} = {{ value = {}, free = true, min = {}, max = {} }}",
                        key(element),
                        num(i.value),
                        num(r.lower),
                        num(r.upper)
                    );
                }
            }
        }
    }
    for o in g.outputs() {
        let (field, text) = match &o.measured {
            Measured::Flow(e) => ("flow", e.clone()),
            Measured::Effort(e) => ("effort", e.clone()),
            Measured::State(e) => ("state", e.clone()),
            Measured::Expression(e) => ("value", e.to_string()),
        };
        let _ = writeln!(
            s,
            "\n[[outputs]]\nname = {}\n{field} = {}\nunit = {}",
            q(&o.name),
            q(&text),
            q(&o.unit)
        );
    }
    for c in g.schedule() {
        let field = match c.what {
            Scheduled::Parameter(_) => "parameter",
            Scheduled::Input(_) => "input",
        };
        let _ = writeln!(
            s,
            "\n[[changes]]\nat = {}\n{field} = {}\nvalue = {}",
            num(c.at),
            q(c.what.name()),
            num(c.value)
        );
        if !c.description.is_empty() {
            let _ = writeln!(s, "description = {}", q(&c.description));
        }
    }
    for c in g.declared() {
        let el = &c.element;
        let _ = writeln!(
            s,
            "\n[[candidates]]\nname = {}\nkind = {}\nat = {}",
            q(&el.name),
            q(&el.symbol()),
            q(&c.at)
        );
        write_law(&mut s, el);
        if !el.description.is_empty() {
            let _ = writeln!(s, "description = {}", q(&el.description));
        }
        if !c.params.is_empty() {
            let _ = writeln!(s, "[candidates.parameters]");
        }
        for (name, p) in &c.params {
            let r = p.free.unwrap_or(Range {
                lower: p.value,
                upper: p.value,
            });
            let _ = write!(
                s,
                "{} = {{ value = {}, unit = {}, min = {}, max = {}",
                key(name),
                num(p.value),
                q(&p.unit),
                num(r.lower),
                num(r.upper)
            );
            if !p.description.is_empty() {
                let _ = write!(s, ", description = {}", q(&p.description));
            }
            s.push_str(" }\n");
        }
    }
    s
}

/// Writes a model file, atomically (an earlier file is replaced only when
/// the new one is complete).
///
/// # Errors
/// [`BondError::Core`] if the file cannot be written.
pub fn write_model_path(g: &BondGraph, path: &Path) -> Result<()> {
    Ok(modelgap_core::io::atomic::write_atomic(
        path,
        write_model(g).as_bytes(),
    )?)
}

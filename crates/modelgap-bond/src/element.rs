//! Bond-graph elements: kinds, laws and parameters.

use std::fmt;

use crate::expr::Expr;

/// The kind of a bond-graph element, in bond-graph notation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ElementKind {
    /// Effort source (a voltage, a torque).
    Se,
    /// Flow source (a current, a velocity).
    Sf,
    /// Dissipation: resistor, damper, friction.
    R,
    /// Capacitive storage: capacitor, spring. State: displacement `q`.
    C,
    /// Inertial storage: inductor, mass, inertia. State: momentum `p`.
    I,
    /// Transformer: `e_out = m e_in`, `f_in = m f_out`.
    Tf,
    /// Gyrator: `e_in = r f_out`, `e_out = r f_in`.
    Gy,
    /// Modulated transformer: a TF whose modulus follows an input signal.
    Mtf,
    /// Modulated gyrator: a GY whose modulus follows an input signal.
    Mgy,
    /// Common-effort junction (parallel connection).
    Zero,
    /// Common-flow junction (series connection).
    One,
}

impl ElementKind {
    /// All kinds, in the order the model file documents them.
    pub const ALL: [ElementKind; 11] = [
        ElementKind::Se,
        ElementKind::Sf,
        ElementKind::R,
        ElementKind::C,
        ElementKind::I,
        ElementKind::Tf,
        ElementKind::Gy,
        ElementKind::Mtf,
        ElementKind::Mgy,
        ElementKind::Zero,
        ElementKind::One,
    ];

    /// The name used in model files and printouts (`Se`, `TF`, `0`, `1`).
    pub fn symbol(self) -> &'static str {
        match self {
            ElementKind::Se => "Se",
            ElementKind::Sf => "Sf",
            ElementKind::R => "R",
            ElementKind::C => "C",
            ElementKind::I => "I",
            ElementKind::Tf => "TF",
            ElementKind::Gy => "GY",
            ElementKind::Mtf => "MTF",
            ElementKind::Mgy => "MGY",
            ElementKind::Zero => "0",
            ElementKind::One => "1",
        }
    }

    /// Parses the symbol written in model files.
    pub fn from_symbol(s: &str) -> Option<ElementKind> {
        ElementKind::ALL.into_iter().find(|k| k.symbol() == s)
    }

    /// Number of bonds the element takes (`None` for junctions: any number ≥ 1).
    pub fn n_ports(self) -> Option<usize> {
        match self {
            ElementKind::Zero | ElementKind::One => None,
            ElementKind::Tf | ElementKind::Gy | ElementKind::Mtf | ElementKind::Mgy => Some(2),
            _ => Some(1),
        }
    }

    /// True for 0 and 1 junctions.
    pub fn is_junction(self) -> bool {
        matches!(self, ElementKind::Zero | ElementKind::One)
    }

    /// True for sources.
    pub fn is_source(self) -> bool {
        matches!(self, ElementKind::Se | ElementKind::Sf)
    }

    /// True for storage elements (C, I).
    pub fn is_storage(self) -> bool {
        matches!(self, ElementKind::C | ElementKind::I)
    }

    /// True for two-port converters (TF, GY and their modulated forms).
    pub fn is_two_port(self) -> bool {
        matches!(
            self,
            ElementKind::Tf | ElementKind::Gy | ElementKind::Mtf | ElementKind::Mgy
        )
    }

    /// True for transformers (TF, MTF).
    pub fn is_transformer(self) -> bool {
        matches!(self, ElementKind::Tf | ElementKind::Mtf)
    }

    /// True for gyrators (GY, MGY).
    pub fn is_gyrator(self) -> bool {
        matches!(self, ElementKind::Gy | ElementKind::Mgy)
    }
}

impl fmt::Display for ElementKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.symbol())
    }
}

/// The constitutive law of an element.
///
/// Laws are written for the bond variables of the element's own bond(s):
/// - `Se`: `effort` is its effort; `Sf`: `flow` is its flow (expressions of
///   inputs, parameters and time `t`).
/// - `R`: linear `e = R f` with `R = coefficient`; or nonlinear `effort(f)`
///   and/or `flow(e)`.
/// - `C`: linear `e = q / C`; or nonlinear `effort(q)`.
/// - `I`: linear `f = p / L`; or nonlinear `flow(p)` (a flux–current curve).
/// - `TF`/`MTF`: modulus `m` with `e_out = m e_in`, `f_in = m f_out`.
/// - `GY`/`MGY`: modulus `r` with `e_in = r f_out`, `e_out = r f_in`.
#[derive(Clone, Debug, PartialEq)]
pub enum Law {
    /// Junctions have no law.
    None,
    /// The value a source imposes.
    Source(Expr),
    /// A linear law with this coefficient (resistance, capacitance, inertance, modulus).
    Linear(Expr),
    /// A nonlinear law: effort as a function of the flow (R) or
    /// displacement (C), and/or flow as a function of the effort (R) or
    /// momentum (I). Laws mention their own variable as `e`, `f`, `p` or `q`.
    Nonlinear {
        /// Effort law, if given.
        effort: Option<Expr>,
        /// Flow law, if given.
        flow: Option<Expr>,
    },
}

/// The physical domain a junction declares (`domain = "hydraulic"` in a
/// model file): it names the physics the candidate menu attaches there when
/// the units do not say.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhysicalDomain {
    /// Voltages and currents.
    Electrical,
    /// Torques and angular speeds.
    Rotational,
    /// Forces and velocities.
    Translational,
    /// Pressures (or levels) and volume flows.
    Hydraulic,
    /// Gas pressures and mass flows.
    Pneumatic,
    /// Temperatures and heat flows.
    Thermal,
    /// Magnetomotive forces and flux rates.
    Magnetic,
}

impl PhysicalDomain {
    /// Every domain, in the order model files document them.
    pub const ALL: [PhysicalDomain; 7] = [
        PhysicalDomain::Electrical,
        PhysicalDomain::Rotational,
        PhysicalDomain::Translational,
        PhysicalDomain::Hydraulic,
        PhysicalDomain::Pneumatic,
        PhysicalDomain::Thermal,
        PhysicalDomain::Magnetic,
    ];

    /// The name written in model files (`hydraulic`).
    pub fn name(self) -> &'static str {
        match self {
            PhysicalDomain::Electrical => "electrical",
            PhysicalDomain::Rotational => "rotational",
            PhysicalDomain::Translational => "translational",
            PhysicalDomain::Hydraulic => "hydraulic",
            PhysicalDomain::Pneumatic => "pneumatic",
            PhysicalDomain::Thermal => "thermal",
            PhysicalDomain::Magnetic => "magnetic",
        }
    }

    /// The domain a model file names.
    pub fn from_name(name: &str) -> Option<PhysicalDomain> {
        PhysicalDomain::ALL.into_iter().find(|d| d.name() == name)
    }
}

/// One element of a bond graph.
#[derive(Clone, Debug, PartialEq)]
pub struct Element {
    /// Unique name (`R`, `L`, `1e`).
    pub name: String,
    /// What the element is.
    pub kind: ElementKind,
    /// Its constitutive law.
    pub law: Law,
    /// A human description ("armature resistance").
    pub description: String,
    /// The physical domain a junction declares, if it does.
    pub domain: Option<PhysicalDomain>,
}

impl Element {
    /// The kind as written in model files: `MSe`/`MSf` for a source whose
    /// value reads a signal (another element's variable), else the kind's
    /// symbol.
    pub fn symbol(&self) -> String {
        match &self.law {
            Law::Source(e) if !e.signals().is_empty() => format!("M{}", self.kind.symbol()),
            _ => self.kind.symbol().to_string(),
        }
    }

    fn new(name: &str, kind: ElementKind, law: Law) -> Element {
        Element {
            name: name.to_string(),
            kind,
            law,
            description: String::new(),
            domain: None,
        }
    }

    /// An effort source imposing the input or parameter called `value`.
    pub fn se(name: &str, value: &str) -> Element {
        Element::new(
            name,
            ElementKind::Se,
            Law::Source(Expr::Param(value.to_string())),
        )
    }

    /// A flow source imposing the input or parameter called `value`.
    pub fn sf(name: &str, value: &str) -> Element {
        Element::new(
            name,
            ElementKind::Sf,
            Law::Source(Expr::Param(value.to_string())),
        )
    }

    /// A linear resistor `e = R f` with the parameter called `param`.
    pub fn r(name: &str, param: &str) -> Element {
        Element::new(
            name,
            ElementKind::R,
            Law::Linear(Expr::Param(param.to_string())),
        )
    }

    /// A linear capacitor `e = q / C` with the parameter called `param`.
    pub fn c(name: &str, param: &str) -> Element {
        Element::new(
            name,
            ElementKind::C,
            Law::Linear(Expr::Param(param.to_string())),
        )
    }

    /// A linear inertia `f = p / L` with the parameter called `param`.
    pub fn i(name: &str, param: &str) -> Element {
        Element::new(
            name,
            ElementKind::I,
            Law::Linear(Expr::Param(param.to_string())),
        )
    }

    /// A transformer of modulus `param`.
    pub fn tf(name: &str, param: &str) -> Element {
        Element::new(
            name,
            ElementKind::Tf,
            Law::Linear(Expr::Param(param.to_string())),
        )
    }

    /// A gyrator of modulus `param`.
    pub fn gy(name: &str, param: &str) -> Element {
        Element::new(
            name,
            ElementKind::Gy,
            Law::Linear(Expr::Param(param.to_string())),
        )
    }

    /// A modulated transformer whose modulus is the input signal `signal`.
    pub fn mtf(name: &str, signal: &str) -> Element {
        Element::new(
            name,
            ElementKind::Mtf,
            Law::Linear(Expr::Param(signal.to_string())),
        )
    }

    /// A modulated gyrator whose modulus is the input signal `signal`.
    pub fn mgy(name: &str, signal: &str) -> Element {
        Element::new(
            name,
            ElementKind::Mgy,
            Law::Linear(Expr::Param(signal.to_string())),
        )
    }

    /// A 0-junction (common effort).
    pub fn zero(name: &str) -> Element {
        Element::new(name, ElementKind::Zero, Law::None)
    }

    /// A 1-junction (common flow).
    pub fn one(name: &str) -> Element {
        Element::new(name, ElementKind::One, Law::None)
    }

    /// An element with a nonlinear law (`effort` and/or `flow` given).
    pub fn nonlinear(
        name: &str,
        kind: ElementKind,
        effort: Option<Expr>,
        flow: Option<Expr>,
    ) -> Element {
        Element::new(name, kind, Law::Nonlinear { effort, flow })
    }

    /// Sets the description.
    #[must_use]
    pub fn described(mut self, description: &str) -> Element {
        self.description = description.to_string();
        self
    }
}

/// A named model parameter with its unit.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// Value in SI units.
    pub value: f64,
    /// Unit, as text (`Ohm`, `H`, `N m/A`).
    pub unit: String,
    /// A human description.
    pub description: String,
    /// `Some` when the value is unknown and calibration fits it within
    /// these bounds (`free = true` in a model file).
    pub free: Option<Range>,
    /// What is known of a free value before the data (`prior = { mean, std }`
    /// in a model file): calibration weighs it against the recording.
    pub prior: Option<modelgap_core::Prior>,
}

/// Bounds of an unknown value that calibration fits: `lower ≤ value ≤ upper`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    /// Lower bound.
    pub lower: f64,
    /// Upper bound.
    pub upper: f64,
}

impl Range {
    /// The bounds a model file gives, or the default around `value` when it
    /// gives none: a value keeps its sign and may grow or shrink a
    /// thousandfold (`[0, 1000 v]` for `v > 0`, `[1000 v, 0]` for `v < 0`).
    /// A nominal value of 0 has no sign or size to go by: `None` (the file
    /// must give both bounds).
    pub fn around(value: f64, lower: Option<f64>, upper: Option<f64>) -> Option<Range> {
        let (lo, hi) = if value > 0.0 {
            (0.0, 1e3 * value)
        } else if value < 0.0 {
            (1e3 * value, 0.0)
        } else {
            (f64::NAN, f64::NAN)
        };
        let r = Range {
            lower: lower.unwrap_or(lo),
            upper: upper.unwrap_or(hi),
        };
        (r.lower.is_finite() && r.upper.is_finite()).then_some(r)
    }

    /// True when `value` lies within the bounds.
    pub fn contains(&self, value: f64) -> bool {
        value >= self.lower && value <= self.upper
    }
}

/// The state of a storage element at the start of every simulation: its
/// displacement `q` (a C) or momentum `p` (an I).
#[derive(Clone, Debug, PartialEq)]
pub struct InitialState {
    /// The value at `t = 0` (0: at rest, uncharged).
    pub value: f64,
    /// `Some` when the start is unknown and calibration fits it.
    pub free: Option<Range>,
}

/// What a scheduled change changes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Scheduled {
    /// A parameter takes a new value (an abrupt fault, a load that steps).
    Parameter(String),
    /// An input not given by the recording steps to a new value (its
    /// default before the first step).
    Input(String),
}

impl Scheduled {
    /// The parameter's or input's name.
    pub fn name(&self) -> &str {
        match self {
            Scheduled::Parameter(n) | Scheduled::Input(n) => n,
        }
    }
}

/// A change at a given time, part of the model (`[[changes]]` in a model
/// file): what `fix` writes when explain finds an abrupt change, and what a
/// user writes for a step they know of.
#[derive(Clone, Debug, PartialEq)]
pub struct ScheduledChange {
    /// When it happens (s, from the start of the run).
    pub at: f64,
    /// What changes.
    pub what: Scheduled,
    /// The value from `at` on.
    pub value: f64,
    /// Why (free text).
    pub description: String,
}

/// A named input signal the model takes (a source value, a duty cycle).
#[derive(Clone, Debug, PartialEq)]
pub struct InputSignal {
    /// Value used when no signal is given.
    pub default: f64,
    /// Unit, as text.
    pub unit: String,
    /// A human description.
    pub description: String,
}

/// Which variable of the graph an output measures.
#[derive(Clone, Debug, PartialEq)]
pub enum Measured {
    /// The effort at an element: a 0-junction's common effort or a one-port's bond effort.
    Effort(String),
    /// The flow at an element: a 1-junction's common flow or a one-port's bond flow.
    Flow(String),
    /// The state of a storage element (momentum of an I, displacement of a C).
    State(String),
    /// An expression of signals (`Tank2.q`), parameters, inputs and `t`: a
    /// sensor with a gain and an offset (`gain * Tank2.q + offset`), a sum.
    Expression(Expr),
}

impl Measured {
    /// The element the output reads directly; `None` for an expression.
    pub fn element(&self) -> Option<&str> {
        match self {
            Measured::Effort(s) | Measured::Flow(s) | Measured::State(s) => Some(s),
            Measured::Expression(_) => None,
        }
    }

    /// The elements the output reads: its element, or every element an
    /// expression names.
    pub fn elements(&self) -> Vec<String> {
        match self {
            Measured::Expression(e) => e.signals().into_iter().map(|(el, _)| el).collect(),
            other => other.element().map(str::to_string).into_iter().collect(),
        }
    }
}

/// A measured output of the model (`i` = flow of the electrical 1-junction).
#[derive(Clone, Debug, PartialEq)]
pub struct Output {
    /// The output's name, as in recordings.
    pub name: String,
    /// What it measures.
    pub measured: Measured,
    /// Unit, as text.
    pub unit: String,
}

/// An effect a model file declares for explain to try (`[[candidates]]`): an
/// element with its law, bonded from junction `at`, whose parameters are
/// fitted within their bounds. `fix` builds it in as a real element.
#[derive(Clone, Debug, PartialEq)]
pub struct DeclaredCandidate {
    /// The element to add (its name is the candidate's name).
    pub element: Element,
    /// The junction it is bonded from.
    pub at: String,
    /// Its parameters, by name, each with the bounds it is fitted within
    /// (`free` always `Some`).
    pub params: Vec<(String, Parameter)>,
}

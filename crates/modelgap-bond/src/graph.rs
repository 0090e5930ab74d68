//! The bond graph: elements joined by bonds, with parameters, inputs and outputs.
//!
//! # Sign convention
//!
//! Every bond carries a half-arrow from `from` to `to`: power `e·f` is
//! positive when it flows in that direction. At a junction, bonds pointing
//! in count `+`, bonds pointing out count `−` (`Σ± e = 0` at a 1-junction,
//! `Σ± f = 0` at a 0-junction). R, C and I elements must have their bond
//! pointing into them (they absorb power); sources may point either way
//! (a load torque source with its bond pointing into it opposes motion).
//! Under this convention the DC motor `Se:V → 1 → GY:k → 1 → I:J` with
//! positive `V` and positive `k` spins forward (`ω > 0`).

use std::collections::BTreeMap;
use std::fmt;

use modelgap_core::recording::MAX_MAGNITUDE;

use crate::element::{
    DeclaredCandidate, Element, ElementKind, InitialState, InputSignal, Law, Measured, Output,
    Parameter, Range, Scheduled, ScheduledChange,
};
use crate::error::{BondError, Result};
use crate::expr::Expr;

/// Index of an element in its graph. Ids are append-only: edits keep old ids valid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ElementId(pub u32);

/// Index of a bond in its graph. Displayed as the bond number (index + 1),
/// so bonds added in order are numbered 1, 2, … as in the paper's figures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct BondId(pub u32);

impl BondId {
    /// The bond's number in equations (`e3`, `f3`): index + 1.
    pub fn number(self) -> u32 {
        self.0 + 1
    }

    /// The bond with this number (1-based).
    pub fn from_number(n: u32) -> Option<BondId> {
        n.checked_sub(1).map(BondId)
    }

    fn index(self) -> usize {
        self.0 as usize
    }
}

/// True for a finite value within [`MAX_MAGNITUDE`] (what a parameter or input default may be).
fn in_range(value: f64) -> bool {
    value.is_finite() && value.abs() <= MAX_MAGNITUDE
}

/// What the linear coefficient of an R, C or I element is (`inductance` for
/// an I whose parameter is in H, `inertia` in kg m², `mass` in kg).
fn coefficient_quantity(kind: ElementKind, unit: &str) -> &'static str {
    use crate::effects::Domain;
    match kind {
        ElementKind::R => "resistance",
        ElementKind::C => "capacitance",
        ElementKind::I => match Domain::of_unit(unit) {
            Some(Domain::Electrical) => "inductance",
            Some(Domain::Rotational) => "inertia",
            Some(Domain::Translational) => "mass",
            None => "inertance",
        },
        _ => "coefficient",
    }
}

impl fmt::Display for BondId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.number())
    }
}

/// A bond, with its power direction from `from` to `to`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bond {
    /// The element the half-arrow starts at.
    pub from: ElementId,
    /// The element the half-arrow points to.
    pub to: ElementId,
}

/// Whether a bond points into or out of an element.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// The half-arrow points into the element.
    In,
    /// The half-arrow points away from the element.
    Out,
}

impl Direction {
    /// `+1` for `In`, `−1` for `Out`: the sign a junction gives the bond.
    pub fn sign(self) -> f64 {
        match self {
            Direction::In => 1.0,
            Direction::Out => -1.0,
        }
    }
}

/// A bond graph with its parameters, input signals and measured outputs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BondGraph {
    /// Model name (`dc-motor`).
    pub name: String,
    /// Human description.
    pub description: String,
    elements: Vec<Element>,
    bonds: Vec<Bond>,
    params: BTreeMap<String, Parameter>,
    inputs: BTreeMap<String, InputSignal>,
    outputs: Vec<Output>,
    /// Initial states by storage element (absent: 0).
    initial: BTreeMap<String, InitialState>,
    /// Effects the model file declares for explain to try.
    declared: Vec<DeclaredCandidate>,
    /// Changes at given times (steps, abrupt faults), in time order.
    schedule: Vec<ScheduledChange>,
}

/// Checks that `range` is finite, ordered and holds `value`.
fn check_range(name: &str, value: f64, range: Option<Range>) -> Result<()> {
    let Some(r) = range else { return Ok(()) };
    if !(in_range(r.lower) && in_range(r.upper) && r.lower < r.upper) {
        return Err(BondError::BadRange {
            name: name.to_string(),
            detail: format!(
                "bounds [{}, {}] must be finite with min < max",
                r.lower, r.upper
            ),
        });
    }
    if !r.contains(value) {
        return Err(BondError::BadRange {
            name: name.to_string(),
            detail: format!(
                "its value {value} lies outside its bounds [{}, {}]",
                r.lower, r.upper
            ),
        });
    }
    Ok(())
}

impl BondGraph {
    /// An empty graph.
    pub fn new() -> BondGraph {
        BondGraph::default()
    }

    /// Adds an element and returns its id.
    ///
    /// # Errors
    /// [`BondError::DuplicateElement`] if the name is taken.
    pub fn add(&mut self, element: Element) -> Result<ElementId> {
        if self.find(&element.name).is_some() {
            return Err(BondError::DuplicateElement { name: element.name });
        }
        self.elements.push(element);
        Ok(ElementId(self.elements.len() as u32 - 1))
    }

    /// Adds a bond with power flowing from `from` to `to`; its number is the
    /// number of bonds so far plus one.
    ///
    /// # Errors
    /// [`BondError::UnknownElement`] for an id not in this graph, or
    /// [`BondError::BadPorts`] for a bond from an element to itself.
    pub fn bond(&mut self, from: ElementId, to: ElementId) -> Result<BondId> {
        for id in [from, to] {
            if id.0 as usize >= self.elements.len() {
                return Err(BondError::UnknownElement {
                    name: format!("#{}", id.0),
                    context: format!(" in bond {}", self.bonds.len() + 1),
                });
            }
        }
        if from == to {
            let e = &self.elements[from.0 as usize];
            return Err(BondError::BadPorts {
                element: e.name.clone(),
                kind: e.kind.to_string(),
                detail: format!("cannot be bonded to itself (bond {})", self.bonds.len() + 1),
            });
        }
        self.bonds.push(Bond { from, to });
        Ok(BondId(self.bonds.len() as u32 - 1))
    }

    /// Puts `element` (a junction) into `bond`, on the side of `end`: the bond now ends
    /// at the new element, and a new bond joins it to `end`, with power flowing the same
    /// way. A 0- or 1-junction with two bonds changes nothing, and effects can then attach
    /// to it (a leakage across a capacitor that sat on a 1-junction).
    ///
    /// # Errors
    /// As [`BondGraph::add`]; [`BondError::BadPorts`] when `end` is not an end of `bond`.
    pub fn split_bond(
        &mut self,
        bond: BondId,
        end: ElementId,
        element: Element,
    ) -> Result<ElementId> {
        let b = self.bonds[bond.index()];
        if b.from != end && b.to != end {
            let e = &self.elements[end.0 as usize];
            return Err(BondError::BadPorts {
                element: e.name.clone(),
                kind: e.kind.to_string(),
                detail: format!("is not an end of bond {}", bond.number()),
            });
        }
        let id = self.add(element)?;
        if b.to == end {
            self.bonds[bond.index()].to = id;
            self.bond(id, end)?;
        } else {
            self.bonds[bond.index()].from = id;
            self.bond(end, id)?;
        }
        Ok(id)
    }

    /// Adds a bond between two elements given by name.
    ///
    /// # Errors
    /// As [`BondGraph::bond`], and [`BondError::UnknownElement`] for a name not found.
    pub fn bond_names(&mut self, from: &str, to: &str) -> Result<BondId> {
        let n = self.bonds.len() + 1;
        let lookup = |g: &BondGraph, name: &str| {
            g.find(name).ok_or_else(|| BondError::UnknownElement {
                name: name.to_string(),
                context: format!(" in bond {n}"),
            })
        };
        let a = lookup(self, from)?;
        let b = lookup(self, to)?;
        self.bond(a, b)
    }

    /// Declares or replaces a parameter.
    ///
    /// # Errors
    /// [`BondError::BadParameter`] for a value that is not finite or beyond
    /// [`MAX_MAGNITUDE`], [`BondError::NameClash`] if an input has the same name.
    pub fn add_param(
        &mut self,
        name: &str,
        value: f64,
        unit: &str,
        description: &str,
    ) -> Result<()> {
        if !in_range(value) {
            return Err(BondError::BadParameter {
                name: name.to_string(),
                value,
            });
        }
        if self.inputs.contains_key(name) {
            return Err(BondError::NameClash {
                name: name.to_string(),
                detail: "declared as an input and as a parameter".to_string(),
            });
        }
        self.params.insert(
            name.to_string(),
            Parameter {
                value,
                unit: unit.to_string(),
                description: description.to_string(),
                free: None,
                prior: None,
            },
        );
        Ok(())
    }

    /// Declares or replaces an input signal with its default value.
    ///
    /// # Errors
    /// [`BondError::BadParameter`] for a default that is not finite or beyond
    /// [`MAX_MAGNITUDE`], [`BondError::NameClash`] if a parameter has the same name.
    pub fn add_input(
        &mut self,
        name: &str,
        default: f64,
        unit: &str,
        description: &str,
    ) -> Result<()> {
        if !in_range(default) {
            return Err(BondError::BadParameter {
                name: name.to_string(),
                value: default,
            });
        }
        if self.params.contains_key(name) {
            return Err(BondError::NameClash {
                name: name.to_string(),
                detail: "declared as a parameter and as an input".to_string(),
            });
        }
        self.inputs.insert(
            name.to_string(),
            InputSignal {
                default,
                unit: unit.to_string(),
                description: description.to_string(),
            },
        );
        Ok(())
    }

    /// Declares a measured output.
    ///
    /// # Errors
    /// [`BondError::BadOutput`] if the name is taken.
    pub fn add_output(&mut self, output: Output) -> Result<()> {
        if self.outputs.iter().any(|o| o.name == output.name) {
            return Err(BondError::BadOutput {
                output: output.name,
                detail: "is declared twice".to_string(),
            });
        }
        self.outputs.push(output);
        Ok(())
    }

    /// Replaces what output `name` measures (a sensor chain an effect adds in
    /// front of it), keeping its name and unit.
    ///
    /// # Errors
    /// [`BondError::BadOutput`] if no output has that name.
    pub fn set_output(&mut self, name: &str, measured: Measured) -> Result<()> {
        let o = (self.outputs.iter_mut().find(|o| o.name == name)).ok_or_else(|| {
            BondError::BadOutput {
                output: name.to_string(),
                detail: "is not an output of the model".to_string(),
            }
        })?;
        o.measured = measured;
        Ok(())
    }

    /// Sets an existing parameter's value (`--set R=1.2`).
    ///
    /// The coefficients of the linear R, C and I elements that use the
    /// parameter are checked at once (see [`BondGraph::check_coefficients`]);
    /// on error the graph is left unchanged.
    ///
    /// # Errors
    /// [`BondError::UnknownParameter`] listing the known names,
    /// [`BondError::BadParameter`] for a value that is not finite or beyond
    /// [`MAX_MAGNITUDE`], [`BondError::UnphysicalParameter`] for a value its element cannot have
    /// (`L = 0`, `R = -1`), [`BondError::LawNotFinite`] for a coefficient that
    /// the value makes infinite (`1/R` at `R = 0`).
    pub fn set_param(&mut self, name: &str, value: f64) -> Result<()> {
        if !in_range(value) {
            return Err(BondError::BadParameter {
                name: name.to_string(),
                value,
            });
        }
        if let Some(p) = self.params.get_mut(name) {
            let old = std::mem::replace(&mut p.value, value);
            let users: Vec<ElementId> = self
                .element_ids()
                .filter(|&id| match &self.element(id).law {
                    Law::Linear(e) => e.params().contains(name),
                    _ => false,
                })
                .collect();
            if let Some(err) = users.into_iter().find_map(|id| self.coefficient_error(id)) {
                if let Some(p) = self.params.get_mut(name) {
                    p.value = old;
                }
                return Err(err);
            }
            return Ok(());
        }
        if let Some(i) = self.inputs.get_mut(name) {
            i.default = value;
            return Ok(());
        }
        Err(BondError::UnknownParameter {
            name: name.to_string(),
            known: self
                .params
                .keys()
                .chain(self.inputs.keys())
                .cloned()
                .collect::<Vec<_>>()
                .join(", "),
        })
    }

    /// A parameter's value.
    ///
    /// # Errors
    /// [`BondError::UnknownParameter`].
    pub fn param(&self, name: &str) -> Result<f64> {
        self.params
            .get(name)
            .map(|p| p.value)
            .ok_or_else(|| BondError::UnknownParameter {
                name: name.to_string(),
                known: self.params.keys().cloned().collect::<Vec<_>>().join(", "),
            })
    }

    /// Parameter `name`, to change, or [`BondError::UnknownParameter`] listing
    /// the known ones.
    fn param_mut(&mut self, name: &str) -> Result<&mut Parameter> {
        let known = self.params.keys().cloned().collect::<Vec<_>>().join(", ");
        self.params
            .get_mut(name)
            .ok_or_else(|| BondError::UnknownParameter {
                name: name.to_string(),
                known,
            })
    }

    /// Marks parameter `name` as unknown, to be fitted within `range` by
    /// calibration (`None`: known again).
    ///
    /// # Errors
    /// [`BondError::UnknownParameter`]; [`BondError::BadParameter`] when the
    /// bounds are not finite and ordered or leave out the current value.
    pub fn set_free(&mut self, name: &str, range: Option<Range>) -> Result<()> {
        let p = self.param_mut(name)?;
        check_range(name, p.value, range)?;
        p.free = range;
        if range.is_none() {
            p.prior = None;
        }
        Ok(())
    }

    /// Gives free parameter `name` a Gaussian prior (`None`: none), which
    /// calibration weighs against the recording.
    ///
    /// # Errors
    /// [`BondError::UnknownParameter`]; [`BondError::BadPrior`] when the
    /// parameter is not free (a prior weighs an unknown value).
    pub fn set_prior(&mut self, name: &str, prior: Option<modelgap_core::Prior>) -> Result<()> {
        let p = self.param_mut(name)?;
        if prior.is_some() && p.free.is_none() {
            return Err(BondError::BadPrior {
                name: name.to_string(),
                detail: "a prior weighs an unknown value; add `free = true`".to_string(),
            });
        }
        p.prior = prior;
        Ok(())
    }

    /// The initial states given, by storage element (the others start at 0).
    pub fn initial(&self) -> &BTreeMap<String, InitialState> {
        &self.initial
    }

    /// Sets the state of storage element `element` at `t = 0` (its `q` or
    /// `p`), fitted by calibration within `free` when given.
    ///
    /// # Errors
    /// [`BondError::UnknownElement`]; [`BondError::BadLaw`] naming the
    /// element when it is not a C or an I; [`BondError::BadParameter`] for
    /// a value that is not finite or bounds that leave it out.
    pub fn set_initial(&mut self, element: &str, state: InitialState) -> Result<()> {
        let id = self.require(element, " for an initial state")?;
        if !self.element(id).kind.is_storage() {
            return Err(BondError::BadLaw {
                element: element.to_string(),
                detail: format!(
                    "is a {}, which has no state to start from (only C and I elements do)",
                    self.element(id).kind
                ),
            });
        }
        let label = format!("{element}(0)");
        if !in_range(state.value) {
            return Err(BondError::BadParameter {
                name: label,
                value: state.value,
            });
        }
        check_range(&label, state.value, state.free)?;
        self.initial.insert(element.to_string(), state);
        Ok(())
    }

    /// The changes the model makes at given times (`[[changes]]`), in time
    /// order.
    pub fn schedule(&self) -> &[ScheduledChange] {
        &self.schedule
    }

    /// Adds a change at a given time (kept in time order; changes at the
    /// same time apply in the order added).
    ///
    /// # Errors
    /// [`BondError::UnknownParameter`] for a parameter or input the model
    /// does not have; [`BondError::BadRange`] for a time that is negative or
    /// not finite, or a value that is not finite; the errors of
    /// [`BondGraph::set_param`] for a parameter value its element cannot
    /// have.
    pub fn add_scheduled(&mut self, change: ScheduledChange) -> Result<()> {
        let name = change.what.name();
        let bad = |detail: String| BondError::BadRange {
            name: format!("change of {name}"),
            detail,
        };
        if !(change.at.is_finite() && change.at >= 0.0) {
            return Err(bad(format!(
                "its time must be finite and not negative (s from the start of the run), found {}",
                change.at
            )));
        }
        if !in_range(change.value) {
            return Err(bad(format!(
                "its value must be finite and at most {} in magnitude, found {}",
                modelgap_core::recording::MAX_MAGNITUDE,
                change.value
            )));
        }
        match &change.what {
            Scheduled::Parameter(p) => {
                self.clone().set_param(p, change.value)?;
            }
            Scheduled::Input(i) => {
                if !self.inputs.contains_key(i) {
                    return Err(BondError::UnknownParameter {
                        name: i.clone(),
                        known: self.inputs.keys().cloned().collect::<Vec<_>>().join(", "),
                    });
                }
            }
        }
        let pos = self.schedule.partition_point(|c| c.at <= change.at);
        self.schedule.insert(pos, change);
        Ok(())
    }

    /// Removes every scheduled change.
    pub fn clear_schedule(&mut self) {
        self.schedule.clear();
    }

    /// The effects the model declares for explain to try (`[[candidates]]`).
    pub fn declared(&self) -> &[DeclaredCandidate] {
        &self.declared
    }

    /// `self` with the declared candidate built in at its parameters'
    /// values: the parameters added, the element bonded from its junction.
    /// The candidate itself is not removed (see
    /// [`BondGraph::remove_declared`]).
    ///
    /// # Errors
    /// Graph errors: a name taken, an unknown junction, a law that names
    /// what the model does not have, a broken structure.
    pub fn with_declared(&self, c: &DeclaredCandidate) -> Result<BondGraph> {
        let mut g = self.clone();
        for (name, p) in &c.params {
            g.add_param(name, p.value, &p.unit, &p.description)?;
        }
        let at = g.require(&c.at, &format!(" for candidate '{}'", c.element.name))?;
        let id = g.add(c.element.clone())?;
        g.bond(at, id)?;
        g.validate()?;
        Ok(g)
    }

    /// Adds a declared candidate, after checking that it builds into the
    /// model ([`BondGraph::with_declared`]) and that its junction is a
    /// junction.
    ///
    /// # Errors
    /// [`BondError::BadLaw`] naming the candidate for a junction that is
    /// not one or a duplicate name; the errors of building it in.
    pub fn add_declared(&mut self, c: DeclaredCandidate) -> Result<()> {
        let name = c.element.name.clone();
        let bad = |detail: String| BondError::BadLaw {
            element: format!("candidate {name}"),
            detail,
        };
        if self.declared.iter().any(|d| d.element.name == name) {
            return Err(bad("is declared twice".to_string()));
        }
        let at = self.require(&c.at, &format!(" for candidate '{name}'"))?;
        if !self.element(at).kind.is_junction() {
            return Err(bad(format!(
                "is bonded at '{}', which is not a junction (0 or 1)",
                c.at
            )));
        }
        self.with_declared(&c)
            .map_err(|e| bad(format!("does not build into the model: {e}")))?;
        self.declared.push(c);
        Ok(())
    }

    /// Removes the declared candidate called `name` (once it is built in).
    pub fn remove_declared(&mut self, name: &str) {
        self.declared.retain(|d| d.element.name != name);
    }

    /// All parameters, by name.
    pub fn params(&self) -> &BTreeMap<String, Parameter> {
        &self.params
    }

    /// All input signals, by name.
    pub fn inputs(&self) -> &BTreeMap<String, InputSignal> {
        &self.inputs
    }

    /// The measured outputs, in declaration order.
    pub fn outputs(&self) -> &[Output] {
        &self.outputs
    }

    /// All elements, indexed by [`ElementId`].
    pub fn elements(&self) -> &[Element] {
        &self.elements
    }

    /// All bonds, indexed by [`BondId`].
    pub fn bonds(&self) -> &[Bond] {
        &self.bonds
    }

    /// Ids of all bonds.
    pub fn bond_ids(&self) -> impl Iterator<Item = BondId> + '_ {
        (0..self.bonds.len() as u32).map(BondId)
    }

    /// Ids of all elements.
    pub fn element_ids(&self) -> impl Iterator<Item = ElementId> + '_ {
        (0..self.elements.len() as u32).map(ElementId)
    }

    /// The element with this id.
    ///
    /// # Panics
    /// If the id is not from this graph (a bug: ids are only handed out by `add`).
    pub fn element(&self, id: ElementId) -> &Element {
        &self.elements[id.0 as usize]
    }

    /// Mutable access to an element (to change its law or description).
    pub fn element_mut(&mut self, id: ElementId) -> &mut Element {
        &mut self.elements[id.0 as usize]
    }

    /// The bond with this id.
    pub fn bond_at(&self, id: BondId) -> Bond {
        self.bonds[id.index()]
    }

    /// The element called `name`.
    pub fn find(&self, name: &str) -> Option<ElementId> {
        self.elements
            .iter()
            .position(|e| e.name == name)
            .map(|i| ElementId(i as u32))
    }

    /// The element called `name`, or an error saying where it was needed.
    ///
    /// # Errors
    /// [`BondError::UnknownElement`].
    pub fn require(&self, name: &str, context: &str) -> Result<ElementId> {
        self.find(name).ok_or_else(|| BondError::UnknownElement {
            name: name.to_string(),
            context: context.to_string(),
        })
    }

    /// The bonds of an element with their direction seen from it, in bond order.
    pub fn ports(&self, id: ElementId) -> Vec<(BondId, Direction)> {
        let mut out = Vec::new();
        for (i, b) in self.bonds.iter().enumerate() {
            if b.to == id {
                out.push((BondId(i as u32), Direction::In));
            }
            if b.from == id {
                out.push((BondId(i as u32), Direction::Out));
            }
        }
        out
    }

    /// The element at the other end of a bond.
    pub fn other_end(&self, bond: BondId, id: ElementId) -> ElementId {
        let b = self.bonds[bond.index()];
        if b.from == id { b.to } else { b.from }
    }

    /// The law of an element with names resolved: a name declared as an
    /// input becomes [`Expr::Input`]; parameters stay [`Expr::Param`].
    pub fn resolved(&self, expr: &Expr) -> Expr {
        expr.map(&mut |e| match e {
            Expr::Param(name) if self.inputs.contains_key(name) => Some(Expr::Input(name.clone())),
            _ => None,
        })
    }

    /// Checks that every linear coefficient that depends on parameters only
    /// is physically possible: an I's inductance, inertia or mass and a C's
    /// capacitance are positive, an R's resistance is zero or positive, and
    /// every such coefficient (also a TF or GY modulus) is finite.
    /// Coefficients that follow an input or time are checked where a
    /// simulation starts instead (see [`crate::simulate::simulate`]).
    ///
    /// [`BondGraph::validate`] (so loading a model file, assigning causality
    /// and compiling) and [`BondGraph::set_param`] run this check.
    ///
    /// # Errors
    /// [`BondError::UnphysicalParameter`] naming the parameter, the element
    /// and its kind, the value and what is expected;
    /// [`BondError::LawNotFinite`] for a coefficient such as `1/0`.
    pub fn check_coefficients(&self) -> Result<()> {
        match self.element_ids().find_map(|id| self.coefficient_error(id)) {
            Some(err) => Err(err),
            None => Ok(()),
        }
    }

    /// The problem with an element's linear coefficient, if it has one.
    fn coefficient_error(&self, id: ElementId) -> Option<BondError> {
        let el = self.element(id);
        let Law::Linear(e) = &el.law else {
            return None;
        };
        let constant = matches!(
            el.kind,
            ElementKind::R | ElementKind::C | ElementKind::I | ElementKind::Tf | ElementKind::Gy
        );
        if !constant {
            return None;
        }
        // Parameters only: a coefficient that follows an input or time has no value here.
        let value = e.eval(&|leaf: &Expr| match leaf {
            Expr::Param(n) => self.params.get(n).map(|p| p.value),
            _ => None,
        })?;
        if !value.is_finite() {
            return Some(BondError::LawNotFinite {
                element: el.name.clone(),
                field: if el.kind.is_two_port() {
                    "modulus"
                } else {
                    "parameter"
                }
                .to_string(),
                law: e.to_string(),
                value,
                point: "whatever the state (it is a constant)".to_string(),
            });
        }
        let (ok, expected) = match el.kind {
            ElementKind::R => (value >= 0.0, "zero or positive"),
            ElementKind::C | ElementKind::I => (value > 0.0, "positive"),
            _ => return None,
        };
        if ok {
            return None;
        }
        let (param, expression) = match e {
            Expr::Param(name) => (name.clone(), false),
            _ => (e.to_string(), true),
        };
        let unit = e
            .params()
            .iter()
            .filter_map(|n| self.params.get(n))
            .map(|p| p.unit.trim())
            .find(|u| !u.is_empty())
            .unwrap_or("")
            .to_string();
        let quantity = coefficient_quantity(el.kind, &unit);
        Some(BondError::UnphysicalParameter {
            param,
            expression,
            element: el.name.clone(),
            kind: el.kind,
            quantity: if unit.is_empty() {
                quantity.to_string()
            } else {
                format!("{quantity}, {unit}")
            },
            expected,
            value,
        })
    }

    /// Checks the structure: bond counts and directions per element kind,
    /// laws present where needed, names in laws declared, outputs pointing
    /// at something that has the variable; then the coefficients
    /// ([`BondGraph::check_coefficients`]).
    ///
    /// # Errors
    /// The first problem found, naming the element, bond or output.
    pub fn validate(&self) -> Result<()> {
        if self.elements.is_empty() {
            return Err(BondError::BadLaw {
                element: self.name.clone(),
                detail: "the model has no elements".to_string(),
            });
        }
        for id in self.element_ids() {
            self.validate_element(id)?;
        }
        for out in &self.outputs {
            use crate::element::Measured;
            let bad = |detail: String| BondError::BadOutput {
                output: out.name.clone(),
                detail,
            };
            if let Measured::Expression(e) = &out.measured {
                for name in e.params() {
                    if !self.params.contains_key(&name) && !self.inputs.contains_key(&name) {
                        return Err(bad(format!(
                            "its expression names '{name}', which is not a parameter or input of the model"
                        )));
                    }
                }
                for local in e.locals() {
                    let Some((element, which)) = crate::expr::split_signal(&local) else {
                        return Err(bad(format!(
                            "its expression uses '{local}' alone; name the element (`Tank2.{local}`)"
                        )));
                    };
                    if let Some(detail) = self.signal_problem(element, which) {
                        return Err(bad(format!("reads '{local}': {detail}")));
                    }
                }
                continue;
            }
            let name = out.measured.element().unwrap_or_default();
            let id = self
                .find(name)
                .ok_or_else(|| bad(format!("refers to unknown element '{name}'")))?;
            let el = self.element(id);
            let ok = match (&out.measured, el.kind) {
                (Measured::State(_), k) => k.is_storage(),
                (Measured::Effort(_), ElementKind::One) => false,
                (Measured::Flow(_), ElementKind::Zero) => false,
                (_, k) => !k.is_two_port(),
            };
            if !ok {
                return Err(bad(format!(
                    "element '{}' ({}) has no single {} (a 1-junction has a common flow, a 0-junction a common effort, storage elements a state)",
                    el.name,
                    el.kind,
                    match out.measured {
                        Measured::Effort(_) => "effort",
                        Measured::Flow(_) => "flow",
                        _ => "state",
                    }
                )));
            }
        }
        self.check_coefficients()
    }

    /// Why `element.which` is not a signal of this model, if it is not: an
    /// unknown element, or one without that single variable.
    fn signal_problem(&self, element: &str, which: &str) -> Option<String> {
        let Some(id) = self.find(element) else {
            return Some(format!("the model has no element '{element}'"));
        };
        let kind = self.element(id).kind;
        let why = match (which, kind) {
            (_, k) if k.is_two_port() => {
                format!("a {k} has two bonds; read the junction or element beside it")
            }
            ("e", ElementKind::One) => {
                "a 1-junction has a common flow, not a single effort".to_string()
            }
            ("f", ElementKind::Zero) => {
                "a 0-junction has a common effort, not a single flow".to_string()
            }
            ("e" | "f", _) => return None,
            ("p", ElementKind::I) | ("q", ElementKind::C) => return None,
            ("p", k) => format!("only an I has a momentum p; '{element}' is a {k}"),
            ("q", k) => format!("only a C has a displacement q; '{element}' is a {k}"),
            (other, _) => format!("'{other}' is not e, f, p or q"),
        };
        Some(why)
    }

    fn validate_element(&self, id: ElementId) -> Result<()> {
        let el = self.element(id);
        let ports = self.ports(id);
        let bad = |detail: String| BondError::BadPorts {
            element: el.name.clone(),
            kind: el.kind.to_string(),
            detail,
        };
        let list = |ports: &[(BondId, Direction)]| {
            ports
                .iter()
                .map(|(b, _)| b.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        };
        match el.kind.n_ports() {
            Some(n) if ports.len() != n => {
                return Err(bad(format!(
                    "needs exactly {n} bond{}, has {}{}",
                    if n == 1 { "" } else { "s" },
                    ports.len(),
                    if ports.is_empty() {
                        String::new()
                    } else {
                        format!(" (bonds {})", list(&ports))
                    }
                )));
            }
            None if ports.is_empty() => return Err(bad("has no bonds".to_string())),
            _ => {}
        }
        if matches!(el.kind, ElementKind::R | ElementKind::C | ElementKind::I)
            && ports[0].1 != Direction::In
        {
            return Err(bad(format!(
                "must have its bond pointing into it (power in), but bond {} points out",
                ports[0].0
            )));
        }
        if el.kind.is_two_port() {
            let n_in = ports.iter().filter(|p| p.1 == Direction::In).count();
            if n_in != 1 {
                return Err(bad(format!(
                    "needs one bond in and one out (power through it), has {n_in} in (bonds {})",
                    list(&ports)
                )));
            }
        }
        // Laws: present where needed, names declared.
        let exprs: Vec<(&str, &Expr)> = match (&el.law, el.kind) {
            (Law::None, k) if k.is_junction() => vec![],
            (Law::Source(e), k) if k.is_source() => vec![("value", e)],
            (Law::Linear(e), k) if !k.is_junction() && !k.is_source() => vec![("parameter", e)],
            (Law::Nonlinear { effort, flow }, ElementKind::R | ElementKind::C | ElementKind::I) => {
                let mut v = Vec::new();
                if let Some(e) = effort {
                    v.push(("effort", e));
                }
                if let Some(f) = flow {
                    v.push(("flow", f));
                }
                if v.is_empty() {
                    return Err(BondError::BadLaw {
                        element: el.name.clone(),
                        detail: "a nonlinear law needs `effort` or `flow`".to_string(),
                    });
                }
                match el.kind {
                    ElementKind::C if effort.is_none() => {
                        return Err(BondError::BadLaw {
                            element: el.name.clone(),
                            detail: "a nonlinear C needs `effort = \"...(q)\"`".to_string(),
                        });
                    }
                    ElementKind::I if flow.is_none() => {
                        return Err(BondError::BadLaw {
                            element: el.name.clone(),
                            detail: "a nonlinear I needs `flow = \"...(p)\"`".to_string(),
                        });
                    }
                    _ => {}
                }
                v
            }
            (law, k) => {
                return Err(BondError::BadLaw {
                    element: el.name.clone(),
                    detail: format!("a {k} element cannot have a law of the form {law:?}"),
                });
            }
        };
        for (field, e) in exprs {
            for name in e.params() {
                if !self.params.contains_key(&name) && !self.inputs.contains_key(&name) {
                    return Err(BondError::UnknownName {
                        element: el.name.clone(),
                        name,
                    });
                }
            }
            let allowed: &[&str] = match (el.kind, field) {
                (ElementKind::R, "effort") => &["f"],
                (ElementKind::R, "flow") => &["e"],
                (ElementKind::C, "effort") => &["q"],
                (ElementKind::I, "flow") => &["p"],
                _ => &[],
            };
            for local in e.locals() {
                if let Some((element, which)) = crate::expr::split_signal(&local) {
                    if let Some(detail) = self.signal_problem(element, which) {
                        return Err(BondError::BadLaw {
                            element: el.name.clone(),
                            detail: format!("its {field} law reads the signal '{local}': {detail}"),
                        });
                    }
                    continue;
                }
                if !allowed.contains(&local.as_str()) {
                    return Err(BondError::BadLaw {
                        element: el.name.clone(),
                        detail: format!(
                            "its {field} law uses '{local}', but may only use {}",
                            if allowed.is_empty() {
                                "parameters, inputs, t and signals (`Tank1.q`)".to_string()
                            } else {
                                format!(
                                    "'{}', parameters, inputs, t and signals (`Tank1.q`)",
                                    allowed.join("', '")
                                )
                            }
                        ),
                    });
                }
            }
            let modulated = !e.inputs().is_empty()
                || e.depends_on_time()
                || !e.signals().is_empty()
                || !self.resolved(e).inputs().is_empty();
            if matches!(el.kind, ElementKind::Tf | ElementKind::Gy) && modulated {
                return Err(BondError::BadLaw {
                    element: el.name.clone(),
                    detail: format!(
                        "a {} modulus may not depend on inputs, signals or time; use M{}",
                        el.kind, el.kind
                    ),
                });
            }
            if matches!(el.kind, ElementKind::Mtf | ElementKind::Mgy) && !modulated {
                return Err(BondError::BadLaw {
                    element: el.name.clone(),
                    detail: format!("a {} modulus must follow an input, a signal or t", el.kind),
                });
            }
        }
        Ok(())
    }
}

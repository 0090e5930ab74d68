//! Sequential causality assignment (SCAP).
//!
//! The order is the textbook one: sources first, then each storage element
//! in integral causality, then each R still free, then any bond still free;
//! after every choice the consequences are propagated through junctions,
//! transformers and gyrators. Conflicts are errors that name the bond and
//! the elements; storage elements that propagation forces into derivative
//! causality, and R elements whose causality had to be chosen (the mark of
//! an algebraic loop), are reported in the result.

use std::collections::VecDeque;

use crate::element::ElementKind;
use crate::error::{BondError, Result};
use crate::graph::{BondGraph, BondId, ElementId};

/// The causal stroke of every bond: which end receives the effort.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Causality {
    effort_into: Vec<ElementId>,
    /// Storage elements forced into derivative causality, with their bond.
    pub derivative: Vec<(ElementId, BondId)>,
    /// R elements whose causality was not forced and had to be chosen
    /// (resistance causality was taken); their presence signals an
    /// algebraic loop among R elements.
    pub chosen_r: Vec<ElementId>,
    /// Bonds whose causality nothing fixed and that were chosen last.
    pub chosen_bonds: Vec<BondId>,
}

impl Causality {
    /// The element that receives the effort on `bond` (where the causal stroke is).
    pub fn effort_into(&self, bond: BondId) -> ElementId {
        self.effort_into[bond.0 as usize]
    }

    /// True when `element` receives the effort on `bond` (and so imposes the flow).
    pub fn receives_effort(&self, bond: BondId, element: ElementId) -> bool {
        self.effort_into(bond) == element
    }

    /// True when a storage element is in integral causality (an I receives
    /// effort, a C receives flow). False for other kinds.
    pub fn is_integral(&self, g: &BondGraph, element: ElementId) -> bool {
        let kind = g.element(element).kind;
        let Some(&(bond, _)) = g.ports(element).first() else {
            return false;
        };
        match kind {
            ElementKind::I => self.receives_effort(bond, element),
            ElementKind::C => !self.receives_effort(bond, element),
            _ => false,
        }
    }

    /// Errors if the equations cannot be simulated as an explicit ODE
    /// because storage elements are in derivative causality.
    ///
    /// # Errors
    /// [`BondError::DerivativeCausality`] naming the elements and bonds.
    pub fn require_integral(&self, g: &BondGraph) -> Result<()> {
        if self.derivative.is_empty() {
            return Ok(());
        }
        Err(BondError::DerivativeCausality {
            elements: self
                .derivative
                .iter()
                .map(|(e, _)| g.element(*e).name.clone())
                .collect::<Vec<_>>()
                .join(", "),
            bonds: self
                .derivative
                .iter()
                .map(|(_, b)| b.to_string())
                .collect::<Vec<_>>()
                .join(", "),
            hint: self.derivative_hint(g),
        })
    }

    /// What to change, by the kinds of storage in derivative causality.
    fn derivative_hint(&self, g: &BondGraph) -> String {
        let kinds: Vec<ElementKind> = (self.derivative.iter())
            .map(|(e, _)| g.element(*e).kind)
            .collect();
        let mut hints = Vec::new();
        if kinds.contains(&ElementKind::I) {
            hints.push(
                "an I there moves rigidly with another inertia or a flow source (its flow is set \
                 through junctions, transformers or gyrators): merge the two inertias into one \
                 (behind a transformer of ratio n an inertia counts n² times on the other side), \
                 or model the compliance between them (a C on a 0-junction: a shaft's \
                 stiffness, a belt's spring)",
            );
        }
        if kinds.contains(&ElementKind::C) {
            hints.push(
                "a C there is held at another capacitance's effort or an effort source's: \
                 merge the two capacitances into one, or model the resistance between them (an \
                 R on a 1-junction: a pipe, a wire)",
            );
        }
        hints.join("; ")
    }
}

/// Runs the sequential causality assignment on a validated graph.
///
/// # Errors
/// [`BondError::CausalConflict`] when two sources (or a source and the
/// structure) demand opposite causality on one bond, or a junction gets no or
/// two causal inputs; the message names the bond, its two elements and the
/// demands that met. Structural errors from [`BondGraph::validate`] first.
pub fn assign_causality(g: &BondGraph) -> Result<Causality> {
    g.validate()?;
    let mut a = Assigner {
        g,
        stroke: vec![None; g.bonds().len()],
        origin: vec![None; g.bonds().len()],
        decision: None,
        queue: VecDeque::new(),
    };
    let ids: Vec<ElementId> = g.element_ids().collect();

    // 1. Sources.
    for &id in &ids {
        if g.element(id).kind.is_source() {
            let (bond, _) = g.ports(id)[0];
            let target = match g.element(id).kind {
                ElementKind::Se => g.other_end(bond, id),
                _ => id,
            };
            a.decision = Some((id, bond));
            a.set(bond, target, id)?;
            a.propagate()?;
        }
    }
    // 2. Storage in integral causality.
    let mut derivative = Vec::new();
    for &id in &ids {
        let kind = g.element(id).kind;
        if !kind.is_storage() {
            continue;
        }
        let (bond, _) = g.ports(id)[0];
        let integral = match kind {
            ElementKind::I => id,
            _ => g.other_end(bond, id),
        };
        match a.stroke[bond.0 as usize] {
            None => {
                a.decision = Some((id, bond));
                a.set(bond, integral, id)?;
                a.propagate()?;
            }
            Some(t) if t != integral => derivative.push((id, bond)),
            Some(_) => {}
        }
    }
    // 3. R elements still free: resistance causality.
    let mut chosen_r = Vec::new();
    for &id in &ids {
        if g.element(id).kind != ElementKind::R {
            continue;
        }
        let (bond, _) = g.ports(id)[0];
        if a.stroke[bond.0 as usize].is_none() {
            chosen_r.push(id);
            a.decision = Some((id, bond));
            a.set(bond, g.other_end(bond, id), id)?;
            a.propagate()?;
        }
    }
    // 4. Anything left (loops of junctions and two-ports).
    let mut chosen_bonds = Vec::new();
    for bond in g.bond_ids() {
        if a.stroke[bond.0 as usize].is_none() {
            chosen_bonds.push(bond);
            let to = g.bond_at(bond).to;
            a.decision = Some((to, bond));
            a.set(bond, to, to)?;
            a.propagate()?;
        }
    }
    // Final check of every constraint (catches junctions left with no causal input).
    for &id in &ids {
        a.check_complete(id)?;
    }
    let effort_into = a.stroke.iter().map(|s| s.unwrap_or(ElementId(0))).collect();
    Ok(Causality {
        effort_into,
        derivative,
        chosen_r,
        chosen_bonds,
    })
}

struct Assigner<'g> {
    g: &'g BondGraph,
    stroke: Vec<Option<ElementId>>,
    /// Per bond, the decision (element and its bond) whose propagation set the stroke.
    origin: Vec<Option<(ElementId, BondId)>>,
    /// The decision being propagated.
    decision: Option<(ElementId, BondId)>,
    queue: VecDeque<ElementId>,
}

impl Assigner<'_> {
    fn name(&self, id: ElementId) -> String {
        let e = self.g.element(id);
        format!("{} '{}'", e.kind, e.name)
    }

    /// " (set by Se 'V1' through bond 1)": who fixed the stroke already on `bond`.
    fn origin(&self, bond: BondId) -> String {
        match self.origin[bond.0 as usize] {
            Some((id, b)) => format!(" (set by {} through bond {b})", self.name(id)),
            None => String::new(),
        }
    }

    fn conflict(&self, bond: BondId, detail: String) -> BondError {
        let b = self.g.bond_at(bond);
        BondError::CausalConflict {
            bond: bond.number(),
            from: self.g.element(b.from).name.clone(),
            to: self.g.element(b.to).name.clone(),
            detail,
        }
    }

    /// Sets the stroke of `bond` so that `into` receives the effort, as
    /// demanded by `by`. Errors if the bond already has the opposite stroke.
    fn set(&mut self, bond: BondId, into: ElementId, by: ElementId) -> Result<()> {
        match self.stroke[bond.0 as usize] {
            Some(t) if t == into => Ok(()),
            Some(t) => Err(self.conflict(
                bond,
                format!(
                    "{} demands that {} receive the effort, but it is already imposed on {}{}",
                    self.name(by),
                    self.name(into),
                    self.name(t),
                    self.origin(bond)
                ),
            )),
            None => {
                self.stroke[bond.0 as usize] = Some(into);
                self.origin[bond.0 as usize] = self.decision;
                let b = self.g.bond_at(bond);
                self.queue.push_back(b.from);
                self.queue.push_back(b.to);
                Ok(())
            }
        }
    }

    fn propagate(&mut self) -> Result<()> {
        while let Some(id) = self.queue.pop_front() {
            self.apply(id)?;
        }
        Ok(())
    }

    /// Applies the causal rule of element `id` to its partially assigned bonds.
    fn apply(&mut self, id: ElementId) -> Result<()> {
        let kind = self.g.element(id).kind;
        let ports = self.g.ports(id);
        match kind {
            ElementKind::Zero | ElementKind::One => {
                // The "strong" bond: the one that imposes the junction's common
                // variable. At a 0-junction it brings the effort in (stroke at
                // the junction); at a 1-junction it brings the flow in (stroke
                // at the other end).
                let is_strong = |s: ElementId| {
                    if kind == ElementKind::Zero {
                        s == id
                    } else {
                        s != id
                    }
                };
                let strong: Vec<BondId> = ports
                    .iter()
                    .filter(|(b, _)| self.stroke[b.0 as usize].is_some_and(is_strong))
                    .map(|(b, _)| *b)
                    .collect();
                let free: Vec<BondId> = ports
                    .iter()
                    .filter(|(b, _)| self.stroke[b.0 as usize].is_none())
                    .map(|(b, _)| *b)
                    .collect();
                let what = if kind == ElementKind::Zero {
                    "effort"
                } else {
                    "flow"
                };
                if strong.len() > 1 {
                    return Err(self.conflict(
                        strong[1],
                        format!(
                            "{} gets its common {what} imposed by bonds {} at once ({}); a junction takes it from exactly one bond",
                            self.name(id),
                            strong.iter().map(|b| b.to_string()).collect::<Vec<_>>().join(" and "),
                            strong.iter().map(|b| self.name(self.g.other_end(*b, id))).collect::<Vec<_>>().join(", "),
                        ),
                    ));
                }
                if strong.len() == 1 {
                    for b in free {
                        let into = if kind == ElementKind::Zero {
                            self.g.other_end(b, id)
                        } else {
                            id
                        };
                        self.set(b, into, id)?;
                    }
                } else if free.len() == 1 {
                    let b = free[0];
                    let into = if kind == ElementKind::Zero {
                        id
                    } else {
                        self.g.other_end(b, id)
                    };
                    self.set(b, into, id)?;
                }
            }
            ElementKind::Tf | ElementKind::Mtf | ElementKind::Gy | ElementKind::Mgy => {
                let (b1, _) = ports[0];
                let (b2, _) = ports[1];
                let same = kind.is_gyrator();
                let other = |s: &Self, from: BondId, to: BondId| -> Option<ElementId> {
                    let into_self = s.stroke[from.0 as usize]? == id;
                    let want_into_self = if same { into_self } else { !into_self };
                    Some(if want_into_self {
                        id
                    } else {
                        s.g.other_end(to, id)
                    })
                };
                if let Some(into) = other(self, b1, b2) {
                    self.set(b2, into, id)?;
                } else if let Some(into) = other(self, b2, b1) {
                    self.set(b1, into, id)?;
                }
            }
            ElementKind::Se | ElementKind::Sf => {
                let (b, _) = ports[0];
                let want = if kind == ElementKind::Se {
                    self.g.other_end(b, id)
                } else {
                    id
                };
                if let Some(s) = self.stroke[b.0 as usize]
                    && s != want
                {
                    return Err(self.conflict(
                        b,
                        format!(
                            "{} must impose its {} but the rest of the graph imposes it on the source{}",
                            self.name(id),
                            if kind == ElementKind::Se { "effort" } else { "flow" },
                            self.origin(b)
                        ),
                    ));
                }
            }
            ElementKind::R | ElementKind::C | ElementKind::I => {}
        }
        Ok(())
    }

    fn check_complete(&self, id: ElementId) -> Result<()> {
        let kind = self.g.element(id).kind;
        if !kind.is_junction() {
            return Ok(());
        }
        let ports = self.g.ports(id);
        let n_strong = ports
            .iter()
            .filter(|(b, _)| {
                let s = self.stroke[b.0 as usize];
                if kind == ElementKind::Zero {
                    s == Some(id)
                } else {
                    s.is_some_and(|s| s != id)
                }
            })
            .count();
        if n_strong != 1 {
            let what = if kind == ElementKind::Zero {
                "effort"
            } else {
                "flow"
            };
            return Err(self.conflict(
                ports[0].0,
                format!(
                    "{} has its common {what} imposed by {n_strong} bonds (bonds {}); it must come from exactly one",
                    self.name(id),
                    ports.iter().map(|(b, _)| b.to_string()).collect::<Vec<_>>().join(", ")
                ),
            ));
        }
        Ok(())
    }
}

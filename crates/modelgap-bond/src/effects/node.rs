//! Where storage-node effects attach: 0-junctions with a C bonded to them —
//! a tank's level, a thermal mass's temperature, a capacitor's voltage, a
//! pressure node. Any domain; the words follow the C's unit when it has one.
//!
//! A capacitor, a thermal mass or a tank whose C a model bonds straight to a
//! 1-junction (a series RLC loop) is a node too: what leaks across it or flows
//! into it has nowhere else to act. Its node is the C itself until an effect
//! attaches there; the edit then puts a 0-junction between the C and its
//! 1-junction ([`Node::junction`]), which changes nothing else. A spring (a C
//! whose unit names no node kind) is left as it is.

use modelgap_core::{Candidate, EffectParam};

use super::edit::ident;
use super::menu::{law_value, place};
use super::scales::Scales;
use super::tag::Tag;
use crate::element::{ElementKind, Law, Measured};
use crate::expr::Expr;
use crate::graph::{BondGraph, ElementId};

/// What a node's storage is: the junction's declared domain, else the unit
/// of its C's parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeKind {
    /// A tank or a pressure node (a C in m^3/Pa, m^5/N, m^2).
    Hydraulic,
    /// A thermal mass (a C in J/K).
    Thermal,
    /// A capacitor node (a C in F).
    Electrical,
    /// No unit to go by.
    Generic,
}

impl NodeKind {
    /// The kind of node a C's parameter unit says.
    pub fn of_unit(unit: &str) -> NodeKind {
        let compact: String = unit.chars().filter(|c| !c.is_whitespace()).collect();
        match compact.as_str() {
            "m^3/Pa" | "m^5/N" | "m^2" | "m3/Pa" | "m²" => NodeKind::Hydraulic,
            "J/K" | "J/degC" => NodeKind::Thermal,
            "F" => NodeKind::Electrical,
            _ => NodeKind::Generic,
        }
    }
}

impl Node {
    /// The units of the node's effort and flow: what its kind says, `e` and
    /// `f` for a generic node. A hydraulic node whose C is an area (m^2)
    /// holds a level in m; otherwise a pressure in Pa.
    pub fn units(self) -> (&'static str, &'static str) {
        if !self.units_known {
            return ("e", "f");
        }
        match self.kind {
            NodeKind::Hydraulic if self.level => ("m", "m^3/s"),
            NodeKind::Hydraulic => ("Pa", "m^3/s"),
            NodeKind::Thermal if self.celsius => ("degC", "W"),
            NodeKind::Thermal => ("K", "W"),
            NodeKind::Electrical => ("V", "A"),
            NodeKind::Generic => ("e", "f"),
        }
    }

    /// The unit of a conductance here (flow per effort).
    pub fn conductance_unit(self) -> String {
        let (e, f) = self.units();
        format!("{f}/{e}")
    }

    /// The unit of a resistance here (effort per flow): `K/W`, `Ohm`,
    /// `s/m^2` for a level, `Pa s/m^3` for a pressure, `e/f` without units.
    pub fn resistance_unit(self) -> String {
        if !self.units_known {
            return "e/f".to_string();
        }
        match self.kind {
            NodeKind::Hydraulic if self.level => "s/m^2".to_string(),
            NodeKind::Hydraulic => "Pa s/m^3".to_string(),
            NodeKind::Thermal => "K/W".to_string(),
            NodeKind::Electrical => "Ohm".to_string(),
            NodeKind::Generic => "e/f".to_string(),
        }
    }

    /// The unit of a storage capacity here (stored quantity per effort):
    /// `J/K`, `F`, `m^2` for a level, `m^3/Pa`, `f s/e` without units.
    pub fn capacity_unit(self) -> String {
        if !self.units_known {
            return "f s/e".to_string();
        }
        match self.kind {
            NodeKind::Hydraulic if self.level => "m^2".to_string(),
            NodeKind::Hydraulic => "m^3/Pa".to_string(),
            NodeKind::Thermal => "J/K".to_string(),
            NodeKind::Electrical => "F".to_string(),
            NodeKind::Generic => "f s/e".to_string(),
        }
    }

    /// The node's capacity (stored quantity per unit of effort): its C's
    /// linear coefficient, else the peak stored quantity over the peak
    /// effort of the run the scales come from, else 1.
    pub(super) fn capacity(self, g: &BondGraph, scales: &Scales) -> f64 {
        if let Law::Linear(c) = &g.element(self.storage).law
            && let Some(v) = law_value(g, c).filter(|v| v.is_finite() && *v > 0.0)
        {
            return v;
        }
        let q = scales.state_peak.get(&self.storage).copied().unwrap_or(0.0);
        let ratio = q / self.effort_peak(scales);
        if ratio.is_finite() && ratio > 0.0 {
            ratio
        } else {
            1.0
        }
    }
}

/// A 0-junction with a C, or a C alone on a 1-junction whose unit names what it
/// stores: where leakage, a constant inflow and an overflow attach.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Node {
    /// The 0-junction; for a C alone on a 1-junction, the C (see [`Node::junction`]).
    pub id: ElementId,
    /// What its storage is.
    pub kind: NodeKind,
    /// True when its C is an area (m^2): the effort is a level.
    pub level: bool,
    /// False when the domain is declared but the C's unit does not say the
    /// effort's unit (a tank whose level is read in a sensor's volts): the
    /// domain's physics apply, its SI units are not claimed.
    pub units_known: bool,
    /// The C that stores at the node.
    pub storage: ElementId,
    /// A thermal node whose temperature is in degrees Celsius (its C in J/degC, or an
    /// output reading its effort in degC): an absolute temperature is not in K.
    pub celsius: bool,
}

impl Node {
    /// The node `id`, when it is a 0-junction with a C bonded to it, or a C alone on a
    /// 1-junction whose unit names a node kind (F, J/K, m², m³/Pa; not a spring).
    pub fn of(g: &BondGraph, id: ElementId) -> Option<Node> {
        match g.element(id).kind {
            ElementKind::Zero => {
                let c = (g.ports(id).into_iter())
                    .map(|(b, _)| g.other_end(b, id))
                    .find(|&o| g.element(o).kind == ElementKind::C)?;
                Node::with_storage(g, id, c)
            }
            // A C alone on a 1-junction, whose unit says what it stores.
            ElementKind::C => {
                let ports = g.ports(id);
                let [(b, _)] = ports.as_slice() else {
                    return None;
                };
                if g.element(g.other_end(*b, id)).kind != ElementKind::One {
                    return None;
                }
                let node = Node::with_storage(g, id, id)?;
                (node.kind != NodeKind::Generic && node.units_known).then_some(node)
            }
            _ => None,
        }
    }

    /// The 0-junction where this node's effects attach: the node's own, or for a C on a
    /// 1-junction one put between them now (or by an earlier edit).
    ///
    /// # Errors
    /// When the junction cannot be added (its name taken).
    pub fn junction(self, g: &mut BondGraph) -> crate::error::Result<ElementId> {
        if g.element(self.id).kind != ElementKind::C {
            return Ok(self.id);
        }
        let ports = g.ports(self.id);
        let Some(&(bond, _)) = ports.first() else {
            return Ok(self.id);
        };
        let other = g.other_end(bond, self.id);
        if g.element(other).kind == ElementKind::Zero {
            return Ok(other);
        }
        let name = g.element(self.id).name.clone();
        let what = match self.kind {
            NodeKind::Electrical => "the voltage across",
            NodeKind::Thermal => "the temperature of",
            NodeKind::Hydraulic => "the level or pressure of",
            NodeKind::Generic => "the effort of",
        };
        let junction =
            crate::element::Element::zero(&super::edit::fresh_element(g, &format!("0_{name}")))
                .described(&format!("{what} {name}"));
        g.split_bond(bond, self.id, junction)
    }

    /// The node at `id` (a 0-junction, or a C on a 1-junction) whose storage is `c`.
    fn with_storage(g: &BondGraph, id: ElementId, c: ElementId) -> Option<Node> {
        // The unit of a parameter of the C's law: its capacity, linear (`parameter = "C"`) or
        // written out (`effort = "q / Cth"`, Cth in J/K). One that names a kind of node
        // first, else the first with a unit.
        let exprs: Vec<&Expr> = match &g.element(c).law {
            Law::Linear(e) => vec![e],
            Law::Nonlinear { effort, flow } => effort.iter().chain(flow.iter()).collect(),
            _ => Vec::new(),
        };
        let units: Vec<String> = (exprs.iter())
            .flat_map(|e| e.params())
            .filter_map(|n| g.params().get(&n))
            .map(|p| p.unit.clone())
            .filter(|u| !u.trim().is_empty())
            .collect();
        let unit = (units.iter())
            .find(|u| NodeKind::of_unit(u) != NodeKind::Generic)
            .or(units.first())
            .cloned()
            .unwrap_or_default();
        let compact: String = unit.chars().filter(|c| !c.is_whitespace()).collect();
        let level = matches!(compact.as_str(), "m^2" | "m²");
        let of_unit = NodeKind::of_unit(&unit);
        let is_celsius = |u: &str| matches!(u.trim(), "degC" | "°C" | "C°" | "Celsius");
        let name = &g.element(id).name;
        let celsius = compact.ends_with("degC")
            || (g.outputs().iter())
                .any(|o| o.measured == Measured::Effort(name.clone()) && is_celsius(&o.unit));
        if let Some(d) = g.element(id).domain {
            use crate::element::PhysicalDomain as D;
            let kind = match d {
                D::Hydraulic | D::Pneumatic => NodeKind::Hydraulic,
                D::Thermal => NodeKind::Thermal,
                D::Electrical => NodeKind::Electrical,
                _ => NodeKind::Generic,
            };
            return Some(Node {
                id,
                kind,
                level: level && kind == NodeKind::Hydraulic,
                units_known: of_unit == kind,
                storage: c,
                celsius,
            });
        }
        Some(Node {
            id,
            kind: of_unit,
            level,
            units_known: true,
            storage: c,
            celsius,
        })
    }

    /// Every node of `g`, in element order.
    pub fn all(g: &BondGraph) -> Vec<Node> {
        g.element_ids().filter_map(|id| Node::of(g, id)).collect()
    }

    /// The node's name (`top`).
    pub(super) fn name(self, g: &BondGraph) -> &str {
        &g.element(self.id).name
    }

    /// The suffix of what an edit adds here.
    pub(super) fn suffix(self, g: &BondGraph) -> String {
        ident(self.name(g))
    }

    /// "tank 1 (top)" from the junction's description, or "junction top"; a C on a
    /// 1-junction by its own description, or "element C" ([`place`]).
    pub(super) fn place(self, g: &BondGraph) -> String {
        place(g, self.id)
    }

    /// The largest effort (level, temperature, voltage) seen at the node.
    pub(super) fn effort_peak(self, scales: &Scales) -> f64 {
        let e = scales.effort(self.id);
        e.peak_or(e.strength())
    }

    /// The largest flow seen into or out of the node.
    pub(super) fn flow_peak(self, scales: &Scales) -> f64 {
        let f = scales.flow(self.id);
        f.peak_or(f.flow())
    }

    /// A missing-element candidate on this node.
    pub(super) fn candidate(
        self,
        g: &BondGraph,
        tag: Tag,
        name: String,
        params: Vec<EffectParam>,
    ) -> Candidate {
        super::junction::missing_element(tag, self.name(g), name, params)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::file::read_model;

    /// A heated block whose heat capacity is written out in the C's law (`q / Cth`, Cth in
    /// J/K): its node is thermal, in K and W, and the menu says so in its units and words.
    #[test]
    fn a_capacity_written_out_in_the_law_gives_the_node_its_units() {
        let src = r#"
name = "block"
[parameters]
Cth = { value = 900.0, unit = "J/K", description = "heat capacity" }
Rth = { value = 0.5, unit = "K/W", description = "convection" }
[inputs]
P = { default = 0.0, unit = "W", description = "heater" }
[[elements]]
name = "heater"
kind = "Sf"
flow = "P"
[[elements]]
name = "block"
kind = "0"
domain = "thermal"
[[elements]]
name = "Mass"
kind = "C"
effort = "q / Cth"
[[elements]]
name = "Convection"
kind = "R"
flow = "e / Rth"
[[bonds]]
from = "heater"
to = "block"
[[bonds]]
from = "block"
to = "Mass"
[[bonds]]
from = "block"
to = "Convection"
[[outputs]]
name = "T"
value = "Mass.q / Cth"
unit = "K"
"#;
        let g = read_model(src).unwrap();
        let id = g.find("block").unwrap();
        let node = Node::of(&g, id).unwrap();
        assert_eq!((node.kind, node.units_known), (NodeKind::Thermal, true));
        assert_eq!(node.units(), ("K", "W"));
        let menu = crate::effects::menu::candidates(&g);
        let cubic = menu
            .iter()
            .find(|c| c.id.starts_with("stiffness@"))
            .unwrap();
        assert_eq!(cubic.params[0].unit, "K/J^3");
        assert!(
            cubic.name.starts_with("a heat capacity that changes"),
            "{}",
            cubic.name
        );
        let relief = menu.iter().find(|c| c.id.starts_with("overflow@")).unwrap();
        let units: Vec<&str> = relief.params.iter().map(|p| p.unit.as_str()).collect();
        assert_eq!(units, ["K", "W/K"]);
        // Read in degrees Celsius, an absolute temperature is not in K.
        let celsius = src.replace(
            "value = \"Mass.q / Cth\"\nunit = \"K\"",
            "effort = \"block\"\nunit = \"degC\"",
        );
        let g = read_model(&celsius).unwrap();
        let node = Node::of(&g, g.find("block").unwrap()).unwrap();
        assert_eq!(node.units(), ("degC", "W"));
        // The power loss is refused where it does not belong, and with a bad value, naming it.
        let power = menu.iter().find(|c| c.id == "power@block").unwrap();
        let err = crate::effects::apply(&g, power, &[f64::NAN, 2.0]).unwrap_err();
        assert!(err.to_string().contains("power@block"), "{err}");
        let tank = read_model(&src.replace("\"thermal\"", "\"hydraulic\"")).unwrap();
        let err = crate::effects::apply(&tank, power, &[1e-3, 2.0]).unwrap_err();
        assert!(err.to_string().contains("not a thermal node"), "{err}");
    }
}

#[cfg(test)]
mod loop_capacitor {
    use super::*;
    use crate::file::read_model;
    use crate::simulate::{Drive, Inputs, SimOptions, simulate, time_grid};

    /// The series RLC loop of the examples: its capacitor bonded straight to the loop.
    const RLC: &str = include_str!("../../../../examples/models/series-rlc.toml");

    /// A capacitor alone on a series loop is an electrical node, its effort's scale is its
    /// voltage over the run, and the edit puts a 0-junction between it and the loop.
    #[test]
    fn a_capacitor_on_a_loop_is_a_node_with_its_voltage_as_scale() {
        let g = read_model(RLC).unwrap();
        let c = g.find("C").unwrap();
        let node = Node::of(&g, c).unwrap();
        assert_eq!((node.kind, node.units_known), (NodeKind::Electrical, true));
        let run = simulate(
            &g,
            &Inputs::new().with("V", Drive::Constant(5.0)),
            &time_grid(0.1, 1e4),
            &SimOptions::default(),
        )
        .unwrap();
        let scales = Scales::of_run(&g, &run);
        let peak = node.effort_peak(&scales);
        assert!(peak > 4.0 && peak < 10.0, "{peak}");
        let mut edited = g.clone();
        let j = node.junction(&mut edited).unwrap();
        assert_eq!(edited.element(j).kind, ElementKind::Zero);
        assert_eq!(node.junction(&mut edited).unwrap(), j, "once");
        assert!(Node::of(&edited, j).is_some() && Node::of(&edited, c).is_none());
        // A bond split at an element that is not its end: a typed error naming both.
        let r = edited.find("R").unwrap();
        let err = edited
            .split_bond(edited.ports(r)[0].0, c, crate::element::Element::zero("x"))
            .unwrap_err();
        let text = err.to_string();
        assert!(
            text.contains("C") && text.contains("is not an end of bond"),
            "{text}"
        );
        assert!(edited.find("x").is_none(), "nothing added");
        // A spring (a compliance in m/N) on a 1-junction is no node.
        let spring = RLC.replace(r#"unit = "F""#, r#"unit = "m/N""#);
        let g = read_model(&spring).unwrap();
        assert!(Node::of(&g, g.find("C").unwrap()).is_none());
    }
}

//! `fault:<p>` / `fault:<u>`: a parameter or a modulus changes abruptly at
//! an unknown time.

use modelgap_core::{Candidate, EffectKind, EffectParam};

use super::def::{EffectDef, QualTarget};
use super::scales::Scales;
use super::tag::Tag;
use super::{Deviation, Factor, T_FAULT};
use crate::error::Result;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

/// What an abrupt change changes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Faulted {
    /// A parameter takes a new value.
    Parameter(Deviation),
    /// The factor on a modulus input (1 before the fault) takes a new value.
    Modulus(Factor),
}

/// An abrupt change at an unknown time: the new value (as the deviation or
/// factor has it) and the fault time [`T_FAULT`]. The graph keeps its
/// nominal value; the change is a [`ParamChange`] during the simulation.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Fault {
    /// What changes.
    pub of: Faulted,
}

impl Fault {
    /// The parameter or modulus input the fault changes (`R`, `m`).
    fn target(&self) -> &str {
        match &self.of {
            Faulted::Parameter(d) => &d.param,
            Faulted::Modulus(f) => &f.input,
        }
    }
}

/// The fault-time parameter ([`T_FAULT`]): initial 0, bounds [0, 1e9] s,
/// which the measurement loop replaces by the recording's span.
fn t_fault_param() -> EffectParam {
    EffectParam::new(T_FAULT, "s", 0.0, (0.0, 1e9), 1.0)
}

impl EffectDef for Fault {
    /// A fault of every parameter, then of every modulus input.
    fn offers(g: &BondGraph) -> Vec<Fault> {
        let params = Deviation::offers(g).into_iter().map(Faulted::Parameter);
        let moduli = Factor::offers(g).into_iter().map(Faulted::Modulus);
        params.chain(moduli).map(|of| Fault { of }).collect()
    }

    fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        let (subject, value) = match &self.of {
            Faulted::Parameter(d) => (d.subject(g), d.value_param(g, scales)),
            Faulted::Modulus(f) => (f.subject(g), f.factor_param()),
        };
        Candidate {
            id: Tag::Fault.id(self.target()),
            name: format!("{subject} changes abruptly at an unknown time"),
            kind: EffectKind::AbruptChange,
            acts_on: self.target().to_string(),
            params: vec![value, t_fault_param()],
        }
    }

    /// Leaves the graph as it is (a modulus gets its factor at 1) and
    /// changes the value at `t_fault`.
    fn edit(&self, g: &mut BondGraph, c: &Candidate, values: &[f64]) -> Result<Vec<ParamChange>> {
        let name = match &self.of {
            Faulted::Parameter(d) => d.param.clone(),
            Faulted::Modulus(f) => f.add_factor(g, c, 1.0)?,
        };
        Ok(vec![ParamChange {
            at: values[1],
            name,
            value: values[0],
        }])
    }

    /// The parameter or input, either sign.
    fn qualitative_signature(&self, _g: &BondGraph) -> Option<Vec<QualTarget>> {
        Some(vec![(self.target().to_string(), None)])
    }
}

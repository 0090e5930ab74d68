//! Bond graphs: modelling, causality, equations, simulation and fault diagnosis.

pub mod arr;
pub mod causality;
pub mod compiled;
pub mod element;
pub mod equations;
pub mod error;
pub mod expr;
pub mod file;
pub mod graph;
pub mod library;
pub mod notation;
pub mod ode;
pub mod simulate;
pub mod state_space;
pub mod table7;

pub use causality::{Causality, assign_causality};
pub use compiled::CompiledModel;
pub use element::{Element, ElementKind, Law, Measured, Output};
pub use equations::Equations;
pub use error::{BondError, Result};
pub use graph::{BondGraph, BondId, ElementId};
pub use state_space::StateSpace;
pub mod causal_graph;
pub mod diagnosis;
pub mod fault_tree;
pub mod qual;
pub mod signature;

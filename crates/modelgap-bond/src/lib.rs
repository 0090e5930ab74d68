//! Bond graphs: modelling, causality, equations, simulation and model-based
//! fault diagnosis.
//!
//! A [`BondGraph`] holds elements (Se, Sf, R, C, I, TF, GY, MTF, MGY, 0, 1)
//! joined by bonds with a power direction, named parameters with units,
//! input signals and measured outputs; it is read from and written to a TOML
//! model file ([`file`](mod@file)). From it the crate derives the causality
//! ([`causality`], the sequential procedure), the causal equations and the
//! state equations in momenta and displacements ([`equations`], printed in
//! the paper's notation by [`notation`]), a compiled tape
//! ([`compiled`]) that the simulator ([`simulate`], with the solvers of
//! [`ode`]) integrates, and the diagnosis of the DC-motor paper: causal
//! graph ([`causal_graph`]), fault trees ([`fault_tree`]), temporal
//! signatures ([`signature`]), the progressive diagnosis of a recording
//! ([`diagnosis`]), the paper's Table 7 ([`table7`]), and analytical
//! redundancy relations ([`arr`]).
//!
//! ```
//! use modelgap_bond::diagnosis::{DiagnosisOptions, diagnose};
//! use modelgap_bond::simulate::{Inputs, ParamChange, SimOptions, simulate, time_grid};
//! use modelgap_bond::{CompiledModel, library};
//!
//! let motor = library::dc_motor();
//! let x0 = CompiledModel::new(&motor).unwrap().steady_state(&[12.0, 0.0], None).unwrap();
//! // The process: R rises 20 % at t = 0.2 s.
//! let fault = ParamChange { at: 0.2, name: "R".into(), value: 1.2 };
//! let opts = SimOptions { initial_state: Some(x0), changes: vec![fault], ..SimOptions::default() };
//! let run = simulate(&motor, &Inputs::new(), &time_grid(1.0, 1000.0), &opts).unwrap();
//! // The diagnosis: a parallel model, residuals, fault trees, signatures.
//! let recording = run.to_recording(false).unwrap();
//! let d = diagnose(&motor, &recording, &DiagnosisOptions { steady_start: true, ..Default::default() }).unwrap();
//! assert!(d.parameters().contains(&"R".to_string()));
//! ```
//!
//! Modules: [`element`], [`graph`] (the model), [`file`](mod@file), [`library`](mod@library)
//! (built-ins `dc-motor`, `buck-motor`), [`expr`] (laws, printing, tape),
//! [`causality`], [`equations`], [`notation`], [`compiled`], [`state_space`]
//! (linearisation, eigenvalues), [`simulate`], [`ode`], [`qual`],
//! [`causal_graph`], [`fault_tree`], [`signature`], [`diagnosis`],
//! [`table7`], [`arr`], [`error`].

pub mod arr;
pub mod causality;
pub mod compiled;
pub mod effects;
pub mod element;
pub mod equations;
pub mod error;
pub mod estimate;
pub mod exact;
pub mod expr;
pub mod file;
pub mod graph;
pub mod hidden;
pub mod input_hold;
pub mod library;
pub mod model;
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
pub use model::BondModel;
pub use state_space::StateSpace;
pub mod causal_graph;
pub mod diagnosis;
pub mod fault_tree;
pub mod qual;
pub mod signature;

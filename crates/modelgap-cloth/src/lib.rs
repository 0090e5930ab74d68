//! Impulse-based simulation of inextensible cloth (Bender & Bayer).
//!
//! A cloth is a mesh of particles joined by distance constraints, one per
//! edge. Each step previews the particles' free motion under constant
//! external forces, then computes equal and opposite impulses at the start of
//! the step so that every constraint holds at its end, within a relative
//! stretch tolerance (0.01 % by default). Gauss–Seidel over the constraints is
//! the paper's any-time iteration; a global Newton solve with a sparse
//! Cholesky factor (kept across iterations and steps) is the fast exact one,
//! and the default.
//! Contacts with static colliders and Coulomb friction are resolved inside the
//! same loop.
//!
//! ```
//! use modelgap_cloth::{ClothWorld, GridCloth, Method, SolverParams};
//!
//! let params = SolverParams { stretch_tolerance: 1e-4, method: Method::Newton, ..SolverParams::default() };
//! let mut world = ClothWorld::new(params);
//! // 10 x 10 vertices, 5 cm apart, hanging from one corner.
//! let cloth = world.add_cloth(GridCloth::new(10, 10, 0.05).pin(0))?;
//! for _ in 0..10 {
//!     let report = world.step(0.01)?; // StepReport { iterations, max_stretch, converged, .. }
//!     assert!(report.converged && report.max_stretch <= 1e-4);
//! }
//! let lowest = world.positions(cloth).iter().map(|x| x.y).fold(f64::INFINITY, f64::min);
//! assert!(lowest < 0.0);
//! # Ok::<(), modelgap_cloth::ClothError>(())
//! ```
//!
//! Modules: [`particles`] ([`ParticleSet`]), [`constraints`]
//! ([`DistanceConstraints`]), `kernel` (crate-private: the terms of one
//! distance constraint — its length and direction, its compliant value, the
//! impulse that satisfies it and its application — written once and used
//! by every solver), [`mesh`] ([`GridCloth`], OBJ meshes, the
//! vertex numbering), [`solver`] ([`SolverParams`], [`StepReport`],
//! [`Fallback`], the Gauss–Seidel sweep), [`colouring`] (constraint colours,
//! the coloured parallel sweep), [`strips`] (acyclic strips solved in linear
//! time, the paper's acceleration), [`newton`] (the global solve), [`contact`]
//! ([`Collider`]), [`world`] ([`ClothWorld`]; its step in named stages:
//! check, preview, choose the solver, warm start, solve the constraints,
//! commit, divergence check), [`kinematic`] ([`PinPath`]:
//! pins that follow a path), [`rail`] ([`Rail`]: a moving frame that pinned
//! vertices ride, its motion an expression of `t` or samples), [`markers`] ([`MarkerRecording`], marker CSV and
//! MCAP files), [`scenes`] (the reference scenes), [`trajectory`] (running a
//! scene, its recorded frames and Foxglove MCAP), [`forces`] (drag, wind,
//! damping, bending springs: [`ClothForces`]; a scene's [`ClothEffects`]),
//! [`bending`] (quadratic bending, integrated implicitly), [`material`]
//! (materials per region: compliance, warp and weft, bending, damping), [`model`]
//! ([`ClothModel`]: a scene as the measurement loop's model), [`hidden`]
//! (recordings with a hidden effect), [`error`].

pub mod bending;
pub mod colouring;
pub mod constraints;
pub mod contact;
pub mod error;
pub mod forces;
pub mod hidden;
mod kernel;
pub mod kinematic;
pub mod markers;
pub mod material;
pub mod mesh;
pub mod model;
pub mod newton;
pub mod particles;
pub mod rail;
pub mod report;
pub mod scene_world;
pub mod scenes;
pub mod solver;
pub mod strips;
pub mod trajectory;
pub mod world;

pub use constraints::DistanceConstraints;
pub use contact::{Collider, ColliderId, Shape};
pub use error::{ClothError, Result};
pub use forces::{ClothEffects, ClothForces, PointMass};
pub use kinematic::{KinematicPin, PinMotion, PinPath};
pub use markers::MarkerRecording;
pub use mesh::{BuildMesh, ClothMesh, GridCloth, GridEdges};
pub use model::{ClothModel, PredictSettings};
pub use particles::{ParticleId, ParticleSet};
pub use rail::Rail;
pub use scenes::Scene;
pub use solver::{Fallback, Integrator, Method, SolverParams, StepReport};
pub use world::{ClothId, ClothWorld, STALL_MARGIN, Stagnation};

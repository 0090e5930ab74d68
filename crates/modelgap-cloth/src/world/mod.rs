//! The cloth world: particles, constraints, colliders, and the step.
//!
//! [`ClothWorld::step`] (in `world/step.rs`) reads top to bottom as its
//! stages, each a small function: check the input, preview the free motion,
//! choose and prepare the solver (falling back to Gauss–Seidel, and saying
//! so, when Newton cannot run), warm-start the impulses, solve the
//! constraints (Newton's global solve, or serial, coloured or strip sweeps
//! until they hold), commit positions and velocities (with the velocity part
//! and contact velocities), and check for divergence. The solvers share one
//! constraint kernel (`kernel.rs`).

mod step;

pub use step::{
    BDF2_BACKOFF, BDF2_MAX_ITERATIONS, BDF2_WEIGHT, STALL_MARGIN, SWEEP_STALL_RATIO,
    SWEEP_STALL_WINDOW,
};

use std::ops::Range;

use nalgebra::Vector3;

use crate::colouring::ColouredSweep;
use crate::constraints::DistanceConstraints;
use crate::contact::{Collider, ColliderId, ContactState};
use crate::error::{ClothError, Result};
use crate::kinematic::{KinematicPin, PinMotion, PinPath};
use crate::mesh::{BuildMesh, ClothMesh};
use crate::newton::NewtonSolver;
use crate::particles::{ParticleId, ParticleSet};
use crate::rail::Rail;
use crate::solver::{SolverParams, StepReport};
use crate::strips::StripSweep;

/// The id of a cloth in a [`ClothWorld`], handed out by [`ClothWorld::add_cloth`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ClothId(pub u32);

/// Where a cloth's particles and constraints live in the world's columns.
#[derive(Clone, Debug)]
struct ClothEntry {
    particles: Range<usize>,
    constraints: Range<usize>,
    triangles: Vec<[u32; 3]>,
}

/// Scratch memory of a step, cleared and reused, never dropped mid-run.
#[derive(Debug, Default)]
struct SolverWorkspace {
    pred: Vec<Vector3<f64>>,
    free: Vec<Vector3<f64>>,
    mu: Vec<f64>,
    contacts: Vec<ContactState>,
    /// The weighted step `β h` of the last solve (s): impulses scale with its
    /// square, so the warm start rescales by the ratio.
    last_dt: Option<f64>,
    /// The state a step started from, kept for the next step's
    /// [`Integrator::Bdf2`](crate::solver::Integrator::Bdf2): dropped when the
    /// state is edited or the topology changes.
    history: Option<History>,
    /// Impulse steps left before BDF2 is tried again (see `BDF2_BACKOFF`).
    bdf2_backoff: usize,
    newton: Option<NewtonSolver>,
    /// The coloured sweep (colouring and scratch), built on the first step
    /// with [`SolverParams::coloured_sweep`], dropped on a topology change.
    coloured: Option<ColouredSweep>,
    /// The strip sweep (strips and scratch), built on the first step with
    /// [`Method::Strips`], dropped on a topology change.
    strips: Option<StripSweep>,
    /// The smallest sweep error so far after each sweep (stagnation).
    best_errors: Vec<f64>,
}

/// The positions and velocities a step of `dt` started from (BDF2's `x_{n−1}`, `v_{n−1}`).
#[derive(Debug, Default)]
struct History {
    positions: Vec<Vector3<f64>>,
    velocities: Vec<Vector3<f64>>,
    dt: f64,
}

/// A world's record of a stretch tolerance it could not reach: the first step
/// whose iteration stagnated (the error stopped falling, see
/// [`StepReport::stagnated`]), the stretch reached, and the tolerance held
/// since. Its [`Display`](std::fmt::Display) is the warning the CLI prints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stagnation {
    /// The tolerance asked for (relative).
    pub requested: f64,
    /// The largest stretch a stagnated step ended with (relative): the
    /// achievable level.
    pub reached: f64,
    /// The first step that stagnated (1-based).
    pub step: usize,
    /// Its end time (s).
    pub time: f64,
    /// The tolerance held since ([`STALL_MARGIN`] × `reached`).
    pub floor: f64,
    /// Steps that stagnated.
    pub steps: usize,
}

impl std::fmt::Display for Stagnation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "stretch tolerance {:.1e} cannot be reached: the solver stopped improving at a \
             stretch of {:.2e} (step {}, t = {} s); the steps after it held {:.1e} instead \
             ({} step{} stagnated)",
            self.requested,
            self.reached,
            self.step,
            crate::error::num(self.time),
            self.floor,
            self.steps,
            if self.steps == 1 { "" } else { "s" }
        )
    }
}

/// All cloths and colliders of a simulation, stepped together.
///
/// # Example
/// ```
/// use modelgap_cloth::{ClothWorld, GridCloth, SolverParams};
/// let mut world = ClothWorld::new(SolverParams::default());
/// let cloth = world.add_cloth(GridCloth::new(10, 10, 0.05).pin(0).pin(9))?;
/// let report = world.step(0.01)?;
/// assert!(report.max_stretch.is_finite());
/// assert_eq!(world.positions(cloth).len(), 100);
/// # Ok::<(), modelgap_cloth::ClothError>(())
/// ```
#[derive(Debug)]
pub struct ClothWorld {
    params: SolverParams,
    particles: ParticleSet,
    constraints: DistanceConstraints,
    cloths: Vec<ClothEntry>,
    colliders: Vec<Collider>,
    kinematic: Vec<KinematicPin>,
    /// External force on each particle (N) besides gravity, constant over a step.
    external_forces: Vec<Vector3<f64>>,
    workspace: SolverWorkspace,
    /// Where the requested stretch tolerance proved out of reach.
    stagnation: Option<Stagnation>,
    time: f64,
    /// Steps taken (successful or diverged).
    n_steps: usize,
}

impl ClothWorld {
    /// An empty world with the given solver parameters.
    #[must_use]
    pub fn new(params: SolverParams) -> Self {
        Self {
            params,
            particles: ParticleSet::new(),
            constraints: DistanceConstraints::new(),
            cloths: Vec::new(),
            colliders: Vec::new(),
            kinematic: Vec::new(),
            external_forces: Vec::new(),
            workspace: SolverWorkspace::default(),
            stagnation: None,
            time: 0.0,
            n_steps: 0,
        }
    }

    /// Adds a cloth: a particle per vertex (pinned vertices static), a
    /// distance constraint per edge with its current length as rest length.
    /// An edge between two pinned vertices is not a constraint (no impulse can
    /// move either end; kinematic pins keep their distance by their motion), so
    /// a whole row or border can be pinned.
    ///
    /// # Errors
    /// The mesh's own errors ([`ClothMesh::check`]): an empty mesh, a
    /// zero-length edge, a non-finite position, a vertex out of range.
    pub fn add_cloth(&mut self, cloth: impl BuildMesh) -> Result<ClothId> {
        let mesh: ClothMesh = cloth.build_mesh()?;
        mesh.check()?;
        let first = self.particles.len();
        for (v, (x, m)) in mesh.positions.iter().zip(&mesh.masses).enumerate() {
            let pinned = mesh.pinned.binary_search(&(v as u32)).is_ok();
            self.particles.push(*x, if pinned { 0.0 } else { 1.0 / m });
        }
        let first_constraint = self.constraints.len();
        for &[a, b] in &mesh.edges {
            let pinned = |v: u32| mesh.pinned.binary_search(&v).is_ok();
            if pinned(a) && pinned(b) {
                continue;
            }
            let rest = (mesh.positions[a as usize] - mesh.positions[b as usize]).norm();
            self.constraints
                .push(first as u32 + a, first as u32 + b, rest);
        }
        self.external_forces
            .resize(self.particles.len(), Vector3::zeros());
        let id = ClothId(self.cloths.len() as u32);
        self.cloths.push(ClothEntry {
            particles: first..self.particles.len(),
            constraints: first_constraint..self.constraints.len(),
            triangles: mesh.triangles,
        });
        self.topology_changed();
        Ok(id)
    }

    /// Makes every constraint of a cloth compliant: it stretches by
    /// `compliance` m per newton of tension (0: inextensible, the default).
    /// Both solvers then hold the compliant length `rest + α λ` within the
    /// stretch tolerance instead of the rest length.
    ///
    /// # Errors
    /// [`ClothError::UnknownCloth`], or [`ClothError::BadParameter`] for a
    /// negative or non-finite compliance.
    pub fn set_compliance(&mut self, cloth: ClothId, compliance: f64) -> Result<()> {
        if !(compliance >= 0.0 && compliance.is_finite()) {
            return Err(ClothError::BadParameter {
                name: "compliance",
                expected: "non-negative and finite (m/N)",
                value: compliance,
            });
        }
        let entry = self
            .cloths
            .get(cloth.0 as usize)
            .ok_or(ClothError::UnknownCloth {
                id: cloth.0,
                n_cloths: self.cloths.len(),
            })?;
        self.constraints.compliance[entry.constraints.clone()].fill(compliance);
        Ok(())
    }

    /// Sets the compliance of each constraint of a cloth from its two ends:
    /// `compliance(a, b)` (m/N) for the edge between mesh vertices `a` and `b`
    /// (materials per region, warp and weft: [`crate::material`]).
    ///
    /// # Errors
    /// [`ClothError::UnknownCloth`], or [`ClothError::BadParameter`] for a
    /// negative or non-finite compliance (nothing is changed then).
    pub fn set_link_compliance(
        &mut self,
        cloth: ClothId,
        mut compliance: impl FnMut(u32, u32) -> f64,
    ) -> Result<()> {
        let entry = self
            .cloths
            .get(cloth.0 as usize)
            .ok_or(ClothError::UnknownCloth {
                id: cloth.0,
                n_cloths: self.cloths.len(),
            })?;
        let first = entry.particles.start as u32;
        let cs = &self.constraints;
        let values: Vec<f64> = entry
            .constraints
            .clone()
            .map(|k| compliance(cs.a[k] - first, cs.b[k] - first))
            .collect();
        if let Some(&bad) = values.iter().find(|a| !(**a >= 0.0 && a.is_finite())) {
            return Err(ClothError::BadParameter {
                name: "compliance",
                expected: "non-negative and finite (m/N)",
                value: bad,
            });
        }
        self.constraints.compliance[entry.constraints.clone()].copy_from_slice(&values);
        Ok(())
    }

    /// Adds a static collider.
    pub fn add_collider(&mut self, collider: Collider) -> ColliderId {
        self.colliders.push(collider);
        ColliderId(self.colliders.len() as u32 - 1)
    }

    /// Makes a pinned vertex of a cloth follow `path` (see [`crate::kinematic`]): it moves
    /// to the path's position at the current time now, and to the path's position at the
    /// end of each step during the step. A vertex that already follows a path (or a rail)
    /// gets the new one.
    ///
    /// # Errors
    ///
    /// [`ClothError::UnknownCloth`], [`ClothError::VertexOutOfRange`], or
    /// [`ClothError::NotPinned`] when the vertex is dynamic.
    pub fn add_kinematic_pin(
        &mut self,
        cloth: ClothId,
        vertex: usize,
        path: PinPath,
    ) -> Result<ParticleId> {
        let particle = self.pinned_particle(cloth, vertex)?;
        self.particles.positions[particle.index()] = path.at(self.time);
        self.set_motion(particle, PinMotion::Path(path));
        Ok(particle)
    }

    /// Makes a pinned vertex of a cloth ride `rail` (see [`crate::rail`]): it keeps its
    /// offset in the rail's frame from where it is now, so attaching does not move it. A
    /// vertex that already follows a path or a rail rides this one instead.
    ///
    /// # Errors
    ///
    /// [`ClothError::UnknownCloth`], [`ClothError::VertexOutOfRange`],
    /// [`ClothError::NotPinned`] when the vertex is dynamic.
    pub fn attach_to_rail(
        &mut self,
        cloth: ClothId,
        vertex: usize,
        rail: std::sync::Arc<Rail>,
    ) -> Result<ParticleId> {
        let particle = self.pinned_particle(cloth, vertex)?;
        let local = rail.local(&self.particles.positions[particle.index()], self.time);
        self.set_motion(particle, PinMotion::Rail { rail, local });
        Ok(particle)
    }

    fn pinned_particle(&self, cloth: ClothId, vertex: usize) -> Result<ParticleId> {
        let particle = self.particle(cloth, vertex)?;
        if self.particles.is_static(particle.index()) {
            Ok(particle)
        } else {
            Err(ClothError::NotPinned { vertex })
        }
    }

    fn set_motion(&mut self, particle: ParticleId, motion: PinMotion) {
        self.particles.velocities[particle.index()] = Vector3::zeros();
        let pin = KinematicPin { particle, motion };
        match self.kinematic.iter_mut().find(|k| k.particle == particle) {
            Some(slot) => *slot = pin,
            None => self.kinematic.push(pin),
        }
    }

    /// The kinematic pins, in the order added.
    #[must_use]
    pub fn kinematic_pins(&self) -> &[KinematicPin] {
        &self.kinematic
    }

    /// Whether (and where) a step found the requested stretch tolerance out of
    /// reach (see [`Stagnation`]); `None` while every step could reach it.
    #[must_use]
    pub fn stagnation(&self) -> Option<&Stagnation> {
        self.stagnation.as_ref()
    }

    /// The stretch tolerance steps hold instead of the requested one after a
    /// step stagnated (twice the stretch it reached); `None` before.
    #[must_use]
    pub fn stretch_floor(&self) -> Option<f64> {
        self.stagnation.map(|s| s.floor)
    }

    /// The solver parameters.
    #[must_use]
    pub fn params(&self) -> &SolverParams {
        &self.params
    }

    /// The solver parameters, to change between steps (method, tolerance, limits).
    pub fn params_mut(&mut self) -> &mut SolverParams {
        &mut self.params
    }

    /// All particles of the world (every cloth's, in the order added).
    #[must_use]
    pub fn particles(&self) -> &ParticleSet {
        &self.particles
    }

    /// All particles, to edit positions or velocities between steps (a
    /// disturbance, a scrambled state). Masses may change but not between
    /// static and dynamic (that is a topology change: add the cloth again).
    pub fn particles_mut(&mut self) -> &mut ParticleSet {
        self.workspace.history = None;
        &mut self.particles
    }

    /// The external force on each particle besides gravity (N), one per
    /// particle of the world, constant over a step: the step previews
    /// `c + h v + h²/2 (g + F/m)`. Zero unless set.
    #[must_use]
    pub fn external_forces(&self) -> &[Vector3<f64>] {
        &self.external_forces
    }

    /// The external forces (N), to set before a step (drag, wind, damping,
    /// bending: evaluated from the state at the start of the step, see
    /// `crate::forces`). Forces on static particles are ignored.
    pub fn external_forces_mut(&mut self) -> &mut [Vector3<f64>] {
        &mut self.external_forces
    }

    /// Sets the mass of a dynamic particle (kg).
    ///
    /// # Errors
    /// [`ClothError::BadParameter`] for a non-positive or non-finite mass, a
    /// particle past the world, or a static particle (it keeps `inv_mass = 0`:
    /// static or dynamic is topology).
    pub fn set_particle_mass(&mut self, particle: ParticleId, kg: f64) -> Result<()> {
        let i = particle.index();
        if !(kg > 0.0 && kg.is_finite()) || i >= self.particles.len() || self.particles.is_static(i)
        {
            return Err(ClothError::BadParameter {
                name: "particle mass",
                expected: "positive and finite, on a dynamic particle of the world",
                value: kg,
            });
        }
        self.particles.inv_mass[i] = 1.0 / kg;
        // The Newton solver caches mass-dependent scalings.
        self.topology_changed();
        Ok(())
    }

    /// All distance constraints of the world.
    #[must_use]
    pub fn constraints(&self) -> &DistanceConstraints {
        &self.constraints
    }

    /// The colliders.
    #[must_use]
    pub fn colliders(&self) -> &[Collider] {
        &self.colliders
    }

    /// Simulated time (s).
    #[must_use]
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken since the world was made (a step that diverged counts).
    #[must_use]
    pub fn n_steps(&self) -> usize {
        self.n_steps
    }

    /// The positions of a cloth's particles (m), in its mesh's vertex order;
    /// empty for an id this world did not hand out.
    #[must_use]
    pub fn positions(&self, cloth: ClothId) -> &[Vector3<f64>] {
        self.range(cloth)
            .map_or(&[], |r| &self.particles.positions[r])
    }

    /// The velocities of a cloth's particles (m/s); empty for an unknown id.
    #[must_use]
    pub fn velocities(&self, cloth: ClothId) -> &[Vector3<f64>] {
        self.range(cloth)
            .map_or(&[], |r| &self.particles.velocities[r])
    }

    /// The world id of a cloth's vertex.
    ///
    /// # Errors
    /// [`ClothError::UnknownCloth`] or [`ClothError::VertexOutOfRange`].
    pub fn particle(&self, cloth: ClothId, vertex: usize) -> Result<ParticleId> {
        let r = self.range(cloth).ok_or(ClothError::UnknownCloth {
            id: cloth.0,
            n_cloths: self.cloths.len(),
        })?;
        if vertex >= r.len() {
            return Err(ClothError::VertexOutOfRange {
                vertex,
                n_vertices: r.len(),
            });
        }
        Ok(ParticleId((r.start + vertex) as u32))
    }

    /// A cloth's triangles (vertex indices of its mesh); empty for an unknown id.
    #[must_use]
    pub fn triangles(&self, cloth: ClothId) -> &[[u32; 3]] {
        self.cloths
            .get(cloth.0 as usize)
            .map_or(&[], |c| &c.triangles)
    }

    /// The largest relative stretch of a cloth's constraints now (0 for an unknown id).
    #[must_use]
    pub fn max_stretch(&self, cloth: ClothId) -> f64 {
        let Some(c) = self.cloths.get(cloth.0 as usize) else {
            return 0.0;
        };
        let mut worst = 0.0_f64;
        for i in c.constraints.clone() {
            let s = self.constraints.stretch(i, &self.particles.positions).abs();
            if s.is_nan() {
                return f64::NAN;
            }
            worst = worst.max(s);
        }
        worst
    }

    fn range(&self, cloth: ClothId) -> Option<Range<usize>> {
        self.cloths
            .get(cloth.0 as usize)
            .map(|c| c.particles.clone())
    }

    fn topology_changed(&mut self) {
        self.workspace.newton = None;
        self.workspace.coloured = None;
        self.workspace.strips = None;
        self.workspace.mu.clear();
        self.workspace.mu.resize(self.constraints.len(), 0.0);
        self.workspace.last_dt = None;
        self.workspace.history = None;
        self.workspace.bdf2_backoff = 0;
    }

    /// Advances the world by `steps` steps of `dt` seconds; the report merges
    /// them (summed iterations, worst stretch, converged if all converged).
    ///
    /// # Errors
    /// As [`step`](Self::step); the steps before the failing one stay done.
    pub fn step_n(&mut self, steps: usize, dt: f64) -> Result<StepReport> {
        let mut total = StepReport {
            converged: true,
            ..StepReport::default()
        };
        for _ in 0..steps {
            total = total.merge(self.step(dt)?);
        }
        Ok(total)
    }
}

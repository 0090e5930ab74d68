//! Solver parameters, the step report, and the Gauss–Seidel constraint sweep.
//!
//! A step of size `h` (Bender & Bayer):
//!
//! 1. **Preview.** External forces are constant over the step, so each
//!    dynamic particle's free end-of-step position is
//!    `c + h v + h² F/(2m)` in closed form.
//! 2. **Impulses.** For a constraint a–b with predicted error
//!    `e = |c_a − c_b|(t+h) − rest`, equal and opposite impulses `p`, `−p`
//!    applied at the start of the step change the relative velocity along the
//!    constraint by `e/h`: `(k_a + k_b) p = e/h`, `k = 1/m` (0 for static
//!    particles). The predicted positions move with them (`h k p`), so the
//!    preview stays exact. Momentum is conserved pair by pair.
//! 3. **Iterate** until every constraint's predicted relative stretch is
//!    within [`SolverParams::stretch_tolerance`] or the iteration limit is
//!    reached, then `c ← preview`, `v ← (c_new − c)/h + h F/(2m)` (the end
//!    velocity of a particle that received its impulses at the start).
//!
//! **The impulse direction is taken from the previewed positions**, not from
//! the positions at the start of the step. With the start-of-step direction a
//! straight row held at both ends under a transverse load (the `two-corners`
//! scene) has no solution: every impulse on the row is along the row, none can
//! hold its weight, and the impulses grow without bound to NaN. Along the
//! previewed direction the correction of each constraint is exact in one
//! projection (moving both ends along the line through their predicted
//! positions changes the distance by exactly `e`), the impulses are still
//! equal and opposite, and the iteration always has a fixed point on the
//! constraint manifold.
//!
//! [`Method::GaussSeidel`] sweeps the constraints one at a time and can be
//! stopped after any sweep with a finite state. [`Method::Strips`] sweeps
//! acyclic strips of constraints, each solved exactly in linear time (see
//! [`crate::strips`]). [`Method::Newton`] solves all constraints at once (see
//! [`crate::newton`]).

use nalgebra::Vector3;

use crate::constraints::DistanceConstraints;
use crate::error::{ClothError, Result};
use crate::kernel::{self, Link};

/// How the constraint impulses of a step are computed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Method {
    /// The paper's iteration: one constraint at a time, in order, until all
    /// hold. Cheap per iteration, any-time (stop it after any sweep), but it
    /// needs thousands of sweeps per step to hold 1e-4 on a 30 × 30 cloth.
    GaussSeidel,
    /// All constraints at once: Newton's method on the end-of-step
    /// positions and impulses together, with the geometric stiffness of
    /// tensioned links; the impulses are eliminated exactly, and the sparse
    /// Cholesky factorisation of the positions' system has its ordering and
    /// symbolic analysis computed once per topology and its numeric
    /// factor is reused across iterations and steps while the error keeps
    /// shrinking fast (see [`crate::newton`]). The default: it holds 1e-4
    /// on every reference scene at every step.
    #[default]
    Newton,
    /// The paper's acceleration: the constraints split into acyclic strips
    /// (chains; a grid's rows and columns), each strip solved directly along
    /// the previewed directions by the linear-time tridiagonal method, one
    /// Gauss–Newton step per strip per sweep, Gauss–Seidel between the
    /// strips (see [`crate::strips`]). Any-time like [`Method::GaussSeidel`]
    /// (stop it after any sweep), with far fewer sweeps.
    /// [`SolverParams::coloured_sweep`] does not apply.
    Strips,
}

/// How a step advances positions and velocities in time around the constraint solve.
///
/// Both solve the same problem each step — a previewed position `x̂` pulled
/// onto the constraints by impulses along their end-of-step directions,
/// `x = x̂ − M⁻¹ Jᵀ μ`, `C(x) = α μ / (β h)²` — and differ in the preview,
/// in the weight `β` of the step and in the velocity they leave.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Integrator {
    /// The paper's step: preview `c + h v + h² a / 2` under constant force,
    /// impulses at the end of the step, velocity `(x − c)/h + h a / 2`
    /// (`β = 1`). First order where the constraints act: a swinging cloth
    /// loses energy to the step, and its trajectory's error falls only in
    /// proportion to the step (on the curtain swaying 3 cm at 0.4 Hz, 1.6 mm
    /// RMS at h = 0.01 s against a run converged in the step). The default.
    #[default]
    Impulse,
    /// The second-order backward differentiation formula (BDF2) on positions
    /// and velocities, with the forces besides the constraints taken at the
    /// start of the step: preview `(4x_n − x_{n−1})/3 + (2h/3)(4v_n −
    /// v_{n−1})/3 + (2h/3)² a`, impulses at the end of the step (`β = 2/3`),
    /// velocity `(3x − 4x_n + x_{n−1})/(2h)`. Second order: the error falls
    /// with the step squared, and it damps only what the step cannot resolve.
    /// It needs the step before: the first step, a step of another size,
    /// and a step after the state was edited or the topology changed are
    /// [`Integrator::Impulse`] steps, and so is every step of a world with
    /// colliders (contact and friction are written for that step).
    Bdf2,
}

/// The largest gravity a world steps with (m/s², magnitude): 1000 m/s², about 100 g.
///
/// Measured on the 30 × 30 reference scenes (h = 0.01 s, Newton, 10 steps): at 1000 m/s²
/// every step of `corner`, `two-corners` and `drape` converges (at most 312 iterations);
/// at 10⁴ m/s² `two-corners` misses 1e-4 on 3 of 10 steps at 1000 iterations each, at
/// 10⁵ `drape` stretches by 186 and `two-corners` converges on no step, and beyond that
/// a step takes seconds and ends far from the constraints.
pub const MAX_GRAVITY: f64 = 1e3;

/// Parameters of the cloth solver.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverParams {
    /// Allowed relative stretch (or compression) of every constraint at the
    /// end of a converged step (dimensionless); default 1e-4 (0.01 %, the paper's value).
    pub stretch_tolerance: f64,
    /// Iteration limit per step: Gauss–Seidel or strip sweeps, or Newton solves;
    /// default 1000. Running out is reported, not an error.
    pub max_iterations: usize,
    /// The constraint method; default [`Method::Newton`].
    pub method: Method,
    /// Gauss–Seidel only: sweep the constraints colour by colour (groups
    /// that share no dynamic particle, see [`crate::colouring`]) instead of
    /// in index order, solving each large colour's constraints in parallel
    /// on the current rayon pool; bitwise the same result for any number of
    /// threads, a different (equally converging) order than the serial
    /// sweep. Default false (the serial sweep).
    pub coloured_sweep: bool,
    /// Gravity (m/s²), the external force per unit mass; default (0, −9.81, 0). Its
    /// magnitude is at most [`MAX_GRAVITY`] (1000 m/s²).
    pub gravity: Vector3<f64>,
    /// Sweeps of the optional velocity part of the distance constraints
    /// (zero relative velocity along each constraint at the end of the step);
    /// default 0 (off).
    pub velocity_iterations: usize,
    /// Start each step from the previous step's impulses (scaled by the step
    /// size squared), and Newton also from its last step's position
    /// correction and contact set; default true.
    pub warm_start: bool,
    /// Newton only: refactor when one iteration shrinks the residual (the
    /// root of the merit of stretch and momentum, see [`crate::newton`]) by
    /// less than this factor (dimensionless, in (0, 1)); default 0.3.
    pub refactor_ratio: f64,
    /// Allowed penetration into colliders at the end of a converged step (m);
    /// default 1e-4.
    pub contact_tolerance: f64,
    /// The time integration around the constraint solve; default
    /// [`Integrator::Impulse`], the paper's.
    pub integrator: Integrator,
}

impl Default for SolverParams {
    fn default() -> Self {
        Self {
            stretch_tolerance: 1e-4,
            max_iterations: 1000,
            method: Method::Newton,
            coloured_sweep: false,
            gravity: Vector3::new(0.0, -9.81, 0.0),
            velocity_iterations: 0,
            warm_start: true,
            refactor_ratio: 0.3,
            contact_tolerance: 1e-4,
            integrator: Integrator::Impulse,
        }
    }
}

impl SolverParams {
    /// Checks the parameters a step uses: tolerances positive and finite, gravity finite
    /// and at most [`MAX_GRAVITY`] in magnitude, `refactor_ratio` in (0, 1).
    ///
    /// # Errors
    /// [`ClothError::BadParameter`] naming the first parameter out of range (for gravity,
    /// the value is its magnitude).
    pub fn check(&self) -> Result<()> {
        let bad = |name: &'static str, expected: &'static str, value: f64| {
            Err(ClothError::BadParameter {
                name,
                expected,
                value,
            })
        };
        for (name, value) in [
            ("stretch_tolerance", self.stretch_tolerance),
            ("contact_tolerance", self.contact_tolerance),
        ] {
            if !(value > 0.0 && value.is_finite()) {
                return bad(name, "positive and finite", value);
            }
        }
        let g = magnitude(&self.gravity);
        if g.is_nan() || g > MAX_GRAVITY {
            return bad(
                "gravity",
                "finite, at most 1000 m/s^2 in magnitude (MAX_GRAVITY)",
                g,
            );
        }
        if !(self.refactor_ratio > 0.0 && self.refactor_ratio < 1.0) {
            return bad("refactor_ratio", "in (0, 1)", self.refactor_ratio);
        }
        Ok(())
    }
}

/// The length of a vector without overflow (1e200 stays 1e200, not infinity); NaN when a
/// component is NaN, infinity when one is infinite.
pub(crate) fn magnitude(v: &Vector3<f64>) -> f64 {
    if v.iter().any(|c| c.is_nan()) {
        return f64::NAN;
    }
    let m = v.iter().fold(0.0_f64, |m, c| m.max(c.abs()));
    if m == 0.0 || m.is_infinite() {
        m
    } else {
        m * (v / m).norm()
    }
}

/// What one step did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Iterations used (Gauss–Seidel or strip sweeps, or Newton solves).
    pub iterations: usize,
    /// Largest relative stretch or compression of any constraint at the end of the step.
    pub max_stretch: f64,
    /// Whether every constraint (and contact) held its tolerance.
    pub converged: bool,
    /// Numeric factorisations done (Newton only).
    pub factorizations: usize,
    /// Gauss–Seidel sweeps done because a Newton step failed even with a
    /// fresh factor (Newton only; 0 when Newton worked throughout). The step
    /// still ran Newton; a step that ran no Newton at all says so in
    /// [`fallback`](Self::fallback).
    pub fallback_sweeps: usize,
    /// Particles in contact with a collider during the step.
    pub n_contacts: usize,
    /// Deepest penetration into a collider at the end of the step (m).
    pub max_penetration: f64,
    /// The method that computed the step's impulses: [`SolverParams::method`],
    /// or [`Method::GaussSeidel`] when the step fell back to it (see
    /// [`fallback`](Self::fallback)). Of merged reports, the last step's.
    pub method_used: Method,
    /// Why the step did not run [`SolverParams::method`]; `None` when it did.
    /// Of merged reports, the first step's that fell back.
    pub fallback: Option<Fallback>,
    /// The iteration stopped because the error stopped falling (the smallest
    /// error so far did not halve over 30 Newton iterations, or did not fall at
    /// all over 100 sweeps): the tolerance asked for is below what this step can reach,
    /// and the step went on with [`max_stretch`](Self::max_stretch), the
    /// achievable level. Of merged reports, whether any step stagnated.
    pub stagnated: bool,
    /// The tolerance the step held instead of
    /// [`SolverParams::stretch_tolerance`] (relative): after a step stagnates,
    /// the world holds twice the stretch reached there
    /// ([`ClothWorld::stretch_floor`](crate::ClothWorld::stretch_floor)), so later
    /// steps stop at the achievable level instead of stagnating again; `None`
    /// while the requested tolerance is held. Of merged reports, the largest.
    pub relaxed_tolerance: Option<f64>,
    /// A [`Integrator::Bdf2`] step that did not converge as BDF2 within
    /// [`BDF2_MAX_ITERATIONS`](crate::world::BDF2_MAX_ITERATIONS) Newton
    /// iterations and was taken again as an impulse step (its iterations and
    /// factorisations count both tries).
    pub first_order: bool,
}

/// Whether an iteration has stagnated: pushes `error` (its error now, in
/// any unit) as the smallest so far onto `best`, and says whether that
/// smallest error has not fallen below the factor `ratio` of what it was
/// `window` iterations ago (with `ratio` 1: has not fallen at all). A NaN
/// error counts as infinite.
pub(crate) fn stalled(best: &mut Vec<f64>, error: f64, window: usize, ratio: f64) -> bool {
    let error = if error.is_nan() { f64::INFINITY } else { error };
    let smallest = best.last().map_or(error, |&b| b.min(error));
    best.push(smallest);
    let n = best.len();
    n > window && smallest >= ratio * best[n - 1 - window]
}

/// Why a step ran [`Method::GaussSeidel`] instead of [`SolverParams::method`]
/// ([`StepReport::fallback`]). Only [`Method::Newton`] falls back; the sweep
/// is the serial one, or the coloured one with [`SolverParams::coloured_sweep`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Fallback {
    /// The Newton solver could not be built for this topology: its
    /// fill-reducing ordering, symbolic factorisation or scratch memory failed
    /// (faer reports only an index overflow or an allocation failure). It is
    /// tried again at the next step.
    NewtonUnavailable,
    /// The world has no constraints: nothing for Newton to solve; the
    /// Gauss–Seidel loop only resolved contacts.
    NoConstraints,
}

impl std::fmt::Display for Fallback {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::NewtonUnavailable => {
                "the Newton solver could not be built (ordering, symbolic factorisation or \
                 memory); Gauss-Seidel ran instead"
            }
            Self::NoConstraints => "no constraints to solve; Gauss-Seidel resolved the contacts",
        })
    }
}

impl StepReport {
    /// Combines the reports of consecutive steps: summed work, worst error,
    /// converged only if every step converged, the last step's method, the
    /// first fallback, stagnated (or taken first order) if any step was, the largest relaxed
    /// tolerance.
    #[must_use]
    pub fn merge(self, next: Self) -> Self {
        Self {
            iterations: self.iterations + next.iterations,
            max_stretch: if next.max_stretch.is_nan() {
                f64::NAN
            } else {
                self.max_stretch.max(next.max_stretch)
            },
            converged: self.converged && next.converged,
            factorizations: self.factorizations + next.factorizations,
            fallback_sweeps: self.fallback_sweeps + next.fallback_sweeps,
            n_contacts: self.n_contacts.max(next.n_contacts),
            max_penetration: self.max_penetration.max(next.max_penetration),
            method_used: next.method_used,
            fallback: self.fallback.or(next.fallback),
            stagnated: self.stagnated || next.stagnated,
            first_order: self.first_order || next.first_order,
            relaxed_tolerance: match (self.relaxed_tolerance, next.relaxed_tolerance) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            },
        }
    }
}

/// Applies the impulses `mu` (impulse × step, kg m) of each constraint along
/// its previewed direction to the previewed positions.
pub(crate) fn apply_impulses(
    constraints: &DistanceConstraints,
    inv_mass: &[f64],
    mu: &[f64],
    pred: &mut [Vector3<f64>],
) {
    for (i, &m) in mu.iter().enumerate().take(constraints.len()) {
        if m == 0.0 {
            continue;
        }
        let link = Link::new(constraints, i, 0.0);
        if let Some(n) = link.separation(pred).n {
            let k = (inv_mass[link.a], inv_mass[link.b]);
            kernel::apply(pred, (link.a, link.b), k, m, &n);
        }
    }
}

/// One Gauss–Seidel sweep over all constraints: each constraint's predicted
/// error is removed by equal and opposite impulses along its previewed
/// direction ([`kernel::project`]). `mu` accumulates each constraint's
/// impulse × step (kg m); `inv_h2 = 1/h²` enters only through compliant
/// constraints, whose correction is `(len − rest − α̃ μ)/(k_a + k_b + α̃)`,
/// `α̃ = α/h²` (XPBD).
pub(crate) fn gauss_seidel_sweep(
    constraints: &DistanceConstraints,
    inv_mass: &[f64],
    pred: &mut [Vector3<f64>],
    mu: &mut [f64],
    inv_h2: f64,
) {
    for i in 0..constraints.len() {
        kernel::project(constraints, i, inv_mass, pred, mu, inv_h2);
    }
}

/// The optional velocity part: sweeps removing the relative velocity along
/// each constraint (direction from `positions`), `p = ((v_a − v_b)·n)/(k_a + k_b)`.
pub(crate) fn velocity_sweep(
    constraints: &DistanceConstraints,
    inv_mass: &[f64],
    positions: &[Vector3<f64>],
    velocities: &mut [Vector3<f64>],
) {
    for i in 0..constraints.len() {
        let link = Link::new(constraints, i, 0.0);
        let k = (inv_mass[link.a], inv_mass[link.b]);
        let w = k.0 + k.1;
        let Some(n) = link.separation(positions).n else {
            continue;
        };
        if w == 0.0 {
            continue;
        }
        let ends = (link.a, link.b);
        let p = kernel::velocity_impulse(velocities, ends, w, &n);
        kernel::apply(velocities, ends, k, p, &n);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_iteration_stalls_when_its_best_error_stops_falling() {
        let mut best = Vec::new();
        // Halving every iteration: never stalled.
        assert!((0..50).all(|k| !stalled(&mut best, 0.5_f64.powi(k), 30, 0.5)));
        // Creeping down by 1 % an iteration: stalled once the window is full.
        best.clear();
        let n = (0..100)
            .position(|k| stalled(&mut best, 0.99_f64.powi(k), 30, 0.5))
            .unwrap();
        assert_eq!(n, 30);
        // With ratio 1, only no fall at all stalls; NaN counts as infinite.
        best.clear();
        assert!(!stalled(&mut best, f64::NAN, 2, 1.0));
        assert!(!stalled(&mut best, 3.0, 2, 1.0));
        assert!(!stalled(&mut best, 2.0, 2, 1.0));
        assert!(!stalled(&mut best, 2.5, 2, 1.0));
        assert!(stalled(&mut best, 2.5, 2, 1.0));
    }

    fn pair(ka: f64, kb: f64) -> (DistanceConstraints, Vec<f64>, Vec<Vector3<f64>>) {
        let mut c = DistanceConstraints::new();
        c.push(0, 1, 1.0);
        (
            c,
            vec![ka, kb],
            vec![Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.3, 0.2, -0.1)],
        )
    }

    #[test]
    fn impulse_conserves_momentum() {
        // Masses 1 kg and 0.25 kg: the position changes weighted by mass cancel.
        let (c, k, mut pred) = pair(1.0, 4.0);
        let before = pred.clone();
        let mut mu = vec![0.0];
        gauss_seidel_sweep(&c, &k, &mut pred, &mut mu, 1.0);
        let dp = (pred[0] - before[0]) / k[0] + (pred[1] - before[1]) / k[1];
        approx::assert_relative_eq!(dp.norm(), 0.0, epsilon = 1e-14);
        // One projection along the previewed direction is exact.
        approx::assert_relative_eq!(c.stretch(0, &pred), 0.0, epsilon = 1e-14);
    }

    #[test]
    fn static_particle_never_moves() {
        let (c, k, mut pred) = pair(0.0, 1.0);
        let anchor = pred[0];
        let mut mu = vec![0.0];
        gauss_seidel_sweep(&c, &k, &mut pred, &mut mu, 1.0);
        apply_impulses(&c, &k, &[0.3], &mut pred);
        assert_eq!(pred[0], anchor);
        let mut v = vec![Vector3::zeros(), Vector3::new(1.0, 0.0, 0.0)];
        velocity_sweep(&c, &k, &pred, &mut v);
        assert_eq!(v[0], Vector3::zeros());
    }

    #[test]
    fn velocity_part_removes_relative_velocity_along_the_constraint() {
        let (c, k, x) = pair(1.0, 1.0);
        let mut v = vec![Vector3::new(1.0, 2.0, 0.0), Vector3::new(-1.0, 0.5, 3.0)];
        velocity_sweep(&c, &k, &x, &mut v);
        let n = (x[0] - x[1]).normalize();
        approx::assert_relative_eq!((v[0] - v[1]).dot(&n), 0.0, epsilon = 1e-14);
    }
}

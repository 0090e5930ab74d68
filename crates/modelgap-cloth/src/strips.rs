//! Acyclic strips and the strip sweep: the paper's acceleration of the
//! Gauss–Seidel iteration ([`Method::Strips`](crate::Method)).
//!
//! Bender & Bayer split the mesh's constraints into acyclic *strips*, solve
//! each strip exactly with the linear-time method for trees and chains
//! (Bender 2007: a sparse direct solve of the strip's constraint system in
//! `O(n)`), and iterate only between strips. Here a strip is a **chain**: a
//! path of constraints `c_0, …, c_{L−1}` through distinct particles
//! `q_0, …, q_L`, constraint `c_t` joining `q_t` and `q_{t+1}`.
//!
//! # The decomposition (any mesh)
//!
//! A greedy path cover of the constraint graph (particles as vertices,
//! constraints as edges), [`StripDecomposition::new`]: the first constraint
//! not yet in a strip, in index order, seeds a new strip, which then grows at
//! both ends, one constraint at a time. At an end particle `p` reached along
//! direction `d` it takes the unused constraint to a particle `q` not yet on
//! the strip whose direction `x_q − x_p` (at the positions given, usually the
//! rest state) turns least from `d`, if it turns by at most
//! [`MAX_TURN_DEGREES`]; otherwise that end stops. Every constraint ends up
//! in exactly one strip. On a grid the strips are its rows and columns; on a
//! triangle mesh they are its straightest lines of edges. A strip never
//! grows **through** a static particle; it may end at one, or at one at each
//! end (a row held at both ends stays one strip: solving it whole is what
//! lifts a taut row under a transverse load, the `two-corners` scene).
//!
//! The strip's constraint Jacobian `J` has full row rank whenever one end of
//! the strip is dynamic (peel the constraints off from that end: each is the
//! only one left acting on its end particle), for any directions. With both
//! ends static it loses rank only when the strip is straight (its `L`
//! constraints act along one line on `L − 1` free particles): an exactly
//! taut row, which the elimination detects (see below).
//!
//! # One strip solve
//!
//! Let `u_t` be the unit direction from `q_t` to `q_{t+1}` at the current
//! predicted (previewed) positions, `k` the inverse masses, `μ` the impulse
//! × step (kg m, as in [`crate::solver`]). Impulses `δμ_t` along the `u_t`
//! (equal and opposite: `q_t` moves by `+k δμ_t u_t`, `q_{t+1}` by
//! `−k δμ_t u_t`) change the constraint lengths, to first order, by
//! `−(J K Jᵀ δμ)_t`. Asking every strip constraint to reach its
//! (compliant) length, `len − rest − α̃ (μ + δμ) = 0` with `α̃ = α/h²`
//! (XPBD, as in the serial sweep), gives the tridiagonal system
//!
//! ```text
//! (k_{q_t} + k_{q_{t+1}} + α̃_t) δμ_t − k_{q_t} (u_{t−1}·u_t) δμ_{t−1}
//!                                    − k_{q_{t+1}} (u_t·u_{t+1}) δμ_{t+1}
//!     = len_t − rest_t − α̃_t μ_t ,
//! ```
//!
//! `J K Jᵀ + diag α̃`, symmetric positive definite when `J` has full rank. It is
//! solved by tridiagonal elimination (the Thomas algorithm; no pivoting
//! needed for an SPD matrix) in `O(L)`, and the impulses are applied along
//! the `u_t` and added to `μ`. For a single constraint this is exactly the
//! Gauss–Seidel projection. For a chain it is one Gauss–Newton step of the
//! strip's constraints: exact when the chain is straight (the directions do
//! not turn as the particles move along them), quadratically convergent
//! otherwise.
//!
//! A **sweep** solves every strip once, in strip order, each against the
//! positions left by the strips before it: block Gauss–Seidel between the
//! strips. The world iterates sweeps until its convergence check holds (the
//! same as for [`Method::GaussSeidel`](crate::Method)). Every impulse is a
//! pair of equal and opposite ones, so momentum is conserved exactly, static
//! particles never move, and the sweep can be stopped after any strip with a
//! finite state: a strip whose elimination meets a pivot below
//! `1e-12` of its diagonal entry, or a non-finite one (a straight row held at
//! both ends, or rounding), is projected constraint by constraint, as in the
//! serial sweep, for that sweep instead.
//!
//! # What it buys
//!
//! A strip sweep costs about 1.6 serial sweeps. Along a strip the coupling
//! is solved exactly, across strips it is still Gauss–Seidel, so the gain
//! depends on how the tension runs: a chain is solved in one sweep when
//! straight, a few when swinging; a 12 × 12 cloth hanging from a corner
//! needs about a third of the serial sweeps; a cloth held by two corners of
//! one edge converges at every step where the serial sweep stalls (its top
//! row, taut, is solved whole); on the 30 × 30 corner scene, whose tension
//! runs diagonally across rows and columns, the gain is about 2.5× in sweeps.
//!
//! Trees instead of chains (the largest acyclic strips: greedy spanning
//! forests, two on a grid, each solved by linear-time elimination of its
//! tree's 3×3 blocks, leaves first) were built and measured on the 30 × 30
//! scenes with a 1000-sweep cap, against the chains' 254, 0 and 86 steps
//! left unconverged on `corner`, `two-corners` and `drape`: with link turns
//! limited per solve, 226, 0 and 69; with a line search on each forest's
//! error, 209 and 153 (`drape` not run); with neither, `corner` diverged.
//! Each forest is solved exactly, but between two large forests the
//! iteration is still Gauss–Seidel, and the coupling across them is what
//! limits it. They were not kept: [`Method::Newton`](crate::Method) holds
//! every scene.

use nalgebra::Vector3;

use crate::constraints::DistanceConstraints;
use crate::error::{ClothError, Result};
use crate::kernel::{self, Link, Projection};

/// A strip grows only along a constraint that turns from its last one by at
/// most this angle (degrees), at the positions the decomposition was built
/// from: 60° keeps a grid's rows and columns apart (a 90° turn starts a new
/// strip) and follows the straight lines of a regular triangle mesh.
pub const MAX_TURN_DEGREES: f64 = 60.0;

/// A pivot below this fraction of its diagonal entry means the strip's
/// elimination lost all its digits; the strip is then projected constraint
/// by constraint instead.
const PIVOT_FLOOR: f64 = 1e-12;

/// The constraints of a world split into acyclic strips (chains), each
/// constraint in exactly one strip.
///
/// # Example
/// ```
/// use modelgap_cloth::strips::StripDecomposition;
/// use modelgap_cloth::{ClothWorld, GridCloth, SolverParams};
/// let mut world = ClothWorld::new(SolverParams::default());
/// world.add_cloth(GridCloth::new(10, 10, 0.1).pin(0))?;
/// let ps = world.particles();
/// let strips = StripDecomposition::new(world.constraints(), &ps.inv_mass, &ps.positions)?;
/// // A 10 x 10 grid: 10 rows and 10 columns of 9 constraints each.
/// assert_eq!(strips.n_strips(), 20);
/// assert!((0..strips.n_strips()).all(|s| strips.strip(s).len() == 9));
/// # Ok::<(), modelgap_cloth::ClothError>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct StripDecomposition {
    /// Constraint indices, strip by strip, each strip in chain order.
    constraints: Vec<u32>,
    /// Strip `s` is `constraints[starts[s]..starts[s + 1]]`.
    starts: Vec<usize>,
    /// The particles each strip visits, in order: strip `s` has
    /// `particles[starts[s] + s..=starts[s + 1] + s]`, one more than its constraints.
    particles: Vec<u32>,
    /// Which particles were static (inverse mass 0) when decomposed.
    is_static: Vec<bool>,
}

impl StripDecomposition {
    /// Splits `constraints` over particles with inverse masses `inv_mass`
    /// (1/kg, 0 for static particles) at positions `positions` (m; they only
    /// choose the straightest continuation) into strips, by the greedy path
    /// cover described in the [module docs](self). `O(Σ degree²)` time.
    ///
    /// # Errors
    /// [`ClothError::VertexOutOfRange`] when a constraint names a particle at
    /// or past `inv_mass.len()`; [`ClothError::BadParameter`] when
    /// `positions` and `inv_mass` differ in length.
    pub fn new(
        constraints: &DistanceConstraints,
        inv_mass: &[f64],
        positions: &[Vector3<f64>],
    ) -> Result<Self> {
        let n = inv_mass.len();
        let m = constraints.len();
        if positions.len() != n {
            return Err(ClothError::BadParameter {
                name: "positions",
                expected: "one position per particle (as many as inverse masses)",
                value: positions.len() as f64,
            });
        }
        constraints.check_particles(n)?;
        let is_static = crate::particles::statics(inv_mass);
        let ends = |i: usize| [constraints.a[i] as usize, constraints.b[i] as usize];

        // The constraints at each particle, ascending (compressed rows).
        let mut incident_starts = vec![0_usize; n + 1];
        for i in 0..m {
            for p in ends(i) {
                incident_starts[p + 1] += 1;
            }
        }
        for p in 0..n {
            incident_starts[p + 1] += incident_starts[p];
        }
        let mut next = incident_starts.clone();
        let mut incident = vec![0_u32; incident_starts[n]];
        for i in 0..m {
            for p in ends(i) {
                incident[next[p]] = i as u32;
                next[p] += 1;
            }
        }

        let min_cos = MAX_TURN_DEGREES.to_radians().cos();
        let mut used = vec![false; m];
        // `on_strip[p] == s + 1` while strip `s` is built and visits `p`.
        let mut on_strip = vec![0_usize; n];
        let mut out = Self {
            constraints: Vec::with_capacity(m),
            starts: vec![0],
            particles: Vec::with_capacity(2 * m),
            is_static,
        };
        let mut back = Growth::default();
        let mut front = Growth::default();
        for seed in 0..m {
            if used[seed] {
                continue;
            }
            let stamp = out.starts.len();
            let [a, b] = ends(seed);
            used[seed] = true;
            on_strip[a] = stamp;
            on_strip[b] = stamp;
            let mut grow = |from: usize, to: usize, growth: &mut Growth| {
                growth.constraints.clear();
                growth.particles.clear();
                let (mut prev, mut end) = (from, to);
                // Never through a static particle.
                while !out.is_static[end] {
                    let dir = positions[end] - positions[prev];
                    let mut best: Option<(f64, usize, usize)> = None;
                    for &e in &incident[incident_starts[end]..incident_starts[end + 1]] {
                        let e = e as usize;
                        if used[e] {
                            continue;
                        }
                        let [ea, eb] = ends(e);
                        let q = if ea == end { eb } else { ea };
                        if on_strip[q] == stamp {
                            continue;
                        }
                        let step = positions[q] - positions[end];
                        let norms = step.norm() * dir.norm();
                        let cos = if norms > 0.0 {
                            step.dot(&dir) / norms
                        } else {
                            -1.0
                        };
                        if cos >= min_cos && best.is_none_or(|(c, _, _)| cos > c) {
                            best = Some((cos, e, q));
                        }
                    }
                    let Some((_, e, q)) = best else { break };
                    used[e] = true;
                    on_strip[q] = stamp;
                    growth.constraints.push(e as u32);
                    growth.particles.push(q as u32);
                    (prev, end) = (end, q);
                }
            };
            grow(a, b, &mut front);
            grow(b, a, &mut back);
            // Strip order: the back growth reversed, a, b, the front growth.
            out.constraints.extend(back.constraints.iter().rev());
            out.constraints.push(seed as u32);
            out.constraints.extend(&front.constraints);
            out.particles.extend(back.particles.iter().rev());
            out.particles.extend([a as u32, b as u32]);
            out.particles.extend(&front.particles);
            out.starts.push(out.constraints.len());
        }
        Ok(out)
    }

    /// The number of strips.
    #[must_use]
    pub fn n_strips(&self) -> usize {
        self.starts.len() - 1
    }

    /// Strip `s`'s constraint indices in chain order (consecutive ones share
    /// a particle, no others do); empty past the last strip.
    #[must_use]
    pub fn strip(&self, s: usize) -> &[u32] {
        match (self.starts.get(s), self.starts.get(s + 1)) {
            (Some(&lo), Some(&hi)) => &self.constraints[lo..hi],
            _ => &[],
        }
    }

    /// The particles strip `s` visits, in order, one more than its
    /// constraints: constraint `t` of the strip joins particles `t` and
    /// `t + 1`; empty past the last strip.
    #[must_use]
    pub fn strip_particles(&self, s: usize) -> &[u32] {
        match (self.starts.get(s), self.starts.get(s + 1)) {
            (Some(&lo), Some(&hi)) => &self.particles[lo + s..=hi + s],
            _ => &[],
        }
    }

    /// The length (constraints) of the longest strip; 0 when there are none.
    #[must_use]
    pub fn longest(&self) -> usize {
        self.starts
            .windows(2)
            .map(|w| w[1] - w[0])
            .max()
            .unwrap_or(0)
    }

    /// Whether this decomposition still holds for these constraints and
    /// particles: the same number of each, and the same particles static.
    /// (Masses and positions may change; a particle turning static or
    /// dynamic needs a new decomposition.)
    #[must_use]
    pub fn fits(&self, constraints: &DistanceConstraints, inv_mass: &[f64]) -> bool {
        self.constraints.len() == constraints.len()
            && crate::particles::same_statics(&self.is_static, inv_mass)
    }
}

/// What one end of a strip grew by, in growing order.
#[derive(Debug, Default)]
struct Growth {
    constraints: Vec<u32>,
    particles: Vec<u32>,
}

/// The strip sweep: a decomposition and the scratch of its strip solves
/// (one entry per constraint position in the longest strip).
#[derive(Clone, Debug)]
pub(crate) struct StripSweep {
    strips: StripDecomposition,
    /// Unit direction `u_t` from `q_t` to `q_{t+1}` (zero for a constraint
    /// left out of this solve).
    dir: Vec<Vector3<f64>>,
    /// Diagonal, then the elimination's pivots (kg⁻¹).
    diag: Vec<f64>,
    /// Off-diagonal between `t` and `t + 1` (kg⁻¹).
    off: Vec<f64>,
    /// Right-hand side (m), then the impulses × step `δμ` (kg m).
    rhs: Vec<f64>,
}

impl StripSweep {
    /// The sweep for these constraints and particles (see [`StripDecomposition::new`]).
    pub(crate) fn new(
        constraints: &DistanceConstraints,
        inv_mass: &[f64],
        positions: &[Vector3<f64>],
    ) -> Result<Self> {
        let strips = StripDecomposition::new(constraints, inv_mass, positions)?;
        let l = strips.longest();
        Ok(Self {
            strips,
            dir: vec![Vector3::zeros(); l],
            diag: vec![0.0; l],
            off: vec![0.0; l],
            rhs: vec![0.0; l],
        })
    }

    /// See [`StripDecomposition::fits`].
    pub(crate) fn fits(&self, constraints: &DistanceConstraints, inv_mass: &[f64]) -> bool {
        self.strips.fits(constraints, inv_mass)
    }

    /// One sweep: every strip solved once (one Gauss–Newton step of its
    /// constraints along the previewed directions), in strip order. `mu`
    /// accumulates each constraint's impulse × step (kg m); `inv_h2 = 1/h²`
    /// (1/s²) weighs compliant constraints as in the serial sweep.
    pub(crate) fn sweep(
        &mut self,
        constraints: &DistanceConstraints,
        inv_mass: &[f64],
        pred: &mut [Vector3<f64>],
        mu: &mut [f64],
        inv_h2: f64,
    ) {
        for s in 0..self.strips.n_strips() {
            self.solve_strip(s, constraints, inv_mass, pred, mu, inv_h2);
        }
    }

    /// One direct solve of strip `s` (see the [module docs](self)).
    fn solve_strip(
        &mut self,
        s: usize,
        constraints: &DistanceConstraints,
        inv_mass: &[f64],
        pred: &mut [Vector3<f64>],
        mu: &mut [f64],
        inv_h2: f64,
    ) {
        let (lo, hi) = (self.strips.starts[s], self.strips.starts[s + 1]);
        let edges = &self.strips.constraints[lo..hi];
        let nodes = &self.strips.particles[lo + s..=hi + s];
        let l = edges.len();
        let (dir, diag, off, rhs) = (
            &mut self.dir[..l],
            &mut self.diag[..l],
            &mut self.off[..l],
            &mut self.rhs[..l],
        );
        // Assemble along the current previewed directions: each row's
        // diagonal, right-hand side and direction are the kernel's projection
        // of its constraint.
        for t in 0..l {
            let i = edges[t] as usize;
            let link = Link::new(constraints, i, inv_h2);
            match Projection::at(&link, inv_mass[link.a], inv_mass[link.b], pred, mu[i]) {
                Some(p) => {
                    // The kernel's `n` points from `b` to `a`, the chain's
                    // `u_t` from `q_t` to `q_{t+1}` (negation is exact).
                    dir[t] = if link.a == nodes[t + 1] as usize {
                        p.n
                    } else {
                        -p.n
                    };
                    diag[t] = p.weight;
                    rhs[t] = p.value;
                }
                // A constraint with no direction (coincident predictions) or
                // no dynamic end is left out of this solve: its row becomes
                // δμ = 0 and, its direction zero, it couples to nothing.
                None => {
                    dir[t] = Vector3::zeros();
                    diag[t] = 1.0;
                    rhs[t] = 0.0;
                }
            }
        }
        for t in 0..l.saturating_sub(1) {
            off[t] = -inv_mass[nodes[t + 1] as usize] * dir[t].dot(&dir[t + 1]);
        }
        // Tridiagonal elimination (Thomas), pivots into `diag`.
        for t in 0..l {
            let entry = diag[t];
            if t > 0 {
                let factor = off[t - 1] / diag[t - 1];
                diag[t] -= factor * off[t - 1];
                rhs[t] -= factor * rhs[t - 1];
            }
            if !(diag[t] > PIVOT_FLOOR * entry && diag[t].is_finite() && rhs[t].is_finite()) {
                project_one_by_one(edges, constraints, inv_mass, pred, mu, inv_h2);
                return;
            }
        }
        rhs[l - 1] /= diag[l - 1];
        for t in (0..l - 1).rev() {
            rhs[t] = (rhs[t] - off[t] * rhs[t + 1]) / diag[t];
        }
        if rhs.iter().any(|x| !x.is_finite()) {
            project_one_by_one(edges, constraints, inv_mass, pred, mu, inv_h2);
            return;
        }
        // Equal and opposite impulses along the directions solved for: `u_t`
        // points from `q_t` to `q_{t+1}`, so `q_{t+1}` is the kernel's first end.
        for t in 0..l {
            let delta = rhs[t];
            if delta == 0.0 {
                continue;
            }
            let (q0, q1) = (nodes[t] as usize, nodes[t + 1] as usize);
            let k = (inv_mass[q1], inv_mass[q0]);
            kernel::apply(pred, (q1, q0), k, delta, &dir[t]);
            mu[edges[t] as usize] += delta;
        }
    }
}

/// The fallback of a strip whose elimination failed: the serial sweep's
/// projection ([`kernel::project`]), constraint by constraint along the strip.
fn project_one_by_one(
    edges: &[u32],
    constraints: &DistanceConstraints,
    inv_mass: &[f64],
    pred: &mut [Vector3<f64>],
    mu: &mut [f64],
    inv_h2: f64,
) {
    for &i in edges {
        kernel::project(constraints, i as usize, inv_mass, pred, mu, inv_h2);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A zig-zag chain 0–1–2–3 with particle 0 static.
    fn zigzag() -> (DistanceConstraints, Vec<f64>, Vec<Vector3<f64>>) {
        let x = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, -0.2, 0.0),
            Vector3::new(2.0, 0.1, 0.3),
            Vector3::new(3.0, -0.1, 0.0),
        ];
        let mut c = DistanceConstraints::new();
        for (a, b) in [(0, 1), (2, 1), (2, 3)] {
            c.push(a, b, (x[a as usize] - x[b as usize]).norm());
        }
        (c, vec![0.0, 1.0, 2.0, 0.5], x)
    }

    #[test]
    fn one_strip_solve_solves_the_linearised_chain_system() {
        let (mut c, k, x0) = zigzag();
        c.compliance[1] = 0.01;
        let mut sweep = StripSweep::new(&c, &k, &x0).unwrap();
        assert_eq!(sweep.strips.n_strips(), 1);
        // Stretch the chain and sweep once; the linearised errors vanish.
        let mut pred: Vec<_> = x0.iter().map(|p| p * 1.05).collect();
        let before = pred.clone();
        let mut mu = vec![0.0; 3];
        let inv_h2 = 1e4;
        sweep.sweep(&c, &k, &mut pred, &mut mu, inv_h2);
        // Linearised residual: len0 + u·(dx1 − dx0) − rest − α̃ μ, for each constraint.
        let nodes = sweep.strips.strip_particles(0).to_vec();
        for (t, &i) in sweep.strips.strip(0).iter().enumerate() {
            let (q0, q1) = (nodes[t] as usize, nodes[t + 1] as usize);
            let d = before[q1] - before[q0];
            let u = d / d.norm();
            let moved = u.dot(&((pred[q1] - before[q1]) - (pred[q0] - before[q0])));
            let alpha = c.compliance[i as usize] * inv_h2;
            let r = d.norm() + moved - c.rest_length[i as usize] - alpha * mu[i as usize];
            approx::assert_abs_diff_eq!(r, 0.0, epsilon = 1e-13);
        }
        // Static particle 0 did not move.
        assert_eq!(pred[0], before[0]);
    }

    /// 0 (static) – 1 – 2 – 3 (static) along x, 1 m links.
    fn held_row(span: f64) -> (DistanceConstraints, [f64; 4], Vec<Vector3<f64>>) {
        let x: Vec<_> = (0..4)
            .map(|i| Vector3::new(f64::from(i) * span / 3.0, 0.0, 0.0))
            .collect();
        let mut c = DistanceConstraints::new();
        for i in 0..3 {
            c.push(i, i + 1, 1.0);
        }
        (c, [0.0, 1.0, 1.0, 0.0], x)
    }

    #[test]
    fn a_straight_taut_row_falls_back_to_projections() {
        // Straight and taut: the strip's system is singular; the sweep
        // projects one by one and stays finite, the pins in place.
        let (c, k, x) = held_row(3.0);
        let mut sweep = StripSweep::new(&c, &k, &x).unwrap();
        assert_eq!(sweep.strips.n_strips(), 1);
        let mut pred = x.clone();
        pred[1].x += 0.1;
        let mut mu = vec![0.0; 3];
        sweep.sweep(&c, &k, &mut pred, &mut mu, 1.0);
        assert!(mu.iter().all(|m| m.is_finite()));
        assert!(c.max_error(&pred, &mu, 1.0) < 0.1);
        assert_eq!((pred[0], pred[3]), (x[0], x[3]));
    }

    #[test]
    fn a_sagging_row_held_at_both_ends_converges() {
        // Slack between the pins (2.5 m apart for 3 m of links), sagging and
        // stretched: the whole row is one strip and converges quadratically.
        let (c, k, x) = held_row(2.5);
        let mut sweep = StripSweep::new(&c, &k, &x).unwrap();
        assert_eq!(sweep.strips.n_strips(), 1);
        let mut pred = vec![
            x[0],
            Vector3::new(1.0, -0.5, 0.0),
            Vector3::new(2.0, -0.5, 0.0),
            x[3],
        ];
        let mut mu = vec![0.0; 3];
        for _ in 0..8 {
            sweep.sweep(&c, &k, &mut pred, &mut mu, 1.0);
        }
        assert!(c.max_error(&pred, &mu, 1.0) < 1e-12);
        assert_eq!((pred[0], pred[3]), (x[0], x[3]));
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let (c, k, x) = zigzag();
        assert!(matches!(
            StripDecomposition::new(&c, &k[..3], &x[..3]),
            Err(ClothError::VertexOutOfRange { vertex: 3, .. })
        ));
        assert!(matches!(
            StripDecomposition::new(&c, &k, &x[..2]),
            Err(ClothError::BadParameter { .. })
        ));
    }
}

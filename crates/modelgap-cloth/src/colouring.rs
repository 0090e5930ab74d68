//! Constraint colouring and the coloured Gauss–Seidel sweep.
//!
//! Two distance constraints that share no dynamic particle can be solved at
//! the same time: neither reads a position the other writes (the paper:
//! "constraints with no common particle can be solved in parallel"). A greedy
//! edge colouring of the constraint graph (particles as vertices,
//! constraints as edges) splits the constraints into such groups, the
//! *colours*. Static particles (inverse mass 0, pins) are ignored by the
//! colouring: no impulse moves them, so any number of constraints of one
//! colour may end on the same static particle.
//!
//! The coloured sweep is a Gauss–Seidel sweep in colour order: colour 0,
//! then colour 1, …, each colour's constraints against the previewed
//! positions left by the colours before it. Within a colour the order does
//! not matter (no constraint sees another's move), so the constraints of a
//! large colour are solved in parallel on rayon's current thread pool, and
//! the result is **bitwise the same for any number of threads**. It is not
//! the same as the serial sweep of [`Method::GaussSeidel`](crate::Method)
//! (that one runs in constraint index order): both converge to the stretch
//! tolerance, along different paths.
//!
//! A colour is solved in two passes, so that the parallel path needs no
//! shared mutable state:
//!
//! 1. *corrections*, in parallel over blocks of constraint indices: each
//!    constraint's correction `corr` and previewed direction `n` from the
//!    current previewed positions, and its impulse `μ += corr`;
//! 2. *moves*, in parallel over blocks of particles: each dynamic particle
//!    of the colour moves by `∓ k corr n` for its one constraint of the colour.
//!
//! Pass 1 reads only positions that no constraint of the colour has moved
//! yet, which is what the sequential in-place loop reads too, and both paths
//! evaluate the same expressions in the same order: same bits.
//!
//! **Threshold.** A colour with fewer than [`PARALLEL_MIN_CONSTRAINTS`]
//! constraints, or any colour when the current pool has one thread, is solved
//! by the sequential in-place loop over the same order (ascending constraint
//! index within the colour): below that size rayon's fork-join overhead
//! outweighs the work.

use nalgebra::Vector3;
use rayon::prelude::*;

use crate::constraints::DistanceConstraints;
use crate::error::Result;
use crate::kernel::{self, Link, Projection};

/// Colours with at least this many constraints are solved in parallel when
/// the current rayon pool has more than one thread; smaller ones in place,
/// one constraint after the other. A constraint costs about 15 ns, so a
/// colour at the threshold is some 60 µs of work, against a few µs for a
/// rayon fork-join on idle cores: the 30 × 30 reference scenes (about 435
/// constraints a colour) stay in place, a 100 × 100 grid (about 5000) and
/// larger ones go parallel.
pub const PARALLEL_MIN_CONSTRAINTS: usize = 4096;

/// Constraints per parallel task in pass 1 (corrections) and in the
/// parallel largest-error scan.
const CONSTRAINT_BLOCK: usize = 4096;

/// Particles per parallel task in pass 2 (moves).
const PARTICLE_BLOCK: usize = 4096;

/// A dynamic particle of one colour and its one constraint of that colour.
#[derive(Clone, Copy, Debug)]
struct Move {
    particle: u32,
    constraint: u32,
    /// The particle is the constraint's second end `b` (moves by `+k corr n`);
    /// otherwise its first end `a` (moves by `−k corr n`).
    is_b: bool,
}

/// A colouring of distance constraints: groups (colours) of constraints of
/// which no two share a dynamic particle, found greedily in constraint order.
///
/// # Example
/// ```
/// use modelgap_cloth::colouring::ConstraintColouring;
/// use modelgap_cloth::{ClothWorld, GridCloth, SolverParams};
/// let mut world = ClothWorld::new(SolverParams::default());
/// world.add_cloth(GridCloth::new(10, 10, 0.1).pin(0))?;
/// let colouring = ConstraintColouring::new(world.constraints(), &world.particles().inv_mass)?;
/// // A grid's particles have up to four structural edges.
/// assert!(colouring.n_colours() >= 4);
/// let n: usize = (0..colouring.n_colours()).map(|c| colouring.colour(c).len()).sum();
/// assert_eq!(n, world.constraints().len());
/// # Ok::<(), modelgap_cloth::ClothError>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct ConstraintColouring {
    /// Constraint indices grouped by colour, ascending within a colour.
    order: Vec<u32>,
    /// Colour `c` is `order[colour_starts[c]..colour_starts[c + 1]]`.
    colour_starts: Vec<usize>,
    /// The dynamic ends of each colour's constraints, sorted by particle.
    moves: Vec<Move>,
    /// Colour `c`'s moves are `moves[move_starts[c]..move_starts[c + 1]]`.
    move_starts: Vec<usize>,
    /// Which particles were static (inverse mass 0) when coloured.
    is_static: Vec<bool>,
}

impl ConstraintColouring {
    /// Colours `constraints` over particles with the inverse masses
    /// `inv_mass` (1/kg, 0 for static particles): each constraint, in index
    /// order, gets the smallest colour not yet used at either of its dynamic
    /// ends. At most `2 Δ − 1` colours, `Δ` the largest number of
    /// constraints at a dynamic particle.
    ///
    /// # Errors
    /// [`ClothError::VertexOutOfRange`](crate::ClothError::VertexOutOfRange) when a constraint names a particle at
    /// or past `inv_mass.len()`.
    pub fn new(constraints: &DistanceConstraints, inv_mass: &[f64]) -> Result<Self> {
        let n = inv_mass.len();
        let m = constraints.len();
        constraints.check_particles(n)?;
        let is_static = crate::particles::statics(inv_mass);
        let ends = |i: usize| [constraints.a[i] as usize, constraints.b[i] as usize];

        // The constraints at each dynamic particle, ascending (compressed rows).
        let mut incident_starts = vec![0_usize; n + 1];
        for i in 0..m {
            for p in ends(i) {
                if !is_static[p] {
                    incident_starts[p + 1] += 1;
                }
            }
        }
        for p in 0..n {
            incident_starts[p + 1] += incident_starts[p];
        }
        let mut next = incident_starts.clone();
        let mut incident = vec![0_u32; incident_starts[n]];
        for i in 0..m {
            for p in ends(i) {
                if !is_static[p] {
                    incident[next[p]] = i as u32;
                    next[p] += 1;
                }
            }
        }

        // Greedy: `taken[c] == i + 1` marks colour c as used next to constraint i.
        let mut colour = vec![0_u32; m];
        let mut taken: Vec<usize> = Vec::new();
        for i in 0..m {
            let mark = i + 1;
            for p in ends(i) {
                if is_static[p] {
                    continue;
                }
                for &j in &incident[incident_starts[p]..incident_starts[p + 1]] {
                    if j as usize >= i {
                        break;
                    }
                    taken[colour[j as usize] as usize] = mark;
                }
            }
            let c = taken.iter().position(|&t| t != mark).unwrap_or(taken.len());
            if c == taken.len() {
                taken.push(0);
            }
            colour[i] = c as u32;
        }
        let n_colours = taken.len();

        // Counting sort by colour, stable: ascending index within a colour.
        let mut colour_starts = vec![0_usize; n_colours + 1];
        for &c in &colour {
            colour_starts[c as usize + 1] += 1;
        }
        for c in 0..n_colours {
            colour_starts[c + 1] += colour_starts[c];
        }
        let mut next = colour_starts.clone();
        let mut order = vec![0_u32; m];
        for (i, &c) in colour.iter().enumerate() {
            order[next[c as usize]] = i as u32;
            next[c as usize] += 1;
        }

        let mut moves = Vec::with_capacity(2 * m);
        let mut move_starts = Vec::with_capacity(n_colours + 1);
        move_starts.push(0);
        for c in 0..n_colours {
            let first = moves.len();
            for &i in &order[colour_starts[c]..colour_starts[c + 1]] {
                for (p, is_b) in [
                    (constraints.a[i as usize], false),
                    (constraints.b[i as usize], true),
                ] {
                    if !is_static[p as usize] {
                        moves.push(Move {
                            particle: p,
                            constraint: i,
                            is_b,
                        });
                    }
                }
            }
            // A particle has at most one constraint per colour: keys are unique.
            moves[first..].sort_unstable_by_key(|mv| mv.particle);
            move_starts.push(moves.len());
        }
        Ok(Self {
            order,
            colour_starts,
            moves,
            move_starts,
            is_static,
        })
    }

    /// The number of colours (0 without constraints).
    #[must_use]
    pub fn n_colours(&self) -> usize {
        self.colour_starts.len().saturating_sub(1)
    }

    /// The constraint indices of colour `c`, ascending; empty past the last colour.
    #[must_use]
    pub fn colour(&self, c: usize) -> &[u32] {
        match (self.colour_starts.get(c), self.colour_starts.get(c + 1)) {
            (Some(&lo), Some(&hi)) => &self.order[lo..hi],
            _ => &[],
        }
    }

    /// Whether this colouring still holds for these constraints and
    /// particles: the same number of each, and the same particles static.
    /// (Masses may change; a particle turning static or dynamic needs a new
    /// colouring.)
    #[must_use]
    pub fn fits(&self, constraints: &DistanceConstraints, inv_mass: &[f64]) -> bool {
        self.order.len() == constraints.len()
            && crate::particles::same_statics(&self.is_static, inv_mass)
    }
}

/// A constraint's correction (kg m) and previewed direction, from pass 1 to pass 2.
#[derive(Clone, Copy, Debug)]
struct Correction {
    corr: f64,
    n: Vector3<f64>,
}

/// The coloured Gauss–Seidel sweep: a colouring and the scratch of its
/// parallel passes (one [`Correction`] per constraint).
#[derive(Clone, Debug)]
pub(crate) struct ColouredSweep {
    colouring: ConstraintColouring,
    corrections: Vec<Correction>,
    parallel_min_constraints: usize,
}

impl ColouredSweep {
    /// The sweep for these constraints and particles (see [`ConstraintColouring::new`]).
    pub(crate) fn new(constraints: &DistanceConstraints, inv_mass: &[f64]) -> Result<Self> {
        Ok(Self {
            colouring: ConstraintColouring::new(constraints, inv_mass)?,
            corrections: vec![
                Correction {
                    corr: 0.0,
                    n: Vector3::zeros(),
                };
                constraints.len()
            ],
            parallel_min_constraints: PARALLEL_MIN_CONSTRAINTS,
        })
    }

    /// Solves colours of at least `n` constraints in parallel (tests use 0).
    #[cfg(test)]
    fn with_parallel_min(mut self, n: usize) -> Self {
        self.parallel_min_constraints = n;
        self
    }

    /// See [`ConstraintColouring::fits`].
    pub(crate) fn fits(&self, constraints: &DistanceConstraints, inv_mass: &[f64]) -> bool {
        self.colouring.fits(constraints, inv_mass)
    }

    /// One sweep over all constraints, colour by colour; `mu` accumulates each
    /// constraint's impulse × step (kg m), `inv_h2 = 1/h²` (1/s²) weighs
    /// compliant constraints as in [`crate::solver`]'s serial sweep.
    pub(crate) fn sweep(
        &mut self,
        constraints: &DistanceConstraints,
        inv_mass: &[f64],
        pred: &mut [Vector3<f64>],
        mu: &mut [f64],
        inv_h2: f64,
    ) {
        debug_assert!(self.fits(constraints, inv_mass));
        debug_assert_eq!(pred.len(), inv_mass.len());
        debug_assert_eq!(mu.len(), constraints.len());
        let parallel = rayon::current_num_threads() > 1;
        for c in 0..self.colouring.n_colours() {
            let colour = self.colouring.colour(c);
            if parallel && colour.len() >= self.parallel_min_constraints {
                self.colour_in_parallel(c, constraints, inv_mass, pred, mu, inv_h2);
            } else {
                colour_in_place(colour, constraints, inv_mass, pred, mu, inv_h2);
            }
        }
    }

    /// Colour `c` in the two passes of the module docs.
    fn colour_in_parallel(
        &mut self,
        c: usize,
        constraints: &DistanceConstraints,
        inv_mass: &[f64],
        pred: &mut [Vector3<f64>],
        mu: &mut [f64],
        inv_h2: f64,
    ) {
        let colour = self.colouring.colour(c);
        let moves =
            &self.colouring.moves[self.colouring.move_starts[c]..self.colouring.move_starts[c + 1]];
        // Pass 1: corrections, each block of constraint indices on its own.
        let seen: &[Vector3<f64>] = pred;
        mu.par_chunks_mut(CONSTRAINT_BLOCK)
            .zip(self.corrections.par_chunks_mut(CONSTRAINT_BLOCK))
            .enumerate()
            .for_each(|(k, (mu_block, corrections))| {
                let lo = k * CONSTRAINT_BLOCK;
                let hi = lo + mu_block.len();
                let first = colour.partition_point(|&i| (i as usize) < lo);
                let last = colour.partition_point(|&i| (i as usize) < hi);
                for &i in &colour[first..last] {
                    let i = i as usize;
                    let j = i - lo;
                    match correction(constraints, i, inv_mass, seen, mu_block[j], inv_h2) {
                        Some((corr, n)) => {
                            mu_block[j] += corr;
                            corrections[j] = Correction { corr, n };
                        }
                        None => corrections[j].corr = 0.0,
                    }
                }
            });
        // Pass 2: moves, each block of particles on its own.
        let corrections = &self.corrections;
        pred.par_chunks_mut(PARTICLE_BLOCK)
            .enumerate()
            .for_each(|(k, block)| {
                let lo = k * PARTICLE_BLOCK;
                let hi = lo + block.len();
                let first = moves.partition_point(|mv| (mv.particle as usize) < lo);
                let last = moves.partition_point(|mv| (mv.particle as usize) < hi);
                for mv in &moves[first..last] {
                    let Correction { corr, n } = corrections[mv.constraint as usize];
                    if corr == 0.0 {
                        continue;
                    }
                    let p = mv.particle as usize;
                    kernel::move_end(&mut block[p - lo], inv_mass[p], corr, &n, mv.is_b);
                }
            });
    }
}

/// The correction `corr` (kg m, impulse × step) and previewed direction `n`
/// of constraint `i` ([`kernel::Projection`]); `None` when both ends are
/// static or the previewed ends coincide (the constraint waits for its
/// neighbours for one sweep).
#[inline]
fn correction(
    constraints: &DistanceConstraints,
    i: usize,
    inv_mass: &[f64],
    pred: &[Vector3<f64>],
    mu: f64,
    inv_h2: f64,
) -> Option<(f64, Vector3<f64>)> {
    let link = Link::new(constraints, i, inv_h2);
    Projection::at(&link, inv_mass[link.a], inv_mass[link.b], pred, mu)
        .map(|p| (p.correction(), p.n))
}

/// One colour, constraint after constraint, in place ([`kernel::project`]):
/// the same expressions as the two parallel passes, in the same order.
fn colour_in_place(
    colour: &[u32],
    constraints: &DistanceConstraints,
    inv_mass: &[f64],
    pred: &mut [Vector3<f64>],
    mu: &mut [f64],
    inv_h2: f64,
) {
    for &i in colour {
        kernel::project(constraints, i as usize, inv_mass, pred, mu, inv_h2);
    }
}

/// The largest `|error|` of all constraints
/// ([`DistanceConstraints::max_error`]), scanned in parallel on the current
/// rayon pool when there are at least [`PARALLEL_MIN_CONSTRAINTS`]
/// constraints and more than one thread. A maximum does not depend on the
/// order it is taken in: the same value as the serial scan, NaN if any is NaN.
pub(crate) fn max_error(
    constraints: &DistanceConstraints,
    pred: &[Vector3<f64>],
    mu: &[f64],
    inv_h2: f64,
) -> f64 {
    let m = constraints.len();
    if m < PARALLEL_MIN_CONSTRAINTS || rayon::current_num_threads() < 2 {
        return constraints.max_error(pred, mu, inv_h2);
    }
    (0..m)
        .into_par_iter()
        .with_min_len(CONSTRAINT_BLOCK)
        .map(|i| constraints.error(i, pred, mu[i], inv_h2).abs())
        .reduce(
            || 0.0,
            |x, y| {
                if x.is_nan() || y.is_nan() {
                    f64::NAN
                } else {
                    x.max(y)
                }
            },
        )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::GridCloth;
    use crate::solver::SolverParams;
    use crate::world::ClothWorld;

    /// A grid world; `pins` are vertex indices.
    fn grid(nx: usize, nz: usize, pins: &[u32], shear_bend: bool) -> ClothWorld {
        let mut cloth = GridCloth::new(nx, nz, 0.02)
            .shear(shear_bend)
            .bend(shear_bend);
        for &p in pins {
            cloth = cloth.pin(p);
        }
        let mut world = ClothWorld::new(SolverParams::default());
        world.add_cloth(cloth).unwrap();
        world
    }

    /// Positions shaken by a fixed pseudo-random offset of up to ±`amplitude` m
    /// per coordinate (a scrambled preview), static particles left in place.
    fn shaken(world: &ClothWorld, amplitude: f64) -> Vec<Vector3<f64>> {
        let ps = world.particles();
        let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1_u64 << 53) as f64 * 2.0 - 1.0
        };
        ps.positions
            .iter()
            .zip(&ps.inv_mass)
            .map(|(x, &k)| {
                let offset = Vector3::new(next(), next(), next()) * amplitude;
                if k == 0.0 { *x } else { x + offset }
            })
            .collect()
    }

    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    }

    fn bits(xs: &[Vector3<f64>]) -> Vec<u64> {
        xs.iter()
            .flat_map(|x| x.iter().map(|c| c.to_bits()))
            .collect()
    }

    fn mu_bits(mu: &[f64]) -> Vec<u64> {
        mu.iter().map(|m| m.to_bits()).collect()
    }

    #[test]
    fn no_two_constraints_of_a_colour_share_a_dynamic_particle() {
        // Shear and bend edges: up to 12 constraints at a particle (greedy
        // needs at most 2 Δ − 1 colours); pins on
        // an edge, a corner and inside.
        let world = grid(30, 30, &[0, 29, 465], true);
        let (cs, k) = (world.constraints(), &world.particles().inv_mass);
        let colouring = ConstraintColouring::new(cs, k).unwrap();
        let mut seen = vec![false; cs.len()];
        let mut max_degree = vec![0_usize; k.len()];
        for i in 0..cs.len() {
            max_degree[cs.a[i] as usize] += 1;
            max_degree[cs.b[i] as usize] += 1;
        }
        let delta = max_degree.iter().copied().max().unwrap();
        assert!(
            colouring.n_colours() < 2 * delta,
            "{} colours",
            colouring.n_colours()
        );
        for c in 0..colouring.n_colours() {
            let mut used = vec![false; k.len()];
            let colour = colouring.colour(c);
            assert!(colour.windows(2).all(|w| w[0] < w[1]), "ascending");
            for &i in colour {
                let i = i as usize;
                assert!(!seen[i], "constraint {i} in two colours");
                seen[i] = true;
                for p in [cs.a[i] as usize, cs.b[i] as usize] {
                    if k[p] != 0.0 {
                        assert!(!used[p], "particle {p} twice in colour {c}");
                        used[p] = true;
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s), "every constraint has a colour");
        assert!(colouring.colour(colouring.n_colours()).is_empty());
    }

    #[test]
    fn constraints_to_a_static_particle_share_a_colour() {
        // A star of six constraints around particle 0.
        let mut cs = DistanceConstraints::new();
        for p in 1..=6 {
            cs.push(0, p, 1.0);
        }
        let mut k = vec![1.0; 7];
        k[0] = 0.0;
        assert_eq!(ConstraintColouring::new(&cs, &k).unwrap().n_colours(), 1);
        k[0] = 2.0;
        assert_eq!(ConstraintColouring::new(&cs, &k).unwrap().n_colours(), 6);
    }

    #[test]
    fn a_particle_past_the_set_is_an_error() {
        let mut cs = DistanceConstraints::new();
        cs.push(0, 3, 1.0);
        let e = ConstraintColouring::new(&cs, &[1.0, 1.0]).unwrap_err();
        assert!(
            matches!(
                e,
                crate::ClothError::VertexOutOfRange {
                    vertex: 3,
                    n_vertices: 2
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn a_particle_turning_static_needs_a_new_colouring() {
        let world = grid(4, 4, &[0], false);
        let (cs, k) = (world.constraints(), &world.particles().inv_mass);
        let colouring = ConstraintColouring::new(cs, k).unwrap();
        assert!(colouring.fits(cs, k));
        let mut heavier = k.clone();
        heavier[5] *= 0.5;
        assert!(
            colouring.fits(cs, &heavier),
            "a mass change keeps the colours"
        );
        let mut pinned = k.clone();
        pinned[5] = 0.0;
        assert!(!colouring.fits(cs, &pinned));
        assert!(!colouring.fits(cs, &k[..15]));
    }

    /// Runs `sweeps` coloured sweeps from `pred`, returning the positions and impulses.
    fn run_sweeps(
        cs: &DistanceConstraints,
        k: &[f64],
        pred: &[Vector3<f64>],
        sweeps: usize,
        parallel_min: usize,
        threads: usize,
    ) -> (Vec<Vector3<f64>>, Vec<f64>) {
        let mut sweep = ColouredSweep::new(cs, k)
            .unwrap()
            .with_parallel_min(parallel_min);
        let mut pred = pred.to_vec();
        let mut mu = vec![0.0; cs.len()];
        pool(threads).install(|| {
            for _ in 0..sweeps {
                sweep.sweep(cs, k, &mut pred, &mut mu, 1e4);
            }
        });
        (pred, mu)
    }

    #[test]
    fn parallel_passes_give_the_bits_of_the_in_place_loop() {
        // 60 x 60 with shear and bend (about 20 000 constraints), every
        // other constraint compliant, pins at two corners.
        let world = grid(60, 60, &[0, 59], true);
        let mut cs = world.constraints().clone();
        cs.compliance.iter_mut().step_by(2).for_each(|a| *a = 1e-3);
        let k = &world.particles().inv_mass;
        let pred = shaken(&world, 0.005);
        let (x_in_place, mu_in_place) = run_sweeps(&cs, k, &pred, 5, usize::MAX, 2);
        let (x_parallel, mu_parallel) = run_sweeps(&cs, k, &pred, 5, 0, 2);
        assert_eq!(bits(&x_in_place), bits(&x_parallel));
        assert_eq!(mu_bits(&mu_in_place), mu_bits(&mu_parallel));
        // The sweeps did something.
        assert_ne!(bits(&x_in_place), bits(&pred));
        let (x_one, mu_one) = run_sweeps(&cs, k, &pred, 5, 0, 1);
        assert_eq!(bits(&x_one), bits(&x_parallel));
        assert_eq!(mu_bits(&mu_one), mu_bits(&mu_parallel));
    }

    #[test]
    fn static_particles_never_move() {
        let world = grid(40, 40, &[0, 39, 820], true);
        let (cs, k) = (world.constraints(), &world.particles().inv_mass);
        let pred = shaken(&world, 0.003);
        for parallel_min in [0, usize::MAX] {
            let (x, _) = run_sweeps(cs, k, &pred, 3, parallel_min, 2);
            for p in [0, 39, 820] {
                assert_eq!(bits(&x[p..=p]), bits(&pred[p..=p]), "particle {p} moved");
            }
            assert_ne!(bits(&x), bits(&pred));
        }
    }

    #[test]
    fn free_cloth_sweep_conserves_momentum() {
        // No static particles, uneven masses: every impulse pair cancels to rounding.
        let mut world = grid(40, 40, &[], true);
        for (i, k) in world.particles_mut().inv_mass.iter_mut().enumerate() {
            *k = 1.0 / (0.001 * (1.0 + (i % 5) as f64));
        }
        let (cs, k) = (world.constraints(), &world.particles().inv_mass);
        let pred = shaken(&world, 0.003);
        for parallel_min in [0, usize::MAX] {
            let (x, _) = run_sweeps(cs, k, &pred, 3, parallel_min, 2);
            let mut dp = Vector3::zeros();
            let mut moved = 0.0;
            for i in 0..k.len() {
                let p = (x[i] - pred[i]) / k[i];
                dp += p;
                moved += p.norm();
            }
            assert!(moved > 0.0);
            // Rounding: a few ulps of each of ~1600 particles' momentum changes.
            assert!(
                dp.norm() <= 1e-12 * moved,
                "|Δp| = {} of {moved}",
                dp.norm()
            );
        }
    }

    #[test]
    fn parallel_max_error_is_the_serial_one() {
        let world = grid(60, 60, &[0], true);
        let pred = shaken(&world, 0.004);
        let cs = world.constraints();
        let mu = vec![0.0; cs.len()];
        let serial = cs.max_error(&pred, &mu, 1e4);
        let parallel = pool(2).install(|| max_error(cs, &pred, &mu, 1e4));
        assert_eq!(serial.to_bits(), parallel.to_bits());
        let mut broken = pred.clone();
        broken[100].x = f64::NAN;
        assert!(
            pool(2)
                .install(|| max_error(cs, &broken, &mu, 1e4))
                .is_nan()
        );
    }
}

//! The global solve: Newton's method on positions and impulses together.
//!
//! # Equations
//!
//! A step of size `h` starts from positions `c` and velocities `v`. The free
//! preview is `x̃ = c + h v + h² g/2` (static particles: `x̃ = c`). The
//! unknowns are the end-of-step positions `x` (three per dynamic particle)
//! and one impulse per constraint, kept as `μ_c = h p_c` (kg m, the impulse
//! times the step, positive under tension). With `M = diag(m)`,
//! `C_c(x) = |x_a − x_b| − L_c` and `∇C_c = n_c = (x_a − x_b)/|x_a − x_b|` on
//! `a` (`−n_c` on `b`):
//!
//! ```text
//! F(x, μ) = M (x − x̃) + J(x)ᵀ μ − r = 0      (momentum, per particle)
//! C(x)    = 0                               (inextensibility, per edge)
//! ```
//!
//! The impulse of each constraint acts along its *current* (end-of-step)
//! direction, equal and opposite on its two particles, as in the paper's
//! preview; `r` are contact impulses (below). Velocities follow from the
//! positions (`v = (x − c)/h + h g/2`, the world's commit), so impulses change
//! velocities exactly as in the impulse form.
//!
//! # Newton's step
//!
//! Linearising both equations at `(x, μ)`:
//!
//! ```text
//! ⎡ K   Jᵀ⎤ ⎡δx⎤     ⎡F⎤        K = M + Σ_c μ_c⁺ ∇²C_c + κ P_contacts
//! ⎣ J  −E ⎦ ⎣δμ⎦ = − ⎣C⎦,       ∇²C_c = [H −H; −H H],  H = (I − n nᵀ)/|x_a − x_b|
//! ```
//!
//! `μ ∇²C` is the geometric stiffness of a link under tension: moving a
//! particle sideways lengthens a tight link, so the tension resists it. The
//! Gauss–Newton (fast projection) step `J M⁻¹ Jᵀ δμ = C` drops it, which is
//! exact for slack cloth and hopeless for a taut row between two pins (the
//! `two-corners` scene), where all the stiffness is geometric. Compressed
//! links contribute `μ⁺ = max(μ, 0)`, so `K` stays positive definite.
//! `E = diag(ε (k_a + k_b) + α_c/h²)` is positive: the compliance `α` of a
//! compliant link, plus a proximal shift [`REGULARISATION`] that changes
//! only the step, not the solution it converges to. Statics have no rows.
//! Momentum: every term of `Jᵀμ` and of `∇²C` comes in equal and opposite
//! pairs, so `Σ F` changes only through `M δx`, and the total momentum is
//! conserved by every step, full or shortened, fresh factor or stale.
//!
//! # The reduced system
//!
//! `E` is diagonal, so the impulses are eliminated exactly:
//! `δμ = E⁻¹ (J δx + C)`, and the positions solve the symmetric positive
//! definite system
//!
//! ```text
//! (K + Jᵀ E⁻¹ J) δx = −F − Jᵀ E⁻¹ C
//! ```
//!
//! of three rows per dynamic particle, whose pattern is the mesh's: a 3×3
//! block per particle and per link. This is the same Newton step as the
//! saddle-point system, at a third of the size (2700 rows instead of 4434
//! on a 30 × 30 cloth). Its Cholesky factor (faer's supernodal `LLᵀ`, the
//! particles numbered once per topology in an approximate minimum degree
//! order) costs about 0.85 ms on 30 × 30, against 3.5 ms for the `LDLᵀ` of
//! the saddle-point matrix with the impulses ordered after their particles
//! (367 k nonzeros) and 2 ms with them ordered by minimum degree (100 k,
//! simplicial). The reduction is the penalty method's matrix with the
//! penalty `E⁻¹` huge, but it is not the penalty method: the impulses are
//! unknowns, the constraint is held exactly at convergence, and `E` only
//! weights the step.
//!
//! # Factor reuse
//!
//! The numeric factor is kept across iterations and steps (a chord method:
//! the residual is always fresh, the matrix may be stale) and recomputed
//! when an iteration shrinks the merit by less than
//! [`SolverParams::refactor_ratio`](crate::SolverParams::refactor_ratio) or a
//! stale step fails the line search. A stale factor is the exact reduction
//! of a stale saddle-point matrix only together with its own `J` and `E`,
//! so the directions and weights of the factorised matrix are kept with it
//! and used for the right-hand side and for `δμ` (with today's directions
//! instead, the stale steps failed and factorisations per step doubled).
//!
//! # Warm start
//!
//! A step starts from the free preview plus last step's correction
//! `x − x̃` (scaled by the step ratio squared), with last step's impulses
//! and contact set. A cloth at rest then starts at rest, and a swinging one
//! with last step's centripetal pull already applied: the initial stretch
//! of `corner` falls from up to 40 % to a few per cent. (Applying last
//! step's impulses along the preview's directions instead stretched
//! `two-corners` without bound; extrapolating the correction linearly in
//! time was worse than keeping it.)
//!
//! # Globalisation
//!
//! Each step is shortened (halved up to [`MAX_HALVINGS`] times) until the
//! merit `Σ (C_c/L_c)² + Σ (|F_i|/(m_i ℓ))²` (`ℓ` the mean rest length)
//! decreases. A fresh-factor step that cannot decrease it (or a factorisation
//! that fails or gives non-finite values) is replaced by one Gauss–Seidel
//! sweep along the current directions, which keeps `F` consistent to second
//! order, and the next iteration refactors; the sweeps are counted in the
//! report ([`StepReport::fallback_sweeps`](crate::StepReport::fallback_sweeps)).
//!
//! # Contacts
//!
//! Contacts form an active set. A particle found inside a collider joins it;
//! an active particle is projected onto its collider's surface at every
//! evaluation, and its contact impulse `r` is the normal part of what it
//! needs (`r·n` of `M(x − x̃) + Jᵀμ`) plus Coulomb friction opposing its
//! tangential motion over the step, regularised below
//! [`FRICTION_SLIP`]: there friction is a stiff tangential spring, so a
//! particle sticks while the cone holds it (creeping by at most
//! `FRICTION_SLIP` per step) and slides with `friction × r·n` when it does
//! not. Between iterations a particle whose normal impulse would pull it
//! into the surface leaves the set. In the matrix an active particle gets a
//! stiff spring `κ = CONTACT_STIFFNESS · m` along the normal and friction's
//! tangential stiffness, so Newton's step sees it as held by the surface.
//! (Holding sticking particles at fixed anchors was tried first: anchors of
//! neighbours need not be a rest length apart, and the impulses between
//! them grew without bound.)
//!
//! # Convergence
//!
//! A step has converged when every relative stretch is at most the
//! tolerance and the momentum residual of every particle in contact is at
//! most the tolerance times the mean rest length (friction acts only
//! through it). Particles in contact are projected onto their surfaces at
//! every evaluation and every other particle is outside every collider, so
//! nothing penetrates. The momentum residual of free particles is driven
//! down by the merit but not required to vanish.
//!
//! # Measured
//!
//! With these choices (refactor ratio 0.3, up to [`MAX_INCREASES`]
//! non-monotone full steps), the 30 × 30 reference scenes (3 s, h = 0.01)
//! hold 1e-4 at every step, on one thread: `corner` 2.6 iterations and
//! 1.16 factorisations per step (0.49 s, 6.0× real time), `two-corners` 2.0
//! and 0.46 (0.26 s, 11×), `drape` 2.5 and 0.93 (0.49 s, 6.0×); see
//! `examples/scene_timing.rs` and `modelgap cloth bench`. Factorisations
//! are about 60 % of the time. On `corner` most of them fall in the snaps,
//! where even fresh Newton steps converge slowly.
//!
//! Meshes beyond the reference scenes (1 s, one thread): `corner` with
//! shear edges (3422 constraints on 2697 degrees of freedom) 50 iterations
//! per step, 4 steps of 100 unconverged (largest stretch 1.5e-4), 9 s; with
//! shear and bend edges (a nearly rigid sheet) 5.2 iterations, 1.5 s; a
//! 25 × 25 cloth dropped on a tilted box above a floor (friction 0.5 and
//! 0.2, 2 s) 76 iterations per step, 8 of 200 steps unconverged, 6 s.
//! Over-constrained meshes and many changing contacts are where Newton is
//! slow; the saddle-point solver before took 81 / 5.2 / 103 iterations per
//! step there, and 69 / 17 / 22 s.
//!
//! Tried and dropped, measured on the same scenes: the saddle-point
//! matrix itself (`LDLᵀ`, 3.5 ms or 2 ms a factorisation, above); GMRES
//! preconditioned by the stale factor instead of refactoring (too many
//! iterations: 2× slower); a penalty `K + Jᵀ W J` with `W` independent of
//! the factor (the stale factor stopped serving); a simplicial instead of
//! the supernodal factorisation (2.3× slower on the reduced matrix);
//! other supernode amalgamation thresholds (none better than faer's);
//! refactor ratios from 0.1 to 0.7 (0.3 is best; 0.7 stalls `drape` at the
//! impact); keeping a stale factor when few more stale iterations are
//! predicted to reach the tolerance (as many iterations added as
//! factorisations saved); a few Gauss–Seidel sweeps before or after each
//! Newton step (no fewer factorisations); the exact friction Jacobian
//! while sliding (no stiffness along the slip: `drape` oscillated between
//! stick and slip, 100× slower); a geometric nested-dissection ordering
//! (more fill than minimum degree).
//!
//! # At scale
//!
//! On a 100 × 100 `corner` (29 997 rows, 238 k nonzeros, a factor of
//! 2.27 M) one numeric factorisation costs about 16 ms and one solve with it
//! 2.7 ms. Over the first second (100 steps) Newton did 330 factorisations
//! (about 70 % of the time) and 561 solves (20 %); assembling the matrix and
//! evaluating the iterates were 2–4 % each. Outside the two snaps a step
//! takes about 3 iterations and one factorisation (about 24 ms, 0.4× real
//! time); 250 of the 330 factorisations fall in the 25 steps of the snaps,
//! where the full steps raise the merit and every iteration refactors
//! (10–23 iterations a step). Measured there and dropped:
//! conjugate gradients on the current reduced matrix preconditioned by the
//! kept factor, refactoring when they need more than 20 iterations (an
//! inexact Newton, relative residual 1e-2): 457 factorisations and 8601
//! solves instead of 330 and 561, 4× slower, because the links' stiff part
//! (`E⁻¹`, a million times the mass) makes a factor built along last
//! iteration's directions a poor preconditioner as soon as they turn;
//! faer's parallel numeric factorisation on 2 threads (1.8× slower than
//! sequential on 100 × 100); refactor ratios 0.1, 0.6 and 0.9 (369, 311 and
//! 303 factorisations against 330 at 0.3, CPU time within the noise); fewer
//! non-monotone steps (0 or 2 instead of [`MAX_INCREASES`]: 55 of 100 steps
//! unconverged); the impulses' own system `J M⁻¹ Jᵀ + E` (one unknown per
//! link, the fast projection's, with the geometric stiffness folded into a
//! preconditioner) measured first on its own: on 100 × 100 (19 800 rows,
//! 0.42–0.61 M nonzeros in its factor) a factorisation took 13–16 ms, no
//! cheaper than the reduced matrix's, so it was not built (2026-11-29). With a direct factor a step cannot get below a
//! factorisation and three solves, so 1× real time on 100 × 100 (10 ms a
//! step) needs an inner solver whose iteration costs a few sweeps over the
//! mesh, such as multigrid over the grid hierarchy that keeps the links'
//! inextensible modes; none is built.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::linalg::{SupernodalThreshold, amd};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use nalgebra::{Matrix3, Vector3};

use crate::constraints::DistanceConstraints;
use crate::contact::{Collider, ContactState};
use crate::kernel::{Link, Separation};
use crate::solver::{self, SolverParams};

/// The proximal shift `ε` in `E = ε (k_a + k_b) + α/h²` (dimensionless:
/// relative to the reduced mass of each link). It changes only Newton's
/// step, not the solution it converges to, and bounds the impulse of a
/// nearly dependent constraint (a straight row between two pins, whose
/// tension the linearisation cannot see): with 1e-10 such a row took huge
/// impulse steps that the next direction change turned into momentum
/// errors; 1e-6 cut `two-corners` from 15 to 4 iterations per step
/// (1e-8 to 1e-5 measured again: 1e-6 is best).
pub const REGULARISATION: f64 = 1e-6;

/// Full Newton steps (fresh factor) that may raise the merit in one step:
/// the merit mixes stretch and momentum residual, and a good step often
/// trades a large fall of one for a rise of the other (halving it instead
/// tripled the iterations on `corner`).
pub const MAX_INCREASES: usize = 10;

/// A full step may raise the merit at most this many times (dimensionless).
pub const WATCHDOG: f64 = 100.0;

/// Contact stiffness in the Newton matrix, per unit particle mass
/// (dimensionless): a particle in contact is treated as held by a spring
/// this many times its mass, so a step barely moves it into the surface.
pub const CONTACT_STIFFNESS: f64 = 1e6;

/// Tangential motion over a step (m) below which friction acts as a stiff
/// spring rather than a constant force: the regularisation of Coulomb's
/// law that lets a particle stick (it creeps by at most this much per step).
pub const FRICTION_SLIP: f64 = 1e-6;

/// A step starts from the free preview instead of the preview plus last
/// step's correction when the merit there is this many times lower
/// (dimensionless). The correction cut `drape`'s factorisations from 2.9 to
/// 0.93 per step. On a mesh with more constraints than degrees of freedom
/// (shear edges: both diagonals of every quad) the impulses are not unique
/// and carry self-stress (`Jᵀμ = 0`) that grows from step to step; there
/// the corrected start's merit grew to 10⁵ and Newton needed 523 iterations
/// per step (160 with this ratio), so such a mesh always starts from the
/// preview (50 iterations per step; 81 before the correction existed). This
/// ratio guards the same where self-stress is local (2 to 10 measured
/// alike).
pub const START_MERIT_RATIO: f64 = 3.0;

/// Halvings of a Newton step tried before the iteration gives up on it.
pub const MAX_HALVINGS: usize = 8;

/// Largest negative geometric stiffness a compressed link may add to the
/// Newton matrix, per unit mass of its lighter dynamic particle
/// (dimensionless); 0: compressed links add none (`μ⁺`), so `K` stays
/// positive definite and Newton's step is inexact only at compressed links.
/// (0.1 was tried: no better on `corner`, worse on `two-corners`.)
pub const COMPRESSION_STIFFNESS: f64 = 0.0;

/// Iterations over which the error must fall by [`STALL_RATIO`], or the step
/// stops as stagnated (see `solver::stalled`).
pub const STALL_WINDOW: usize = 30;

/// The factor the smallest error so far must fall by over [`STALL_WINDOW`]
/// iterations (dimensionless). A sound Newton step shrinks it by orders in a
/// few iterations (a stale factor by at least `refactor_ratio` per
/// iteration); where the requested tolerance is below what the problem
/// allows (a straight row between pins under a transverse load at 1e-9)
/// the stretch creeps down by 0.3 % per iteration and would run the
/// iteration cap on every step.
pub const STALL_RATIO: f64 = 0.5;

const NONE: u32 = u32::MAX;

/// Why the solver could not be built: faer's ordering, symbolic
/// factorisation or scratch allocation failed, which it reports only for an
/// index overflow or an allocation failure (no mesh the limits admit gets
/// there). The world then runs Gauss–Seidel and says so
/// ([`Fallback::NewtonUnavailable`](crate::solver::Fallback::NewtonUnavailable)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct FactorFailed;

#[cfg(test)]
thread_local! {
    /// Tests: [`NewtonSolver::new`] fails on this thread while set (see [`FailBuilds`]).
    static FAIL_BUILDS: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Tests: while this guard lives, [`NewtonSolver::new`] fails on this thread,
/// so the world's Gauss–Seidel fallback can be tested (no input provokes it).
#[cfg(test)]
pub(crate) struct FailBuilds;

#[cfg(test)]
impl FailBuilds {
    pub(crate) fn new() -> Self {
        FAIL_BUILDS.set(true);
        Self
    }
}

#[cfg(test)]
impl Drop for FailBuilds {
    fn drop(&mut self) {
        FAIL_BUILDS.set(false);
    }
}

/// What one Newton solve did.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct NewtonOutcome {
    pub(crate) iterations: usize,
    pub(crate) factorizations: usize,
    pub(crate) fallback_sweeps: usize,
    pub(crate) converged: bool,
    /// The error stopped falling ([`STALL_WINDOW`], [`STALL_RATIO`]).
    pub(crate) stagnated: bool,
    pub(crate) max_stretch: f64,
}

/// The inputs of a step that Newton's iteration does not change.
pub(crate) struct StepInput<'a> {
    pub(crate) constraints: &'a DistanceConstraints,
    pub(crate) inv_mass: &'a [f64],
    /// Positions at the start of the step (m).
    pub(crate) start: &'a [Vector3<f64>],
    /// The free preview `x̃` (m).
    pub(crate) free: &'a [Vector3<f64>],
    pub(crate) colliders: &'a [Collider],
    pub(crate) params: &'a SolverParams,
    /// `1/h²` (1/s²): compliant constraints' error is `len − rest − α μ/h²`.
    pub(crate) inv_h2: f64,
    /// Hold the momentum residual of every particle, not only of those in
    /// contact, within the tolerance (a BDF2 step: its velocity reads the
    /// positions of two steps, so what the solve leaves of the momentum
    /// equation becomes velocity).
    pub(crate) hold_momentum: bool,
}

/// An iterate and everything evaluated at it.
#[derive(Debug, Default, Clone)]
struct State {
    x: Vec<Vector3<f64>>,
    mu: Vec<f64>,
    /// Contact impulses (kg m).
    r: Vec<Vector3<f64>>,
    /// Contact of each particle (the active set).
    contact: Vec<Contact>,
    /// `Σ_c ±μ_c n_c` per particle (kg m).
    g: Vec<Vector3<f64>>,
    /// Momentum residual per particle (kg m).
    f: Vec<Vector3<f64>>,
    normals: Vec<Vector3<f64>>,
    lengths: Vec<f64>,
    /// `C_c` (m).
    c: Vec<f64>,
    merit: f64,
    max_stretch: f64,
    max_residual: f64,
    /// Largest momentum residual of a particle in contact (m): friction
    /// acts only through it, so a step has not converged until it is small.
    contact_residual: f64,
}

#[derive(Clone, Copy, Debug, Default)]
struct Contact {
    normal: Vector3<f64>,
    friction: f64,
    collider: u32,
    active: bool,
    /// `friction × normal impulse / tangential motion` (kg): friction's
    /// tangential stiffness at the last evaluation.
    tangential_stiffness: f64,
}

/// Newton's linear system of one topology, reduced to the positions: its
/// pattern, ordering, symbolic and numeric factors, value slots, iterates and
/// scratch. Nothing is allocated per iteration.
pub(crate) struct NewtonSolver {
    n_particles: usize,
    n_constraints: usize,
    /// First row of each particle (`NONE` for a static one).
    dof: Vec<u32>,
    dim: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
    /// Slots of each dynamic particle's 3×3 diagonal block, `[row][col]`
    /// mapped to the upper triangle.
    diag_slots: Vec<[u32; 9]>,
    /// Slots of the off-diagonal block of each constraint between two
    /// dynamic particles (`NONE` otherwise).
    edge_slots: Vec<[u32; 9]>,
    /// `1/E_c` of the factorised matrix (kg m per m): the weight of each
    /// constraint in the Schur complement, kept so the right-hand side and
    /// the impulse update match the factor even when it is stale.
    inv_e: Vec<f64>,
    /// Constraint directions of the factorised matrix: a stale factor is
    /// the exact reduction of a stale `J` only with its own directions.
    factor_normals: Vec<Vector3<f64>>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    has_factor: bool,
    mem: MemBuffer,
    mean_rest: f64,
    rhs: Vec<f64>,
    /// `x − x̃` of the last solve (m): the next step starts from its
    /// preview plus this correction.
    pub(crate) last_correction: Vec<Vector3<f64>>,
    /// The smallest error so far after each iteration of a solve (scratch).
    best_errors: Vec<f64>,
    cur: State,
    trial: State,
}

impl std::fmt::Debug for NewtonSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NewtonSolver")
            .field("dim", &self.dim)
            .field("nnz", &self.row_idx.len())
            .field("factor_nnz", &self.l_values.len())
            .finish_non_exhaustive()
    }
}

/// One index of a symmetric 3×3 entry (either triangle's).
fn sym(i: usize, j: usize) -> (usize, usize) {
    (i.min(j), i.max(j))
}

impl NewtonSolver {
    /// Builds the pattern of the reduced matrix, its ordering and its
    /// symbolic factor.
    pub(crate) fn new(
        constraints: &DistanceConstraints,
        inv_mass: &[f64],
    ) -> Result<Self, FactorFailed> {
        #[cfg(test)]
        if FAIL_BUILDS.get() {
            return Err(FactorFailed);
        }
        let n_particles = inv_mass.len();
        let m = constraints.len();
        let dof = fill_reducing_rows(constraints, inv_mass)?;
        let dim = 3 * dof.iter().filter(|&&d| d != NONE).count();

        // Pattern (upper triangle) as (col, row) pairs: a 3×3 block per
        // dynamic particle and per constraint between two of them.
        let mut entries: Vec<(usize, usize)> = Vec::new();
        for &d in &dof {
            if d == NONE {
                continue;
            }
            let d = d as usize;
            for j in 0..3 {
                for i in 0..=j {
                    entries.push((d + j, d + i));
                }
            }
        }
        for c in 0..m {
            let (da, db) = (
                dof[constraints.a[c] as usize],
                dof[constraints.b[c] as usize],
            );
            if da != NONE && db != NONE {
                let (lo, hi) = (da.min(db) as usize, da.max(db) as usize);
                for j in 0..3 {
                    for i in 0..3 {
                        entries.push((hi + j, lo + i));
                    }
                }
            }
        }
        entries.sort_unstable();
        entries.dedup();
        let mut col_ptr = vec![0usize; dim + 1];
        let mut row_idx = Vec::with_capacity(entries.len());
        for &(col, row) in &entries {
            col_ptr[col + 1] += 1;
            row_idx.push(row);
        }
        for c in 0..dim {
            col_ptr[c + 1] += col_ptr[c];
        }
        let slot = |row: usize, col: usize| -> u32 {
            let (row, col) = (row.min(col), row.max(col));
            let r = &row_idx[col_ptr[col]..col_ptr[col + 1]];
            match r.binary_search(&row) {
                Ok(k) => (col_ptr[col] + k) as u32,
                Err(_) => NONE,
            }
        };
        let mut diag_slots = vec![[NONE; 9]; n_particles];
        for (p, &d) in dof.iter().enumerate() {
            if d == NONE {
                continue;
            }
            let d = d as usize;
            for i in 0..3 {
                for j in 0..3 {
                    let (r, c) = sym(d + i, d + j);
                    diag_slots[p][3 * i + j] = slot(r, c);
                }
            }
        }
        let mut edge_slots = vec![[NONE; 9]; m];
        for c in 0..m {
            let (da, db) = (
                dof[constraints.a[c] as usize],
                dof[constraints.b[c] as usize],
            );
            if da != NONE && db != NONE {
                for i in 0..3 {
                    for j in 0..3 {
                        // Row i of a, column j of b: the block is symmetric
                        // (a multiple of a symmetric matrix), so either
                        // triangle's slot holds the same value.
                        edge_slots[c][3 * i + j] = slot(da as usize + i, db as usize + j);
                    }
                }
            }
        }

        // The rows are already in a fill-reducing order: the symbolic factor
        // is a supernodal Cholesky factor of the matrix as it is (faer would
        // otherwise permute the values at every factorisation).
        let symbolic = {
            let pattern = SymbolicSparseColMatRef::new_checked(dim, dim, &col_ptr, None, &row_idx);
            let params = CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..CholeskySymbolicParams::default()
            };
            factorize_symbolic_cholesky(pattern, Side::Upper, SymmetricOrdering::Identity, params)
                .map_err(|_| FactorFailed)?
        };
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        let mem = MemBuffer::try_new(req).map_err(|_| FactorFailed)?;
        let mean_rest = if m == 0 {
            1.0
        } else {
            constraints.rest_length.iter().sum::<f64>() / m as f64
        };
        let state = State {
            x: vec![Vector3::zeros(); n_particles],
            mu: vec![0.0; m],
            r: vec![Vector3::zeros(); n_particles],
            contact: vec![Contact::default(); n_particles],
            g: vec![Vector3::zeros(); n_particles],
            f: vec![Vector3::zeros(); n_particles],
            normals: vec![Vector3::zeros(); m],
            lengths: vec![0.0; m],
            c: vec![0.0; m],
            ..State::default()
        };
        Ok(Self {
            n_particles,
            n_constraints: m,
            dof,
            dim,
            values: vec![0.0; row_idx.len()],
            l_values: vec![0.0; symbolic.len_val()],
            col_ptr,
            row_idx,
            diag_slots,
            edge_slots,
            inv_e: vec![0.0; m],
            factor_normals: vec![Vector3::zeros(); m],
            symbolic,
            has_factor: false,
            mem,
            mean_rest,
            rhs: vec![0.0; dim],
            last_correction: vec![Vector3::zeros(); n_particles],
            best_errors: Vec::with_capacity(STALL_WINDOW + 1),
            cur: state.clone(),
            trial: state,
        })
    }

    /// Solves one step: `x` holds the initial guess on entry (the preview,
    /// possibly with warm-start impulses applied) and the end-of-step
    /// positions on return; `mu` likewise holds the impulses (kg m).
    /// `contacts` receives the final contact of each particle.
    pub(crate) fn solve(
        &mut self,
        input: &StepInput<'_>,
        x: &mut [Vector3<f64>],
        mu: &mut [f64],
        contacts: &mut [ContactState],
        warm: Option<f64>,
    ) -> NewtonOutcome {
        debug_assert_eq!(x.len(), self.n_particles);
        debug_assert_eq!(mu.len(), self.n_constraints);
        let params = input.params;
        let tol = params.stretch_tolerance;
        let mut out = NewtonOutcome::default();
        self.cur.x.copy_from_slice(x);
        self.cur.mu.copy_from_slice(mu);
        match warm {
            Some(scale) => {
                // Warm start: last step's contacts stay active (evaluate
                // projects them onto their surfaces and the iteration
                // releases those that pull), and the particles start from
                // their preview plus last step's correction `x − x̃`, which
                // scales with the step squared: a cloth at rest then starts
                // at rest, and a swinging one with the centripetal pull of
                // the last step already applied. From the preview alone
                // when the merit there is START_MERIT_RATIO times lower, and
                // always on a mesh with more constraints than degrees of
                // freedom (see START_MERIT_RATIO).
                let n_colliders = input.colliders.len();
                for ct in &mut self.cur.contact {
                    if ct.collider as usize >= n_colliders {
                        ct.active = false;
                    }
                }
                let (cur, trial) = (&mut self.cur, &mut self.trial);
                if self.n_constraints <= self.dim {
                    trial.x.copy_from_slice(&cur.x);
                    trial.mu.copy_from_slice(&cur.mu);
                    trial.r.copy_from_slice(&cur.r);
                    trial.contact.copy_from_slice(&cur.contact);
                    for (i, x) in cur.x.iter_mut().enumerate() {
                        if input.inv_mass[i] > 0.0 {
                            *x += self.last_correction[i] * scale;
                        }
                    }
                    evaluate(trial, input, self.mean_rest);
                    evaluate(cur, input, self.mean_rest);
                    if cur.merit > START_MERIT_RATIO * trial.merit {
                        std::mem::swap(cur, trial);
                    }
                } else {
                    evaluate(cur, input, self.mean_rest);
                }
            }
            None => {
                self.cur.r.fill(Vector3::zeros());
                self.cur.contact.fill(Contact::default());
                evaluate(&mut self.cur, input, self.mean_rest);
            }
        }
        let mut need_refactor = false;
        let mut increases_left = MAX_INCREASES;
        self.best_errors.clear();
        loop {
            out.max_stretch = self.cur.max_stretch;
            let momentum = if input.hold_momentum {
                self.cur.max_residual
            } else {
                self.cur.contact_residual
            };
            if self.cur.max_stretch <= tol && momentum <= tol * self.mean_rest {
                out.converged = true;
                break;
            }
            // The error in tolerances: stretch, and the momentum residual of
            // particles in contact (of every particle in a BDF2 step).
            let error = (self.cur.max_stretch / tol).max(momentum / (tol * self.mean_rest));
            if solver::stalled(&mut self.best_errors, error, STALL_WINDOW, STALL_RATIO) {
                out.stagnated = true;
                break;
            }
            if out.iterations >= params.max_iterations || !self.cur.merit.is_finite() {
                break;
            }
            out.iterations += 1;
            let mut accepted = false;
            for attempt in 0..2 {
                let fresh = need_refactor || !self.has_factor || attempt == 1;
                if fresh {
                    out.factorizations += 1;
                    if self.factorize(input).is_err() {
                        break;
                    }
                }
                let allow_increase = fresh && increases_left > 0;
                if self.newton_step(input, fresh, allow_increase) {
                    accepted = true;
                    break;
                }
                if fresh {
                    break;
                }
            }
            need_refactor = false;
            if accepted && update_contacts(&mut self.trial, input) {
                evaluate(&mut self.trial, input, self.mean_rest);
                std::mem::swap(&mut self.cur, &mut self.trial);
                need_refactor = false;
                continue;
            }
            if accepted && self.trial.merit >= self.cur.merit {
                // A full Newton step that raised the merit (allowed a few
                // times per step: the merit mixes stretch and momentum, and
                // a good step can trade one for the other): keep the factor
                // fresh until the merit falls again.
                increases_left -= 1;
                std::mem::swap(&mut self.cur, &mut self.trial);
                need_refactor = true;
                continue;
            }
            if accepted {
                let ratio = (self.trial.merit / self.cur.merit).sqrt();
                if ratio > params.refactor_ratio {
                    need_refactor = true;
                }
                std::mem::swap(&mut self.cur, &mut self.trial);
            } else {
                // Newton failed even with a fresh factor: one Gauss–Seidel
                // sweep along the current directions, then a fresh factor.
                self.has_factor = false;
                out.fallback_sweeps += 1;
                solver::gauss_seidel_sweep(
                    input.constraints,
                    input.inv_mass,
                    &mut self.cur.x,
                    &mut self.cur.mu,
                    input.inv_h2,
                );
                evaluate(&mut self.cur, input, self.mean_rest);
            }
        }
        for i in 0..x.len() {
            self.last_correction[i] = self.cur.x[i] - input.free[i];
        }
        x.copy_from_slice(&self.cur.x);
        mu.copy_from_slice(&self.cur.mu);
        for (s, c) in contacts.iter_mut().zip(&self.cur.contact) {
            *s = ContactState {
                normal: c.normal,
                friction: c.friction,
                active: c.active,
            };
        }
        out
    }

    /// Solves with the current factor at `cur` and line-searches into
    /// `trial`; returns whether a step decreased the merit.
    fn newton_step(&mut self, input: &StepInput<'_>, fresh: bool, allow_increase: bool) -> bool {
        let cs = input.constraints;
        let cur = &self.cur;
        // Right-hand side of the reduced system: −F − Jᵀ E⁻¹ C.
        for (p, &d) in self.dof.iter().enumerate() {
            if d != NONE {
                let d = d as usize;
                for i in 0..3 {
                    self.rhs[d + i] = -cur.f[p][i];
                }
            }
        }
        for c in 0..self.n_constraints {
            let v = self.factor_normals[c] * (self.inv_e[c] * cur.c[c]);
            for (p, sign) in [(cs.a[c] as usize, -1.0), (cs.b[c] as usize, 1.0)] {
                let d = self.dof[p];
                if d != NONE {
                    let d = d as usize;
                    for i in 0..3 {
                        self.rhs[d + i] += sign * v[i];
                    }
                }
            }
        }
        let llt = LltRef::new(&self.symbolic, &self.l_values);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut self.rhs, self.dim, 1),
            Par::Seq,
            MemStack::new(&mut self.mem),
        );
        if self.rhs.iter().any(|v| !v.is_finite()) {
            self.has_factor = false;
            return false;
        }
        let dof = &self.dof;
        let rhs = &self.rhs;
        let step = |p: usize| -> Vector3<f64> {
            match dof[p] {
                NONE => Vector3::zeros(),
                d => {
                    let d = d as usize;
                    Vector3::new(rhs[d], rhs[d + 1], rhs[d + 2])
                }
            }
        };
        // The impulses follow from the positions: δμ = E⁻¹ (J δx + C).
        let mut alpha = 1.0;
        for _ in 0..=MAX_HALVINGS {
            let (cur, trial) = (&self.cur, &mut self.trial);
            trial.r.copy_from_slice(&cur.r);
            trial.contact.copy_from_slice(&cur.contact);
            for p in 0..self.n_particles {
                trial.x[p] = cur.x[p] + alpha * step(p);
            }
            for c in 0..self.n_constraints {
                let (a, b) = (cs.a[c] as usize, cs.b[c] as usize);
                let n = self.factor_normals[c];
                let dmu = self.inv_e[c] * (n.dot(&(step(a) - step(b))) + cur.c[c]);
                trial.mu[c] = cur.mu[c] + alpha * dmu;
            }
            evaluate(trial, input, self.mean_rest);
            if trial.merit < (1.0 - 1e-4 * alpha) * cur.merit {
                return true;
            }
            if alpha == 1.0
                && allow_increase
                && trial.merit.is_finite()
                && trial.merit < WATCHDOG * cur.merit
            {
                return true;
            }
            if !fresh {
                // A stale factor's step that does not decrease the merit:
                // refactor rather than shorten it.
                return false;
            }
            alpha *= 0.5;
        }
        false
    }

    /// Fills the reduced matrix `K + Jᵀ E⁻¹ J` at `cur` and factorises it.
    fn factorize(&mut self, input: &StepInput<'_>) -> Result<(), FactorFailed> {
        let cs = input.constraints;
        let cur = &self.cur;
        self.values.fill(0.0);
        let add = |values: &mut [f64], slots: &[u32; 9], block: &Matrix3<f64>, sym_block: bool| {
            for i in 0..3 {
                for j in 0..3 {
                    // A diagonal block maps (i, j) and (j, i) to one slot:
                    // add its upper triangle only.
                    if sym_block && i > j {
                        continue;
                    }
                    values[slots[3 * i + j] as usize] += block[(i, j)];
                }
            }
        };
        for (p, &d) in self.dof.iter().enumerate() {
            if d == NONE {
                continue;
            }
            let m = 1.0 / input.inv_mass[p];
            let mut block = Matrix3::identity() * m;
            let ct = &cur.contact[p];
            if ct.active {
                let kappa = CONTACT_STIFFNESS * m;
                let nn = ct.normal * ct.normal.transpose();
                block += nn * kappa + (Matrix3::identity() - nn) * ct.tangential_stiffness;
            }
            add(&mut self.values, &self.diag_slots[p], &block, true);
        }
        for c in 0..self.n_constraints {
            let (pa, pb) = (cs.a[c] as usize, cs.b[c] as usize);
            let n = cur.normals[c];
            self.factor_normals[c] = n;
            // E = ε (k_a + k_b) + α/h²: the proximal shift and the
            // compliance (see REGULARISATION), the kernel's weight.
            let e = Link::new(cs, c, input.inv_h2).weight(
                input.inv_mass[pa],
                input.inv_mass[pb],
                REGULARISATION,
            );
            self.inv_e[c] = 1.0 / e;
            let mut block = n * n.transpose() * self.inv_e[c];
            // Compression enters with a bounded negative stiffness so that
            // K stays positive definite (see COMPRESSION_STIFFNESS).
            let m_min = 1.0 / input.inv_mass[pa].max(input.inv_mass[pb]);
            let tension = cur.mu[c].max(-COMPRESSION_STIFFNESS * m_min * cur.lengths[c]);
            if tension != 0.0 && cur.lengths[c] > f64::MIN_POSITIVE {
                block += (Matrix3::identity() - n * n.transpose()) * (tension / cur.lengths[c]);
            }
            for p in [pa, pb] {
                if self.dof[p] != NONE {
                    add(&mut self.values, &self.diag_slots[p], &block, true);
                }
            }
            if self.edge_slots[c][0] != NONE {
                add(&mut self.values, &self.edge_slots[c], &(-block), false);
            }
        }
        let pattern = SymbolicSparseColMatRef::new_checked(
            self.dim,
            self.dim,
            &self.col_ptr,
            None,
            &self.row_idx,
        );
        let a = SparseColMatRef::new(pattern, &self.values);
        let result = self.symbolic.factorize_numeric_llt(
            &mut self.l_values,
            a,
            Side::Upper,
            LltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut self.mem),
            Default::default(),
        );
        self.has_factor = result.is_ok();
        result.map(|_| ()).map_err(|_| FactorFailed)
    }
}

/// The first row of each dynamic particle's three (`NONE` for a static
/// one), numbered in an approximate minimum degree ordering of the graph of
/// dynamic particles and the constraints between them, so the Cholesky
/// factor of the reduced matrix stays sparse.
fn fill_reducing_rows(
    constraints: &DistanceConstraints,
    inv_mass: &[f64],
) -> Result<Vec<u32>, FactorFailed> {
    let mut node = vec![NONE; inv_mass.len()];
    let mut particle_of = Vec::new();
    for (i, &k) in inv_mass.iter().enumerate() {
        if k > 0.0 {
            node[i] = particle_of.len() as u32;
            particle_of.push(i);
        }
    }
    let n = particle_of.len();
    let mut dof = vec![NONE; inv_mass.len()];
    if n == 0 {
        return Ok(dof);
    }
    // The graph's pattern, upper triangle, column by column.
    let mut adj: Vec<(usize, usize)> = (0..n).map(|p| (p, p)).collect();
    for c in 0..constraints.len() {
        let (a, b) = (
            node[constraints.a[c] as usize],
            node[constraints.b[c] as usize],
        );
        if a != NONE && b != NONE {
            adj.push((a.max(b) as usize, a.min(b) as usize));
        }
    }
    adj.sort_unstable();
    adj.dedup();
    let mut col_ptr = vec![0usize; n + 1];
    let rows: Vec<usize> = adj.iter().map(|&(_, row)| row).collect();
    for &(col, _) in &adj {
        col_ptr[col + 1] += 1;
    }
    for c in 0..n {
        col_ptr[c + 1] += col_ptr[c];
    }
    let mut perm = vec![0usize; n];
    let mut perm_inv = vec![0usize; n];
    let pattern = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &rows);
    let mut buf =
        MemBuffer::try_new(amd::order_scratch::<usize>(n, rows.len())).map_err(|_| FactorFailed)?;
    amd::order(
        &mut perm,
        &mut perm_inv,
        pattern,
        amd::Control::default(),
        MemStack::new(&mut buf),
    )
    .map_err(|_| FactorFailed)?;
    for (k, &q) in perm.iter().enumerate() {
        dof[particle_of[q]] = (3 * k) as u32;
    }
    Ok(dof)
}

/// Between iterations: releases contacts whose impulse pulls the particle
/// into the surface, and lets slide those whose tangential impulse leaves the
/// friction cone. Returns whether the set changed.
fn update_contacts(s: &mut State, input: &StepInput<'_>) -> bool {
    let mut changed = false;
    for i in 0..s.x.len() {
        let ct = &mut s.contact[i];
        if !ct.active {
            continue;
        }
        if s.r[i].dot(&ct.normal) < 0.0 {
            // Released: it leaves the surface (outward, so no penetration).
            ct.active = false;
            changed = true;
        }
    }
    let _ = input;
    changed
}

/// Contact update, then constraint and momentum residuals and the merit.
fn evaluate(s: &mut State, input: &StepInput<'_>, mean_rest: f64) {
    let cs = input.constraints;
    let k = input.inv_mass;
    // Contacts (an active set): an active particle is held on its
    // collider's surface, and its contact impulse `r` is whatever the held
    // directions need; a particle found inside a collider joins the set
    // here, and [`update_contacts`] releases the others between iterations.
    if !input.colliders.is_empty() {
        #[allow(clippy::needless_range_loop)] // columns indexed together
        for i in 0..s.x.len() {
            if k[i] == 0.0 {
                continue;
            }
            let ct = &mut s.contact[i];
            if !ct.active {
                for (ci, col) in input.colliders.iter().enumerate() {
                    let (phi, n) = col.swept_distance(&input.start[i], &s.x[i]);
                    if phi < 0.0 {
                        *ct = Contact {
                            normal: n,
                            friction: col.friction,
                            collider: ci as u32,
                            active: true,
                            ..Contact::default()
                        };
                        break;
                    }
                }
            }
            if ct.active {
                let col = &input.colliders[ct.collider as usize];
                let (phi, n) = col.swept_distance(&input.start[i], &s.x[i]);
                ct.normal = n;
                s.x[i] -= phi * n;
            }
        }
    }
    // Directions, impulse sums, constraint errors.
    s.g.fill(Vector3::zeros());
    let mut merit = 0.0;
    let mut max_stretch = 0.0_f64;
    for c in 0..cs.len() {
        let link = Link::new(cs, c, input.inv_h2);
        let Separation { len, n } = link.separation(&s.x);
        // Coincident ends keep their last direction.
        if let Some(n) = n {
            s.normals[c] = n;
        }
        s.lengths[c] = len;
        let p = s.mu[c] * s.normals[c];
        s.g[link.a] += p;
        s.g[link.b] -= p;
        s.c[c] = link.value(len, s.mu[c]);
        let rel = link.relative(s.c[c]);
        merit += rel * rel;
        max_stretch = max_stretch.max(rel.abs());
        if rel.is_nan() {
            max_stretch = f64::NAN;
        }
    }
    let mut max_residual = 0.0_f64;
    let mut contact_residual = 0.0_f64;
    #[allow(clippy::needless_range_loop)] // columns indexed together
    for i in 0..s.x.len() {
        if k[i] == 0.0 {
            s.f[i] = Vector3::zeros();
            continue;
        }
        let f = (s.x[i] - input.free[i]) / k[i] + s.g[i];
        let ct = &s.contact[i];
        s.r[i] = if ct.active {
            // The normal impulse holds it on the surface; Coulomb friction
            // opposes its tangential motion over the step, regularised
            // below FRICTION_SLIP (a stiff tangential spring: sticking).
            let n = ct.normal;
            let rn = f.dot(&n);
            let motion = s.x[i] - input.start[i];
            let tangential = motion - motion.dot(&n) * n;
            let stiffness = ct.friction * rn.max(0.0) / tangential.norm().max(FRICTION_SLIP);
            s.contact[i].tangential_stiffness = stiffness;
            rn * n - tangential * stiffness
        } else {
            Vector3::zeros()
        };
        s.f[i] = f - s.r[i];
        let e = s.f[i].norm() * k[i];
        max_residual = max_residual.max(e);
        if s.contact[i].active {
            contact_residual = contact_residual.max(e);
        }
        let rel = e / mean_rest;
        merit += rel * rel;
    }
    s.merit = if max_stretch.is_nan() {
        f64::NAN
    } else {
        merit
    };
    s.max_stretch = max_stretch;
    s.max_residual = max_residual;
    s.contact_residual = contact_residual;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newton_solves_a_chain_and_conserves_momentum() {
        // Three particles in a chain, both links stretched by 10 %.
        let mut c = DistanceConstraints::new();
        c.push(0, 1, 1.0);
        c.push(1, 2, 1.0);
        let k = [1.0, 2.0, 0.5];
        let free = vec![
            Vector3::zeros(),
            Vector3::new(1.1, 0.0, 0.0),
            Vector3::new(2.2, 0.1, 0.0),
        ];
        let params = SolverParams::default();
        let input = StepInput {
            constraints: &c,
            inv_mass: &k,
            start: &free,
            free: &free,
            colliders: &[],
            params: &params,
            inv_h2: 1.0,
            hold_momentum: false,
        };
        let mut solver = NewtonSolver::new(&c, &k).unwrap();
        let mut x = free.clone();
        let mut mu = vec![0.0; 2];
        let mut contacts = vec![ContactState::default(); 3];
        let out = solver.solve(&input, &mut x, &mut mu, &mut contacts, None);
        assert!(out.converged && out.fallback_sweeps == 0, "{out:?}");
        assert!(c.max_stretch(&x) < 1e-4);
        assert!(out.iterations <= 6, "{out:?}");
        let dp: Vector3<f64> = (0..3).map(|i| (x[i] - free[i]) / k[i]).sum();
        // Sums of three terms of order 0.1 kg m.
        approx::assert_relative_eq!(dp.norm(), 0.0, epsilon = 1e-12);
        // Impulses in tension pull the stretched chain together.
        assert!(mu.iter().all(|&m| m > 0.0), "{mu:?}");
    }
}

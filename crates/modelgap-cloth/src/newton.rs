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
//! ⎣ J   0 ⎦ ⎣δμ⎦ = − ⎣C⎦,       ∇²C_c = [H −H; −H H],  H = (I − n nᵀ)/|x_a − x_b|
//! ```
//!
//! `μ ∇²C` is the geometric stiffness of a link under tension: moving a
//! particle sideways lengthens a tight link, so the tension resists it. The
//! Gauss–Newton (fast projection) step `J M⁻¹ Jᵀ δμ = C` drops it, which is
//! exact for slack cloth and hopeless for a taut row between two pins (the
//! `two-corners` scene), where all the stiffness is geometric. Compressed
//! links contribute `μ⁺ = max(μ, 0)`: `K` stays positive definite, so the
//! matrix is quasi-definite (`K ≻ 0`, a tiny `−ε` on the impulse block) and
//! its `LDLᵀ` factorisation exists for any symmetric ordering whose pivots
//! are of the expected sign. Statics have no rows. Momentum: every term of
//! `Jᵀμ` and of `∇²C` comes in equal and opposite pairs, so `Σ F` changes
//! only through `M δx`, and the total momentum is conserved by every step,
//! full or shortened, fresh factor or stale.
//!
//! # Factorisation and reuse
//!
//! The sparsity of the KKT matrix is fixed by the topology. The ordering is
//! computed once: an approximate minimum degree ordering of the particle
//! graph, each particle's three rows followed by the impulses of the
//! constraints whose dynamic particles are then all eliminated. Every
//! impulse pivot therefore comes after a positive position pivot and is
//! well scaled (negative, of order the reduced mass), so no pivoting is
//! needed. The impulse rows are scaled by the reduced mass `1/(k_a + k_b)`
//! so both kinds of pivot have the same magnitude. The symbolic
//! factorisation is done once per topology (faer's supernodal/simplicial
//! `LDLᵀ`); the numeric factor is kept across iterations and steps (a chord
//! method: the residual is always fresh, the matrix may be stale) and
//! recomputed when an iteration shrinks the residual by less than
//! [`SolverParams::refactor_ratio`](crate::SolverParams::refactor_ratio) or a
//! stale step fails the line search.
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
//! tolerance and nothing penetrates a collider by more than the contact
//! tolerance (the Gauss–Seidel criterion). The momentum residual `|F_i|/m_i`
//! is driven down by the merit but not required to vanish.
//!
//! # Measured
//!
//! With these choices (start from the free preview and last step's
//! impulses; refactor when an iteration shrinks the merit by less than
//! [`SolverParams::refactor_ratio`](crate::SolverParams::refactor_ratio)
//! = 0.3; up to [`MAX_INCREASES`] non-monotone full steps), the 30 × 30
//! reference scenes (3 s, h = 0.01) hold 1e-4 at every step: `corner`
//! 3.1 iterations and 1.1 factorisations per step, `two-corners` 3.4 and
//! 0.44, `drape` 3.7 and 2.5. A factorisation of the 4434 × 4434 KKT matrix
//! costs about 3.5 ms and a solve 0.1–0.3 ms, so factorisations dominate
//! (about 1.3 s CPU for `corner`, 0.8 s for `two-corners`, 3 s for `drape`,
//! one thread); see `examples/scene_timing.rs` and `modelgap cloth bench`.
//!
//! Tried and dropped, measured on the same scenes: GMRES preconditioned by
//! the stale factor instead of refactoring (a preconditioned iteration costs
//! a tenth of a factorisation, and it needed too many: 2× slower);
//! eliminating the impulses into a positions-only SPD system `K + Jᵀ W J`
//! (factorisation 1.5× cheaper, but the stale factor no longer serves, since
//! `W` is huge and follows the directions: no faster overall); a simplicial
//! instead of the supernodal factorisation (3× slower); refactor ratios
//! from 0.3 to 0.99 (no better); a geometric nested-dissection ordering of
//! the particles instead of AMD (factor 418 k instead of 367 k nonzeros,
//! 10 % slower).

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use nalgebra::{Matrix3, Vector3};

use crate::constraints::DistanceConstraints;
use crate::contact::{Collider, ContactState};
use crate::solver::{self, SolverParams};

/// Relative shift `−ε` on the (scaled) impulse diagonal of the KKT matrix
/// (dimensionless): a proximal term on the impulses. It changes only Newton's
/// step, not the solution it converges to, and bounds the impulse of a
/// nearly dependent constraint (a straight row between two pins, whose
/// tension the linearisation cannot see): with 1e-10 such a row took huge
/// impulse steps that the next direction change turned into momentum
/// errors; 1e-6 cut `two-corners` from 15 to 4 iterations per step.
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

/// Halvings of a Newton step tried before the iteration gives up on it.
pub const MAX_HALVINGS: usize = 8;

/// Largest negative geometric stiffness a compressed link may add to the
/// Newton matrix, per unit mass of its lighter dynamic particle
/// (dimensionless); 0: compressed links add none (`μ⁺`), so `K` stays
/// positive definite and Newton's step is inexact only at compressed links.
/// (0.1 was tried: no better on `corner`, worse on `two-corners`.)
pub const COMPRESSION_STIFFNESS: f64 = 0.0;

const NONE: u32 = u32::MAX;

/// Why the solver could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct FactorFailed;

/// What one Newton solve did.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct NewtonOutcome {
    pub(crate) iterations: usize,
    pub(crate) factorizations: usize,
    pub(crate) fallback_sweeps: usize,
    pub(crate) converged: bool,
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
    penetration: f64,
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

/// The KKT system of one topology: ordering, symbolic and numeric factors,
/// value slots, iterates and scratch. Nothing is allocated per iteration.
pub(crate) struct NewtonSolver {
    n_particles: usize,
    n_constraints: usize,
    /// First KKT row of each particle (`NONE` for a static one).
    dof: Vec<u32>,
    n_dof: usize,
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
    /// Slots of `J` (stored as `Jᵀ` above the diagonal): a's three, b's three.
    jac_slots: Vec<[u32; 6]>,
    mu_diag_slot: Vec<u32>,
    /// Scale of each impulse row, the reduced mass `1/(k_a + k_b)` (kg).
    scale: Vec<f64>,
    signs: Vec<i8>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    has_factor: bool,
    mem: MemBuffer,
    mass_scale: f64,
    mean_rest: f64,
    rhs: Vec<f64>,
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

/// Upper-triangle index of a symmetric 3×3 entry.
fn sym(i: usize, j: usize) -> (usize, usize) {
    (i.min(j), i.max(j))
}

impl NewtonSolver {
    /// Builds the KKT pattern, its ordering and its symbolic factor.
    pub(crate) fn new(
        constraints: &DistanceConstraints,
        inv_mass: &[f64],
    ) -> Result<Self, FactorFailed> {
        let n_particles = inv_mass.len();
        let m = constraints.len();
        let mut dof = vec![NONE; n_particles];
        let mut n_dyn = 0usize;
        for (i, &k) in inv_mass.iter().enumerate() {
            if k > 0.0 {
                dof[i] = (3 * n_dyn) as u32;
                n_dyn += 1;
            }
        }
        let n_dof = 3 * n_dyn;
        let dim = n_dof + m;
        let mu_row = |c: usize| n_dof + c;

        // Pattern (upper triangle) as (col, row) pairs.
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
            for d in [da, db] {
                if d != NONE {
                    for i in 0..3 {
                        entries.push((mu_row(c), d as usize + i));
                    }
                }
            }
            entries.push((mu_row(c), mu_row(c)));
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
        let mut jac_slots = vec![[NONE; 6]; m];
        let mut mu_diag_slot = vec![NONE; m];
        let mut scale = vec![0.0; m];
        for c in 0..m {
            let (pa, pb) = (constraints.a[c] as usize, constraints.b[c] as usize);
            let (da, db) = (dof[pa], dof[pb]);
            if da != NONE && db != NONE {
                for i in 0..3 {
                    for j in 0..3 {
                        // Row i of a, column j of b: the block is symmetric
                        // (a multiple of a symmetric H), so either triangle's
                        // slot holds the same value.
                        edge_slots[c][3 * i + j] = slot(da as usize + i, db as usize + j);
                    }
                }
            }
            for (side, d) in [da, db].into_iter().enumerate() {
                if d != NONE {
                    for i in 0..3 {
                        jac_slots[c][3 * side + i] = slot(d as usize + i, mu_row(c));
                    }
                }
            }
            mu_diag_slot[c] = slot(mu_row(c), mu_row(c));
            let w = inv_mass[pa] + inv_mass[pb];
            scale[c] = if w > 0.0 { 1.0 / w } else { 0.0 };
        }

        // Ordering: AMD on the graph of dynamic particles, then each
        // particle's rows followed by the impulses it completes.
        let (fwd, inv) = {
            let mut adj: Vec<(usize, usize)> = Vec::new();
            for p in 0..n_dyn {
                adj.push((p, p));
            }
            for c in 0..m {
                let (da, db) = (
                    dof[constraints.a[c] as usize],
                    dof[constraints.b[c] as usize],
                );
                if da != NONE && db != NONE {
                    let (a, b) = ((da / 3) as usize, (db / 3) as usize);
                    adj.push((a.max(b), a.min(b)));
                }
            }
            adj.sort_unstable();
            adj.dedup();
            let mut pc = vec![0usize; n_dyn + 1];
            let mut pr = Vec::with_capacity(adj.len());
            for &(col, row) in &adj {
                pc[col + 1] += 1;
                pr.push(row);
            }
            for c in 0..n_dyn {
                pc[c + 1] += pc[c];
            }
            let mut perm = vec![0usize; n_dyn];
            let mut perm_inv = vec![0usize; n_dyn];
            if n_dyn > 0 {
                let pattern = SymbolicSparseColMatRef::new_checked(n_dyn, n_dyn, &pc, None, &pr);
                let mut buf = MemBuffer::try_new(amd::order_scratch::<usize>(n_dyn, pr.len()))
                    .map_err(|_| FactorFailed)?;
                amd::order(
                    &mut perm,
                    &mut perm_inv,
                    pattern,
                    amd::Control::default(),
                    MemStack::new(&mut buf),
                )
                .map_err(|_| FactorFailed)?;
            }
            // Dynamic-particle index -> world particle, and incident constraints.
            let mut particle_of = Vec::with_capacity(n_dyn);
            for (p, &d) in dof.iter().enumerate() {
                if d != NONE {
                    particle_of.push(p);
                }
            }
            let mut incident: Vec<Vec<u32>> = vec![Vec::new(); n_particles];
            for c in 0..m {
                incident[constraints.a[c] as usize].push(c as u32);
                incident[constraints.b[c] as usize].push(c as u32);
            }
            let mut eliminated = vec![false; n_particles];
            let mut placed = vec![false; m];
            let mut fwd = Vec::with_capacity(dim);
            for &q in &perm {
                let p = particle_of[q];
                eliminated[p] = true;
                for i in 0..3 {
                    fwd.push(dof[p] as usize + i);
                }
                for &c in &incident[p] {
                    let c = c as usize;
                    let (pa, pb) = (constraints.a[c] as usize, constraints.b[c] as usize);
                    let done = |x: usize| dof[x] == NONE || eliminated[x];
                    if !placed[c] && done(pa) && done(pb) {
                        placed[c] = true;
                        fwd.push(mu_row(c));
                    }
                }
            }
            // Constraints between two statics cannot exist (rejected at the
            // door); any left over go last.
            for (c, &done) in placed.iter().enumerate() {
                if !done {
                    fwd.push(mu_row(c));
                }
            }
            let mut inv = vec![0usize; dim];
            for (new, &old) in fwd.iter().enumerate() {
                inv[old] = new;
            }
            (fwd, inv)
        };
        let symbolic = {
            let pattern = SymbolicSparseColMatRef::new_checked(dim, dim, &col_ptr, None, &row_idx);
            let perm = PermRef::new_checked(&fwd, &inv, dim);
            factorize_symbolic_cholesky(
                pattern,
                Side::Upper,
                SymmetricOrdering::Custom(perm),
                CholeskySymbolicParams::default(),
            )
            .map_err(|_| FactorFailed)?
        };
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        let mem = MemBuffer::try_new(req).map_err(|_| FactorFailed)?;
        let mut signs = vec![1i8; dim];
        signs[n_dof..].fill(-1);
        let masses: Vec<f64> = inv_mass
            .iter()
            .filter(|&&k| k > 0.0)
            .map(|&k| 1.0 / k)
            .collect();
        let mass_scale = if masses.is_empty() {
            1.0
        } else {
            masses.iter().sum::<f64>() / masses.len() as f64
        };
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
            n_dof,
            dim,
            values: vec![0.0; row_idx.len()],
            l_values: vec![0.0; symbolic.len_val()],
            col_ptr,
            row_idx,
            diag_slots,
            edge_slots,
            jac_slots,
            mu_diag_slot,
            scale,
            signs,
            symbolic,
            has_factor: false,
            mem,
            mass_scale,
            mean_rest,
            rhs: vec![0.0; dim],
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
    ) -> NewtonOutcome {
        debug_assert_eq!(x.len(), self.n_particles);
        debug_assert_eq!(mu.len(), self.n_constraints);
        let params = input.params;
        let tol = params.stretch_tolerance;
        let mut out = NewtonOutcome::default();
        self.cur.x.copy_from_slice(x);
        self.cur.mu.copy_from_slice(mu);
        self.cur.r.fill(Vector3::zeros());
        self.cur.contact.fill(Contact::default());
        evaluate(&mut self.cur, input, self.mean_rest);
        let mut need_refactor = false;
        let mut increases_left = MAX_INCREASES;
        loop {
            out.max_stretch = self.cur.max_stretch;
            if self.cur.max_stretch <= tol
                && self.cur.penetration <= params.contact_tolerance
                && self.cur.contact_residual <= tol * self.mean_rest
            {
                out.converged = true;
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
        let cur = &self.cur;
        for (p, &d) in self.dof.iter().enumerate() {
            if d == NONE {
                continue;
            }
            let d = d as usize;
            for i in 0..3 {
                self.rhs[d + i] = -cur.f[p][i];
            }
        }
        for c in 0..self.n_constraints {
            self.rhs[self.n_dof + c] = -cur.c[c] * self.scale[c];
        }
        let ldlt = LdltRef::new(&self.symbolic, &self.l_values);
        ldlt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut self.rhs, self.dim, 1),
            Par::Seq,
            MemStack::new(&mut self.mem),
        );
        if self.rhs.iter().any(|v| !v.is_finite()) {
            self.has_factor = false;
            return false;
        }
        let mut alpha = 1.0;
        for _ in 0..=MAX_HALVINGS {
            let (cur, trial) = (&self.cur, &mut self.trial);
            trial.r.copy_from_slice(&cur.r);
            trial.contact.copy_from_slice(&cur.contact);
            for (p, &d) in self.dof.iter().enumerate() {
                trial.x[p] = if d == NONE {
                    cur.x[p]
                } else {
                    let d = d as usize;
                    cur.x[p] + alpha * Vector3::new(self.rhs[d], self.rhs[d + 1], self.rhs[d + 2])
                };
            }
            for c in 0..self.n_constraints {
                trial.mu[c] = cur.mu[c] + alpha * self.rhs[self.n_dof + c] * self.scale[c];
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

    /// Fills the KKT values at `cur` and factorises them.
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
            // Compression enters with a bounded negative stiffness so that
            // K stays positive definite (see COMPRESSION_STIFFNESS).
            let m_min = 1.0 / input.inv_mass[pa].max(input.inv_mass[pb]);
            let tension = cur.mu[c].max(-COMPRESSION_STIFFNESS * m_min * cur.lengths[c]);
            if tension != 0.0 && cur.lengths[c] > f64::MIN_POSITIVE {
                let h = (Matrix3::identity() - n * n.transpose()) * (tension / cur.lengths[c]);
                for p in [pa, pb] {
                    if self.dof[p] != NONE {
                        add(&mut self.values, &self.diag_slots[p], &h, true);
                    }
                }
                if self.edge_slots[c][0] != NONE {
                    add(&mut self.values, &self.edge_slots[c], &(-h), false);
                }
            }
            let s = self.scale[c];
            for i in 0..3 {
                if self.jac_slots[c][i] != NONE {
                    self.values[self.jac_slots[c][i] as usize] = s * n[i];
                }
                if self.jac_slots[c][3 + i] != NONE {
                    self.values[self.jac_slots[c][3 + i] as usize] = -s * n[i];
                }
            }
            let alpha = cs.compliance[c] * input.inv_h2;
            let reg = REGULARISATION;
            self.values[self.mu_diag_slot[c] as usize] = -reg * s - alpha * s * s;
        }
        let pattern = SymbolicSparseColMatRef::new_checked(
            self.dim,
            self.dim,
            &self.col_ptr,
            None,
            &self.row_idx,
        );
        let a = SparseColMatRef::new(pattern, &self.values);
        let result = self.symbolic.factorize_numeric_ldlt(
            &mut self.l_values,
            a,
            Side::Upper,
            LdltRegularization {
                dynamic_regularization_signs: Some(&self.signs),
                dynamic_regularization_delta: 1e-8 * self.mass_scale,
                dynamic_regularization_epsilon: 1e-13 * self.mass_scale,
            },
            Par::Seq,
            MemStack::new(&mut self.mem),
            Default::default(),
        );
        self.has_factor = result.is_ok();
        result.map(|_| ()).map_err(|_| FactorFailed)
    }
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
    s.g.fill(Vector3::zeros());
    for c in 0..cs.len() {
        let (a, b) = (cs.a[c] as usize, cs.b[c] as usize);
        let d = s.x[a] - s.x[b];
        let len = d.norm();
        if len > f64::MIN_POSITIVE {
            s.normals[c] = d / len;
        }
        s.lengths[c] = len;
        let p = s.mu[c] * s.normals[c];
        s.g[a] += p;
        s.g[b] -= p;
    }
    // Contacts (an active set): an active particle is held on its
    // collider's surface (at its anchor while friction sticks it), and its
    // contact impulse `r` is whatever the held directions need; a particle
    // found inside a collider joins the set here, and
    // [`update_contacts`] releases or lets slide the others between
    // iterations.
    if !input.colliders.is_empty() {
        let mut moved = false;
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
                if phi != 0.0 {
                    s.x[i] -= phi * n;
                    moved = true;
                }
            }
        }
        if moved {
            // Positions moved: refresh the directions and impulse sums.
            s.g.fill(Vector3::zeros());
            for c in 0..cs.len() {
                let (a, b) = (cs.a[c] as usize, cs.b[c] as usize);
                let d = s.x[a] - s.x[b];
                let len = d.norm();
                if len > f64::MIN_POSITIVE {
                    s.normals[c] = d / len;
                }
                s.lengths[c] = len;
                let p = s.mu[c] * s.normals[c];
                s.g[a] += p;
                s.g[b] -= p;
            }
        }
    }
    let mut merit = 0.0;
    let mut max_stretch = 0.0_f64;
    for c in 0..cs.len() {
        s.c[c] = s.lengths[c] - cs.rest_length[c] - cs.compliance[c] * s.mu[c] * input.inv_h2;
        let rel = s.c[c] / cs.rest_length[c];
        merit += rel * rel;
        max_stretch = max_stretch.max(rel.abs());
        if rel.is_nan() {
            max_stretch = f64::NAN;
        }
    }
    let mut max_residual = 0.0_f64;
    let mut contact_residual = 0.0_f64;
    let mut penetration = 0.0_f64;
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
        if !s.contact[i].active {
            for col in input.colliders {
                penetration = penetration.max(-col.swept_distance(&input.start[i], &s.x[i]).0);
            }
        }
    }
    s.merit = if max_stretch.is_nan() {
        f64::NAN
    } else {
        merit
    };
    s.max_stretch = max_stretch;
    s.max_residual = max_residual;
    s.contact_residual = contact_residual;
    s.penetration = penetration;
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
        };
        let mut solver = NewtonSolver::new(&c, &k).unwrap();
        let mut x = free.clone();
        let mut mu = vec![0.0; 2];
        let mut contacts = vec![ContactState::default(); 3];
        let out = solver.solve(&input, &mut x, &mut mu, &mut contacts);
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

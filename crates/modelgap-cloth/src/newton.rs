//! The global solve: all distance constraints of a step at once.
//!
//! Each iteration linearises the constraints at the previewed positions `x`:
//! with `J` the constraint gradients (unit directions `n_i` of the previewed
//! edges, `+n_i` on `a`, `−n_i` on `b`) and `W = diag(1/m)`, the impulses
//! `μ = h p` (kg m) that remove the errors `C(x) = |x_a − x_b| − rest` to first
//! order solve
//!
//! ```text
//! (J W Jᵀ) δμ = C(x),    x ← x − W Jᵀ δμ
//! ```
//!
//! which is Newton's method (Gauss–Newton) on the paper's impulse equations
//! `(k_a + k_b) p = e/h` of all constraints together, the fast projection of
//! Goldenthal et al. (2007) cited by the paper. Every update is a sum of equal
//! and opposite impulse pairs along previewed directions, so momentum is
//! conserved as in the Gauss–Seidel sweep, and static particles (`k = 0`) never
//! move.
//!
//! `A = J W Jᵀ` couples constraints that share a particle: its sparsity is fixed
//! by the topology, so the fill-reducing ordering (AMD) and the symbolic
//! Cholesky factorisation are computed once per topology (faer). The numeric
//! factor is kept across iterations and across steps (a chord method: `J` and
//! `C` are fresh, `A` may be stale) and recomputed only when an iteration
//! shrinks the largest stretch by less than [`SolverParams::refactor_ratio`](crate::SolverParams::refactor_ratio).
//! A tiny relative diagonal shift ([`REGULARISATION`]) keeps the factorisation
//! defined where constraints are dependent (a straight row between two pins).
//! Each step is shortened (halved up to six times) until the largest stretch
//! falls; when none does, the caller does one Gauss–Seidel sweep instead.
//!
//! Known limit: near a straightened row between two pins (the `two-corners`
//! scene) the linearisation ignores how sideways motion lengthens a tight
//! link, steps shrink to nothing and the solve degrades to Gauss–Seidel.
//! The cure measured in the issue is Newton on the full system of positions
//! and impulses with the geometric stiffness of tensioned links.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use nalgebra::Vector3;

use crate::constraints::DistanceConstraints;

/// Relative shift added to the diagonal of `J W Jᵀ` before factorising
/// (dimensionless). It changes each Newton step by about this fraction, far
/// below the stretch tolerance, and keeps the matrix positive definite when
/// constraints are linearly dependent.
pub const REGULARISATION: f64 = 1e-10;

/// Halvings of the Newton step tried before an iteration gives up and the
/// caller falls back to a Gauss–Seidel sweep.
const MAX_HALVINGS: usize = 6;

/// One contribution `k_s σ_i σ_j (n_i · n_j)` to a value slot of `A`.
#[derive(Clone, Copy, Debug)]
struct Term {
    slot: u32,
    particle: u32,
    i: u32,
    j: u32,
    sign: f64,
}

/// Why a Newton iteration could not be done.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct FactorFailed;

/// The sparse system of one topology, its symbolic and numeric factors and
/// all scratch memory: nothing is allocated per iteration.
pub(crate) struct NewtonSolver {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
    terms: Vec<Term>,
    diag_slot: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    has_factor: bool,
    mem: MemBuffer,
    normals: Vec<Vector3<f64>>,
    rhs: Vec<f64>,
    trial: Vec<Vector3<f64>>,
}

impl std::fmt::Debug for NewtonSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NewtonSolver")
            .field("n", &self.n)
            .field("nnz", &self.row_idx.len())
            .field("factor_nnz", &self.l_values.len())
            .finish_non_exhaustive()
    }
}

impl NewtonSolver {
    /// Builds the pattern of `J W Jᵀ` (upper triangle) and its symbolic factor.
    pub(crate) fn new(
        constraints: &DistanceConstraints,
        inv_mass: &[f64],
    ) -> Result<Self, FactorFailed> {
        let n = constraints.len();
        let n_particles = inv_mass.len();
        let mut incident: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n_particles];
        for i in 0..n {
            incident[constraints.a[i] as usize].push((i as u32, 1.0));
            incident[constraints.b[i] as usize].push((i as u32, -1.0));
        }
        // (col, row, particle, sign)
        let mut entries: Vec<(u32, u32, u32, f64)> = Vec::new();
        for i in 0..n {
            for p in [constraints.a[i], constraints.b[i]] {
                entries.push((i as u32, i as u32, p, 1.0));
            }
        }
        for (s, list) in incident.iter().enumerate() {
            if inv_mass[s] == 0.0 {
                continue;
            }
            for (x, &(ci, si)) in list.iter().enumerate() {
                for &(cj, sj) in &list[x + 1..] {
                    let (row, col) = (ci.min(cj), ci.max(cj));
                    entries.push((col, row, s as u32, si * sj));
                }
            }
        }
        entries.sort_by_key(|x| (x.0, x.1));
        let mut col_ptr = vec![0usize; n + 1];
        let mut row_idx = Vec::new();
        let mut terms = Vec::with_capacity(entries.len());
        let mut diag_slot = vec![0usize; n];
        let mut last: Option<(u32, u32)> = None;
        for &(col, row, particle, sign) in &entries {
            if last != Some((col, row)) {
                row_idx.push(row as usize);
                col_ptr[col as usize + 1] += 1;
                last = Some((col, row));
                if col == row {
                    diag_slot[col as usize] = row_idx.len() - 1;
                }
            }
            terms.push(Term {
                slot: (row_idx.len() - 1) as u32,
                particle,
                i: row,
                j: col,
                sign,
            });
        }
        for c in 0..n {
            col_ptr[c + 1] += col_ptr[c];
        }
        let symbolic = {
            let pattern = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
            factorize_symbolic_cholesky(
                pattern,
                Side::Upper,
                SymmetricOrdering::Amd,
                CholeskySymbolicParams::default(),
            )
            .map_err(|_| FactorFailed)?
        };
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        let mem = MemBuffer::try_new(req).map_err(|_| FactorFailed)?;
        Ok(Self {
            n,
            values: vec![0.0; row_idx.len()],
            l_values: vec![0.0; symbolic.len_val()],
            col_ptr,
            row_idx,
            terms,
            diag_slot,
            symbolic,
            has_factor: false,
            mem,
            normals: vec![Vector3::zeros(); n],
            rhs: vec![0.0; n],
            trial: vec![Vector3::zeros(); n_particles],
        })
    }

    /// Whether a numeric factor is available.
    pub(crate) fn has_factor(&self) -> bool {
        self.has_factor
    }

    /// Forgets the numeric factor (the next iteration refactors).
    pub(crate) fn invalidate(&mut self) {
        self.has_factor = false;
    }

    /// One Newton iteration at the previewed positions `pred`: fresh
    /// directions and errors, the kept factor (or a new one when `refactor`),
    /// one solve, and the update of `pred` and the accumulated impulses `mu`.
    /// Returns whether it refactored.
    pub(crate) fn iterate(
        &mut self,
        constraints: &DistanceConstraints,
        inv_mass: &[f64],
        pred: &mut [Vector3<f64>],
        mu: &mut [f64],
        refactor: bool,
    ) -> Result<bool, FactorFailed> {
        debug_assert_eq!(constraints.len(), self.n);
        for i in 0..self.n {
            let d = pred[constraints.a[i] as usize] - pred[constraints.b[i] as usize];
            let len = d.norm();
            if len > f64::MIN_POSITIVE {
                self.normals[i] = d / len;
            }
            self.rhs[i] = len - constraints.rest_length[i];
        }
        let refactored = refactor || !self.has_factor;
        if refactored {
            self.factorize(inv_mass)?;
        }
        let stack = MemStack::new(&mut self.mem);
        let llt = LltRef::new(&self.symbolic, &self.l_values);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut self.rhs, self.n, 1),
            Par::Seq,
            stack,
        );
        #[allow(clippy::needless_range_loop)] // columns indexed together
        if self.rhs.iter().any(|d| !d.is_finite()) {
            self.has_factor = false;
            return Err(FactorFailed);
        }
        // Backtracking on the largest stretch: far from the solution (a
        // crumpled or straightened cloth) the linearisation overshoots, and a
        // shorter step along the same impulses still helps.
        let current = constraints.max_stretch(pred);
        let mut alpha = 1.0;
        for _ in 0..MAX_HALVINGS {
            self.trial.copy_from_slice(pred);
            for i in 0..self.n {
                let (a, b) = (constraints.a[i] as usize, constraints.b[i] as usize);
                let step = alpha * self.rhs[i] * self.normals[i];
                self.trial[a] -= inv_mass[a] * step;
                self.trial[b] += inv_mass[b] * step;
            }
            if constraints.max_stretch(&self.trial) < current {
                pred.copy_from_slice(&self.trial);
                for (m, d) in mu.iter_mut().zip(&self.rhs) {
                    *m += alpha * d;
                }
                return Ok(refactored);
            }
            alpha *= 0.5;
        }
        Err(FactorFailed)
    }

    fn factorize(&mut self, inv_mass: &[f64]) -> Result<(), FactorFailed> {
        self.values.fill(0.0);
        for t in &self.terms {
            let k = inv_mass[t.particle as usize];
            let dot = self.normals[t.i as usize].dot(&self.normals[t.j as usize]);
            self.values[t.slot as usize] += k * t.sign * dot;
        }
        for &s in &self.diag_slot {
            self.values[s] *= 1.0 + REGULARISATION;
        }
        let pattern = SymbolicSparseColMatRef::new_checked(
            self.n,
            self.n,
            &self.col_ptr,
            None,
            &self.row_idx,
        );
        let a = SparseColMatRef::new(pattern, &self.values);
        let stack = MemStack::new(&mut self.mem);
        let result = self.symbolic.factorize_numeric_llt(
            &mut self.l_values,
            a,
            Side::Upper,
            LltRegularization::default(),
            Par::Seq,
            stack,
            Default::default(),
        );
        self.has_factor = result.is_ok();
        result.map(|_| ()).map_err(|_| FactorFailed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_newton_step_solves_a_chain_and_conserves_momentum() {
        // Three particles in a chain, both links stretched by 10 %.
        let mut c = DistanceConstraints::new();
        c.push(0, 1, 1.0);
        c.push(1, 2, 1.0);
        let k = [1.0, 2.0, 0.5];
        let mut pred = vec![
            Vector3::zeros(),
            Vector3::new(1.1, 0.0, 0.0),
            Vector3::new(2.2, 0.0, 0.0),
        ];
        let before = pred.clone();
        let mut solver = NewtonSolver::new(&c, &k).unwrap();
        let mut mu = vec![0.0; 2];
        solver.iterate(&c, &k, &mut pred, &mut mu, true).unwrap();
        // Collinear: the linearisation is exact, up to the regularisation.
        assert!(c.max_stretch(&pred) < 1e-9);
        let dp: Vector3<f64> = (0..3).map(|i| (pred[i] - before[i]) / k[i]).sum();
        approx::assert_relative_eq!(dp.norm(), 0.0, epsilon = 1e-12);
    }
}

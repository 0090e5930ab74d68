//! In-place LU decomposition with partial pivoting for the Rosenbrock matrix.
//!
//! nalgebra's `LU::new` takes its matrix by value and allocates a fresh
//! permutation on every call, and offers no way to factor into existing
//! storage. The Rosenbrock step factors a small dense matrix once per attempt,
//! so this module does the same Gaussian elimination with partial pivoting
//! in a `DMatrix` and a pivot vector that live for the whole solve.

use nalgebra::DMatrix;

/// LU factors `P A = L U` of a square matrix, stored in place.
pub(super) struct Lu {
    /// `L` (unit diagonal, below) and `U` (on and above the diagonal), column-major.
    a: DMatrix<f64>,
    /// Row exchanged with row `k` at elimination step `k`.
    piv: Vec<usize>,
}

impl Lu {
    /// Storage for `n × n` factors.
    pub(super) fn new(n: usize) -> Self {
        Self {
            a: DMatrix::zeros(n, n),
            piv: vec![0; n],
        }
    }

    /// Factors `diag·I − jac`. Returns `false` when it is singular (a zero
    /// or non-finite pivot), leaving the factors unusable.
    pub(super) fn factor_shifted(&mut self, jac: &DMatrix<f64>, diag: f64) -> bool {
        let n = self.piv.len();
        debug_assert!(jac.nrows() == n && jac.ncols() == n);
        let a = self.a.as_mut_slice();
        for (dst, src) in a.iter_mut().zip(jac.as_slice()) {
            *dst = -src;
        }
        for i in 0..n {
            a[i * n + i] += diag;
        }
        factor(a, n, &mut self.piv)
    }

    /// Solves `A z = b` in place (`b` becomes `z`) with the last factors.
    pub(super) fn solve(&self, b: &mut [f64]) {
        solve(self.a.as_slice(), self.piv.len(), &self.piv, b);
    }
}

/// Factors the column-major `n × n` matrix `a` in place; `false` if singular.
fn factor(a: &mut [f64], n: usize, piv: &mut [usize]) -> bool {
    for k in 0..n {
        let col_k = k * n;
        let mut p = k;
        let mut max = a[col_k + k].abs();
        for i in k + 1..n {
            let v = a[col_k + i].abs();
            if v > max {
                max = v;
                p = i;
            }
        }
        piv[k] = p;
        if max == 0.0 || !max.is_finite() {
            return false;
        }
        if p != k {
            for j in 0..n {
                a.swap(j * n + k, j * n + p);
            }
        }
        let inv = 1.0 / a[col_k + k];
        for i in k + 1..n {
            a[col_k + i] *= inv;
        }
        for j in k + 1..n {
            let akj = a[j * n + k];
            if akj != 0.0 {
                for i in k + 1..n {
                    a[j * n + i] -= a[col_k + i] * akj;
                }
            }
        }
    }
    true
}

/// Solves with the factors of [`factor`].
fn solve(a: &[f64], n: usize, piv: &[usize], b: &mut [f64]) {
    debug_assert_eq!(b.len(), n);
    // The factorization exchanged whole rows (L included, as LAPACK's
    // DGETRF), so all exchanges apply to b before the forward sweep.
    for (k, &p) in piv.iter().enumerate() {
        if p != k {
            b.swap(k, p);
        }
    }
    for k in 0..n {
        let bk = b[k];
        if bk != 0.0 {
            for i in k + 1..n {
                b[i] -= a[k * n + i] * bk;
            }
        }
    }
    for k in (0..n).rev() {
        b[k] /= a[k * n + k];
        let bk = b[k];
        for i in 0..k {
            b[i] -= a[k * n + i] * bk;
        }
    }
}

#[cfg(test)]
mod tests {
    //! Tests of the in-place LU.

    use approx::assert_relative_eq;
    use nalgebra::{DMatrix, DVector};

    use super::Lu;

    #[test]
    fn solves_a_system_that_needs_pivoting() {
        // 5·I − J with a zero leading entry: 5 − 5 = 0 forces a row exchange.
        let jac = DMatrix::from_row_slice(3, 3, &[5.0, 2.0, -1.0, 3.0, 1.0, 4.0, -2.0, 7.0, 0.5]);
        let mut lu = Lu::new(3);
        assert!(lu.factor_shifted(&jac, 5.0));
        let a = DMatrix::identity(3, 3) * 5.0 - &jac;
        let z_true = DVector::from_vec(vec![1.0, -2.0, 0.5]);
        let mut b: Vec<f64> = (&a * &z_true).iter().copied().collect();
        lu.solve(&mut b);
        for i in 0..3 {
            // A well-conditioned 3×3 system: round-off of a few ε.
            assert_relative_eq!(b[i], z_true[i], epsilon = 1e-13);
        }
    }

    #[test]
    fn reports_a_singular_matrix() {
        // 1·I − J = [[1, 2], [2, 4]] has rank 1.
        let jac = DMatrix::from_row_slice(2, 2, &[0.0, -2.0, -2.0, -3.0]);
        let mut lu = Lu::new(2);
        assert!(!lu.factor_shifted(&jac, 1.0));
    }
}

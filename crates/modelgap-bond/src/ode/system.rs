//! The problem seen by the solvers: [`OdeSystem`], and the finite-difference
//! Jacobian that is its default.

use nalgebra::DMatrix;

/// A system of ordinary differential equations `dx/dt = f(t, x)`.
pub trait OdeSystem {
    /// Number of states.
    fn dim(&self) -> usize;

    /// Writes `dx = f(t, x)`. Must write every component of `dx`.
    ///
    /// `t` is in s; `x` and `dx` have [`dim`](Self::dim) components.
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]);

    /// Writes the Jacobian `∂f/∂x` (`dim × dim`, row `i` = component of `f`,
    /// column `j` = state) into `jac`, which the solver allocates with that shape.
    ///
    /// The default is [`finite_difference_jacobian`]: forward differences,
    /// `dim + 1` calls of [`rhs`](Self::rhs). Override it when an exact
    /// Jacobian is cheap: the Rosenbrock method's order assumes an exact one.
    fn jacobian(&mut self, t: f64, x: &[f64], jac: &mut DMatrix<f64>) {
        finite_difference_jacobian(self, t, x, jac);
    }
}

/// Largest dimension for which [`finite_difference_jacobian`] keeps its
/// scratch on the stack (larger systems allocate `2 dim` numbers per call).
const FD_STACK_DIM: usize = 32;

/// Forward-difference Jacobian `∂f/∂x` of `sys` at `(t, x)` into `jac` (`dim × dim`).
///
/// Column `j` is `(f(t, x + δ_j e_j) − f(t, x)) / δ_j` with
/// `δ_j = sqrt(ε · max(1e-5, |x_j|))` (ε = `f64::EPSILON`), the choice of
/// Hairer & Wanner's RADAU5 and RODAS codes. Compared with `sqrt(ε)·|x_j|` it
/// perturbs small states (bond-graph momenta and displacements in SI units are
/// often 1e-6–1e-2) by more than their round-off, and compared with
/// `sqrt(ε)·max(|x_j|, 1)` it does not swamp them. The divisor is the
/// perturbation actually represented, `(x_j + δ_j) − x_j`.
///
/// Costs `dim + 1` calls of [`OdeSystem::rhs`]; allocates nothing for
/// `dim ≤ 32`.
pub fn finite_difference_jacobian<S: OdeSystem + ?Sized>(
    sys: &mut S,
    t: f64,
    x: &[f64],
    jac: &mut DMatrix<f64>,
) {
    let n = x.len();
    assert!(
        jac.nrows() == n && jac.ncols() == n,
        "jacobian matrix is {}x{} but the state has {n} components",
        jac.nrows(),
        jac.ncols()
    );
    let mut stack = [0.0; 2 * FD_STACK_DIM];
    let mut heap = Vec::new();
    let scratch: &mut [f64] = if n <= FD_STACK_DIM {
        &mut stack[..2 * n]
    } else {
        heap.resize(2 * n, 0.0);
        &mut heap
    };
    let (xp, f0) = scratch.split_at_mut(n);
    xp.copy_from_slice(x);
    sys.rhs(t, x, f0);
    // DMatrix is column-major: column j is the contiguous run j*n..(j+1)*n.
    let columns = jac.as_mut_slice();
    for j in 0..n {
        let xj = x[j];
        let delta = (f64::EPSILON * xj.abs().max(1e-5)).sqrt();
        xp[j] = xj + delta;
        let delta = xp[j] - xj;
        let column = &mut columns[j * n..(j + 1) * n];
        sys.rhs(t, xp, column);
        for (c, f) in column.iter_mut().zip(f0.iter()) {
            *c = (*c - f) / delta;
        }
        xp[j] = xj;
    }
}

#[cfg(test)]
mod tests {
    //! Tests of the finite-difference Jacobian.

    use approx::assert_relative_eq;
    use nalgebra::DMatrix;

    use super::OdeSystem;

    /// The DC motor in momentum coordinates: x = (p3, p8), dx = A x + (V, 0).
    struct DcMotor;
    const R: f64 = 1.0;
    const L: f64 = 5e-3;
    const K: f64 = 0.05;
    const J: f64 = 1e-4;
    const BETA: f64 = 1e-5;
    impl OdeSystem for DcMotor {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
            dx[0] = -R / L * x[0] - K / J * x[1] + 12.0;
            dx[1] = K / L * x[0] - BETA / J * x[1];
        }
    }

    #[test]
    fn finite_difference_jacobian_matches_the_dc_motor_matrix() {
        let mut jac = DMatrix::zeros(2, 2);
        DcMotor.jacobian(0.0, &[1e-4, 0.02], &mut jac);
        let exact = [[-R / L, -K / J], [K / L, -BETA / J]];
        for i in 0..2 {
            for j in 0..2 {
                // Forward differences of a linear map: only round-off of f
                // (~1e-16 · |f| / δ with δ ~ 1e-10..1e-9) remains, far below 1e-4.
                assert_relative_eq!(jac[(i, j)], exact[i][j], max_relative = 1e-4);
            }
        }
    }

    #[test]
    fn finite_difference_jacobian_of_a_nonlinear_system_is_accurate() {
        /// f = (x0² x1, sin x1), J = [[2 x0 x1, x0²], [0, cos x1]].
        struct Nonlinear;
        impl OdeSystem for Nonlinear {
            fn dim(&self) -> usize {
                2
            }
            fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
                dx[0] = x[0] * x[0] * x[1];
                dx[1] = x[1].sin();
            }
        }
        let x = [1.5, 0.3];
        let mut jac = DMatrix::zeros(2, 2);
        Nonlinear.jacobian(0.0, &x, &mut jac);
        let exact = [[2.0 * x[0] * x[1], x[0] * x[0]], [0.0, x[1].cos()]];
        for i in 0..2 {
            for j in 0..2 {
                // Forward differences err by ~δ |f''| / 2 with δ = sqrt(ε |x_j|)
                // ≈ 1e-8: about 1e-8 here, plus round-off ε |f| / δ ≈ 1e-8.
                assert_relative_eq!(jac[(i, j)], exact[i][j], epsilon = 1e-6);
            }
        }
    }
}

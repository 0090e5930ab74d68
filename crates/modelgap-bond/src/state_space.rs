//! Linearisation to state space `ẋ = A x + B u`, `y = C x + D u`, with
//! eigenvalues and time constants.

use nalgebra::{Complex, DMatrix};

use crate::compiled::CompiledModel;
use crate::error::Result;
use crate::graph::BondGraph;

/// A linear(ised) state-space model with the names of its states, inputs and outputs.
#[derive(Clone, Debug, PartialEq)]
pub struct StateSpace {
    /// State names (`p3`, `p8`).
    pub states: Vec<String>,
    /// Input names.
    pub inputs: Vec<String>,
    /// Output names.
    pub outputs: Vec<String>,
    /// Dynamics matrix (n × n).
    pub a: DMatrix<f64>,
    /// Input matrix (n × m).
    pub b: DMatrix<f64>,
    /// Output matrix (p × n).
    pub c: DMatrix<f64>,
    /// Feedthrough matrix (p × m).
    pub d: DMatrix<f64>,
    /// The operating point's state.
    pub x0: Vec<f64>,
    /// The operating point's inputs.
    pub u0: Vec<f64>,
    /// The state derivative at the operating point, `f(x0, u0)`.
    pub f0: Vec<f64>,
}

/// An eigenvalue with its time constant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mode {
    /// The eigenvalue (1/s).
    pub eigenvalue: Complex<f64>,
    /// `−1 / Re(λ)` (s); infinite for a mode that does not decay.
    pub time_constant: f64,
}

impl StateSpace {
    /// Linearises a graph at the operating point `(x0, u0)` (`None`: zero
    /// state, default inputs). Exact for linear models; central differences
    /// scaled to each variable otherwise.
    ///
    /// # Errors
    /// Causality and equation errors of the graph.
    ///
    /// # Example
    /// ```
    /// # use modelgap_bond::{library, state_space::StateSpace};
    /// let ss = StateSpace::linearise(&library::dc_motor(), None, None).unwrap();
    /// let modes = ss.modes();
    /// assert!((modes[0].eigenvalue.re + 29.41).abs() < 0.01);
    /// ```
    pub fn linearise(g: &BondGraph, x0: Option<&[f64]>, u0: Option<&[f64]>) -> Result<StateSpace> {
        let model = CompiledModel::new(g)?;
        Ok(StateSpace::of_compiled(&model, x0, u0))
    }

    /// Linearises a compiled model (see [`StateSpace::linearise`]).
    pub fn of_compiled(
        model: &CompiledModel,
        x0: Option<&[f64]>,
        u0: Option<&[f64]>,
    ) -> StateSpace {
        let n = model.n_states();
        let m = model.n_inputs();
        let p = model.n_outputs();
        let x0: Vec<f64> = x0.map_or_else(|| vec![0.0; n], <[f64]>::to_vec);
        let u0: Vec<f64> = u0.map_or_else(|| model.input_defaults.clone(), <[f64]>::to_vec);
        let mut scratch = model.scratch();
        let mut dx = vec![0.0; n];
        let mut y = vec![0.0; p];
        let mut eval = |x: &[f64], u: &[f64], dx: &mut [f64], y: &mut [f64]| {
            model.eval(0.0, x, u, &mut scratch);
            model.read_derivatives(&scratch, dx);
            model.read_outputs(&scratch, y);
        };
        let (mut a, mut b, mut c, mut d) = (
            DMatrix::zeros(n, n),
            DMatrix::zeros(n, m),
            DMatrix::zeros(p, n),
            DMatrix::zeros(p, m),
        );
        let (mut dx2, mut y2) = (vec![0.0; n], vec![0.0; p]);
        eval(&x0, &u0, &mut dx, &mut y);
        let f0 = dx.clone();
        let mut x = x0.clone();
        for j in 0..n {
            // Central difference; exact up to rounding for affine models.
            let h = 1e-6 * x0[j].abs().max(1.0);
            x[j] = x0[j] + h;
            eval(&x, &u0, &mut dx, &mut y);
            x[j] = x0[j] - h;
            eval(&x, &u0, &mut dx2, &mut y2);
            x[j] = x0[j];
            for i in 0..n {
                a[(i, j)] = (dx[i] - dx2[i]) / (2.0 * h);
            }
            for i in 0..p {
                c[(i, j)] = (y[i] - y2[i]) / (2.0 * h);
            }
        }
        let mut u = u0.clone();
        for j in 0..m {
            let h = 1e-6 * u0[j].abs().max(1.0);
            u[j] = u0[j] + h;
            eval(&x0, &u, &mut dx, &mut y);
            u[j] = u0[j] - h;
            eval(&x0, &u, &mut dx2, &mut y2);
            u[j] = u0[j];
            for i in 0..n {
                b[(i, j)] = (dx[i] - dx2[i]) / (2.0 * h);
            }
            for i in 0..p {
                d[(i, j)] = (y[i] - y2[i]) / (2.0 * h);
            }
        }
        StateSpace {
            states: model.state_names.clone(),
            inputs: model.input_names.clone(),
            outputs: model.output_names.clone(),
            a,
            b,
            c,
            d,
            x0,
            u0,
            f0,
        }
    }

    /// Eigenvalues of A with time constants, slowest decay first.
    pub fn modes(&self) -> Vec<Mode> {
        let mut modes: Vec<Mode> = self
            .a
            .complex_eigenvalues()
            .iter()
            .map(|&l| Mode {
                eigenvalue: l,
                time_constant: if l.re < 0.0 {
                    -1.0 / l.re
                } else {
                    f64::INFINITY
                },
            })
            .collect();
        modes.sort_by(|x, y| {
            y.time_constant
                .total_cmp(&x.time_constant)
                .then(x.eigenvalue.im.total_cmp(&y.eigenvalue.im))
        });
        modes
    }

    /// The steady state of the linearisation for inputs `u`:
    /// `x = x0 − A⁻¹ (f0 + B (u − u0))`, one Newton step from the operating
    /// point (exact for linear models; see [`CompiledModel::steady_state`]
    /// for nonlinear ones). `None` if A is singular.
    pub fn steady_state(&self, u: &[f64]) -> Option<Vec<f64>> {
        let du =
            nalgebra::DVector::from_iterator(u.len(), u.iter().zip(&self.u0).map(|(a, b)| a - b));
        let rhs = -(nalgebra::DVector::from_column_slice(&self.f0) + &self.b * du);
        let dx = self.a.clone().lu().solve(&rhs)?;
        Some(self.x0.iter().zip(dx.iter()).map(|(a, b)| a + b).collect())
    }

    /// The outputs `y = C x + D u`.
    pub fn outputs_at(&self, x: &[f64], u: &[f64]) -> Vec<f64> {
        let y = &self.c * nalgebra::DVector::from_column_slice(x)
            + &self.d * nalgebra::DVector::from_column_slice(u);
        y.iter().copied().collect()
    }
}

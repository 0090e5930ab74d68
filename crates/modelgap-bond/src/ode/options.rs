//! Options, statistics and the choice of method of [`solve`](crate::ode::solve).

/// Which integration method [`solve`](crate::ode::solve) uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Method {
    /// Dormand–Prince 5(4), explicit: the cheapest per step for non-stiff systems.
    #[default]
    Dopri5,
    /// RODAS4, linearly implicit (one LU per step): for stiff systems.
    Rosenbrock,
    /// Starts with `Dopri5` and switches to `Rosenbrock`, once and for the
    /// rest of the solve, when Hairer's stiffness test fires (the step size
    /// times the estimated dominant eigenvalue, `h·|λ|`, is at least 3.25 for
    /// 15 accepted steps without 6 non-stiff ones in between).
    Auto,
}

/// Tolerances and limits of [`solve`](crate::ode::solve).
#[derive(Clone, Debug, PartialEq)]
pub struct OdeOptions {
    /// Relative tolerance of the local error per step (dimensionless).
    /// Default `1e-6`.
    pub rtol: f64,
    /// Absolute tolerance of the local error per step, in the states' units;
    /// must be positive. The error of component `i` is measured against
    /// `atol + rtol·max(|x_i|, |x_new_i|)`. Default `1e-9`.
    pub atol: f64,
    /// Largest step, in s. Default `f64::INFINITY`.
    pub max_step: f64,
    /// First step, in s; `None` lets the solver guess it (Hairer's
    /// algorithm from the first derivatives). Default `None`.
    pub initial_step: Option<f64>,
    /// A fixed step, in s: [`Method::Rosenbrock`] then takes steps of exactly
    /// this size (the last of each stretch between breakpoints stretched or
    /// shortened to land on it), with no error control and no rejection. Its
    /// result is then a smooth function of the system's parameters — an
    /// adaptive step sequence jumps when a parameter moves, which makes the
    /// finite-difference Jacobian of a fit noisy — and its accuracy is the
    /// caller's to check (RODAS4 is of order 4 and L-stable: a fast mode is
    /// damped, never blown up). A stage that is not finite or a singular
    /// matrix ends the solve with its error. Other methods refuse it.
    /// Default `None` (adaptive).
    pub fixed_step: Option<f64>,
    /// Largest number of attempted steps (accepted plus rejected) before
    /// [`OdeError::TooManySteps`](crate::ode::OdeError::TooManySteps).
    /// Default `10_000_000`.
    pub max_steps: usize,
}

impl Default for OdeOptions {
    fn default() -> Self {
        Self {
            rtol: 1e-6,
            atol: 1e-9,
            max_step: f64::INFINITY,
            initial_step: None,
            fixed_step: None,
            max_steps: 10_000_000,
        }
    }
}

/// Work done by one [`solve`](crate::ode::solve).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OdeStats {
    /// Accepted steps.
    pub steps: usize,
    /// Rejected step attempts (error too large, a non-finite trial value, or
    /// a singular Rosenbrock matrix).
    pub rejected: usize,
    /// Calls of [`OdeSystem::rhs`](crate::ode::OdeSystem::rhs) made by the
    /// solver itself (those made inside
    /// [`OdeSystem::jacobian`](crate::ode::OdeSystem::jacobian) are not
    /// visible to it and not counted).
    pub rhs_evals: usize,
    /// Calls of [`OdeSystem::jacobian`](crate::ode::OdeSystem::jacobian).
    pub jacobian_evals: usize,
    /// LU decompositions of the Rosenbrock matrix `I/(γh) − J`.
    pub lu_decompositions: usize,
    /// Switches from `Dopri5` to `Rosenbrock` made by [`Method::Auto`] (0 or 1).
    pub stiff_switches: usize,
}

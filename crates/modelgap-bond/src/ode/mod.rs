//! ODE solvers for the simulator: an explicit Dormand–Prince 5(4) pair, an
//! L-stable Rosenbrock method for stiff systems, and an automatic switch from
//! the first to the second.
//!
//! The simulator evaluates a compiled right-hand side of a small system (2–20
//! states) many times, so these solvers are built for that case:
//!
//! - all scratch is allocated once per [`solve`]; the step loop allocates
//!   nothing and makes one dynamic call per stage (the right-hand side);
//! - steps end exactly at the `breakpoints` (PWM switching instants, sample
//!   instants of zero-order-hold inputs, fault onsets) and restart there;
//! - the state at each requested output time comes from the method's dense
//!   output, so output times never shorten a step.
//!
//! | [`Method`] | scheme | module |
//! |---|---|---|
//! | `Dopri5` | Dormand–Prince 5(4), FSAL, PI step control, 4th-order dense output | `dopri5` |
//! | `Rosenbrock` | RODAS4: order 4(3), L-stable, stiffly accurate, 3rd-order dense output | `rosenbrock` |
//! | `Auto` | `Dopri5` until Hairer's stiffness test fires, then `Rosenbrock` | both |
//!
//! Inside, `driver` runs [`solve`]'s segments between breakpoints and writes
//! the outputs, `control` holds what both steppers share (initial step,
//! step budget, finiteness checks), and `lu` the in-place LU of the
//! Rosenbrock matrix.
//!
//! # Breakpoints and one-sided evaluation
//!
//! The right-hand side may jump at a breakpoint, and a model may describe the
//! jump with either `t < t_b` or `t <= t_b`. So the solver never evaluates it
//! exactly at a breakpoint: stages that fall on the breakpoint at the end of a
//! step use the largest `f64` below it, and the first stage after the restart
//! uses the smallest `f64` above it. Either way of writing the model then
//! selects the right piece; the one-ulp shift in time is far below any
//! tolerance.
//!
//! # Dense output in the stiff limit
//!
//! Error control acts on step ends. In a stiff system whose fast states
//! follow an explicitly time-dependent input (x' = λ (x − u(t)) with
//! h |λ| ≫ 1), RODAS's step ends land on the smooth solution whatever the
//! step, so steps grow long, and between them RODAS's interpolant (derived
//! for non-stiff order 3) is only about as good as a low-order fit across
//! the step (measured 7e-4 on sin t with 0.5 s steps at rtol 1e-8). When such
//! outputs matter, bound the step with [`OdeOptions::max_step`] or list the
//! output times as breakpoints, which makes them step ends.
//!
//! # Example
//!
//! ```
//! use modelgap_bond::ode::{solve, Method, OdeOptions, OdeSystem};
//!
//! /// dx/dt = -2 x
//! struct Decay;
//! impl OdeSystem for Decay {
//!     fn dim(&self) -> usize { 1 }
//!     fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) { dx[0] = -2.0 * x[0]; }
//! }
//!
//! let t_out = [0.0, 0.5, 1.0];
//! let mut out = [0.0; 3];
//! let opts = OdeOptions::default();
//! let stats = solve(&mut Decay, Method::Dopri5, 0.0, &[1.0], &t_out, &[], &opts, &mut out)?;
//! assert!((out[2] - (-2.0f64).exp()).abs() < 1e-6);
//! assert!(stats.steps > 0);
//! # Ok::<(), modelgap_bond::ode::OdeError>(())
//! ```

mod control;
mod dopri5;
mod driver;
mod error;
mod lu;
mod options;
mod rosenbrock;
mod system;

pub use driver::solve;
pub use error::OdeError;
pub use options::{Method, OdeOptions, OdeStats};
pub use system::{OdeSystem, finite_difference_jacobian};

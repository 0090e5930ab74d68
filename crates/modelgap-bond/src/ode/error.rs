//! Why a solve stops early.

use crate::error::num;

/// Why [`solve`](crate::ode::solve) stopped without reaching the last output time.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum OdeError {
    /// The step size fell below what the time's precision can resolve.
    #[error(
        "step size underflow at t = {} s: a step of {} s is too small to advance the solution",
        num(*t),
        num(*h)
    )]
    StepSizeUnderflow {
        /// Time reached, in s.
        t: f64,
        /// The step size that was too small, in s.
        h: f64,
    },
    /// A state or its derivative became NaN or infinite.
    #[error("state {component} or its derivative is not finite at t = {} s", num(*t))]
    NonFinite {
        /// Time at which it was found (the last finite state), in s.
        t: f64,
        /// Index of the state.
        component: usize,
    },
    /// The step budget
    /// [`OdeOptions::max_steps`](crate::ode::OdeOptions::max_steps) ran out.
    #[error(
        "gave up at t = {} s after {max_steps} steps (the limit set by max_steps)",
        num(*t)
    )]
    TooManySteps {
        /// Time reached, in s.
        t: f64,
        /// The limit that was reached.
        max_steps: usize,
    },
    /// The Rosenbrock matrix `I/(γh) − J` stayed singular after halving the step 5 times.
    #[error(
        "the matrix I/(gamma h) - J is singular at t = {} s, even with smaller steps",
        num(*t)
    )]
    SingularMatrix {
        /// Time reached, in s.
        t: f64,
    },
    /// The arguments of [`solve`](crate::ode::solve) cannot work; the message
    /// says which and why.
    #[error("bad solver input: {0}")]
    BadInput(String),
}

#[cfg(test)]
mod tests {
    //! Tests of the error messages.

    use super::OdeError;

    #[test]
    fn error_messages_name_time_and_state() {
        let e = OdeError::NonFinite {
            t: 0.25,
            component: 3,
        };
        assert_eq!(
            e.to_string(),
            "state 3 or its derivative is not finite at t = 0.25 s"
        );
        let e = OdeError::StepSizeUnderflow { t: 1.5, h: 1e-20 };
        assert!(
            e.to_string()
                .starts_with("step size underflow at t = 1.5 s")
        );
    }
}

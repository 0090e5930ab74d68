//! Dormand–Prince 5(4): explicit Runge–Kutta pair with FSAL, PI step-size
//! control, a 4th-order continuous extension and Hairer's stiffness test.
//!
//! Follows Hairer's code DOPRI5 (Hairer, Nørsett & Wanner, *Solving Ordinary
//! Differential Equations I*, 2nd ed., Springer 1993, Sect. II.4–II.6 and
//! the appendix): coefficients from Dormand & Prince, "A family of embedded
//! Runge–Kutta formulae", J. Comput. Appl. Math. 6 (1980) 19–26; dense output
//! from Shampine, "Some practical Runge–Kutta formulas", Math. Comp. 46 (1986)
//! 135–150; stiffness detection from Hairer & Wanner, *Solving Ordinary
//! Differential Equations II*, 2nd ed., Sect. IV.2.

use super::control::{check_budget, check_step_size, first_nonfinite, initial_step};
use super::driver::Segment;
use super::{OdeError, OdeOptions, OdeStats, OdeSystem};

const C2: f64 = 0.2;
const C3: f64 = 0.3;
const C4: f64 = 0.8;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 0.2;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
/// Error weights: 5th-order minus 4th-order solution.
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
/// Dense-output weights (Shampine's continuous extension, as in DOPRI5's `CONTD5`).
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// Safety factor on the predicted step (DOPRI5's `SAFE`).
const SAFE: f64 = 0.9;
/// PI controller gain on the previous error (DOPRI5's `BETA`, its
/// recommended 0.04).
const BETA: f64 = 0.04;
/// Exponent on the current error: `1/5 − 0.75 β` (DOPRI5's `EXPO1`).
const EXPO1: f64 = 0.2 - BETA * 0.75;
/// Largest step decrease `h / h_new` (DOPRI5's `1/FAC1`, `FAC1 = 0.2`).
const MAX_SHRINK: f64 = 5.0;
/// Smallest `h / h_new`, i.e. largest increase ×10 (DOPRI5's `1/FAC2`).
const MIN_SHRINK: f64 = 0.1;
/// `ln(1e-4)`: DOPRI5 remembers `max(err, 1e-4)` for the PI controller.
const LN_ERR_FLOOR: f64 = -9.210_340_371_976_182;
/// `h·|λ|` above which a step counts as stiff: the explicit stability
/// region of DOPRI5 reaches about −3.3 on the real axis.
const STIFF_H_LAMBDA: f64 = 3.25;
/// Consecutive-ish stiff steps that declare the problem stiff.
const STIFF_STEPS: u32 = 15;
/// Non-stiff steps that reset the stiff count.
const NONSTIFF_STEPS: u32 = 6;

/// Workspace and state of the Dormand–Prince stepper; allocated once per solve.
pub(super) struct Dopri5 {
    /// Current time, s.
    pub t: f64,
    /// Current state.
    pub x: Vec<f64>,
    /// Step size to try next, s (0 before the first step: guess it).
    pub h: f64,
    /// Start of the last accepted step, s.
    t_old: f64,
    /// Length of the last accepted step, s.
    h_done: f64,
    /// `1 / h_done`, 1/s (set with the dense-output coefficients).
    inv_h_done: f64,
    /// State at `t_old`.
    x_old: Vec<f64>,
    /// f at the current point (FSAL: the last stage of the previous step).
    k1: Vec<f64>,
    /// f at `t_old` (the first stage of the last accepted step).
    k1_old: Vec<f64>,
    k2: Vec<f64>,
    k3: Vec<f64>,
    k4: Vec<f64>,
    k5: Vec<f64>,
    k6: Vec<f64>,
    /// f at the trial state (the 7th stage).
    k7: Vec<f64>,
    /// Stage argument.
    y: Vec<f64>,
    /// Argument of the 6th stage (kept for the stiffness test).
    ysti: Vec<f64>,
    /// Trial state at `t + h`.
    x_new: Vec<f64>,
    /// Dense-output coefficients, 5 rows of `dim`.
    cont: Vec<f64>,
    /// Whether `cont` describes the last accepted step.
    dense_ready: bool,
    /// `max(err, 1e-4)^β` of the previous accepted step (PI controller memory).
    facold_beta: f64,
    /// Whether the previous attempt was rejected.
    reject: bool,
    /// Whether to run the stiffness test.
    detect_stiffness: bool,
    n_stiff: u32,
    n_nonstiff: u32,
}

impl Dopri5 {
    /// A stepper at `(t, x)` that tries step `h` first (0: guess it).
    pub(super) fn new(t: f64, x: &[f64], h: f64, detect_stiffness: bool) -> Self {
        let n = x.len();
        Self {
            t,
            x: x.to_vec(),
            h,
            t_old: t,
            h_done: 0.0,
            inv_h_done: 0.0,
            x_old: x.to_vec(),
            k1: vec![0.0; n],
            k1_old: vec![0.0; n],
            k2: vec![0.0; n],
            k3: vec![0.0; n],
            k4: vec![0.0; n],
            k5: vec![0.0; n],
            k6: vec![0.0; n],
            k7: vec![0.0; n],
            y: vec![0.0; n],
            ysti: vec![0.0; n],
            x_new: vec![0.0; n],
            cont: vec![0.0; 5 * n],
            dense_ready: false,
            facold_beta: 1e-4f64.powf(BETA),
            reject: false,
            detect_stiffness,
            n_stiff: 0,
            n_nonstiff: 0,
        }
    }

    /// Starts a segment: evaluates f afresh at the current point (the FSAL
    /// value from before a breakpoint belongs to the other side of the jump)
    /// and guesses the first step if none is set.
    pub(super) fn restart(
        &mut self,
        sys: &mut dyn OdeSystem,
        seg: &Segment,
        opts: &OdeOptions,
        stats: &mut OdeStats,
    ) -> Result<(), OdeError> {
        let t_eval = seg.first_eval_time(self.t);
        sys.rhs(t_eval, &self.x, &mut self.k1);
        stats.rhs_evals += 1;
        if let Some(component) = first_nonfinite(&self.k1) {
            return Err(OdeError::NonFinite {
                t: self.t,
                component,
            });
        }
        if self.h <= 0.0 {
            self.h = initial_step(
                sys,
                t_eval,
                &self.x,
                &self.k1,
                5,
                opts.max_step.min(seg.t_end - self.t),
                seg.t_end.next_down(),
                opts,
                &mut self.y,
                &mut self.k2,
                stats,
            );
        }
        Ok(())
    }

    /// Takes one accepted step (retrying rejected attempts) towards
    /// `seg.t_end`, landing on it exactly when within reach. Returns whether
    /// the stiffness test has just declared the problem stiff.
    pub(super) fn step(
        &mut self,
        sys: &mut dyn OdeSystem,
        seg: &Segment,
        opts: &OdeOptions,
        stats: &mut OdeStats,
    ) -> Result<bool, OdeError> {
        let n = self.x.len();
        let Self {
            x,
            k1,
            k2,
            k3,
            k4,
            k5,
            k6,
            k7,
            y,
            ysti,
            x_new,
            ..
        } = self;
        let (x, k1, k2, k3, k4, k5, k6, k7, y, ysti, x_new) = (
            &x[..n],
            &k1[..n],
            &mut k2[..n],
            &mut k3[..n],
            &mut k4[..n],
            &mut k5[..n],
            &mut k6[..n],
            &mut k7[..n],
            &mut y[..n],
            &mut ysti[..n],
            &mut x_new[..n],
        );
        let t = self.t;
        let mut nonfinite = None;
        let stiff = loop {
            check_budget(stats, opts, t)?;
            let h_proposed = self.h.min(opts.max_step);
            check_step_size(t, h_proposed, nonfinite)?;
            let (h, last) = seg.clamp(t, h_proposed);
            let clock = seg.clock(t, h, last);

            for i in 0..n {
                y[i] = x[i] + h * A21 * k1[i];
            }
            sys.rhs(clock.at(C2), y, k2);
            for i in 0..n {
                y[i] = x[i] + h * (A31 * k1[i] + A32 * k2[i]);
            }
            sys.rhs(clock.at(C3), y, k3);
            for i in 0..n {
                y[i] = x[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
            }
            sys.rhs(clock.at(C4), y, k4);
            for i in 0..n {
                y[i] = x[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
            }
            sys.rhs(clock.at(C5), y, k5);
            for i in 0..n {
                ysti[i] = x[i]
                    + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i]);
            }
            sys.rhs(clock.at(1.0), ysti, k6);
            for i in 0..n {
                x_new[i] = x[i]
                    + h * (A71 * k1[i] + A73 * k3[i] + A74 * k4[i] + A75 * k5[i] + A76 * k6[i]);
            }
            sys.rhs(clock.at(1.0), x_new, k7);
            stats.rhs_evals += 6;

            let mut sum = 0.0;
            for i in 0..n {
                let e = h
                    * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
                let sk = opts.atol + opts.rtol * x[i].abs().max(x_new[i].abs());
                sum += (e / sk) * (e / sk);
            }
            let err = (sum / n as f64).sqrt();

            // Step-size control as DOPRI5: `fac11` drives a rejection, the PI
            // ratio with Lund stabilization an acceptance.
            // err^a as exp(a ln err): one ln and two exp per step instead of
            // two pow calls (err = 0 gives ln = −∞ and exp(−∞) = 0).
            let ln_err = err.ln();
            let fac11 = (EXPO1 * ln_err).exp();
            if !err.is_finite() || err > 1.0 {
                if err.is_finite() {
                    self.h = h / MAX_SHRINK.min(fac11 / SAFE);
                } else {
                    // A non-finite trial: shrink as much as allowed, and
                    // remember which state it was in case the step underflows.
                    nonfinite = first_nonfinite(x_new)
                        .or_else(|| first_nonfinite(k7))
                        .or_else(|| first_nonfinite(k6))
                        .or(Some(0));
                    self.h = h / MAX_SHRINK;
                }
                self.reject = true;
                stats.rejected += 1;
                continue;
            }

            // Accepted.
            let t_new = if last { seg.t_end } else { t + h };
            if let Some(component) = first_nonfinite(x_new) {
                return Err(OdeError::NonFinite {
                    t: t_new,
                    component,
                });
            }
            stats.steps += 1;
            let fac = (fac11 / self.facold_beta / SAFE).clamp(MIN_SHRINK, MAX_SHRINK);
            self.facold_beta = (BETA * ln_err.max(LN_ERR_FLOOR)).exp();
            let mut h_new = (h / fac).min(opts.max_step);
            if self.reject {
                h_new = h_new.min(h);
            }
            if last && h_new >= h {
                // A step cut short by the segment end says nothing against
                // the step that was proposed before the cut.
                h_new = h_new.max(h_proposed);
            }
            self.reject = false;
            self.h = h_new;

            let stiff = self.detect_stiffness && {
                // h·|λ| ≈ h ‖f(x_new) − f(ysti)‖ / ‖x_new − ysti‖: both points
                // are at t + h, so their difference probes the Jacobian.
                let (mut num, mut den) = (0.0, 0.0);
                for i in 0..n {
                    num += (k7[i] - k6[i]) * (k7[i] - k6[i]);
                    den += (x_new[i] - ysti[i]) * (x_new[i] - ysti[i]);
                }
                if den > 0.0 && h * (num / den).sqrt() > STIFF_H_LAMBDA {
                    self.n_nonstiff = 0;
                    self.n_stiff += 1;
                } else {
                    self.n_nonstiff += 1;
                    if self.n_nonstiff == NONSTIFF_STEPS {
                        self.n_stiff = 0;
                    }
                }
                self.n_stiff >= STIFF_STEPS
            };

            self.t_old = t;
            self.t = t_new;
            self.h_done = h;
            self.dense_ready = false;
            break stiff;
        };
        // Keep what the dense output needs, then advance by exchanging
        // buffers rather than copying them: x_old ← x ← x_new, and
        // k1_old ← k1 ← k7 (FSAL: k7 is the first stage of the next step).
        std::mem::swap(&mut self.x_old, &mut self.x);
        std::mem::swap(&mut self.x, &mut self.x_new);
        std::mem::swap(&mut self.k1_old, &mut self.k1);
        std::mem::swap(&mut self.k1, &mut self.k7);
        Ok(stiff)
    }

    /// Computes the dense-output coefficients of the last accepted step
    /// (only needed when an output time falls inside it).
    pub(super) fn prepare_dense(&mut self) {
        if self.dense_ready {
            return;
        }
        let n = self.x.len();
        let h = self.h_done;
        let (c0, rest) = self.cont.split_at_mut(n);
        let (c1, rest) = rest.split_at_mut(n);
        let (c2, rest) = rest.split_at_mut(n);
        let (c3, c4) = rest.split_at_mut(n);
        // After the step, `k1` holds f(t_new, x_new), the 7th stage.
        let (k1, k7) = (&self.k1_old, &self.k1);
        for i in 0..n {
            let dx = self.x[i] - self.x_old[i];
            let bspl = h * k1[i] - dx;
            c0[i] = self.x_old[i];
            c1[i] = dx;
            c2[i] = bspl;
            c3[i] = dx - h * k7[i] - bspl;
            c4[i] = h
                * (D1 * k1[i]
                    + D3 * self.k3[i]
                    + D4 * self.k4[i]
                    + D5 * self.k5[i]
                    + D6 * self.k6[i]
                    + D7 * k7[i]);
        }
        self.inv_h_done = 1.0 / h;
        self.dense_ready = true;
    }

    /// The dense output at `t` inside the last accepted step into `out`.
    /// Call [`prepare_dense`](Self::prepare_dense) first.
    #[inline]
    pub(super) fn interpolate(&self, t: f64, out: &mut [f64]) {
        debug_assert!(self.dense_ready, "prepare_dense before interpolate");
        let n = self.x.len();
        let s = (t - self.t_old) * self.inv_h_done;
        let s1 = 1.0 - s;
        let (c0, rest) = self.cont.split_at(n);
        let (c1, rest) = rest.split_at(n);
        let (c2, rest) = rest.split_at(n);
        let (c3, c4) = rest.split_at(n);
        let rows = c0.iter().zip(c1).zip(c2).zip(c3).zip(c4);
        for (o, ((((a0, a1), a2), a3), a4)) in out.iter_mut().zip(rows) {
            *o = a0 + s * (a1 + s1 * (a2 + s * (a3 + s1 * a4)));
        }
    }
}

#[cfg(test)]
mod tests {
    //! Tests of the Dormand–Prince stepper through `solve`.

    use super::super::{Method, OdeOptions, OdeSystem, solve};

    /// x'' = −ω² x as (x, v).
    struct Oscillator {
        omega: f64,
    }
    impl OdeSystem for Oscillator {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
            dx[0] = x[1];
            dx[1] = -self.omega * self.omega * x[0];
        }
    }

    #[test]
    fn harmonic_oscillator_keeps_phase_and_energy_over_many_periods() {
        let omega = 2.0 * std::f64::consts::PI; // period 1 s
        let periods = 100.0;
        let t_out: Vec<f64> = (0..=1000).map(|i| periods * i as f64 / 1000.0).collect();
        let mut out = vec![0.0; 2 * t_out.len()];
        let opts = OdeOptions {
            rtol: 1e-10,
            atol: 1e-12,
            ..OdeOptions::default()
        };
        let stats = solve(
            &mut Oscillator { omega },
            Method::Dopri5,
            0.0,
            &[1.0, 0.0],
            &t_out,
            &[],
            &opts,
            &mut out,
        )
        .unwrap();
        let mut worst_phase: f64 = 0.0;
        let mut worst_energy: f64 = 0.0;
        for (k, &t) in t_out.iter().enumerate() {
            let (x, v) = (out[2 * k], out[2 * k + 1]);
            let energy = 0.5 * (v * v + omega * omega * x * x);
            worst_energy = worst_energy.max((energy / (0.5 * omega * omega) - 1.0).abs());
            // Deviation from the exact (cos ωt, −ω sin ωt), in units of the amplitude.
            let dev =
                ((x - (omega * t).cos()).powi(2) + (v / omega + (omega * t).sin()).powi(2)).sqrt();
            worst_phase = worst_phase.max(dev);
        }
        // Local errors of 1e-10 relative add up linearly over the ~20 steps
        // per period of 100 periods (~2000 steps): a few 1e-7 at most.
        assert!(worst_phase < 1e-6, "phase/amplitude error {worst_phase}");
        assert!(worst_energy < 1e-6, "energy error {worst_energy}");
        assert_eq!(stats.stiff_switches, 0);
    }

    #[test]
    fn dense_output_is_accurate_between_long_steps() {
        /// x' = cos t, exact x = sin t.
        struct Cosine;
        impl OdeSystem for Cosine {
            fn dim(&self) -> usize {
                1
            }
            fn rhs(&mut self, t: f64, _x: &[f64], dx: &mut [f64]) {
                dx[0] = t.cos();
            }
        }
        let t_out: Vec<f64> = (0..=2000).map(|i| 10.0 * i as f64 / 2000.0).collect();
        let mut out = vec![0.0; t_out.len()];
        let opts = OdeOptions {
            rtol: 1e-8,
            atol: 1e-10,
            ..OdeOptions::default()
        };
        let stats = solve(
            &mut Cosine,
            Method::Dopri5,
            0.0,
            &[0.0],
            &t_out,
            &[],
            &opts,
            &mut out,
        )
        .unwrap();
        // Many outputs per step: the outputs do not shorten steps.
        assert!(stats.steps < 200, "{stats:?}");
        for (&t, &x) in t_out.iter().zip(&out) {
            // The 4th-order interpolant errs by about the step's local error
            // (tolerance 1e-8 on |x| <= 1); 1e-7 leaves a margin.
            assert!((x - t.sin()).abs() < 1e-7, "t = {t}: {x}");
        }
    }

    #[test]
    fn stiffness_test_fires_on_a_stiff_linear_system() {
        struct Stiff;
        impl OdeSystem for Stiff {
            fn dim(&self) -> usize {
                2
            }
            fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
                dx[0] = -1e4 * (x[0] - x[1]);
                dx[1] = -x[1];
            }
        }
        let mut out = [0.0; 4];
        let stats = solve(
            &mut Stiff,
            Method::Auto,
            0.0,
            &[1.0, 1.0],
            &[0.0, 1.0],
            &[],
            &OdeOptions::default(),
            &mut out,
        )
        .unwrap();
        assert_eq!(stats.stiff_switches, 1);
        // The stiff mode has decayed; x0 follows x1 = e^{-t} within rtol.
        assert!((out[3] - (-1.0f64).exp()).abs() < 1e-5);
        assert!((out[2] - out[3]).abs() < 1e-4);
    }
}

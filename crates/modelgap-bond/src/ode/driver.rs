//! [`solve`]: validation, the segments between breakpoints, the switch of
//! [`Method::Auto`], and the writing of outputs.

use super::dopri5::Dopri5;
use super::rosenbrock::Rosenbrock;
use super::{Method, OdeError, OdeOptions, OdeStats, OdeSystem};

/// Integrates `sys` from `t0`, `x0` and writes the state at each time of
/// `t_out` into `out`.
///
/// - `t_out` (s) must be sorted (non-decreasing) with every time `≥ t0`; the
///   solve ends at its last time. Outputs at `t0` are `x0`; outputs that
///   coincide with the end of a step (a breakpoint, the last time) are that
///   step's state; all others come from the method's dense output.
/// - `out` is row-major, `t_out.len() × dim`: row `k` is the state at `t_out[k]`.
/// - `breakpoints` (s) must be sorted; those `≤ t0` or `≥ t_out`'s last time
///   are ignored. A step never crosses one: it ends exactly there, and the next
///   step restarts with a fresh evaluation of the right-hand side (no FSAL
///   reuse), because the right-hand side may jump there. See the
///   [module docs](crate::ode) for how the right-hand side is evaluated next to a
///   breakpoint.
///
/// # Errors
///
/// - [`OdeError::BadInput`]: `x0.len() != sys.dim()`, `dim == 0`, a non-finite
///   `t0`, `x0`, `t_out` or breakpoint, unsorted `t_out` or `breakpoints`, a
///   time in `t_out` before `t0`, `out.len() != t_out.len() · dim`, or invalid
///   options (`rtol < 0`, `atol ≤ 0`, `max_step ≤ 0`, `initial_step ≤ 0`,
///   `max_steps == 0`).
/// - [`OdeError::NonFinite`]: the state or its derivative became NaN or infinite.
/// - [`OdeError::StepSizeUnderflow`], [`OdeError::TooManySteps`],
///   [`OdeError::SingularMatrix`]: the integration could not continue.
///
/// On error, the rows of `out` before the failure time are already written.
///
/// # Example
///
/// ```
/// use modelgap_bond::ode::{solve, Method, OdeOptions, OdeSystem};
///
/// /// dx/dt = u(t) - x with u switching from 0 to 1 at t = 0.3 s.
/// struct Step;
/// impl OdeSystem for Step {
///     fn dim(&self) -> usize { 1 }
///     fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
///         let u = if t < 0.3 { 0.0 } else { 1.0 };
///         dx[0] = u - x[0];
///     }
/// }
///
/// let t_out = [0.3, 1.0];
/// let mut out = [0.0; 2];
/// let opts = OdeOptions { rtol: 1e-10, atol: 1e-12, ..OdeOptions::default() };
/// solve(&mut Step, Method::Rosenbrock, 0.0, &[0.0], &t_out, &[0.3], &opts, &mut out)?;
/// assert!(out[0].abs() < 1e-12);
/// assert!((out[1] - (1.0 - (-0.7f64).exp())).abs() < 1e-8);
/// # Ok::<(), modelgap_bond::ode::OdeError>(())
/// ```
#[allow(clippy::too_many_arguments)] // each argument is one part of the problem
pub fn solve(
    sys: &mut dyn OdeSystem,
    method: Method,
    t0: f64,
    x0: &[f64],
    t_out: &[f64],
    breakpoints: &[f64],
    opts: &OdeOptions,
    out: &mut [f64],
) -> Result<OdeStats, OdeError> {
    validate(
        sys.dim(),
        method,
        t0,
        x0,
        t_out,
        breakpoints,
        opts,
        out.len(),
    )?;
    let n = x0.len();
    let mut stats = OdeStats::default();
    let mut outputs = Outputs {
        t_out,
        out,
        n,
        next: 0,
    };
    outputs.emit_exact(t0, x0);
    let Some(&t_last) = t_out.last() else {
        return Ok(stats);
    };
    if outputs.done() {
        return Ok(stats);
    }

    let h0 = opts.fixed_step.or(opts.initial_step).unwrap_or(0.0);
    let mut active = match method {
        Method::Dopri5 | Method::Auto => {
            Active::Dopri(Dopri5::new(t0, x0, h0, method == Method::Auto))
        }
        Method::Rosenbrock => Active::Rodas(Rosenbrock::new(t0, x0, h0)),
    };
    let mut breakpoints = breakpoints.iter().copied();
    let mut seg = Segment {
        t_start: t0,
        t_end: t0,
        start_is_breakpoint: false,
    };
    loop {
        let t = seg.t_end;
        seg.t_end = breakpoints
            .by_ref()
            .find(|&b| b > t)
            .filter(|&b| b < t_last)
            .unwrap_or(t_last);
        match &mut active {
            Active::Dopri(d) => d.restart(sys, &seg, opts, &mut stats)?,
            Active::Rodas(r) => r.restart(sys, &seg, opts, &mut stats)?,
        }
        loop {
            let switch = match &mut active {
                Active::Dopri(d) => {
                    if d.t >= seg.t_end {
                        break;
                    }
                    let stiff = d.step(sys, &seg, opts, &mut stats)?;
                    if outputs.pending_until(d.t) {
                        d.prepare_dense();
                        outputs.emit_step(d.t, &d.x, |tq, row| d.interpolate(tq, row));
                    }
                    stiff && method == Method::Auto
                }
                Active::Rodas(r) => {
                    if r.t >= seg.t_end {
                        break;
                    }
                    r.step(sys, &seg, opts, &mut stats)?;
                    outputs.emit_step(r.t, &r.x, |tq, row| r.interpolate(tq, row));
                    false
                }
            };
            if switch && let Active::Dopri(d) = &active {
                // Rosenbrock evaluates f and J itself at the start of each
                // step, so it needs no restart here; it continues with the
                // step size Dopri5 would have tried next.
                active = Active::Rodas(Rosenbrock::new(d.t, &d.x, d.h));
                stats.stiff_switches += 1;
            }
        }
        if seg.t_end >= t_last {
            break;
        }
        seg.t_start = seg.t_end;
        seg.start_is_breakpoint = true;
    }
    debug_assert!(outputs.done(), "every output time is reached");
    Ok(stats)
}

/// The stepper in use.
enum Active {
    Dopri(Dopri5),
    Rodas(Rosenbrock),
}

/// The stretch between two restarts: from `t0` or a breakpoint to the next
/// breakpoint or the last output time.
#[derive(Clone, Copy, Debug)]
pub(super) struct Segment {
    /// Start, s.
    pub(super) t_start: f64,
    /// End, s; steps end exactly here.
    pub(super) t_end: f64,
    /// Whether `t_start` is a breakpoint (the right-hand side may jump there).
    pub(super) start_is_breakpoint: bool,
}

impl Segment {
    /// Clamps a proposed step `h` from `t` to the segment; `last` says that
    /// the step ends exactly at `t_end`. Stretches by up to 1 % rather than
    /// leave a sliver (as DOPRI5 does).
    pub(super) fn clamp(&self, t: f64, h: f64) -> (f64, bool) {
        if t + 1.01 * h >= self.t_end {
            (self.t_end - t, true)
        } else {
            (h, false)
        }
    }

    /// The times at which stages of the step `t → t + h` are evaluated.
    pub(super) fn clock(&self, t: f64, h: f64, last: bool) -> StageClock {
        let hi = if last {
            self.t_end.next_down().max(t)
        } else {
            t + h
        };
        let lo = self.first_eval_time(t).min(hi);
        StageClock { t, h, lo, hi }
    }

    /// Where to evaluate the right-hand side for a stage at the step start `t`:
    /// just after a breakpoint when `t` is one.
    pub(super) fn first_eval_time(&self, t: f64) -> f64 {
        if self.start_is_breakpoint && t == self.t_start {
            t.next_up()
        } else {
            t
        }
    }
}

/// Stage times of one step, kept inside `[lo, hi]` so that no stage lands on a
/// breakpoint (see the module docs).
#[derive(Clone, Copy, Debug)]
pub(super) struct StageClock {
    t: f64,
    h: f64,
    lo: f64,
    hi: f64,
}

impl StageClock {
    /// Time of a stage at fraction `c` of the step, in s.
    #[inline]
    pub(super) fn at(&self, c: f64) -> f64 {
        (self.t + c * self.h).max(self.lo).min(self.hi)
    }
}

/// The rows of `out` still to be written.
struct Outputs<'a> {
    t_out: &'a [f64],
    out: &'a mut [f64],
    n: usize,
    next: usize,
}

impl Outputs<'_> {
    fn done(&self) -> bool {
        self.next >= self.t_out.len()
    }

    /// Whether some output time is `≤ t`.
    fn pending_until(&self, t: f64) -> bool {
        self.t_out.get(self.next).is_some_and(|&tq| tq <= t)
    }

    /// Writes `x` for every output time equal to `t`.
    fn emit_exact(&mut self, t: f64, x: &[f64]) {
        while self.t_out.get(self.next).is_some_and(|&tq| tq == t) {
            let k = self.next;
            self.out[k * self.n..(k + 1) * self.n].copy_from_slice(x);
            self.next += 1;
        }
    }

    /// Writes every output time up to the end `t_new` of a step: `x_new` at
    /// `t_new` itself, the dense output `interpolate` before it.
    fn emit_step(
        &mut self,
        t_new: f64,
        x_new: &[f64],
        mut interpolate: impl FnMut(f64, &mut [f64]),
    ) {
        while let Some(&tq) = self.t_out.get(self.next) {
            if tq > t_new {
                break;
            }
            let k = self.next;
            let row = &mut self.out[k * self.n..(k + 1) * self.n];
            if tq == t_new {
                row.copy_from_slice(x_new);
            } else {
                interpolate(tq, row);
            }
            self.next += 1;
        }
    }
}

/// Checks the arguments of [`solve`].
#[allow(clippy::too_many_arguments)] // each argument is one part of the problem
fn validate(
    dim: usize,
    method: Method,
    t0: f64,
    x0: &[f64],
    t_out: &[f64],
    breakpoints: &[f64],
    opts: &OdeOptions,
    out_len: usize,
) -> Result<(), OdeError> {
    let bad = |msg: String| Err(OdeError::BadInput(msg));
    if dim == 0 {
        return bad("the system has no states (dim = 0)".into());
    }
    if x0.len() != dim {
        return bad(format!(
            "x0 has {} components but the system has {dim} states",
            x0.len()
        ));
    }
    if !t0.is_finite() {
        return bad(format!("t0 must be finite, found {t0} s"));
    }
    if let Some((i, v)) = x0.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return bad(format!("x0[{i}] must be finite, found {v}"));
    }
    check_times("t_out", t_out)?;
    check_times("breakpoints", breakpoints)?;
    if let Some(&first) = t_out.first()
        && first < t0
    {
        return bad(format!(
            "t_out[0] = {first} s is before t0 = {t0} s (output times must be >= t0)"
        ));
    }
    if out_len != t_out.len() * dim {
        return bad(format!(
            "out has {out_len} values but {} output times x {dim} states need {}",
            t_out.len(),
            t_out.len() * dim
        ));
    }
    if !opts.rtol.is_finite() || opts.rtol < 0.0 {
        return bad(format!("rtol must be finite and >= 0, found {}", opts.rtol));
    }
    if !opts.atol.is_finite() || opts.atol <= 0.0 {
        return bad(format!("atol must be finite and > 0, found {}", opts.atol));
    }
    if opts.max_step.is_nan() || opts.max_step <= 0.0 {
        return bad(format!("max_step must be > 0, found {} s", opts.max_step));
    }
    if let Some(h) = opts.initial_step
        && (!h.is_finite() || h <= 0.0)
    {
        return bad(format!("initial_step must be finite and > 0, found {h} s"));
    }
    if let Some(h) = opts.fixed_step {
        if !(h.is_finite() && h > 0.0) {
            return bad(format!("fixed_step must be finite and > 0, found {h} s"));
        }
        if method != Method::Rosenbrock {
            return bad(format!(
                "fixed_step needs Method::Rosenbrock (an L-stable method), not {method:?}"
            ));
        }
    }
    if opts.max_steps == 0 {
        return bad("max_steps must be > 0, found 0".into());
    }
    Ok(())
}

/// Checks that `times` are finite and non-decreasing.
fn check_times(name: &str, times: &[f64]) -> Result<(), OdeError> {
    // Fast path without early exits (it vectorizes): a NaN fails some
    // comparison, and between finite ends a sorted slice has no infinity.
    let sorted = times
        .iter()
        .zip(times.iter().skip(1))
        .fold(true, |ok, (a, b)| ok & (a <= b));
    let finite_ends =
        times.first().is_none_or(|t| t.is_finite()) && times.last().is_none_or(|t| t.is_finite());
    if sorted && finite_ends {
        return Ok(());
    }
    let mut prev = f64::NEG_INFINITY;
    for (i, &t) in times.iter().enumerate() {
        if !t.is_finite() {
            return Err(OdeError::BadInput(format!(
                "{name}[{i}] must be finite, found {t}"
            )));
        }
        if t < prev {
            return Err(OdeError::BadInput(format!(
                "{name} must be sorted: {name}[{i}] = {t} s comes after {name}[{}] = {prev} s",
                i - 1
            )));
        }
        prev = t;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    //! Tests of the driver: outputs, breakpoints, errors, and the three
    //! methods on problems with closed-form solutions.

    use approx::assert_relative_eq;

    use super::super::{Method, OdeError, OdeOptions, OdeStats, OdeSystem};
    use super::solve;

    const METHODS: [Method; 3] = [Method::Dopri5, Method::Rosenbrock, Method::Auto];

    /// dx/dt = λ x.
    struct Decay {
        lambda: f64,
    }
    impl OdeSystem for Decay {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
            dx[0] = self.lambda * x[0];
        }
    }

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

    /// dx/dt = u(t) − a x with a square wave u ∈ {0, 1}, high on
    /// [0.1, 0.35), [0.6, 0.85), ... (period 0.5 s). `inclusive` chooses how
    /// the model writes the switching instant.
    struct SquareWave {
        a: f64,
        inclusive: bool,
    }
    const SW_PERIOD: f64 = 0.5;
    const SW_ON: f64 = 0.1;
    const SW_OFF: f64 = 0.35;
    fn switching_times(t_end: f64) -> Vec<f64> {
        let mut v = Vec::new();
        let mut k = 0.0;
        while k * SW_PERIOD < t_end {
            v.push(k * SW_PERIOD + SW_ON);
            v.push(k * SW_PERIOD + SW_OFF);
            k += 1.0;
        }
        v
    }
    impl SquareWave {
        fn u(&self, t: f64) -> f64 {
            let phase = t - (t / SW_PERIOD).floor() * SW_PERIOD;
            let on = if self.inclusive {
                (SW_ON..=SW_OFF).contains(&phase)
            } else {
                (SW_ON..SW_OFF).contains(&phase)
            };
            if on { 1.0 } else { 0.0 }
        }
        /// Closed form: piecewise x = u/a + (x_k − u/a) e^{−a (t − t_k)}.
        fn exact(&self, t: f64) -> f64 {
            let mut x = 0.0;
            let mut tk = 0.0;
            let mut u = 0.0;
            for ts in switching_times(t) {
                if ts >= t {
                    break;
                }
                x = u / self.a + (x - u / self.a) * (-self.a * (ts - tk)).exp();
                tk = ts;
                u = 1.0 - u;
            }
            u / self.a + (x - u / self.a) * (-self.a * (t - tk)).exp()
        }
    }
    impl OdeSystem for SquareWave {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
            dx[0] = self.u(t) - self.a * x[0];
        }
    }

    fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
            .collect()
    }

    fn tight() -> OdeOptions {
        OdeOptions {
            rtol: 1e-10,
            atol: 1e-12,
            ..OdeOptions::default()
        }
    }

    #[test]
    fn exponential_decay_matches_exact_solution() {
        let t_out = linspace(0.0, 5.0, 51);
        for method in METHODS {
            let mut out = vec![0.0; t_out.len()];
            let stats = solve(
                &mut Decay { lambda: -1.3 },
                method,
                0.0,
                &[2.0],
                &t_out,
                &[],
                &tight(),
                &mut out,
            )
            .unwrap();
            for (t, x) in t_out.iter().zip(&out) {
                let exact = 2.0 * (-1.3 * t).exp();
                // rtol = 1e-10 per step; the global error of this contracting
                // problem stays within a few hundred local errors, and the
                // dense output (order 4 or 3) adds the same order: 1e-7
                // absolute on a solution of size <= 2 leaves a wide margin.
                assert!(
                    (x - exact).abs() < 1e-7,
                    "{method:?} at t = {t}: {x} vs {exact}"
                );
            }
            assert!(stats.steps > 0 && stats.rhs_evals > 0);
        }
    }

    #[test]
    fn output_at_t0_is_the_initial_state() {
        for method in METHODS {
            let t_out = [0.0, 0.0, 1.0];
            let mut out = vec![f64::NAN; 6];
            solve(
                &mut DcMotor,
                method,
                0.0,
                &[1e-4, 2e-3],
                &t_out,
                &[],
                &OdeOptions::default(),
                &mut out,
            )
            .unwrap();
            // Exactly x0: rows at t0 are copied, not computed.
            assert_eq!(&out[..4], &[1e-4, 2e-3, 1e-4, 2e-3]);
        }
    }

    #[test]
    fn only_t0_outputs_need_no_steps() {
        let mut out = [0.0];
        let stats = solve(
            &mut Decay { lambda: -1.0 },
            Method::Dopri5,
            1.0,
            &[3.0],
            &[1.0],
            &[],
            &OdeOptions::default(),
            &mut out,
        )
        .unwrap();
        assert_eq!(out[0], 3.0);
        assert_eq!(stats, OdeStats::default());
    }

    #[test]
    fn dc_motor_reaches_its_steady_state() {
        // Steady state of A x + (12, 0) = 0: ω = 12 / (R β / k + k), i = β ω / k.
        let omega = 12.0 / (R * BETA / K + K);
        let current = BETA * omega / K;
        assert_relative_eq!(omega, 239.0438, epsilon = 1e-4);
        assert_relative_eq!(current, 0.04781, epsilon = 1e-5);
        let t_out = linspace(0.0, 4.0, 4001); // 1 kHz
        // p3 = L i ≈ 2.4e-4 V s: with the default atol = 1e-9 alone the
        // per-step tolerance on p3 is 4e-6 relative, and Dopri5, held at its
        // stability limit by the -170.69 s^-1 mode, keeps an error of that
        // size alive (measured 1.9e-6). atol = 1e-12 scales to the state.
        let opts = OdeOptions {
            atol: 1e-12,
            ..OdeOptions::default()
        };
        for method in METHODS {
            let mut out = vec![0.0; 2 * t_out.len()];
            let stats = solve(
                &mut DcMotor,
                method,
                0.0,
                &[0.0, 0.0],
                &t_out,
                &[],
                &opts,
                &mut out,
            )
            .unwrap();
            let last = &out[2 * 4000..];
            // The slowest mode decays as e^{-29.4 t}: after 4 s it is e^{-117},
            // so the solution is the fixed point up to the solver's error,
            // which the stable dynamics damp; 1e-6 relative is the brief's bound.
            assert_relative_eq!(last[1] / J, omega, max_relative = 1e-6);
            assert_relative_eq!(last[0] / L, current, max_relative = 1e-6);
            assert_eq!(stats.stiff_switches, usize::from(method == Method::Auto));
        }
    }

    #[test]
    fn dc_motor_transient_agrees_across_methods() {
        let t_out = linspace(0.0, 0.2, 201);
        let mut reference = vec![0.0; 2 * t_out.len()];
        let opts = OdeOptions {
            rtol: 1e-12,
            atol: 1e-15,
            ..OdeOptions::default()
        };
        solve(
            &mut DcMotor,
            Method::Dopri5,
            0.0,
            &[0.0, 0.0],
            &t_out,
            &[],
            &opts,
            &mut reference,
        )
        .unwrap();
        for method in METHODS {
            let mut out = vec![0.0; 2 * t_out.len()];
            solve(
                &mut DcMotor,
                method,
                0.0,
                &[0.0, 0.0],
                &t_out,
                &[],
                &tight(),
                &mut out,
            )
            .unwrap();
            for (k, (a, b)) in out.iter().zip(&reference).enumerate() {
                // Scale of each state: p3 <= ~1e-3 V s, p8 <= 0.024 N m s.
                let scale = if k % 2 == 0 { 1e-3 } else { 0.024 };
                // rtol 1e-10 against a 1e-12 reference: the global error at the
                // dense-output points stays below 1e-7 of the state's scale.
                assert!(
                    (a - b).abs() < 1e-7 * scale,
                    "{method:?} row {}: {a} vs {b}",
                    k / 2
                );
            }
        }
    }

    #[test]
    fn square_wave_is_exact_with_breakpoints() {
        for inclusive in [false, true] {
            for method in METHODS {
                let mut sys = SquareWave { a: 3.0, inclusive };
                let t_end = 2.0;
                let breakpoints = switching_times(t_end);
                // Outputs at and between the switching instants.
                let mut t_out = linspace(0.0, t_end, 101);
                t_out.extend(breakpoints.iter().copied().filter(|&b| b < t_end));
                t_out.sort_by(f64::total_cmp);
                let mut out = vec![0.0; t_out.len()];
                solve(
                    &mut sys,
                    method,
                    0.0,
                    &[0.0],
                    &t_out,
                    &breakpoints,
                    &tight(),
                    &mut out,
                )
                .unwrap();
                for (&t, &x) in t_out.iter().zip(&out) {
                    let exact = sys.exact(t);
                    // The brief's bound: 1e-8 relative to the solution's scale
                    // (x <= 1/a = 0.33); rtol = 1e-10 per smooth segment.
                    assert!(
                        (x - exact).abs() <= 1e-8 * (1.0 / sys.a),
                        "{method:?} inclusive={inclusive} t={t}: {x} vs {exact}"
                    );
                }
            }
        }
    }

    #[test]
    fn square_wave_without_breakpoints_costs_more_or_loses_accuracy() {
        let t_end = 2.0;
        let t_out = linspace(0.0, t_end, 101);
        let breakpoints = switching_times(t_end);
        let opts = OdeOptions {
            rtol: 1e-8,
            atol: 1e-12,
            ..OdeOptions::default()
        };
        for method in METHODS {
            let mut sys = SquareWave {
                a: 3.0,
                inclusive: false,
            };
            let mut run = |bps: &[f64]| {
                let mut out = vec![0.0; t_out.len()];
                let stats =
                    solve(&mut sys, method, 0.0, &[0.0], &t_out, bps, &opts, &mut out).unwrap();
                let exact = SquareWave {
                    a: 3.0,
                    inclusive: false,
                };
                let err = t_out
                    .iter()
                    .zip(&out)
                    .map(|(&t, &x)| (x - exact.exact(t)).abs())
                    .fold(0.0, f64::max);
                (err, stats)
            };
            let (err_with, stats_with) = run(&breakpoints);
            let (err_without, stats_without) = run(&[]);
            // With breakpoints the segments are smooth, so no step is rejected
            // at a jump and the error is at the tolerance's level.
            assert!(err_with < 1e-8, "{method:?}: {err_with}");
            // Without them the error control has to find each jump by
            // rejecting steps: more attempts, and a larger error.
            let attempts = |s: OdeStats| s.steps + s.rejected;
            assert!(
                attempts(stats_without) > attempts(stats_with),
                "{method:?}: {stats_without:?} vs {stats_with:?}"
            );
            assert!(
                err_without > err_with,
                "{method:?}: {err_without} vs {err_with}"
            );
        }
    }

    #[test]
    fn breakpoints_outside_the_interval_are_ignored() {
        let t_out = [0.0, 1.0];
        for method in METHODS {
            let mut plain = [0.0; 2];
            let mut with = [0.0; 2];
            let sys = || Decay { lambda: -2.0 };
            let a = solve(
                &mut sys(),
                method,
                0.0,
                &[1.0],
                &t_out,
                &[],
                &tight(),
                &mut plain,
            )
            .unwrap();
            let b = solve(
                &mut sys(),
                method,
                0.0,
                &[1.0],
                &t_out,
                &[-1.0, 0.0, 1.0, 1.0, 2.0],
                &tight(),
                &mut with,
            )
            .unwrap();
            assert_eq!(plain, with);
            assert_eq!(a, b);
        }
    }

    #[test]
    fn duplicate_and_close_breakpoints_are_handled() {
        let bps = [0.5, 0.5, 0.5 + 1e-16, 0.5f64.next_up(), 0.7];
        let t_out = [0.5, 1.0];
        for method in METHODS {
            let mut out = [0.0; 2];
            solve(
                &mut Decay { lambda: -2.0 },
                method,
                0.0,
                &[1.0],
                &t_out,
                &bps,
                &tight(),
                &mut out,
            )
            .unwrap();
            // Same global-error budget as the decay test.
            assert!((out[0] - (-1.0f64).exp()).abs() < 1e-8, "{method:?}");
            assert!((out[1] - (-2.0f64).exp()).abs() < 1e-8, "{method:?}");
        }
    }

    #[test]
    fn nan_rhs_reports_its_component() {
        /// Component 1 of the derivative is NaN from the start.
        struct NanRhs;
        impl OdeSystem for NanRhs {
            fn dim(&self) -> usize {
                3
            }
            fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
                dx[0] = -x[0];
                dx[1] = f64::NAN;
                dx[2] = 0.0;
            }
        }
        for method in METHODS {
            let mut out = [0.0; 6];
            let err = solve(
                &mut NanRhs,
                method,
                0.0,
                &[1.0, 1.0, 1.0],
                &[0.0, 1.0],
                &[],
                &OdeOptions::default(),
                &mut out,
            )
            .unwrap_err();
            assert_eq!(
                err,
                OdeError::NonFinite {
                    t: 0.0,
                    component: 1
                },
                "{method:?}"
            );
        }
    }

    #[test]
    fn state_leaving_the_domain_reports_non_finite_near_that_time() {
        /// x0 decays as e^{-t}; x1' = sqrt(x0 - e^{-1}) is NaN once x0 < e^{-1}, at t = 1 s.
        struct Sqrt;
        impl OdeSystem for Sqrt {
            fn dim(&self) -> usize {
                2
            }
            fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
                dx[0] = -x[0];
                dx[1] = (x[0] - (-1.0f64).exp()).sqrt();
            }
        }
        for method in METHODS {
            let mut out = [0.0; 4];
            let err = solve(
                &mut Sqrt,
                method,
                0.0,
                &[1.0, 0.0],
                &[0.0, 2.0],
                &[],
                &OdeOptions::default(),
                &mut out,
            )
            .unwrap_err();
            match err {
                OdeError::NonFinite { t, component } => {
                    assert_eq!(component, 1, "{method:?}");
                    // The solver closes in on the boundary until the step
                    // underflows; the state's own error (rtol 1e-6) decides
                    // how close x0 gets to e^{-1}, hence 1e-3 in time.
                    assert!((t - 1.0).abs() < 1e-3, "{method:?}: t = {t}");
                }
                other => panic!("{method:?}: {other:?}"),
            }
        }
    }

    #[test]
    fn unsorted_t_out_is_bad_input() {
        let mut out = [0.0; 3];
        let err = solve(
            &mut Decay { lambda: -1.0 },
            Method::Dopri5,
            0.0,
            &[1.0],
            &[0.0, 2.0, 1.0],
            &[],
            &OdeOptions::default(),
            &mut out,
        )
        .unwrap_err();
        assert!(
            matches!(&err, OdeError::BadInput(m) if m.contains("t_out[2]")),
            "{err}"
        );
    }

    #[test]
    fn inconsistent_inputs_are_bad_input() {
        let opts = OdeOptions::default();
        let mut sys = Decay { lambda: -1.0 };
        /// t0, x0, t_out, breakpoints, out length, options.
        type Case<'a> = (f64, &'a [f64], &'a [f64], &'a [f64], usize, OdeOptions);
        let cases: [Case; 8] = [
            (0.0, &[1.0, 2.0], &[1.0], &[], 1, opts.clone()), // x0 length
            (0.0, &[f64::NAN], &[1.0], &[], 1, opts.clone()), // x0 finite
            (0.0, &[1.0], &[-1.0], &[], 1, opts.clone()),     // before t0
            (0.0, &[1.0], &[1.0], &[], 2, opts.clone()),      // out length
            (0.0, &[1.0], &[1.0], &[0.5, 0.2], 1, opts.clone()), // breakpoints order
            (f64::NAN, &[1.0], &[1.0], &[], 1, opts.clone()), // t0 finite
            (
                0.0,
                &[1.0],
                &[1.0],
                &[],
                1,
                OdeOptions {
                    atol: 0.0,
                    ..opts.clone()
                },
            ),
            (
                0.0,
                &[1.0],
                &[1.0],
                &[],
                1,
                OdeOptions {
                    max_step: f64::NAN,
                    ..opts.clone()
                },
            ),
        ];
        for (t0, x0, t_out, bps, out_len, o) in cases {
            let mut out = vec![0.0; out_len];
            let r = solve(&mut sys, Method::Dopri5, t0, x0, t_out, bps, &o, &mut out);
            assert!(matches!(r, Err(OdeError::BadInput(_))), "{r:?}");
        }
    }

    #[test]
    fn step_budget_is_enforced() {
        let opts = OdeOptions {
            max_steps: 5,
            ..OdeOptions::default()
        };
        for method in METHODS {
            let mut out = [0.0; 4];
            let err = solve(
                &mut DcMotor,
                method,
                0.0,
                &[0.0, 0.0],
                &[0.0, 4.0],
                &[],
                &opts,
                &mut out,
            )
            .unwrap_err();
            assert!(
                matches!(err, OdeError::TooManySteps { max_steps: 5, t } if t > 0.0 && t < 4.0),
                "{method:?}: {err:?}"
            );
        }
    }

    #[test]
    fn max_step_bounds_every_step() {
        let mut out = [0.0; 2];
        let opts = OdeOptions {
            max_step: 0.01,
            ..OdeOptions::default()
        };
        for method in METHODS {
            let stats = solve(
                &mut Decay { lambda: -1.0 },
                method,
                0.0,
                &[1.0],
                &[0.0, 1.0],
                &[],
                &opts,
                &mut out,
            )
            .unwrap();
            // 1 s in steps of at most 0.01 s (the last may stretch by 1 %).
            assert!(stats.steps >= 99, "{method:?}: {stats:?}");
        }
    }
}

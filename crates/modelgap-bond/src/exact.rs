//! Exact integration of models that are affine in their states.
//!
//! `ẋ = A x + b(u)`, `y = C x + d(u)`: over an interval of length `h` on
//! which the forcing is constant or linear in time, the state moves exactly
//! by `x⁺ = Φ x + Γ0 w0 + Γ1 (w1 − w0)` with `Φ = e^{A h}`, `Γ0 = ∫₀ʰ e^{A s} ds`
//! and `Γ1` the first-order-hold term, all read from one matrix exponential
//! (Van Loan's block trick) and cached per interval length.
//!
//! - An LTI model (`b(u) = B u + c`) takes any drive: sample times of
//!   sampled inputs and PWM edges are on the grid, a linear-hold input is
//!   exactly linear between them, a zero-order hold or PWM exactly constant.
//! - A state-affine model whose inputs enter nonlinearly (a switch's
//!   `m · Vs`) takes piecewise-constant drives: `b(u)` is evaluated once per
//!   interval and held.
//!
//! The stepping loop is flat: no allocation, no tape evaluation for LTI
//! models (outputs come from `C`, `D` too).

#![allow(clippy::needless_range_loop)] // row-major matrix arithmetic reads best with indices

use nalgebra::DMatrix;

use crate::compiled::CompiledModel;
use crate::error::{BondError, Result};
use crate::ode::OdeStats;
use crate::simulate::{CUBIC_PIECES, Drive, Hold};

/// `ẋ = A x + B u + c`, `y = C x + D u + e`, read off the tape with unit
/// vectors (exact, since the tape is affine). For a state-affine model that
/// is not LTI, `B`, `c`, `D`, `e` are those at `u = 0` and only `A`, `C` are
/// meaningful.
pub struct Affine {
    /// Number of states.
    pub n: usize,
    /// Number of inputs.
    pub m: usize,
    /// Number of outputs.
    pub p: usize,
    /// A, row-major n × n.
    pub a: Vec<f64>,
    /// B, row-major n × m.
    pub b: Vec<f64>,
    /// c, n.
    pub c: Vec<f64>,
    /// C, row-major p × n.
    pub cy: Vec<f64>,
    /// D, row-major p × m.
    pub dy: Vec<f64>,
    /// e, p.
    pub ey: Vec<f64>,
}

impl Affine {
    /// Reads the matrices of a state-affine compiled model.
    pub fn of(model: &CompiledModel) -> Affine {
        let (n, m, p) = (model.n_states(), model.n_inputs(), model.n_outputs());
        let mut scratch = model.scratch();
        let (mut dx, mut y) = (vec![0.0; n], vec![0.0; p]);
        let mut eval = |x: &[f64], u: &[f64], dx: &mut [f64], y: &mut [f64]| {
            model.eval(0.0, x, u, &mut scratch);
            model.read_derivatives(&scratch, dx);
            model.read_outputs(&scratch, y);
        };
        let (mut x, mut u) = (vec![0.0; n], vec![0.0; m]);
        let (mut c, mut ey) = (vec![0.0; n], vec![0.0; p]);
        eval(&x, &u, &mut c, &mut ey);
        let (mut a, mut b) = (vec![0.0; n * n], vec![0.0; n * m]);
        let (mut cy, mut dy) = (vec![0.0; p * n], vec![0.0; p * m]);
        for j in 0..n {
            x[j] = 1.0;
            eval(&x, &u, &mut dx, &mut y);
            x[j] = 0.0;
            for i in 0..n {
                a[i * n + j] = dx[i] - c[i];
            }
            for i in 0..p {
                cy[i * n + j] = y[i] - ey[i];
            }
        }
        for j in 0..m {
            u[j] = 1.0;
            eval(&x, &u, &mut dx, &mut y);
            u[j] = 0.0;
            for i in 0..n {
                b[i * m + j] = dx[i] - c[i];
            }
            for i in 0..p {
                dy[i * m + j] = y[i] - ey[i];
            }
        }
        Affine {
            n,
            m,
            p,
            a,
            b,
            c,
            cy,
            dy,
            ey,
        }
    }

    /// A as an nalgebra matrix.
    pub fn a_matrix(&self) -> DMatrix<f64> {
        DMatrix::from_row_slice(self.n, self.n, &self.a)
    }
}

/// Interval lengths within this relative difference share one
/// discretisation: times on a uniform grid (`k / rate`) differ in their last
/// bits, and a relative step error of 1e-9 moves the state by about
/// `‖A‖ h · 1e-9`, far below any measurement.
const SAME_STEP: f64 = 1e-9;

/// `Φ`, `Γ0`, `Γ1` over one interval, row-major, for a forcing of `q` columns.
struct Step {
    h: f64,
    phi: Vec<f64>,
    gamma0: Vec<f64>,
    gamma1: Vec<f64>,
}

/// Above this 1-norm, the matrix exponential is taken of a copy scaled down
/// by a power of two and squared back here. nalgebra's own scaling reads
/// `‖M⁶‖`, `‖M⁸‖`, `‖M¹⁰‖`: past a norm of about 1e30 they overflow, its
/// squaring count becomes `inf as u64` and the call never returns (issue
/// 11: `--set k=1e60`). Below it, nalgebra's path is kept bit for bit.
const MAX_EXP_NORM: f64 = 1e20;

/// `e^M`, also for a matrix of huge or non-finite norm (NaN then, which the
/// caller reports as a state that is not finite).
fn expm(m: DMatrix<f64>) -> DMatrix<f64> {
    let norm = (0..m.ncols())
        .map(|j| m.column(j).iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max);
    if !norm.is_finite() {
        return DMatrix::from_element(m.nrows(), m.ncols(), f64::NAN);
    }
    if norm <= MAX_EXP_NORM {
        return m.exp();
    }
    // At most ~1030 squarings for a finite norm.
    let s = (norm / MAX_EXP_NORM).log2().ceil() as i32;
    let mut e = (m * 2.0_f64.powi(-s)).exp();
    for _ in 0..s {
        e = &e * &e;
    }
    e
}

/// Van Loan: `exp([[A h, I h, 0], [0, 0, I], [0, 0, 0]])` holds `Φ`, `Γ0`
/// (times the forcing `w`) and `Γ1` (times its change over the interval).
fn discretise(a: &DMatrix<f64>, h: f64) -> Step {
    let n = a.nrows();
    let mut big = DMatrix::zeros(3 * n, 3 * n);
    big.view_mut((0, 0), (n, n)).copy_from(&(a * h));
    for i in 0..n {
        big[(i, n + i)] = h;
        big[(n + i, 2 * n + i)] = 1.0;
    }
    let e = expm(big);
    let rows = |c0: usize| -> Vec<f64> {
        let mut v = Vec::with_capacity(n * n);
        for i in 0..n {
            for j in 0..n {
                v.push(e[(i, c0 + j)]);
            }
        }
        v
    };
    Step {
        h,
        phi: rows(0),
        gamma0: rows(n),
        gamma1: rows(2 * n),
    }
}

/// The merge of the sorted output times `a` and extra grid points `b` from
/// `t0` on; extra points that nearly repeat the last point are dropped.
struct Merge<'a> {
    a: &'a [f64],
    b: &'a [f64],
    i: usize,
    j: usize,
    last: f64,
    t0: f64,
}

impl Iterator for Merge<'_> {
    type Item = f64;

    #[inline]
    fn next(&mut self) -> Option<f64> {
        loop {
            // Output times are always yielded (each needs its row); an extra
            // point close to the last point is dropped.
            let (next, output) = match (self.a.get(self.i), self.b.get(self.j)) {
                (Some(&x), Some(&y)) if x <= y => {
                    self.i += 1;
                    (x, true)
                }
                (_, Some(&y)) => {
                    self.j += 1;
                    (y, false)
                }
                (Some(&x), None) => {
                    self.i += 1;
                    (x, true)
                }
                (None, None) => return None,
            };
            let fresh = if output {
                next > self.last
            } else {
                (next - self.last).abs() > 1e-12 * next.abs().max(1.0)
            };
            if next >= self.t0 && fresh {
                self.last = next;
                return Some(next);
            }
        }
    }
}

/// Piecewise-constant drives (and constants): `b(u)` may then be held per interval.
pub fn piecewise_constant(drives: &[Drive]) -> bool {
    drives.iter().all(|d| {
        matches!(
            d,
            Drive::Constant(_)
                | Drive::Pwm { .. }
                | Drive::Sampled {
                    hold: Hold::Zero,
                    ..
                }
        )
    })
}

/// Integrates exactly from `t0`; returns the states at the output times,
/// one `Vec` per state.
///
/// # Errors
/// [`BondError::BadOptions`] if the model is not state-affine, or is not LTI
/// and a drive is not piecewise constant; [`BondError::NonFiniteState`] for a
/// state that stops being finite (an unstable model run far).
pub fn integrate(
    model: &CompiledModel,
    drives: &[Drive],
    t0: f64,
    x0: &[f64],
    t_out: &[f64],
) -> Result<(Vec<Vec<f64>>, OdeStats)> {
    if !(model.is_lti || model.is_state_affine && piecewise_constant(drives)) {
        return Err(BondError::BadOptions(
            "the exact solver needs a model affine in its states (no nonlinear law) and, unless it is linear in its inputs too, piecewise-constant inputs (constant, PWM, zero-order hold)".to_string(),
        ));
    }
    let lti = model.is_lti;
    let aff = Affine::of(model);
    let (n, m) = (aff.n, aff.m);
    let a = aff.a_matrix();
    // The grid: output times, input sample times, PWM edges.
    let t_end = *t_out.last().unwrap_or(&t0);
    let mut extra: Vec<f64> = Vec::new();
    let mut linear = vec![false; m];
    for (j, d) in drives.iter().enumerate() {
        match d {
            Drive::Sampled {
                t,
                hold: Hold::Linear,
                ..
            } => {
                extra.extend(t.iter().copied().filter(|&x| x > t0 && x < t_end));
                linear[j] = true;
            }
            // A cubic followed by straight lines over quarters of each interval.
            Drive::Sampled {
                t,
                hold: Hold::Cubic,
                ..
            } => {
                for w in t.windows(2) {
                    let step = (w[1] - w[0]) / CUBIC_PIECES as f64;
                    extra.extend(
                        (0..CUBIC_PIECES)
                            .map(|k| w[0] + k as f64 * step)
                            .filter(|&x| x > t0 && x < t_end),
                    );
                }
                if let Some(&last) = t.last().filter(|&&x| x > t0 && x < t_end) {
                    extra.push(last);
                }
                linear[j] = true;
            }
            Drive::Sampled {
                hold: Hold::Zero, ..
            }
            | Drive::Pwm { .. } => d.breakpoints(t0, t_end, &mut extra),
            Drive::Constant(_) => {}
        }
    }
    extra.push(t0);
    extra.sort_by(f64::total_cmp);
    // The grid is the merge of the (sorted) output times and these, walked
    // without building it: most runs have no extra points at all.
    let mut merge = Merge {
        a: t_out,
        b: &extra,
        i: 0,
        j: 0,
        last: f64::NEG_INFINITY,
        t0,
    };
    let mut cache: Vec<Step> = Vec::new();
    let mut scratch = model.scratch();
    let mut cursors = vec![0usize; m];
    let all_constant = drives.iter().all(|d| matches!(d, Drive::Constant(_)));
    let mut u = vec![0.0; m];
    let mut u_next = vec![0.0; m];
    let mut x = x0.to_vec();
    let mut x_next = vec![0.0; n];
    let mut w0 = vec![0.0; n];
    let mut dw = vec![0.0; n];
    let zero_x = vec![0.0; n];
    let mut k_out = 0;
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(1.0);
    // Forcing b(u) at the start of an interval (held) or, for an LTI model
    // with linear-hold inputs, B u + c at both ends.
    let forcing = |u: &[f64], out: &mut [f64], scratch: &mut [f64]| {
        if lti {
            for i in 0..n {
                let mut v = aff.c[i];
                for j in 0..m {
                    v += aff.b[i * m + j] * u[j];
                }
                out[i] = v;
            }
        } else {
            model.eval(0.0, &zero_x, u, scratch);
            model.read_derivatives(scratch, out);
        }
    };
    // States at the output times, row by row; outputs are computed after
    // the loop (from C, D for an LTI model, with the tape otherwise).
    let mut columns: Vec<Vec<f64>> = (0..n).map(|_| Vec::with_capacity(t_out.len())).collect();
    let mut t = merge.next().unwrap_or(t0);
    for (j, d) in drives.iter().enumerate() {
        u[j] = d.value(t, &mut cursors[j]);
    }
    if k_out < t_out.len() && close(t, t_out[k_out]) {
        for (column, v) in columns.iter_mut().zip(&x) {
            column.push(*v);
        }
        k_out += 1;
    }
    let any_linear = linear.iter().any(|l| *l);
    // The forcing's contribution Γ0 w0 (+ Γ1 Δw) is recomputed only when the
    // inputs or the interval length change: a constant input over a uniform
    // grid costs one matrix–vector product per step.
    let mut g = vec![0.0; n];
    let mut last_idx = usize::MAX;
    let mut dirty = true;
    let mut steps = 0;
    // Fast path: constant inputs on a uniform output grid from t0 — one
    // discretisation, and each step is `x ← Φ x + g`.
    let h0 = t_out.get(1).map_or(0.0, |t1| t1 - t_out[0]);
    let uniform = all_constant
        && extra.len() == 1
        && t_out.len() > 2
        && close(t0, t_out[0])
        && h0 > 0.0
        && t_out
            .windows(2)
            .all(|w| ((w[1] - w[0]) - h0).abs() <= SAME_STEP * h0);
    if uniform {
        let step = discretise(&a, h0);
        forcing(&u, &mut w0, &mut scratch);
        for i in 0..n {
            g[i] = step.gamma0[i * n..(i + 1) * n]
                .iter()
                .zip(&w0)
                .map(|(a, b)| a * b)
                .sum();
        }
        for _ in 1..t_out.len() {
            for i in 0..n {
                let row = &step.phi[i * n..(i + 1) * n];
                x_next[i] = g[i] + row.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>();
            }
            std::mem::swap(&mut x, &mut x_next);
            for (column, v) in columns.iter_mut().zip(&x) {
                column.push(*v);
            }
        }
        steps = t_out.len() - 1;
        merge.i = t_out.len();
        merge.j = extra.len();
    }
    for t_next in merge {
        let h = t_next - t;
        let idx = if last_idx < cache.len() && (cache[last_idx].h - h).abs() <= SAME_STEP * h {
            last_idx
        } else {
            match cache.iter().position(|s| (s.h - h).abs() <= SAME_STEP * h) {
                Some(i) => i,
                None => {
                    cache.push(discretise(&a, h));
                    cache.len() - 1
                }
            }
        };
        // Inputs over the interval: their value at its start (right-continuous
        // for held inputs); linear-hold inputs also at its end.
        if !all_constant {
            for (j, d) in drives.iter().enumerate() {
                let v = d.value(t, &mut cursors[j]);
                if v != u[j] {
                    u[j] = v;
                    dirty = true;
                }
            }
        }
        if dirty || any_linear || idx != last_idx {
            let step = &cache[idx];
            forcing(&u, &mut w0, &mut scratch);
            if any_linear {
                for (j, d) in drives.iter().enumerate() {
                    u_next[j] = if linear[j] {
                        d.value(t_next, &mut cursors[j])
                    } else {
                        u[j]
                    };
                }
                forcing(&u_next, &mut dw, &mut scratch);
                for i in 0..n {
                    dw[i] -= w0[i];
                }
            }
            for i in 0..n {
                let row = i * n;
                let mut v = 0.0;
                for j in 0..n {
                    v += step.gamma0[row + j] * w0[j];
                }
                if any_linear {
                    for j in 0..n {
                        v += step.gamma1[row + j] * dw[j];
                    }
                }
                g[i] = v;
            }
            dirty = false;
            last_idx = idx;
        }
        let phi = &cache[idx].phi;
        for i in 0..n {
            let row = &phi[i * n..(i + 1) * n];
            let mut v = g[i];
            for (pj, xj) in row.iter().zip(&x) {
                v += pj * xj;
            }
            x_next[i] = v;
        }
        std::mem::swap(&mut x, &mut x_next);
        steps += 1;
        t = t_next;
        if k_out < t_out.len() && close(t, t_out[k_out]) {
            for (column, v) in columns.iter_mut().zip(&x) {
                column.push(*v);
            }
            k_out += 1;
        }
    }
    if columns.iter().any(|c| c.len() != t_out.len()) {
        return Err(BondError::BadOptions(format!(
            "output times could not all be reached (got {} of {}); they must be strictly increasing from the start time",
            columns.first().map_or(0, Vec::len),
            t_out.len()
        )));
    }
    for (i, column) in columns.iter().enumerate() {
        if let Some(k) = column.iter().position(|v| !v.is_finite()) {
            return Err(model.non_finite_state(i, t_out[k]));
        }
    }
    Ok((
        columns,
        OdeStats {
            steps,
            ..OdeStats::default()
        },
    ))
}

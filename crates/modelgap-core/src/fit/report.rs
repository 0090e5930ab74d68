//! The outcome of a fit ([`FitReport`], [`Termination`]) and the parameter uncertainty
//! computed from the Jacobian at the solution.

use std::fmt;

use crate::math::DMatrix;

/// Why a fit stopped. Every outcome leaves a usable [`FitReport`]: the best point found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Termination {
    /// A tolerance of [`super::FitOptions`] was met: the gradient is orthogonal to the
    /// residual (`gtol`), the cost stopped falling (`ftol`), the step became shorter than
    /// `xtol` scales, the residual is exactly zero, or every parameter sits on a bound that
    /// the gradient pushes against.
    Converged,
    /// `max_iterations` steps were taken without meeting a tolerance.
    MaxIterations,
    /// The fit could not go on: trial points kept failing (errors or non-finite residuals)
    /// until the damping shrank the step below `xtol`, the damping ran away, or a tolerance
    /// was met while the Jacobian at the final point lacked a column (the residuals failed
    /// on both sides of a parameter), so the point is not known to be stationary.
    Stalled,
    /// The [`super::Cancel`] flag was set.
    Cancelled,
}

impl fmt::Display for Termination {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Termination::Converged => "converged",
            Termination::MaxIterations => "max-iterations",
            Termination::Stalled => "stalled",
            Termination::Cancelled => "cancelled",
        })
    }
}

/// The result of [`super::fit`]: the best parameters found, their uncertainty, and how the
/// fit went.
///
/// No field holds NaN. A standard error of `f64::INFINITY` means "not determined by the
/// data": the parameter is pinned at a bound (its gradient pushes outward), it does not
/// change the residuals, it moves with other parameters in a direction the residuals cannot
/// see, there are no more residuals than free parameters, or the fit was cancelled before a
/// Jacobian at the returned point existed. (JSON, via `serde_json`, writes infinity as
/// `null`.)
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FitReport {
    /// The best parameters found, in the problem's order and units.
    pub params: Vec<f64>,
    /// One standard error per parameter, in its unit, assuming white residuals:
    /// sqrt(diag((JᵀJ)⁻¹) · s²) with s² = 2·cost_after / (m − n_free).
    /// `f64::INFINITY` when not determined (see the type's docs).
    pub std_errors: Vec<f64>,
    /// ½Σr² at the start point (after moving it into the bounds).
    pub cost_before: f64,
    /// ½Σr² at [`Self::params`].
    pub cost_after: f64,
    /// The number of accepted steps.
    pub iterations: usize,
    /// The number of residual evaluations, finite differences and failed trials included.
    pub evaluations: usize,
    /// Why the fit stopped.
    pub termination: Termination,
    /// Correlation matrix of the parameters (n × n, from the same (JᵀJ)⁻¹ as the standard
    /// errors). A parameter with an infinite standard error has 1 on the diagonal and 0
    /// elsewhere in its row and column.
    pub correlation: Vec<Vec<f64>>,
    /// One standard error per parameter that holds when the residuals are correlated in
    /// time (coloured noise, or a model error the fit leaves): the sandwich
    /// `(JᵀJ)⁻¹ S (JᵀJ)⁻¹`, `S` the long-run covariance of the fit's score `J_tᵀ r_t`
    /// over time (Newey–West weights, bandwidth by Andrews' AR(1) rule; see
    /// [`super::ResidualProblem::series_length`] for how rows map to times).
    /// `f64::INFINITY` where [`Self::std_errors`] is.
    pub robust_std_errors: Vec<f64>,
    /// The bandwidth (in samples) the robust standard errors summed correlations over.
    pub robust_lags: usize,
}

impl FitReport {
    /// Standard errors rescaled for correlated residuals: each multiplied by
    /// sqrt(n / n_eff), where `n` is the number of residuals and `n_eff` their effective
    /// sample size (see [`crate::residual::effective_sample_size`]).
    ///
    /// Infinite standard errors stay infinite; an `n_eff` that is not a positive finite
    /// number makes every standard error infinite.
    pub fn scaled_std_errors(&self, n_eff: f64, n: usize) -> Vec<f64> {
        let factor = if n_eff > 0.0 && n_eff.is_finite() {
            (n as f64 / n_eff).sqrt()
        } else {
            f64::INFINITY
        };
        self.std_errors
            .iter()
            .map(|&se| {
                if se.is_infinite() || factor.is_infinite() {
                    f64::INFINITY
                } else {
                    se * factor
                }
            })
            .collect()
    }
}

/// An eigenvalue of the equilibrated normal matrix (unit diagonal) below this fraction of
/// the largest marks a direction the residuals cannot see: its variance would be inflated
/// by more than 10¹⁰, far beyond what a finite-difference Jacobian (relative error ~10⁻⁶)
/// resolves.
const COV_RCOND: f64 = 1e-10;

/// A parameter whose component in such a null direction is at least this fraction of the
/// direction's largest component is declared undetermined.
const NULL_COMPONENT: f64 = 0.1;

/// Standard errors and correlations from the normal matrix at the solution.
///
/// `jtj` is JᵀJ in scaled variables z = x / scale (n × n, row-major); `free` marks the
/// parameters that are not pinned at a bound; `m` is the number of residuals.
pub(super) fn uncertainty(
    jtj: &[f64],
    free: &[bool],
    scales: &[f64],
    cost: f64,
    m: usize,
) -> (Vec<f64>, Vec<Vec<f64>>) {
    let n = free.len();
    debug_assert_eq!(jtj.len(), n * n);
    let mut std_errors = vec![f64::INFINITY; n];
    let mut correlation: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
        .collect();

    let n_free = free.iter().filter(|&&f| f).count();
    let s2 = if m > n_free {
        2.0 * cost / (m - n_free) as f64
    } else {
        f64::INFINITY
    };

    // Equilibrate: B = D⁻¹ A D⁻¹ with D = sqrt(diag A), so B has a unit diagonal and its
    // conditioning reflects correlation, not units.
    let diag = |i: usize| jtj[i * n + i];
    let mut set: Vec<usize> = (0..n)
        .filter(|&i| free[i] && diag(i) > 0.0 && diag(i).is_finite())
        .collect();
    let equilibrated = |set: &[usize]| {
        DMatrix::from_fn(set.len(), set.len(), |a, b| {
            let (i, j) = (set[a], set[b]);
            jtj[i * n + j] / (diag(i).sqrt() * diag(j).sqrt())
        })
    };
    // Drop the parameters that span numerically singular directions, until none is left.
    while !set.is_empty() {
        let eigen = equilibrated(&set).symmetric_eigen();
        let largest = eigen.eigenvalues.iter().copied().fold(0.0, f64::max);
        let mut drop = vec![false; set.len()];
        for (k, &lambda) in eigen.eigenvalues.iter().enumerate() {
            if lambda.is_finite() && lambda > COV_RCOND * largest {
                continue;
            }
            let v = eigen.eigenvectors.column(k);
            let top = v.iter().fold(0.0_f64, |acc, c| acc.max(c.abs()));
            for (a, c) in v.iter().enumerate() {
                if c.abs() >= NULL_COMPONENT * top {
                    drop[a] = true;
                }
            }
        }
        if !drop.contains(&true) {
            break;
        }
        set = set
            .iter()
            .zip(&drop)
            .filter(|&(_, &d)| !d)
            .map(|(&i, _)| i)
            .collect();
    }
    if set.is_empty() {
        return (std_errors, correlation);
    }

    let b = equilibrated(&set);
    let inverse = match b.clone().cholesky() {
        Some(chol) => Some(chol.inverse()),
        None => b.try_inverse(),
    };
    let Some(inverse) = inverse else {
        return (std_errors, correlation);
    };
    if (0..set.len()).any(|a| !(inverse[(a, a)] > 0.0 && inverse[(a, a)].is_finite())) {
        return (std_errors, correlation);
    }

    for (a, &i) in set.iter().enumerate() {
        // Var(x_i) = scale_i² · [A⁻¹]_ii · s², and [A⁻¹]_ii = [B⁻¹]_ii / A_ii.
        let variance = scales[i] * scales[i] * inverse[(a, a)] / diag(i) * s2;
        std_errors[i] = variance.sqrt();
        for (b_idx, &j) in set.iter().enumerate().skip(a + 1) {
            let r = inverse[(a, b_idx)] / (inverse[(a, a)].sqrt() * inverse[(b_idx, b_idx)].sqrt());
            // One value for both halves: the matrix is symmetric to the bit.
            correlation[i][j] = r.clamp(-1.0, 1.0);
            correlation[j][i] = correlation[i][j];
        }
    }
    (std_errors, correlation)
}

/// Longest bandwidth of the robust standard errors (samples), and the largest
/// share of a series it may span.
const MAX_LAGS: usize = 2000;
/// Largest AR(1) coefficient of a score the bandwidth rule takes.
const MAX_SCORE_RHO: f64 = 0.98;

/// Standard errors robust to residuals correlated in time, and the bandwidth
/// used: the sandwich `(JᵀJ)⁻¹ S (JᵀJ)⁻¹` over the parameters whose white
/// standard error is finite (`white`). `jac` is J in scaled variables
/// (column `i` at `i·m..(i+1)·m`), `r` the residuals, `series` the length of
/// each time series the rows hold one after the other (rows past the last
/// whole series are independent). `S = Γ₀ + Σ_{l=1}^{L} (1 − l/(L+1))(Γ_l +
/// Γ_lᵀ)`, `Γ_l = Σ_t g_t g_{t−l}ᵀ` with `g_t` the score at time `t` summed
/// over the series; `L` from Andrews' (1991) AR(1) plug-in rule on each
/// score component, `1.1447 (α T)^{1/3}`. The small-sample factor
/// `m/(m − k)` is applied.
pub(super) fn robust_uncertainty(
    jac: &[f64],
    r: &[f64],
    white: &[f64],
    scales: &[f64],
    series: Option<usize>,
) -> (Vec<f64>, usize) {
    let n = white.len();
    let m = r.len();
    let mut out = vec![f64::INFINITY; n];
    let set: Vec<usize> = (0..n).filter(|&i| white[i].is_finite()).collect();
    let k = set.len();
    if k == 0 || m <= k || jac.len() != n * m {
        return (out, 0);
    }
    let t_len = series.filter(|&t| t > 0 && t <= m).unwrap_or(m);
    let n_series = m / t_len;
    let col = |i: usize| &jac[i * m..(i + 1) * m];
    // The score at each time, summed over the series.
    let mut g = vec![0.0; t_len * k];
    for (a, &i) in set.iter().enumerate() {
        let c = col(i);
        for s in 0..n_series {
            for t in 0..t_len {
                g[t * k + a] += c[s * t_len + t] * r[s * t_len + t];
            }
        }
    }
    // Independent rows past the series (priors).
    let extra: Vec<Vec<f64>> = (n_series * t_len..m)
        .map(|row| set.iter().map(|&i| col(i)[row] * r[row]).collect())
        .collect();
    // Andrews' bandwidth from each score component's AR(1) fit.
    let (mut num, mut den) = (0.0, 0.0);
    for a in 0..k {
        let (mut c0, mut c1) = (0.0, 0.0);
        for t in 0..t_len {
            c0 += g[t * k + a] * g[t * k + a];
            if t > 0 {
                c1 += g[t * k + a] * g[(t - 1) * k + a];
            }
        }
        if c0 <= 0.0 {
            continue;
        }
        let rho = (c1 / c0).clamp(-MAX_SCORE_RHO, MAX_SCORE_RHO);
        let s4 = (c0 / t_len as f64 * (1.0 - rho * rho)).powi(2);
        num += 4.0 * rho * rho * s4 / ((1.0 - rho).powi(6) * (1.0 + rho).powi(2));
        den += s4 / (1.0 - rho).powi(4);
    }
    let alpha = if den > 0.0 { num / den } else { 0.0 };
    let lags = ((1.1447 * (alpha * t_len as f64).cbrt()).ceil() as usize)
        .min(MAX_LAGS)
        .min(t_len / 4);
    // Each lag's Γ_l summed flat (k × k, row-major), weighted into S with its transpose.
    let mut s_flat = vec![0.0; k * k];
    let mut gamma = vec![0.0; k * k];
    for l in 0..=lags {
        gamma.fill(0.0);
        for (gt, gl) in g.chunks_exact(k).skip(l).zip(g.chunks_exact(k)) {
            for (row, &x) in gamma.chunks_exact_mut(k).zip(gt) {
                for (cell, &y) in row.iter_mut().zip(gl) {
                    *cell += x * y;
                }
            }
        }
        let w = 1.0 - l as f64 / (lags as f64 + 1.0);
        for a in 0..k {
            for b in 0..k {
                s_flat[a * k + b] += w * gamma[a * k + b];
                if l > 0 {
                    s_flat[b * k + a] += w * gamma[a * k + b];
                }
            }
        }
    }
    let mut sm = DMatrix::from_row_slice(k, k, &s_flat);
    for e in &extra {
        for a in 0..k {
            for b in 0..k {
                sm[(a, b)] += e[a] * e[b];
            }
        }
    }
    // (JᵀJ)⁻¹ on the set, equilibrated for the inversion.
    let jtj = DMatrix::from_fn(k, k, |a, b| {
        let (ca, cb) = (col(set[a]), col(set[b]));
        ca.iter().zip(cb).map(|(x, y)| x * y).sum::<f64>()
    });
    let d: Vec<f64> = (0..k).map(|a| jtj[(a, a)].sqrt()).collect();
    if d.iter().any(|v| !(*v > 0.0 && v.is_finite())) {
        return (out, lags);
    }
    let eq = DMatrix::from_fn(k, k, |a, b| jtj[(a, b)] / (d[a] * d[b]));
    let Some(inv) = eq.cholesky().map(|c| c.inverse()) else {
        return (out, lags);
    };
    let inv = DMatrix::from_fn(k, k, |a, b| inv[(a, b)] / (d[a] * d[b]));
    let cov = &inv * sm * &inv;
    let small = m as f64 / (m - k) as f64;
    for (a, &i) in set.iter().enumerate() {
        let v = cov[(a, a)] * small;
        if v.is_finite() && v >= 0.0 {
            out[i] = scales[i] * v.sqrt();
        }
    }
    (out, lags)
}

#[cfg(test)]
mod tests {
    use approx::assert_relative_eq;

    use super::*;

    fn report(std_errors: Vec<f64>) -> FitReport {
        let n = std_errors.len();
        FitReport {
            params: vec![0.0; n],
            robust_std_errors: std_errors.clone(),
            robust_lags: 0,
            std_errors,
            cost_before: 1.0,
            cost_after: 0.5,
            iterations: 1,
            evaluations: 3,
            termination: Termination::Converged,
            correlation: vec![vec![0.0; n]; n],
        }
    }

    #[test]
    fn scaled_std_errors_multiply_by_sqrt_of_n_over_n_eff() {
        let r = report(vec![0.1, f64::INFINITY, 0.0]);
        let s = r.scaled_std_errors(25.0, 100);
        // sqrt(100 / 25) = 2 exactly.
        assert_relative_eq!(s[0], 0.2, epsilon = 1e-15);
        assert_eq!(s[1], f64::INFINITY);
        assert_eq!(s[2], 0.0);
    }

    #[test]
    fn scaled_std_errors_with_invalid_n_eff_are_infinite() {
        let r = report(vec![0.1, 0.0]);
        for n_eff in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(
                r.scaled_std_errors(n_eff, 10)
                    .iter()
                    .all(|s| s.is_infinite())
            );
        }
    }

    #[test]
    fn uncertainty_of_independent_parameters_is_diagonal() {
        // J = diag(2, 4) in z; scales 1 and 10; cost 1 with m = 4 → s² = 2/(4-2) = 1.
        let jtj = [4.0, 0.0, 0.0, 16.0];
        let (se, corr) = uncertainty(&jtj, &[true, true], &[1.0, 10.0], 1.0, 4);
        assert_relative_eq!(se[0], 0.5, epsilon = 1e-15);
        assert_relative_eq!(se[1], 10.0 * 0.25, epsilon = 1e-15);
        assert_eq!(corr, vec![vec![1.0, 0.0], vec![0.0, 1.0]]);
    }

    #[test]
    fn uncertainty_marks_perfectly_correlated_parameters_undetermined() {
        // Only a + b matters: JᵀJ = [[1, 1], [1, 1]]; the third parameter is independent.
        let jtj = [1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 2.0];
        let (se, corr) = uncertainty(&jtj, &[true; 3], &[1.0; 3], 1.0, 10);
        assert!(se[0].is_infinite() && se[1].is_infinite());
        assert!(se[2].is_finite() && se[2] > 0.0);
        assert_eq!(corr[0][1], 0.0);
        assert_eq!(corr[0][0], 1.0);
        assert!(corr.iter().flatten().all(|c| c.is_finite()));
    }

    #[test]
    fn uncertainty_of_pinned_or_insensitive_parameter_is_infinite() {
        let jtj = [4.0, 0.0, 0.0, 0.0];
        let (se, _) = uncertainty(&jtj, &[true, true], &[1.0, 1.0], 1.0, 4);
        assert!(se[0].is_finite() && se[1].is_infinite());
        let (se, _) = uncertainty(&jtj, &[false, true], &[1.0, 1.0], 1.0, 4);
        assert!(se[0].is_infinite() && se[1].is_infinite());
    }

    #[test]
    fn uncertainty_without_spare_residuals_is_infinite() {
        let jtj = [4.0];
        let (se, corr) = uncertainty(&jtj, &[true], &[1.0], 0.0, 1);
        assert!(se[0].is_infinite());
        assert_eq!(corr, vec![vec![1.0]]);
    }

    /// A constant fitted to `y` (J = 1): the robust error of the mean against the spread
    /// of many means.
    fn mean_and_errors(y: &[f64]) -> (f64, f64, f64) {
        let m = y.len();
        let mean = y.iter().sum::<f64>() / m as f64;
        let r: Vec<f64> = y.iter().map(|v| mean - v).collect();
        let s2 = r.iter().map(|v| v * v).sum::<f64>() / (m - 1) as f64;
        let white = (s2 / m as f64).sqrt();
        let (robust, _) = robust_uncertainty(&vec![1.0; m], &r, &[white], &[1.0], None);
        (mean, white, robust[0])
    }

    #[test]
    fn robust_errors_match_white_ones_on_white_noise_and_cover_ar1_noise() {
        let mut state = 0x2545_F491_4F6C_DD1D_u64;
        let mut gauss = move || {
            let mut u = || {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
            };
            let (a, b) = (u(), u());
            (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
        };
        let white: Vec<f64> = (0..4000).map(|_| gauss()).collect();
        let (_, w, rob) = mean_and_errors(&white);
        assert!((rob / w - 1.0).abs() < 0.15, "{rob} against {w}");
        // AR(0.9): the mean's true standard error is √((1 + ρ)/(1 − ρ)) = 4.36 times the
        // white formula's; over 200 records the robust one covers the means' spread.
        let (mut means, mut robusts, mut whites) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..200 {
            let mut e = 0.0;
            let y: Vec<f64> = (0..2000)
                .map(|_| {
                    e = 0.9 * e + gauss();
                    e
                })
                .collect();
            let (mean, w, rob) = mean_and_errors(&y);
            means.push(mean);
            robusts.push(rob);
            whites.push(w);
        }
        let spread = (means.iter().map(|m| m * m).sum::<f64>() / means.len() as f64).sqrt();
        let typical = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let (rob, w) = (typical(&robusts), typical(&whites));
        assert!(
            spread / w > 3.5,
            "the white formula must under-state it: {spread} {w}"
        );
        assert!(
            (rob / spread - 1.0).abs() < 0.25,
            "robust {rob} against the spread {spread}"
        );
    }

    #[test]
    fn termination_prints_and_serializes_in_kebab_case() {
        assert_eq!(Termination::MaxIterations.to_string(), "max-iterations");
        let json = serde_json::to_string(&Termination::Cancelled).unwrap();
        assert_eq!(json, "\"cancelled\"");
    }
}

//! The constraint kernel: the terms of one distance constraint, written once
//! for every solver.
//!
//! A constraint joins particles `a` and `b` (inverse masses `k_a`, `k_b`; 0
//! for a static particle) at rest length `L` (m), with compliance `α` (m/N;
//! 0 when inextensible). Over a step of size `h` it is weighed by
//! `α̃ = α/h²` (1/kg), and its impulse is kept as `μ = h p` (kg m, the
//! impulse times the step, positive under tension). At positions `x` (the
//! previewed end-of-step positions while a step is solved) it has
//!
//! - a **separation** ([`Separation`]): the length `ℓ = |x_a − x_b|` and the
//!   unit direction `n = (x_a − x_b)/ℓ` from `b` to `a`, none when the ends
//!   coincide (`ℓ ≤ f64::MIN_POSITIVE`: the constraint then waits for its
//!   neighbours rather than divide by zero);
//! - a **value** `C = ℓ − L − α̃ μ` (m, [`Link::value`]): its error over the
//!   step, the XPBD form; `C/L` ([`Link::relative`]) is what the solvers drive
//!   below the stretch tolerance, and `(ℓ − L)/L` ([`Link::stretch`]) the
//!   relative stretch;
//! - a **weight** `s (k_a + k_b) + α̃` (1/kg, [`Link::weight`]): with `s = 1`
//!   the denominator of its projection and the diagonal of a strip's system,
//!   with Newton's proximal shift `s = ε` the entry `E` of Newton's system;
//! - a **projection** ([`Projection`], [`project`]): the correction
//!   `δμ = C/(k_a + k_b + α̃)` which, applied along `n` as equal and opposite
//!   impulses ([`apply`]: `x_a −= k_a δμ n`, `x_b += k_b δμ n`), satisfies
//!   the constraint exactly: moving both ends along the line through them
//!   changes the distance by exactly the move, and `μ + δμ` updates `α̃ μ`.
//!   Static ends are never touched, and the momentum `Σ x/k` is unchanged.
//!
//! The solvers and what they take from here:
//!
//! - Gauss–Seidel ([`crate::solver`]): [`project`] per constraint;
//!   [`apply`] for the warm start's impulses; [`velocity_impulse`] and
//!   [`apply`] for the velocity part.
//! - The coloured sweep ([`crate::colouring`]): [`project`] in place; in
//!   parallel, [`Projection::at`] in pass 1 and [`move_end`] in pass 2.
//! - Strips ([`crate::strips`]): [`Projection::at`] for each row of a
//!   chain's tridiagonal system (its direction, right-hand side and
//!   diagonal), [`apply`] for the chain's impulses, [`project`] when the
//!   elimination fails.
//! - Newton ([`crate::newton`]): [`Link::separation`], [`Link::value`] and
//!   [`Link::relative`] for the residual and the merit, [`Link::weight`] for
//!   the diagonal `E` of its system.
//! - The convergence checks ([`crate::constraints`]): [`Link::value`],
//!   [`Link::relative`], [`Link::stretch`].
//!
//! Everything here is `#[inline]` and allocates nothing: it runs once per
//! constraint per sweep.

use nalgebra::Vector3;

use crate::constraints::DistanceConstraints;

/// One constraint read from the columns of a [`DistanceConstraints`], its
/// compliance scaled for a step.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Link {
    /// First particle.
    pub(crate) a: usize,
    /// Second particle.
    pub(crate) b: usize,
    /// Rest length `L` (m).
    pub(crate) rest: f64,
    /// Compliance `α` (m/N).
    compliance: f64,
    /// `1/h²` (1/s²).
    inv_h2: f64,
}

impl Link {
    /// Constraint `i`; `inv_h2 = 1/h²` (1/s²) only scales its compliance
    /// (pass 0 where it does not enter: the stretch, the velocity part).
    #[inline]
    pub(crate) fn new(constraints: &DistanceConstraints, i: usize, inv_h2: f64) -> Self {
        Self {
            a: constraints.a[i] as usize,
            b: constraints.b[i] as usize,
            rest: constraints.rest_length[i],
            compliance: constraints.compliance[i],
            inv_h2,
        }
    }

    /// `α̃ = α/h²` (1/kg): the compliance over the step.
    #[inline]
    pub(crate) fn alpha(&self) -> f64 {
        self.compliance * self.inv_h2
    }

    /// The length `|x_a − x_b|` (m).
    #[inline]
    pub(crate) fn length(&self, x: &[Vector3<f64>]) -> f64 {
        (x[self.a] - x[self.b]).norm()
    }

    /// The length and direction at `x` (see [`Separation`]).
    #[inline]
    pub(crate) fn separation(&self, x: &[Vector3<f64>]) -> Separation {
        Separation::between(x, self.a, self.b)
    }

    /// The value `C = len − L − α̃ μ` (m) at length `len` (m) and impulse ×
    /// step `mu` (kg m). (Rounded as `α μ/h²`: `(α/h²) μ` rounds differently.)
    #[inline]
    pub(crate) fn value(&self, len: f64, mu: f64) -> f64 {
        len - self.rest - self.compliance * mu * self.inv_h2
    }

    /// A value relative to the rest length, `C/L` (dimensionless).
    #[inline]
    pub(crate) fn relative(&self, value: f64) -> f64 {
        value / self.rest
    }

    /// The relative stretch `(len − L)/L` at length `len` (m), whatever the
    /// compliance (signed: positive when stretched).
    #[inline]
    pub(crate) fn stretch(&self, len: f64) -> f64 {
        (len - self.rest) / self.rest
    }

    /// The weight `mass_scale (k_a + k_b) + α̃` (1/kg): with `mass_scale = 1`
    /// the denominator of the projection, with Newton's proximal shift the
    /// entry `E` of its system.
    #[inline]
    pub(crate) fn weight(&self, ka: f64, kb: f64, mass_scale: f64) -> f64 {
        mass_scale * (ka + kb) + self.alpha()
    }
}

/// The length of a constraint at some positions and its direction.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Separation {
    /// `|x_a − x_b|` (m).
    pub(crate) len: f64,
    /// `(x_a − x_b)/len`, from `b` to `a`; `None` when the ends coincide
    /// (`len ≤ f64::MIN_POSITIVE`) or `len` is NaN.
    pub(crate) n: Option<Vector3<f64>>,
}

impl Separation {
    /// The separation of particles `a` and `b` at `x`.
    #[inline]
    pub(crate) fn between(x: &[Vector3<f64>], a: usize, b: usize) -> Self {
        let d = x[a] - x[b];
        let len = d.norm();
        Self {
            len,
            n: (len > f64::MIN_POSITIVE).then(|| d / len),
        }
    }
}

/// A constraint's projection at previewed positions: what a Gauss–Seidel
/// step, a coloured pass and a strip's row need.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Projection {
    /// The direction `n` from `b` to `a` (unit).
    pub(crate) n: Vector3<f64>,
    /// The value `C = ℓ − L − α̃ μ` (m).
    pub(crate) value: f64,
    /// The weight `k_a + k_b + α̃` (1/kg).
    pub(crate) weight: f64,
}

impl Projection {
    /// Constraint `link` at `x` with impulse × step `mu` (kg m) between ends
    /// of inverse masses `ka`, `kb` (1/kg); `None` when both ends are static
    /// or the ends coincide.
    #[inline]
    pub(crate) fn at(link: &Link, ka: f64, kb: f64, x: &[Vector3<f64>], mu: f64) -> Option<Self> {
        let Separation { len, n } = link.separation(x);
        if ka + kb == 0.0 {
            return None;
        }
        Some(Self {
            n: n?,
            value: link.value(len, mu),
            weight: link.weight(ka, kb, 1.0),
        })
    }

    /// The correction `δμ = C/(k_a + k_b + α̃)` (kg m) that satisfies the
    /// constraint along `n`.
    #[inline]
    pub(crate) fn correction(&self) -> f64 {
        self.value / self.weight
    }
}

/// Equal and opposite impulses `s` (impulse × step, kg m, on positions; or an
/// impulse, kg m/s, on velocities) along `n`: `x_a −= k_a s n`,
/// `x_b += k_b s n`. A static end (`k = 0`) is not touched.
#[inline]
pub(crate) fn apply(
    x: &mut [Vector3<f64>],
    (a, b): (usize, usize),
    (ka, kb): (f64, f64),
    s: f64,
    n: &Vector3<f64>,
) {
    move_end(&mut x[a], ka, s, n, false);
    move_end(&mut x[b], kb, s, n, true);
}

/// One end's share of [`apply`]: the second end `b` moves by `+k s n`, the
/// first by `−k s n`; a static end (`k = 0`) stays.
#[inline]
pub(crate) fn move_end(x: &mut Vector3<f64>, k: f64, s: f64, n: &Vector3<f64>, is_b: bool) {
    if k == 0.0 {
        return;
    }
    let shift = k * s * n;
    if is_b {
        *x += shift;
    } else {
        *x -= shift;
    }
}

/// One Gauss–Seidel projection: constraint `i` satisfied at `x` along its
/// direction by equal and opposite impulses, its correction added to
/// `mu[i]` (kg m); nothing when both ends are static or they coincide.
#[inline]
pub(crate) fn project(
    constraints: &DistanceConstraints,
    i: usize,
    inv_mass: &[f64],
    x: &mut [Vector3<f64>],
    mu: &mut [f64],
    inv_h2: f64,
) {
    let link = Link::new(constraints, i, inv_h2);
    let k = (inv_mass[link.a], inv_mass[link.b]);
    if let Some(p) = Projection::at(&link, k.0, k.1, x, mu[i]) {
        let corr = p.correction();
        apply(x, (link.a, link.b), k, corr, &p.n);
        mu[i] += corr;
    }
}

/// The impulse (kg m/s) that removes the relative velocity of `a` and `b`
/// along `n`: `((v_a − v_b)·n)/(k_a + k_b)`, `w = k_a + k_b > 0`.
#[inline]
pub(crate) fn velocity_impulse(
    v: &[Vector3<f64>],
    (a, b): (usize, usize),
    w: f64,
    n: &Vector3<f64>,
) -> f64 {
    (v[a] - v[b]).dot(n) / w
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One constraint of rest length 1 m between particles 0 and 1.
    fn one(compliance: f64) -> DistanceConstraints {
        let mut c = DistanceConstraints::new();
        c.push(0, 1, 1.0);
        c.compliance[0] = compliance;
        c
    }

    #[test]
    fn one_projection_satisfies_a_compliant_constraint_and_conserves_momentum() {
        let (c, k) = (one(1e-3), [1.0, 4.0]);
        let mut x = vec![Vector3::zeros(), Vector3::new(1.3, 0.2, -0.1)];
        let before = x.clone();
        let mut mu = [0.5];
        let inv_h2 = 1e4;
        project(&c, 0, &k, &mut x, &mut mu, inv_h2);
        let link = Link::new(&c, 0, inv_h2);
        // The value with the updated impulse vanishes to rounding (terms of order 10 m).
        approx::assert_abs_diff_eq!(link.value(link.length(&x), mu[0]), 0.0, epsilon = 1e-13);
        let dp = (x[0] - before[0]) / k[0] + (x[1] - before[1]) / k[1];
        approx::assert_abs_diff_eq!(dp.norm(), 0.0, epsilon = 1e-14);
    }

    #[test]
    fn static_ends_and_coincident_ends_are_left_alone() {
        let c = one(0.0);
        let mut x = vec![Vector3::zeros(), Vector3::new(2.0, 0.0, 0.0)];
        let mut mu = [0.0];
        project(&c, 0, &[0.0, 1.0], &mut x, &mut mu, 1.0);
        assert_eq!(x[0], Vector3::zeros());
        approx::assert_abs_diff_eq!(x[1].x, 1.0, epsilon = 1e-15);
        // Both static, or coincident ends: no projection.
        let link = Link::new(&c, 0, 1.0);
        assert!(Projection::at(&link, 0.0, 0.0, &x, 0.0).is_none());
        let same = [Vector3::new(1.0, 2.0, 3.0); 2];
        assert!(Projection::at(&link, 1.0, 1.0, &same, 0.0).is_none());
        assert!(link.separation(&same).n.is_none());
    }

    #[test]
    fn weight_is_the_projection_denominator_or_newtons_diagonal() {
        let link = Link::new(&one(2e-4), 0, 1e4);
        approx::assert_relative_eq!(link.alpha(), 2.0, epsilon = 1e-15);
        approx::assert_relative_eq!(link.weight(1.0, 3.0, 1.0), 6.0, epsilon = 1e-15);
        approx::assert_relative_eq!(link.weight(1.0, 3.0, 1e-6), 2.0 + 4e-6, epsilon = 1e-15);
        approx::assert_relative_eq!(link.stretch(1.1), 0.1, epsilon = 1e-12);
    }
}

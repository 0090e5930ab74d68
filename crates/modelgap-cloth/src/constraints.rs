//! Distance constraints as columns: particle pairs, rest lengths and compliances.
//!
//! A constraint is inextensible by default (`compliance` 0). A compliant
//! constraint (compliance `α`, m/N) stretches under its tension `λ` (N) to
//! `|c_a − c_b| = rest + α λ`; with the impulse kept as `μ = h p = h² λ`
//! (kg m, see [`crate::newton`]) its error over a step of size `h` is
//! `|c_a − c_b| − rest − α μ / h²` (the XPBD form). The solvers drive this
//! error, relative to the rest length, below the stretch tolerance; for an
//! inextensible constraint it is the relative stretch. The formulas of one
//! constraint, which every solver shares, live in the crate's constraint
//! kernel (`kernel.rs`).

use nalgebra::Vector3;

use crate::kernel::Link;

/// Distance constraints `|c_a − c_b| = rest_length`, one per mesh edge,
/// stored as one `Vec` per attribute (indices into a [`ParticleSet`](crate::ParticleSet)).
#[derive(Clone, Debug, Default)]
pub struct DistanceConstraints {
    /// First particle of each constraint.
    pub a: Vec<u32>,
    /// Second particle of each constraint.
    pub b: Vec<u32>,
    /// Rest length of each constraint (m), positive.
    pub rest_length: Vec<f64>,
    /// Compliance of each constraint (m/N, ≥ 0): stretch per unit tension;
    /// 0 for an inextensible constraint.
    pub compliance: Vec<f64>,
}

impl DistanceConstraints {
    /// No constraints.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// The number of constraints.
    #[must_use]
    pub fn len(&self) -> usize {
        self.a.len()
    }

    /// Whether there are no constraints.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.a.is_empty()
    }

    /// Adds a constraint between particles `a` and `b` with the given rest length (m).
    pub fn push(&mut self, a: u32, b: u32, rest_length: f64) {
        self.a.push(a);
        self.b.push(b);
        self.rest_length.push(rest_length);
        self.compliance.push(0.0);
    }

    /// The error of constraint `i` relative to its rest length:
    /// `(|c_a − c_b| − rest − α μ/h²) / rest`, with `mu` its impulse × step
    /// (kg m) and `inv_h2 = 1/h²`; the relative stretch when inextensible.
    #[must_use]
    pub fn error(&self, i: usize, positions: &[Vector3<f64>], mu: f64, inv_h2: f64) -> f64 {
        let link = Link::new(self, i, inv_h2);
        link.relative(link.value(link.length(positions), mu))
    }

    /// The largest `|error|` ([`error`](Self::error)) over all constraints;
    /// NaN if any is NaN; 0 when there are none.
    #[must_use]
    pub fn max_error(&self, positions: &[Vector3<f64>], mu: &[f64], inv_h2: f64) -> f64 {
        let mut worst = 0.0_f64;
        for (i, &m) in mu.iter().enumerate().take(self.len()) {
            let e = self.error(i, positions, m, inv_h2).abs();
            if e.is_nan() {
                return f64::NAN;
            }
            worst = worst.max(e);
        }
        worst
    }

    /// Checks that every constraint names a particle below `n_particles`.
    ///
    /// # Errors
    /// [`ClothError::VertexOutOfRange`](crate::ClothError::VertexOutOfRange)
    /// for the first that does not.
    pub fn check_particles(&self, n_particles: usize) -> crate::Result<()> {
        for &p in self.a.iter().chain(&self.b) {
            if p as usize >= n_particles {
                return Err(crate::ClothError::VertexOutOfRange {
                    vertex: p as usize,
                    n_vertices: n_particles,
                });
            }
        }
        Ok(())
    }

    /// Whether any constraint is compliant.
    #[must_use]
    pub fn any_compliant(&self) -> bool {
        self.compliance.iter().any(|&a| a > 0.0)
    }

    /// The relative stretch `(|c_a − c_b| − rest) / rest` of constraint `i`
    /// at the given positions (signed: positive when stretched).
    #[must_use]
    pub fn stretch(&self, i: usize, positions: &[Vector3<f64>]) -> f64 {
        let link = Link::new(self, i, 0.0);
        link.stretch(link.length(positions))
    }

    /// The largest relative stretch or compression `| |c_a − c_b| / rest − 1 |`
    /// over all constraints (0 when there are none).
    #[must_use]
    pub fn max_stretch(&self, positions: &[Vector3<f64>]) -> f64 {
        let mut worst = 0.0_f64;
        for i in 0..self.len() {
            let s = self.stretch(i, positions).abs();
            // NaN must not hide: `max` would drop it.
            if s.is_nan() {
                return f64::NAN;
            }
            worst = worst.max(s);
        }
        worst
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stretch_is_relative_and_signed() {
        let mut c = DistanceConstraints::new();
        c.push(0, 1, 2.0);
        let x = [Vector3::zeros(), Vector3::new(2.2, 0.0, 0.0)];
        approx::assert_relative_eq!(c.stretch(0, &x), 0.1, epsilon = 1e-12);
        let y = [Vector3::zeros(), Vector3::new(1.0, 0.0, 0.0)];
        approx::assert_relative_eq!(c.max_stretch(&y), 0.5, epsilon = 1e-12);
    }
}

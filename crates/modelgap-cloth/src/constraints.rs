//! Distance constraints as columns: particle pairs and rest lengths.

use nalgebra::Vector3;

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
    }

    /// The relative stretch `(|c_a − c_b| − rest) / rest` of constraint `i`
    /// at the given positions (signed: positive when stretched).
    #[must_use]
    pub fn stretch(&self, i: usize, positions: &[Vector3<f64>]) -> f64 {
        let d = positions[self.a[i] as usize] - positions[self.b[i] as usize];
        (d.norm() - self.rest_length[i]) / self.rest_length[i]
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

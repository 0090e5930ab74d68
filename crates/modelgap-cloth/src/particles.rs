//! Particles as columns: positions, velocities and inverse masses.

use nalgebra::Vector3;

/// The id of a particle in a [`ClothWorld`](crate::ClothWorld): its index in the
/// world's [`ParticleSet`]. Particles are never removed, so ids stay valid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ParticleId(pub u32);

impl ParticleId {
    /// The index into the particle columns.
    #[must_use]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// Particles as one `Vec` per attribute. A static particle has `inv_mass = 0`:
/// a fixed position and no velocity.
#[derive(Clone, Debug, Default)]
pub struct ParticleSet {
    /// Positions (m).
    pub positions: Vec<Vector3<f64>>,
    /// Velocities (m/s).
    pub velocities: Vec<Vector3<f64>>,
    /// Inverse masses (1/kg); 0 for static particles.
    pub inv_mass: Vec<f64>,
}

impl ParticleSet {
    /// An empty set.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// The number of particles.
    #[must_use]
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether the set has no particles.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Adds a particle at rest; `inv_mass` 0 makes it static.
    pub fn push(&mut self, position: Vector3<f64>, inv_mass: f64) -> ParticleId {
        let id = ParticleId(u32::try_from(self.positions.len()).unwrap_or(u32::MAX));
        self.positions.push(position);
        self.velocities.push(Vector3::zeros());
        self.inv_mass.push(inv_mass);
        id
    }

    /// Whether the particle is static (infinite mass).
    #[must_use]
    pub fn is_static(&self, i: usize) -> bool {
        self.inv_mass[i] == 0.0
    }

    /// Total linear momentum of the dynamic particles (kg m/s).
    #[must_use]
    pub fn momentum(&self) -> Vector3<f64> {
        let mut p = Vector3::zeros();
        for i in 0..self.len() {
            if self.inv_mass[i] > 0.0 {
                p += self.velocities[i] / self.inv_mass[i];
            }
        }
        p
    }
}

/// Which particles are static (inverse mass 0), as a structure built on
/// them (a colouring, a strip decomposition) remembers them.
pub(crate) fn statics(inv_mass: &[f64]) -> Vec<bool> {
    inv_mass.iter().map(|&k| k == 0.0).collect()
}

/// Whether `is_static` (from [`statics`]) still describes these inverse
/// masses: the same number of particles, the same ones static.
pub(crate) fn same_statics(is_static: &[bool], inv_mass: &[f64]) -> bool {
    is_static.len() == inv_mass.len()
        && is_static
            .iter()
            .zip(inv_mass)
            .all(|(&s, &k)| s == (k == 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_hands_out_sequential_ids_and_rest_state() {
        let mut set = ParticleSet::new();
        let a = set.push(Vector3::new(1.0, 2.0, 3.0), 1.0);
        let b = set.push(Vector3::zeros(), 0.0);
        assert_eq!((a.index(), b.index()), (0, 1));
        assert!(set.is_static(1) && !set.is_static(0));
        assert_eq!(set.velocities[0], Vector3::zeros());
        assert_eq!(set.momentum(), Vector3::zeros());
    }
}

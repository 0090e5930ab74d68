//! Kinematic pins: pinned (static) vertices that follow a prescribed path.
//!
//! A kinematic pin keeps `inv_mass = 0` (no impulse moves it), but before each step the
//! world puts its end-of-step position on its path, `x(t + h)`, so the constraints that
//! join it to the cloth see the motion and drag the cloth along; after the step it sits
//! exactly on the path with velocity `(x(t + h) − x(t)) / h`.
//!
//! A path is piecewise linear through points `(t, x, y, z)` and held at its first point
//! before the first time and at its last point after the last: a scene file's
//! `[[pins.paths]]`, or a marker recording's track ([`follow_markers`]). A pin can also
//! ride a [`Rail`] shared with other pins (a scene file's `[[rails]]` and
//! `[[pins.attach]]`, see [`crate::rail`]).
//!
//! # Example
//!
//! ```
//! use modelgap_cloth::{ClothWorld, GridCloth, PinPath, SolverParams};
//!
//! let mut world = ClothWorld::new(SolverParams::default());
//! let cloth = world.add_cloth(GridCloth::new(5, 5, 0.1).pin(0))?;
//! // Vertex 0 moves 0.2 m along +x in 1 s, then stays.
//! let path = PinPath::from_rows(&[[0.0, 0.0, 0.0, 0.0], [1.0, 0.2, 0.0, 0.0]])?;
//! world.add_kinematic_pin(cloth, 0, path)?;
//! world.step_n(50, 0.01)?;
//! assert!((world.positions(cloth)[0].x - 0.1).abs() < 1e-12);
//! # Ok::<(), modelgap_cloth::ClothError>(())
//! ```

use std::sync::Arc;

use nalgebra::Vector3;

use crate::error::{ClothError, Result};
use crate::markers::MarkerRecording;
use crate::particles::ParticleId;
use crate::rail::Rail;
use crate::world::{ClothId, ClothWorld};

/// A piecewise-linear path through points at strictly increasing times.
#[derive(Clone, Debug, PartialEq)]
pub struct PinPath {
    t: Vec<f64>,
    points: Vec<Vector3<f64>>,
}

impl PinPath {
    /// A path through `points` (m) at times `t` (s).
    ///
    /// # Errors
    ///
    /// [`ClothError::BadPinPath`] for no points, lengths that differ, a non-finite value or
    /// time that does not strictly increase.
    pub fn new(t: Vec<f64>, points: Vec<Vector3<f64>>) -> Result<Self> {
        let bad = |index: usize, message: String| ClothError::BadPinPath { index, message };
        if t.is_empty() {
            return Err(bad(0, "expected at least one point, found none".into()));
        }
        if t.len() != points.len() {
            return Err(bad(
                t.len().min(points.len()),
                format!(
                    "expected one point per time ({}), found {}",
                    t.len(),
                    points.len()
                ),
            ));
        }
        for (k, (&tk, p)) in t.iter().zip(&points).enumerate() {
            if !(tk.is_finite() && p.iter().all(|c| c.is_finite())) {
                return Err(bad(
                    k,
                    format!(
                        "expected finite values, found t = {tk}, [{}, {}, {}]",
                        p.x, p.y, p.z
                    ),
                ));
            }
            if k > 0 && tk <= t[k - 1] {
                return Err(bad(
                    k,
                    format!(
                        "expected time after {} s, found {tk} s (times must strictly increase)",
                        t[k - 1]
                    ),
                ));
            }
        }
        Ok(Self { t, points })
    }

    /// A path from rows `[t, x, y, z]` (s, m), the form of a scene file.
    ///
    /// # Errors
    ///
    /// As [`new`](Self::new).
    pub fn from_rows(rows: &[[f64; 4]]) -> Result<Self> {
        Self::new(
            rows.iter().map(|r| r[0]).collect(),
            rows.iter()
                .map(|r| Vector3::new(r[1], r[2], r[3]))
                .collect(),
        )
    }

    /// The times of the points (s).
    #[must_use]
    pub fn t(&self) -> &[f64] {
        &self.t
    }

    /// The points (m).
    #[must_use]
    pub fn points(&self) -> &[Vector3<f64>] {
        &self.points
    }

    /// The position at time `t` (s): linear between points, held before the first and
    /// after the last. At a point's time it is exactly that point.
    #[must_use]
    pub fn at(&self, t: f64) -> Vector3<f64> {
        let i = self.t.partition_point(|&ti| ti <= t);
        if i == 0 {
            return self.points[0];
        }
        if i == self.t.len() {
            return self.points[i - 1];
        }
        let (t0, t1) = (self.t[i - 1], self.t[i]);
        let (a, b) = (self.points[i - 1], self.points[i]);
        let s = (t - t0) / (t1 - t0);
        if s == 0.0 { a } else { a + (b - a) * s }
    }
}

/// How a kinematic pin moves: its own path, or riding a [`Rail`].
#[derive(Clone, Debug, PartialEq)]
pub enum PinMotion {
    /// Its own path (absolute positions).
    Path(PinPath),
    /// A point of a rail's frame ([`Rail::local`]), shared with every vertex on the rail.
    Rail {
        /// The rail.
        rail: Arc<Rail>,
        /// The point of the rail's frame the particle sits at (m).
        local: Vector3<f64>,
    },
}

impl PinMotion {
    /// The position at time `t` (s).
    #[must_use]
    pub fn at(&self, t: f64) -> Vector3<f64> {
        match self {
            Self::Path(path) => path.at(t),
            Self::Rail { rail, local } => rail.world(local, t),
        }
    }
}

/// A pinned particle of a world and how it moves.
#[derive(Clone, Debug, PartialEq)]
pub struct KinematicPin {
    /// The particle (static, `inv_mass = 0`).
    pub particle: ParticleId,
    /// Its motion.
    pub motion: PinMotion,
}

/// Makes every pinned vertex of `cloth` whose id appears in `recording` follow the recorded
/// positions (recording time = world time); returns how many pins follow the recording.
/// Markers on dynamic vertices or past the mesh are left alone.
///
/// # Errors
///
/// [`ClothError::UnknownCloth`] for an id the world did not hand out.
pub fn follow_markers(
    world: &mut ClothWorld,
    cloth: ClothId,
    recording: &MarkerRecording,
) -> Result<usize> {
    let n_vertices = world.positions(cloth).len();
    if n_vertices == 0 {
        return Err(ClothError::UnknownCloth {
            id: cloth.0,
            n_cloths: 0,
        });
    }
    let mut n = 0;
    for (k, &id) in recording.ids().iter().enumerate() {
        let vertex = id as usize;
        if vertex >= n_vertices {
            continue;
        }
        let particle = world.particle(cloth, vertex)?;
        if !world.particles().is_static(particle.index()) {
            continue;
        }
        let points = recording
            .positions()
            .iter()
            .map(|frame| Vector3::from(frame[k]))
            .collect();
        let path = PinPath::new(recording.t().to_vec(), points)?;
        world.add_kinematic_pin(cloth, vertex, path)?;
        n += 1;
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_interpolates_linearly_and_holds_its_ends() {
        let path = PinPath::from_rows(&[[1.0, 0.0, 0.0, 0.0], [3.0, 2.0, -4.0, 0.0]]).unwrap();
        assert_eq!(path.at(0.0), Vector3::zeros());
        assert_eq!(path.at(1.0), Vector3::zeros());
        assert_eq!(path.at(2.0), Vector3::new(1.0, -2.0, 0.0));
        assert_eq!(path.at(3.0), Vector3::new(2.0, -4.0, 0.0));
        assert_eq!(path.at(10.0), Vector3::new(2.0, -4.0, 0.0));
    }

    #[test]
    fn bad_paths_name_the_point() {
        let e = PinPath::from_rows(&[[0.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]]).unwrap_err();
        assert!(matches!(e, ClothError::BadPinPath { index: 1, .. }), "{e}");
        let e = PinPath::from_rows(&[[0.0, f64::NAN, 0.0, 0.0]]).unwrap_err();
        assert!(matches!(e, ClothError::BadPinPath { index: 0, .. }), "{e}");
        assert!(PinPath::from_rows(&[]).is_err());
    }
}

//! [`Rail`]: a rigid frame that moves on a prescribed motion, named once, that any set of
//! pinned vertices can ride (a curtain's top row on its rail, a border held by a frame).
//!
//! A rail has an `origin` (m) and a motion: a translation of the origin and, optionally, a
//! rotation about it (rad, axis × angle), each either three expressions of `t`
//! ([`TimeExpr`]) or samples `[t, x, y, z]` (linear between them, held before the first and
//! after the last, like a [`PinPath`]). Its pose at time `t` is
//! `x ↦ origin + T(t) + R(t) (x − origin)`.
//!
//! A vertex attached to a rail ([`ClothWorld::attach_to_rail`](crate::ClothWorld::attach_to_rail))
//! keeps its offset in the rail's frame from where it is when it is attached: with the pose
//! `P(t)` it is at `P(t) P(t₀)⁻¹ x₀`, so attaching never moves it, and a translation that
//! does not start at zero (`0.5 + 0.03 sin(…)`) moves the vertices exactly as one that
//! does.
//!
//! ```
//! use std::sync::Arc;
//! use modelgap_cloth::rail::{Motion, Rail};
//! use modelgap_cloth::{ClothWorld, GridCloth, SolverParams};
//!
//! // A 6 x 6 curtain hanging from its whole top row, which moves 2 cm along x.
//! let rail = Arc::new(Rail::new("top", Motion::expressions(["0.02 * t", "0", "0"])?));
//! let mut world = ClothWorld::new(SolverParams::default());
//! let cloth = world.add_cloth(GridCloth::new(6, 6, 0.1).pin_row(0))?;
//! for col in 0..6 {
//!     world.attach_to_rail(cloth, col, Arc::clone(&rail))?;
//! }
//! world.step_n(100, 0.01)?;
//! assert!((world.positions(cloth)[3].x - (0.3 + 0.02)).abs() < 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod expr;
pub mod file;

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

pub use expr::{TimeExpr, TimeExprError};
pub use file::{RailPins, VertexSet};

use crate::kinematic::PinPath;

/// A vector quantity of time: three expressions of `t`, or samples.
#[derive(Clone, Debug, PartialEq)]
pub enum Motion {
    /// Three expressions of `t`, one per axis.
    Expressions(Box<[TimeExpr; 3]>),
    /// Samples `[t, x, y, z]`, linear between them.
    Samples(PinPath),
}

impl Motion {
    /// No motion: zero at every time.
    #[must_use]
    pub fn zero() -> Self {
        Self::Expressions(Box::new(std::array::from_fn(|_| TimeExpr::constant(0.0))))
    }

    /// Three expressions of `t`.
    ///
    /// # Errors
    /// The first one that does not parse; its message starts with the axis (`x: `).
    pub fn expressions(texts: [&str; 3]) -> Result<Self, TimeExprError> {
        let parse = |axis: usize| {
            TimeExpr::parse(texts[axis]).map_err(|e| TimeExprError {
                column: e.column,
                message: format!("{}: {}", ["x", "y", "z"][axis], e.message),
            })
        };
        Ok(Self::Expressions(Box::new([
            parse(0)?,
            parse(1)?,
            parse(2)?,
        ])))
    }

    /// The value at time `t`.
    #[must_use]
    pub fn at(&self, t: f64) -> Vector3<f64> {
        match self {
            Self::Expressions(e) => Vector3::new(e[0].eval(t), e[1].eval(t), e[2].eval(t)),
            Self::Samples(path) => path.at(t),
        }
    }

    /// Whether it is zero at every time (no motion).
    #[must_use]
    pub fn is_zero(&self) -> bool {
        match self {
            Self::Expressions(e) => e.iter().all(|x| *x == TimeExpr::constant(0.0)),
            Self::Samples(_) => false,
        }
    }
}

/// A rigid frame on a prescribed motion (see the [module docs](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct Rail {
    /// Its name in a scene file.
    pub name: String,
    /// The origin at rest (m): the point the translation moves and the rotation turns about.
    pub origin: Vector3<f64>,
    /// The translation of the origin (m).
    pub translation: Motion,
    /// The rotation about the origin (rad, axis × angle); `None` for none.
    pub rotation: Option<Motion>,
}

impl Rail {
    /// A rail at the world's origin translating by `translation`, without rotation.
    #[must_use]
    pub fn new(name: impl Into<String>, translation: Motion) -> Self {
        Self {
            name: name.into(),
            origin: Vector3::zeros(),
            translation,
            rotation: None,
        }
    }

    /// The pose at time `t`: `x ↦ origin + T(t) + R(t) (x − origin)`.
    #[must_use]
    pub fn pose(&self, t: f64) -> Isometry3<f64> {
        let rotation = self
            .rotation
            .as_ref()
            .map_or_else(UnitQuaternion::identity, |r| {
                UnitQuaternion::from_scaled_axis(r.at(t))
            });
        let o = self.origin;
        let shift = o + self.translation.at(t) - rotation * o;
        Isometry3::from_parts(Translation3::from(shift), rotation)
    }

    /// The point of the rail's frame that is at `x` at time `t`: where a vertex attached
    /// then stays in the frame.
    #[must_use]
    pub fn local(&self, x: &Vector3<f64>, t: f64) -> Vector3<f64> {
        self.pose(t)
            .inverse_transform_point(&Point3::from(*x))
            .coords
    }

    /// Where the frame's point `local` ([`local`](Self::local)) is at time `t`.
    #[must_use]
    pub fn world(&self, local: &Vector3<f64>, t: f64) -> Vector3<f64> {
        (self.pose(t) * Point3::from(*local)).coords
    }

    /// Where a point that is at `x0` at time `t0` and rides the rail is at time `t`.
    #[must_use]
    pub fn carry(&self, x0: &Vector3<f64>, t0: f64, t: f64) -> Vector3<f64> {
        self.world(&self.local(x0, t0), t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rail_translates_and_turns_about_its_origin() {
        let mut rail = Rail::new(
            "r",
            Motion::expressions(["0.5 + 0.1 * t", "0", "0"]).unwrap(),
        );
        // Attached at t = 0: the constant 0.5 does not move anything.
        let x0 = Vector3::new(1.0, 2.0, 3.0);
        assert!((rail.carry(&x0, 0.0, 0.0) - x0).norm() < 1e-15);
        assert!((rail.carry(&x0, 0.0, 2.0) - Vector3::new(1.2, 2.0, 3.0)).norm() < 1e-15);
        rail.origin = Vector3::new(1.0, 0.0, 3.0);
        rail.translation = Motion::zero();
        rail.rotation = Some(Motion::expressions(["0", "0", "pi / 2 * t"]).unwrap());
        // A quarter turn about z through (1, 0, 3): (1, 2, 3) goes to (-1, 0, 3).
        let x1 = rail.carry(&x0, 0.0, 1.0);
        assert!((x1 - Vector3::new(-1.0, 0.0, 3.0)).norm() < 1e-12, "{x1:?}");
        // Samples, held after the last.
        let path = PinPath::from_rows(&[[0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 1.0]]).unwrap();
        let rail = Rail::new("s", Motion::Samples(path));
        assert!((rail.carry(&x0, 0.0, 5.0) - Vector3::new(1.0, 2.0, 4.0)).norm() < 1e-15);
    }
}

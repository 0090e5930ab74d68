//! Static colliders and contacts with Coulomb friction, resolved inside the
//! solver loop by the same preview as the distance constraints.
//!
//! Each iteration pushes every particle whose *predicted* end-of-step
//! position lies inside a collider back to its surface, along the surface
//! normal (a normal impulse applied at the start of the step), and removes up
//! to `friction ×` that normal correction of the particle's tangential motion
//! over the step (the Coulomb cone on impulses). Because the test uses the
//! end-of-step position, a particle cannot pass through a thin collider in one
//! step. After the step, the normal velocity into the surface is removed and
//! the tangential velocity is reduced by friction (an inelastic contact).
//!
//! The shapes here are analytic (plane and ball).

use nalgebra::Vector3;

/// The id of a collider in a [`ClothWorld`](crate::ClothWorld).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ColliderId(pub u32);

/// The geometry of a static collider.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum Shape {
    /// A half-space: everything behind the plane through `point` with outward `normal` is solid.
    Plane {
        /// A point on the plane (m).
        point: Vector3<f64>,
        /// The outward unit normal.
        normal: Vector3<f64>,
    },
    /// A solid ball.
    Ball {
        /// Centre (m).
        center: Vector3<f64>,
        /// Radius (m).
        radius: f64,
    },
}

/// A static collider: a shape and a Coulomb friction coefficient.
#[derive(Clone, Debug, PartialEq)]
pub struct Collider {
    /// The geometry.
    pub shape: Shape,
    /// Coulomb friction coefficient (dimensionless); default 0.
    pub friction: f64,
}

impl Collider {
    /// A solid ball of `radius` m at `center`, frictionless.
    #[must_use]
    pub fn ball(center: Vector3<f64>, radius: f64) -> Self {
        Self {
            shape: Shape::Ball { center, radius },
            friction: 0.0,
        }
    }

    /// The half-space behind the plane through `point` with outward `normal`
    /// (normalised here), frictionless.
    #[must_use]
    pub fn plane(point: Vector3<f64>, normal: Vector3<f64>) -> Self {
        let normal = normal.try_normalize(0.0).unwrap_or_else(Vector3::y);
        Self {
            shape: Shape::Plane { point, normal },
            friction: 0.0,
        }
    }

    /// Sets the Coulomb friction coefficient.
    #[must_use]
    pub fn friction(mut self, mu: f64) -> Self {
        self.friction = mu;
        self
    }

    /// Signed distance of `x` to the surface (m, negative inside) and the
    /// outward unit normal at the closest surface point.
    #[must_use]
    pub fn signed_distance(&self, x: &Vector3<f64>) -> (f64, Vector3<f64>) {
        match &self.shape {
            Shape::Plane { point, normal } => ((x - point).dot(normal), *normal),
            Shape::Ball { center, radius } => {
                let d = x - center;
                let r = d.norm();
                let n = if r > 0.0 { d / r } else { Vector3::y() };
                (r - radius, n)
            }
        }
    }
}

/// Per-particle contact of the current step: the collider and normal of the
/// last push, if any.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ContactState {
    pub(crate) normal: Vector3<f64>,
    pub(crate) friction: f64,
    pub(crate) active: bool,
}

/// Projects predicted positions out of the colliders with Coulomb friction;
/// returns the deepest penetration found before projection (m, ≥ 0).
pub(crate) fn project_contacts(
    colliders: &[Collider],
    start: &[Vector3<f64>],
    inv_mass: &[f64],
    pred: &mut [Vector3<f64>],
    state: &mut [ContactState],
) -> f64 {
    let mut deepest = 0.0_f64;
    if colliders.is_empty() {
        return deepest;
    }
    for i in 0..pred.len() {
        if inv_mass[i] == 0.0 {
            continue;
        }
        for c in colliders {
            let (phi, n) = c.signed_distance(&pred[i]);
            if phi >= 0.0 {
                continue;
            }
            deepest = deepest.max(-phi);
            pred[i] -= phi * n;
            let motion = pred[i] - start[i];
            let tangential = motion - motion.dot(&n) * n;
            let t_len = tangential.norm();
            let allowed = c.friction * (-phi);
            if t_len <= allowed {
                pred[i] -= tangential;
            } else if t_len > 0.0 {
                pred[i] -= tangential * (allowed / t_len);
            }
            state[i] = ContactState {
                normal: n,
                friction: c.friction,
                active: true,
            };
        }
    }
    deepest
}

/// Largest penetration of the predicted positions into any collider (m, ≥ 0).
pub(crate) fn max_penetration(
    colliders: &[Collider],
    inv_mass: &[f64],
    pred: &[Vector3<f64>],
) -> f64 {
    let mut deepest = 0.0_f64;
    for (i, x) in pred.iter().enumerate() {
        if inv_mass[i] == 0.0 {
            continue;
        }
        for c in colliders {
            deepest = deepest.max(-c.signed_distance(x).0);
        }
    }
    deepest
}

/// The velocity part of the contacts: no velocity into the surface, Coulomb
/// friction on the tangential velocity. Returns the number of contacts.
pub(crate) fn contact_velocities(velocities: &mut [Vector3<f64>], state: &[ContactState]) -> usize {
    let mut n_contacts = 0;
    for (v, s) in velocities.iter_mut().zip(state) {
        if !s.active {
            continue;
        }
        n_contacts += 1;
        let vn = v.dot(&s.normal);
        if vn < 0.0 {
            *v -= vn * s.normal;
            let vt = *v - v.dot(&s.normal) * s.normal;
            let len = vt.norm();
            let cut = s.friction * (-vn);
            if len <= cut {
                *v -= vt;
            } else if len > 0.0 {
                *v -= vt * (cut / len);
            }
        }
    }
    n_contacts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ball_and_plane_signed_distances() {
        let ball = Collider::ball(Vector3::zeros(), 1.0);
        let (phi, n) = ball.signed_distance(&Vector3::new(0.0, 0.5, 0.0));
        approx::assert_relative_eq!(phi, -0.5, epsilon = 1e-15);
        assert_eq!(n, Vector3::y());
        let plane = Collider::plane(Vector3::zeros(), Vector3::new(0.0, 2.0, 0.0));
        approx::assert_relative_eq!(
            plane.signed_distance(&Vector3::new(3.0, -0.25, 1.0)).0,
            -0.25
        );
    }

    #[test]
    fn projection_pushes_out_and_sticks_within_the_cone() {
        let plane = [Collider::plane(Vector3::zeros(), Vector3::y()).friction(1.0)];
        let start = [Vector3::new(0.0, 0.0, 0.0)];
        let mut pred = [Vector3::new(0.05, -0.1, 0.0)];
        let mut state = [ContactState::default()];
        let deepest = project_contacts(&plane, &start, &[1.0], &mut pred, &mut state);
        approx::assert_relative_eq!(deepest, 0.1);
        approx::assert_relative_eq!(pred[0], Vector3::zeros(), epsilon = 1e-15);
        assert!(state[0].active);
    }
}

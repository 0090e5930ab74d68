//! The contact response inside the solver loop: projection of predicted
//! positions out of the colliders with Coulomb friction, the deepest
//! penetration, and the inelastic velocity update after the step.

use nalgebra::Vector3;

use super::Collider;

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
            // The path start → pred lies within its length of pred.
            if c.clearly_outside(&pred[i], (pred[i] - start[i]).norm()) {
                continue;
            }
            let (phi, n) = c.swept_distance(&start[i], &pred[i]);
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
            if c.clearly_outside(x, 0.0) {
                continue;
            }
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

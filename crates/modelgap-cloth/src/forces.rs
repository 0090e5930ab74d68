//! External force terms beyond gravity: aerodynamic drag and wind, velocity
//! damping, bending springs; and the other physical terms a scene may hold
//! ([`ClothEffects`]: stretch compliance, warp and weft, quadratic bending,
//! materials per region ([`crate::material`]), extra point masses).
//! Quadratic bending ([`crate::bending`]) is not here: it is integrated
//! implicitly over the step, by [`crate::scene_world::SceneWorld`].
//!
//! As gravity in the paper, every force here is **evaluated at the start of a
//! step from the positions and velocities, and held constant over the step**:
//! the world previews `c + h v + h²/2 (g + F/m)` and commits
//! `v = (c_new − c)/h + h/2 (g + F/m)` ([`ClothWorld::external_forces_mut`]).
//! The constraint impulses then keep the cloth inextensible (or compliant)
//! under them. Explicit forces need the step to resolve them: a damping rate
//! `c` with `c h ≪ 1` and a bending spring `k` with `k h²/m ≪ 1`; the
//! candidate bounds of [`crate::model`] keep to that.
//!
//! - **Air drag** on each triangle of area `A` and unit normal `n`, moving at
//!   the mean velocity `v` of its vertices through air moving at the wind `w`,
//!   in two parts, a third of each to each vertex. The normal (pressure) part
//!   `F_n = −½ ρ C_d A u_n |u_n| n`, `u_n = (v − w)·n`, acts on the relative
//!   velocity across the sheet; the tangential (skin-friction) part
//!   `F_t = −½ ρ C_f A |u_t| u_t`, `u_t = (v − w) − u_n n`, on the relative
//!   velocity along it, so a sheet sliding in its own plane (a curtain whose
//!   rail moves along it) feels drag too. `ρ` is the air density
//!   ([`AIR_DENSITY`] by default), `C_d` the drag coefficient and `C_f` the
//!   skin-friction coefficient (0 by default: the normal part alone).
//! - **Wind**: the same drag with the relative velocity `v − w`; a constant
//!   wind `w` (m/s) with `C_d > 0` pushes a cloth at rest, and with `C_f > 0`
//!   a wind along the sheet pulls it.
//! - **Velocity damping**: `F_i = −c m_i v_i` (rate `c`, 1/s), what air
//!   resistance looks like to a model that ignores the cloth's shape.
//! - **Bending springs** (`bend_stiffness`; kept for the scene files that use
//!   them — the bending law is [`crate::bending`]): a linear spring of stiffness `k` (N/m) on each
//!   *bend pair* of a grid — vertices two apart along a row or a column,
//!   rest length their initial distance. An inextensible cloth can only fold,
//!   and folding brings a bend pair closer, so the spring pushes it back
//!   apart: `F_a = −k (|x_a − x_b| − L) (x_a − x_b)/|x_a − x_b|`, `F_b = −F_a`.
//!   Pairs are only pushed apart, never pulled together beyond `L`
//!   (inextensible structural edges hold that anyway). They have no stiffness
//!   about a flat sheet (a pair of a flat row is at its rest length to first
//!   order in a fold) and, explicit, need `k h²/m ≪ 1`.
//!
//! # Example
//!
//! ```
//! use modelgap_cloth::forces::ClothForces;
//! use modelgap_cloth::{ClothWorld, GridCloth, SolverParams};
//! use nalgebra::Vector3;
//!
//! let mut world = ClothWorld::new(SolverParams::default());
//! let cloth = world.add_cloth(GridCloth::new(5, 5, 0.1).pin(0))?;
//! let forces = ClothForces { drag_coefficient: 1.0, wind: Vector3::new(2.0, 0.0, 0.0), ..ClothForces::default() };
//! // The flat cloth lies in the x–z plane: a horizontal wind along x is in
//! // its plane and does not push it, gravity makes it fall.
//! forces.apply(&mut world, cloth, &[]);
//! world.step(0.01)?;
//! assert!(world.positions(cloth)[24].y < 0.0);
//! # Ok::<(), modelgap_cloth::ClothError>(())
//! ```

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::material::{Material, MaterialRegion, VertexMaterials};
use crate::world::{ClothId, ClothWorld};

/// Density of air at 15 °C and sea level (kg/m³).
pub const AIR_DENSITY: f64 = 1.225;

/// A pair of vertices joined by a bending spring, and its rest length (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BendPair {
    /// First vertex (index in the cloth's mesh).
    pub a: u32,
    /// Second vertex.
    pub b: u32,
    /// Rest length (m): the pair's initial distance.
    pub rest_length: f64,
}

/// The bend pairs of an `nx × nz` grid (vertex `row * nx + col`): vertices two
/// apart along each row and each column, with rest lengths from `positions`
/// (the grid's initial positions, one per vertex). Pairs whose vertex falls
/// outside `positions` are skipped.
#[must_use]
pub fn grid_bend_pairs(nx: usize, nz: usize, positions: &[Vector3<f64>]) -> Vec<BendPair> {
    let mut pairs = Vec::new();
    let mut push = |a: usize, b: usize| {
        if let (Some(xa), Some(xb)) = (positions.get(a), positions.get(b)) {
            pairs.push(BendPair {
                a: a as u32,
                b: b as u32,
                rest_length: (xa - xb).norm(),
            });
        }
    };
    for row in 0..nz {
        for col in 0..nx {
            let v = row * nx + col;
            if col + 2 < nx {
                push(v, v + 2);
            }
            if row + 2 < nz {
                push(v, v + 2 * nx);
            }
        }
    }
    pairs
}

/// Force terms evaluated at the start of each step (see the [module docs](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct ClothForces {
    /// Air density ρ (kg/m³); default [`AIR_DENSITY`].
    pub air_density: f64,
    /// Drag coefficient `C_d` of the cloth's triangles (dimensionless); default 0 (no drag).
    pub drag_coefficient: f64,
    /// Skin-friction coefficient `C_f` (dimensionless): drag on the velocity along the
    /// sheet relative to the air; default 0 (none).
    pub skin_friction: f64,
    /// Wind velocity `w` (m/s): drag acts on the velocity relative to it; default 0.
    pub wind: Vector3<f64>,
    /// Velocity damping rate `c` (1/s): force `−c m v` on each particle; default 0.
    pub damping: f64,
    /// Stiffness `k` (N/m) of the springs on the bend pairs; default 0 (no bending).
    pub bend_stiffness: f64,
}

impl Default for ClothForces {
    fn default() -> Self {
        Self {
            air_density: AIR_DENSITY,
            drag_coefficient: 0.0,
            skin_friction: 0.0,
            wind: Vector3::zeros(),
            damping: 0.0,
            bend_stiffness: 0.0,
        }
    }
}

impl ClothForces {
    /// Whether every term is off (no force besides gravity).
    #[must_use]
    pub fn is_none(&self) -> bool {
        self.drag_coefficient == 0.0
            && self.skin_friction == 0.0
            && self.damping == 0.0
            && self.bend_stiffness == 0.0
    }

    /// Writes the forces on a cloth's particles (N) for its current state
    /// into `out` (one per vertex, overwritten). `masses` (kg, one per vertex;
    /// 0 for static ones) weighs the damping; `triangles` and `bend` give the
    /// geometry (see [`grid_bend_pairs`]).
    pub fn evaluate(
        &self,
        positions: &[Vector3<f64>],
        velocities: &[Vector3<f64>],
        masses: &[f64],
        triangles: &[[u32; 3]],
        bend: &[BendPair],
        out: &mut [Vector3<f64>],
    ) {
        debug_assert!(positions.len() == velocities.len() && positions.len() == out.len());
        out.fill(Vector3::zeros());
        if self.damping != 0.0 {
            for ((f, v), m) in out.iter_mut().zip(velocities).zip(masses) {
                *f -= self.damping * m * v;
            }
        }
        if self.drag_coefficient != 0.0 || self.skin_friction != 0.0 {
            let k = 0.5 * self.air_density * self.drag_coefficient;
            let kt = 0.5 * self.air_density * self.skin_friction;
            for t in triangles {
                let [a, b, c] = t.map(|i| i as usize);
                // Twice the area times the unit normal.
                let n2 = (positions[b] - positions[a]).cross(&(positions[c] - positions[a]));
                let twice_area = n2.norm();
                if twice_area == 0.0 {
                    continue;
                }
                let n = n2 / twice_area;
                let v = (velocities[a] + velocities[b] + velocities[c]) / 3.0 - self.wind;
                let vn = v.dot(&n);
                let vt = v - n * vn;
                // −½ ρ A (C_d (v·n)|v·n| n + C_f |v_t| v_t), a third on each vertex.
                let area = 0.5 * twice_area;
                let f = n * (-k * area * vn * vn.abs() / 3.0) - vt * (kt * area * vt.norm() / 3.0);
                out[a] += f;
                out[b] += f;
                out[c] += f;
            }
        }
        if self.bend_stiffness != 0.0 {
            for p in bend {
                let (a, b) = (p.a as usize, p.b as usize);
                let d = positions[a] - positions[b];
                let len = d.norm();
                if len >= p.rest_length || len == 0.0 {
                    continue;
                }
                let f = d * (self.bend_stiffness * (p.rest_length - len) / len);
                out[a] += f;
                out[b] -= f;
            }
        }
    }

    /// Evaluates the forces on `cloth` in `world` now and sets them as the
    /// world's external forces for the next step. Static particles get none.
    pub fn apply(&self, world: &mut ClothWorld, cloth: ClothId, bend: &[BendPair]) {
        let Ok(first) = world.particle(cloth, 0) else {
            return;
        };
        let first = first.index();
        let n = world.positions(cloth).len();
        let masses: Vec<f64> = world.particles().inv_mass[first..first + n]
            .iter()
            .map(|&k| if k > 0.0 { 1.0 / k } else { 0.0 })
            .collect();
        let mut out = vec![Vector3::zeros(); n];
        self.evaluate(
            world.positions(cloth),
            world.velocities(cloth),
            &masses,
            world.triangles(cloth),
            bend,
            &mut out,
        );
        world.external_forces_mut()[first..first + n].copy_from_slice(&out);
    }
}

/// An extra point mass at a vertex (a sensor, a clip, a wet patch).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointMass {
    /// The vertex (index `row * nx + col`).
    pub vertex: u32,
    /// The mass added to the vertex's particle (kg).
    pub mass: f64,
}

/// The physical terms of a scene beyond gravity and the inextensible
/// cloth: the forces, the cloth's material (stretch compliance, warp and
/// weft, quadratic bending, and regions with their own), extra point masses.
/// All zero (none) by default: the paper's cloth.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClothEffects {
    /// Drag, wind, damping, bending springs.
    pub forces: ClothForces,
    /// Compliance of every distance constraint (m/N): stretch per newton
    /// of tension; 0 is inextensible.
    pub compliance: f64,
    /// Compliance of the links along a row (warp), instead of `compliance` (m/N).
    pub warp_compliance: Option<f64>,
    /// Compliance of the links along a column (weft), instead of `compliance` (m/N).
    pub weft_compliance: Option<f64>,
    /// Quadratic bending rigidity `B` (N·m, [`crate::bending`]); 0: none.
    pub bending_rigidity: f64,
    /// Regions with their own material, laid over the cloth's in order
    /// ([`crate::material`]).
    pub materials: Vec<MaterialRegion>,
    /// Extra masses at vertices.
    pub point_masses: Vec<PointMass>,
}

impl ClothEffects {
    /// The cloth's own material (the fields of `[cloth]`).
    #[must_use]
    pub fn base_material(&self) -> Material {
        Material {
            compliance: Some(self.compliance),
            warp_compliance: self.warp_compliance,
            weft_compliance: self.weft_compliance,
            bending_rigidity: Some(self.bending_rigidity),
            damping: Some(self.forces.damping),
        }
    }

    /// Whether the cloth's own compliance sets warp or weft apart.
    #[must_use]
    pub fn compliance_is_anisotropic(&self) -> bool {
        self.warp_compliance.is_some() || self.weft_compliance.is_some()
    }

    /// Every vertex's material on an `nx × nz` grid.
    #[must_use]
    pub fn vertex_materials(&self, nx: usize, nz: usize) -> VertexMaterials {
        VertexMaterials::resolve(&self.base_material(), &self.materials, nx, nz)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::GridCloth;
    use crate::solver::SolverParams;

    fn square() -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
        let x = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 0.0, 1.0),
        ];
        (x, vec![[0, 2, 1]])
    }

    #[test]
    fn drag_opposes_normal_velocity_with_the_quadratic_law() {
        let (x, tri) = square();
        // Triangle area ½ m², normal ±y; moving down at 2 m/s.
        let v = vec![Vector3::new(0.0, -2.0, 0.0); 3];
        let forces = ClothForces {
            drag_coefficient: 1.5,
            ..ClothForces::default()
        };
        let mut out = vec![Vector3::zeros(); 3];
        forces.evaluate(&x, &v, &[1.0; 3], &tri, &[], &mut out);
        let total: Vector3<f64> = out.iter().sum();
        // ½ ρ C_d A v² = ½ · 1.225 · 1.5 · 0.5 · 4, upward.
        let expected = 0.5 * AIR_DENSITY * 1.5 * 0.5 * 4.0;
        approx::assert_relative_eq!(total.y, expected, epsilon = 1e-12);
        approx::assert_relative_eq!(total.x.abs() + total.z.abs(), 0.0, epsilon = 1e-15);
        // In-plane motion feels no drag.
        let v = vec![Vector3::new(3.0, 0.0, 0.0); 3];
        forces.evaluate(&x, &v, &[1.0; 3], &tri, &[], &mut out);
        assert!(out.iter().all(|f| f.norm() == 0.0));
    }

    #[test]
    fn skin_friction_drags_a_sheet_sliding_in_its_own_plane() {
        let (x, tri) = square();
        let forces = ClothForces {
            drag_coefficient: 1.5,
            skin_friction: 0.4,
            ..ClothForces::default()
        };
        // Sliding along +x at 3 m/s: ½ ρ C_f A v² against it, nothing across.
        let v = vec![Vector3::new(3.0, 0.0, 0.0); 3];
        let mut out = vec![Vector3::zeros(); 3];
        forces.evaluate(&x, &v, &[1.0; 3], &tri, &[], &mut out);
        let total: Vector3<f64> = out.iter().sum();
        approx::assert_relative_eq!(
            total.x,
            -0.5 * AIR_DENSITY * 0.4 * 0.5 * 9.0,
            epsilon = 1e-12
        );
        approx::assert_relative_eq!(total.y.abs() + total.z.abs(), 0.0, epsilon = 1e-15);
        // Moving at 45°: each part sees its own component.
        let v = vec![Vector3::new(2.0, -2.0, 0.0); 3];
        forces.evaluate(&x, &v, &[1.0; 3], &tri, &[], &mut out);
        let total: Vector3<f64> = out.iter().sum();
        approx::assert_relative_eq!(
            total.y,
            0.5 * AIR_DENSITY * 1.5 * 0.5 * 4.0,
            epsilon = 1e-12
        );
        approx::assert_relative_eq!(
            total.x,
            -0.5 * AIR_DENSITY * 0.4 * 0.5 * 4.0,
            epsilon = 1e-12
        );
        // A wind along the sheet pulls a sheet at rest the way it moves.
        let windy = ClothForces {
            skin_friction: 0.4,
            wind: Vector3::new(0.0, 0.0, 2.0),
            ..ClothForces::default()
        };
        assert!(!windy.is_none());
        windy.evaluate(&x, &[Vector3::zeros(); 3], &[1.0; 3], &tri, &[], &mut out);
        let total: Vector3<f64> = out.iter().sum();
        approx::assert_relative_eq!(
            total.z,
            0.5 * AIR_DENSITY * 0.4 * 0.5 * 4.0,
            epsilon = 1e-12
        );
    }

    #[test]
    fn wind_pushes_a_cloth_at_rest_as_drag_pushes_a_moving_one() {
        let (x, tri) = square();
        let forces = ClothForces {
            drag_coefficient: 1.0,
            wind: Vector3::new(0.0, 2.0, 0.0),
            ..ClothForces::default()
        };
        let mut at_rest = vec![Vector3::zeros(); 3];
        forces.evaluate(
            &x,
            &[Vector3::zeros(); 3],
            &[1.0; 3],
            &tri,
            &[],
            &mut at_rest,
        );
        let still_air = ClothForces {
            drag_coefficient: 1.0,
            ..ClothForces::default()
        };
        let mut moving = vec![Vector3::zeros(); 3];
        let v = vec![Vector3::new(0.0, -2.0, 0.0); 3];
        still_air.evaluate(&x, &v, &[1.0; 3], &tri, &[], &mut moving);
        for (a, b) in at_rest.iter().zip(&moving) {
            approx::assert_relative_eq!(a, b, epsilon = 1e-15);
        }
    }

    #[test]
    fn damping_is_proportional_to_mass_and_velocity() {
        let (x, tri) = square();
        let v = vec![Vector3::new(1.0, 2.0, 3.0); 3];
        let forces = ClothForces {
            damping: 0.5,
            ..ClothForces::default()
        };
        let mut out = vec![Vector3::zeros(); 3];
        forces.evaluate(&x, &v, &[2.0, 0.0, 1.0], &tri, &[], &mut out);
        approx::assert_relative_eq!(out[0], -v[0], epsilon = 1e-15);
        assert_eq!(out[1], Vector3::zeros());
        approx::assert_relative_eq!(out[2], -0.5 * v[2], epsilon = 1e-15);
    }

    #[test]
    fn bend_springs_push_folded_pairs_apart_and_conserve_momentum() {
        let x: Vec<Vector3<f64>> = (0..9)
            .map(|i| Vector3::new((i % 3) as f64, 0.0, (i / 3) as f64))
            .collect();
        let pairs = grid_bend_pairs(3, 3, &x);
        // Rows and columns of 3 vertices: one pair each.
        assert_eq!(pairs.len(), 6);
        let mut folded = x.clone();
        folded[2] = Vector3::new(1.0, 1.0, 0.0); // row 0 folded at vertex 1
        let forces = ClothForces {
            bend_stiffness: 10.0,
            ..ClothForces::default()
        };
        let mut out = vec![Vector3::zeros(); 9];
        forces.evaluate(
            &folded,
            &[Vector3::zeros(); 9],
            &[1.0; 9],
            &[],
            &pairs,
            &mut out,
        );
        let total: Vector3<f64> = out.iter().sum();
        approx::assert_relative_eq!(total.norm(), 0.0, epsilon = 1e-12);
        // Vertex 0 is pushed away from vertex 2 (towards −x, −y).
        assert!(out[0].x < 0.0 && out[0].y < 0.0, "{:?}", out[0]);
        // Unfolded: no force.
        forces.evaluate(&x, &[Vector3::zeros(); 9], &[1.0; 9], &[], &pairs, &mut out);
        assert!(out.iter().all(|f| f.norm() == 0.0));
    }

    #[test]
    fn drag_slows_a_falling_cloth() {
        let fall = |cd: f64| {
            let mut world = ClothWorld::new(SolverParams::default());
            let cloth = world.add_cloth(GridCloth::new(4, 4, 0.1)).unwrap();
            let forces = ClothForces {
                drag_coefficient: cd,
                ..ClothForces::default()
            };
            for _ in 0..50 {
                forces.apply(&mut world, cloth, &[]);
                world.step(0.01).unwrap();
            }
            world.positions(cloth)[0].y
        };
        let free = fall(0.0);
        // Free fall for 0.5 s: ½ g t² (the scheme is exact for constant force).
        approx::assert_relative_eq!(free, -0.5 * 9.81 * 0.25, epsilon = 1e-9);
        assert!(fall(1.0) > free + 0.05);
    }
}

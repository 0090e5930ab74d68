//! Static colliders and contacts with Coulomb friction, resolved inside the
//! solver loop by the same preview as the distance constraints.
//!
//! # Shapes
//!
//! [`Shape::Plane`] (a half-space) and [`Shape::Ball`] are analytic;
//! [`Shape::Cuboid`], [`Shape::Capsule`] and [`Shape::TriMesh`] are answered
//! by parry (`parry3d-f64`) through the private `geometry` submodule, the one
//! module that converts between nalgebra and parry's math types. Every shape
//! gives a signed distance (negative inside) and the outward unit normal at
//! the closest surface point ([`Collider::signed_distance`]).
//!
//! A triangle mesh whose edges are each shared by exactly two triangles of
//! opposite orientation is **closed**: it is a solid, and a point is inside
//! when it is behind the angle-weighted pseudo-normal of its closest feature
//! (parry's oriented projection), however deep. Any other mesh is **open**: a
//! surface with a front (where its triangles' counter-clockwise normals point)
//! and no inside. A point penetrates it when it is behind the surface by at
//! most its shell thickness ([`DEFAULT_SHELL_THICKNESS`] unless given); a
//! point further behind is on the back side, outside. A cloth approaching an
//! open mesh from the back is stopped there by the preview below, but one
//! that rests on the back is pushed to the front once it comes within the
//! shell thickness: open meshes are meant to be met from the front (a floor,
//! a table top, a terrain). Along a boundary edge the shell ends in a rounded
//! lip: a point just beyond the edge and below the surface, within the shell
//! thickness of the edge, is pushed out radially from it, so cloth hanging
//! over the edge of an open mesh wraps a rounding of that radius.
//!
//! # Contacts
//!
//! The response lives in the private `solve` submodule. Each iteration
//! pushes every particle whose *predicted* end-of-step position lies inside a
//! collider back to its surface, along the surface normal (a normal impulse
//! applied at the start of the step), and removes up to `friction ×` that
//! normal correction of the particle's tangential motion over the step (the
//! Coulomb cone on impulses). The test is swept
//! ([`Collider::swept_distance`]): when the straight path from the
//! start-of-step position to the predicted one enters a collider, the
//! particle is held at the plane tangent to the surface where it entered, so
//! a particle cannot pass through a thin cuboid or a mesh in one step, however
//! fast it moves. After the step, the normal velocity into the surface is
//! removed and the tangential velocity is reduced by friction (an inelastic
//! contact).

mod geometry;
mod solve;

use std::sync::Arc;

use nalgebra::{Isometry3, Point3, Vector3};

use self::geometry::{Hit, MeshGeometry};
use crate::error::{ClothError, Result};

pub(crate) use self::solve::{ContactState, contact_velocities, max_penetration, project_contacts};

/// Shell thickness of an open triangle mesh unless given (m): a point up to
/// this far behind its surface penetrates it.
pub const DEFAULT_SHELL_THICKNESS: f64 = 0.01;

/// A particle this close to a collider's surface (m) is on it: a path that
/// starts there enters, if at all, where it starts. Well above the rounding of
/// a projected position, well below any contact tolerance.
pub const SURFACE_TOLERANCE: f64 = 1e-9;

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
    /// A solid box.
    Cuboid {
        /// Half the box's extent along each of its local axes (m).
        half_extents: Vector3<f64>,
        /// The box's pose: its centre (m) and the rotation of its local axes.
        world_from_local: Isometry3<f64>,
    },
    /// A solid capsule: the points within `radius` of the segment `a`–`b`.
    Capsule {
        /// One end of the axis (m).
        a: Vector3<f64>,
        /// The other end of the axis (m).
        b: Vector3<f64>,
        /// Radius (m).
        radius: f64,
    },
    /// A triangle mesh, closed (a solid) or open (a surface with a front).
    TriMesh(TriMeshShape),
}

/// A triangle mesh collider's data: vertices in its local frame, triangles,
/// pose, and the parry mesh built from them once.
#[derive(Clone, Debug)]
pub struct TriMeshShape {
    vertices: Vec<Vector3<f64>>,
    triangles: Vec<[u32; 3]>,
    world_from_local: Isometry3<f64>,
    shell_thickness: Option<f64>,
    geometry: Arc<MeshGeometry>,
    /// A ball holding every vertex, in the local frame: centre (m) and radius (m).
    bound: (Vector3<f64>, f64),
}

impl PartialEq for TriMeshShape {
    fn eq(&self, other: &Self) -> bool {
        // The parry mesh is a function of the rest.
        self.vertices == other.vertices
            && self.triangles == other.triangles
            && self.world_from_local == other.world_from_local
            && self.shell_thickness == other.shell_thickness
    }
}

impl TriMeshShape {
    /// Vertex positions in the mesh's local frame (m).
    #[must_use]
    pub fn vertices(&self) -> &[Vector3<f64>] {
        &self.vertices
    }

    /// Triangles as vertex indices, counter-clockwise seen from the front (outside).
    #[must_use]
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The mesh's pose.
    #[must_use]
    pub fn world_from_local(&self) -> &Isometry3<f64> {
        &self.world_from_local
    }

    /// Whether the mesh is closed (a solid): every edge is shared by exactly
    /// two triangles that run along it in opposite directions.
    #[must_use]
    pub fn is_closed(&self) -> bool {
        self.shell_thickness.is_none()
    }

    /// The shell thickness of an open mesh (m); `None` for a closed one.
    #[must_use]
    pub fn shell_thickness(&self) -> Option<f64> {
        self.shell_thickness
    }

    fn signed_distance(&self, x: &Vector3<f64>) -> (f64, Vector3<f64>) {
        let iso = &self.world_from_local;
        let local = iso.inverse_transform_vector(&(x - iso.translation.vector));
        let p = self.geometry.project(&local);
        let n = iso.rotation * p.normal;
        match (p.behind, self.shell_thickness) {
            (false, _) => (p.distance, n),
            (true, None) => (-p.distance, n),
            (true, Some(t)) if p.distance <= t => (-p.distance, n),
            // Beyond the shell, on the back side: outside, facing backwards.
            (true, Some(_)) => (p.distance, -n),
        }
    }

    fn ray(&self, origin: &Vector3<f64>, motion: &Vector3<f64>) -> Option<Hit> {
        let iso = &self.world_from_local;
        let local_origin = iso.inverse_transform_vector(&(origin - iso.translation.vector));
        let local_motion = iso.inverse_transform_vector(motion);
        let hit = self.geometry.ray(&local_origin, &local_motion)?;
        Some(Hit {
            normal: iso.rotation * hit.normal,
            ..hit
        })
    }
}

/// A static collider: a shape and a Coulomb friction coefficient.
#[derive(Clone, Debug, PartialEq)]
pub struct Collider {
    /// The geometry.
    pub shape: Shape,
    /// Coulomb friction coefficient (dimensionless); default 0.
    pub friction: f64,
}

fn vec_text(v: &Vector3<f64>) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

fn bad(shape: &'static str, field: impl Into<String>, expected: &str, found: String) -> ClothError {
    ClothError::BadCollider {
        shape,
        field: field.into(),
        expected: expected.into(),
        found,
    }
}

fn check_finite_vec(shape: &'static str, field: &str, v: &Vector3<f64>) -> Result<()> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(bad(shape, field, "finite", vec_text(v)))
    }
}

fn check_positive(shape: &'static str, field: &str, value: f64) -> Result<()> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(bad(shape, field, "positive and finite", value.to_string()))
    }
}

fn check_pose(shape: &'static str, iso: &Isometry3<f64>) -> Result<()> {
    check_finite_vec(
        shape,
        "world_from_local.translation",
        &iso.translation.vector,
    )?;
    let q = iso.rotation.quaternion();
    if q.coords.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(bad(
            shape,
            "world_from_local.rotation",
            "finite",
            format!("{q}"),
        ))
    }
}

/// Whether every edge of the triangles is used exactly once in each direction.
fn is_closed(triangles: &[[u32; 3]]) -> bool {
    let mut edges: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .collect();
    edges.sort_unstable();
    let unique = edges.windows(2).all(|w| w[0] != w[1]);
    unique
        && edges
            .iter()
            .all(|&(a, b)| edges.binary_search(&(b, a)).is_ok())
}

impl Collider {
    /// A solid ball of `radius` m at `center`, frictionless. [`check`](Self::check)
    /// tells whether the radius is usable.
    #[must_use]
    pub fn ball(center: Vector3<f64>, radius: f64) -> Self {
        Self {
            shape: Shape::Ball { center, radius },
            friction: 0.0,
        }
    }

    /// The half-space behind the plane through `point` with outward `normal`
    /// (normalised here; a zero or non-finite normal becomes +y, so validate
    /// user input before), frictionless.
    #[must_use]
    pub fn plane(point: Vector3<f64>, normal: Vector3<f64>) -> Self {
        let normal = normal
            .try_normalize(0.0)
            .filter(|n| n.iter().all(|c| c.is_finite()))
            .unwrap_or_else(Vector3::y);
        Self {
            shape: Shape::Plane { point, normal },
            friction: 0.0,
        }
    }

    /// A solid box of `half_extents` (m, along its local axes) placed by
    /// `world_from_local` (its centre and rotation), frictionless.
    ///
    /// # Errors
    /// [`ClothError::BadCollider`] for a half extent that is not positive and
    /// finite, or a non-finite pose.
    pub fn cuboid(half_extents: Vector3<f64>, world_from_local: Isometry3<f64>) -> Result<Self> {
        if !half_extents.iter().all(|&h| h > 0.0 && h.is_finite()) {
            return Err(bad(
                "cuboid",
                "half_extents",
                "positive and finite",
                vec_text(&half_extents),
            ));
        }
        check_pose("cuboid", &world_from_local)?;
        Ok(Self {
            shape: Shape::Cuboid {
                half_extents,
                world_from_local,
            },
            friction: 0.0,
        })
    }

    /// A solid capsule: the points within `radius` m of the segment `a`–`b`
    /// (equal ends make a ball), frictionless.
    ///
    /// # Errors
    /// [`ClothError::BadCollider`] for a non-finite end or a radius that is not
    /// positive and finite.
    pub fn capsule(a: Vector3<f64>, b: Vector3<f64>, radius: f64) -> Result<Self> {
        check_finite_vec("capsule", "a", &a)?;
        check_finite_vec("capsule", "b", &b)?;
        check_positive("capsule", "radius", radius)?;
        Ok(Self {
            shape: Shape::Capsule { a, b, radius },
            friction: 0.0,
        })
    }

    /// A triangle mesh of `vertices` (m) and `triangles` (vertex indices,
    /// counter-clockwise seen from outside), frictionless. A closed mesh is a
    /// solid; an open one has the shell thickness [`DEFAULT_SHELL_THICKNESS`]
    /// (see the [module docs](self)).
    ///
    /// # Errors
    /// [`ClothError::BadCollider`] for no triangles, a non-finite vertex, a
    /// triangle index out of range, or a degenerate triangle (repeated
    /// vertices or zero area).
    pub fn trimesh(vertices: Vec<Vector3<f64>>, triangles: Vec<[u32; 3]>) -> Result<Self> {
        Self::trimesh_with_shell(vertices, triangles, DEFAULT_SHELL_THICKNESS)
    }

    /// As [`trimesh`](Self::trimesh), with the shell thickness (m) an open mesh gets.
    ///
    /// # Errors
    /// As [`trimesh`](Self::trimesh), and [`ClothError::BadCollider`] for a
    /// shell thickness that is not positive and finite.
    pub fn trimesh_with_shell(
        vertices: Vec<Vector3<f64>>,
        triangles: Vec<[u32; 3]>,
        shell_thickness: f64,
    ) -> Result<Self> {
        const S: &str = "trimesh";
        check_positive(S, "shell_thickness", shell_thickness)?;
        if triangles.is_empty() {
            return Err(bad(S, "triangles", "at least one triangle", "none".into()));
        }
        for (i, v) in vertices.iter().enumerate() {
            check_finite_vec(S, &format!("vertices[{i}]"), v)?;
        }
        let n = vertices.len();
        let scale = vertices.iter().map(|v| v.amax()).fold(0.0_f64, f64::max);
        for (k, t) in triangles.iter().enumerate() {
            let field = || format!("triangles[{k}]");
            let found = || format!("[{}, {}, {}]", t[0], t[1], t[2]);
            if t.iter().any(|&v| v as usize >= n) {
                return Err(bad(
                    S,
                    field(),
                    &format!("vertex indices below {n} (the number of vertices)"),
                    found(),
                ));
            }
            let [a, b, c] = t.map(|v| vertices[v as usize]);
            // Relative to the mesh's size: a sliver this thin has no usable normal.
            let area2 = (b - a).cross(&(c - a)).norm();
            if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] || area2 <= 1e-14 * scale * scale {
                return Err(bad(
                    S,
                    field(),
                    "three distinct vertices spanning a non-zero area",
                    format!(
                        "{} at {}, {}, {}",
                        found(),
                        vec_text(&a),
                        vec_text(&b),
                        vec_text(&c)
                    ),
                ));
            }
        }
        let geometry = MeshGeometry::new(&vertices, &triangles)
            .map_err(|e| bad(S, "triangles", "a valid mesh", e.to_string()))?;
        let shell_thickness = (!is_closed(&triangles)).then_some(shell_thickness);
        let lo = vertices
            .iter()
            .fold(Vector3::repeat(f64::INFINITY), |m, v| m.inf(v));
        let hi = vertices
            .iter()
            .fold(Vector3::repeat(f64::NEG_INFINITY), |m, v| m.sup(v));
        let bound = ((lo + hi) / 2.0, (hi - lo).norm() / 2.0);
        Ok(Self {
            shape: Shape::TriMesh(TriMeshShape {
                vertices,
                triangles,
                world_from_local: Isometry3::identity(),
                shell_thickness,
                geometry: Arc::new(geometry),
                bound,
            }),
            friction: 0.0,
        })
    }

    /// A triangle mesh read from OBJ text (`v` and `f` lines, polygons fanned
    /// into triangles), as [`trimesh`](Self::trimesh).
    ///
    /// # Errors
    /// The OBJ reader's errors ([`ClothError::Obj`], [`ClothError::VertexOutOfRange`],
    /// [`ClothError::EmptyMesh`]) and those of [`trimesh`](Self::trimesh).
    pub fn trimesh_from_obj(reader: impl std::io::BufRead) -> Result<Self> {
        let mesh = crate::mesh::ClothMesh::from_obj(reader, crate::mesh::DEFAULT_PARTICLE_MASS)?;
        Self::trimesh(mesh.positions, mesh.triangles)
    }

    /// Sets the Coulomb friction coefficient.
    #[must_use]
    pub fn friction(mut self, mu: f64) -> Self {
        self.friction = mu;
        self
    }

    /// The same collider moved by `world_from_local` (applied after its own pose).
    #[must_use]
    pub fn transformed(mut self, world_from_local: &Isometry3<f64>) -> Self {
        let iso = world_from_local;
        let point = |p: &Vector3<f64>| (iso * Point3::from(*p)).coords;
        self.shape = match self.shape {
            Shape::Plane { point: p, normal } => Shape::Plane {
                point: point(&p),
                normal: iso.rotation * normal,
            },
            Shape::Ball { center, radius } => Shape::Ball {
                center: point(&center),
                radius,
            },
            Shape::Cuboid {
                half_extents,
                world_from_local: pose,
            } => Shape::Cuboid {
                half_extents,
                world_from_local: iso * pose,
            },
            Shape::Capsule { a, b, radius } => Shape::Capsule {
                a: point(&a),
                b: point(&b),
                radius,
            },
            Shape::TriMesh(mut mesh) => {
                mesh.world_from_local = iso * mesh.world_from_local;
                Shape::TriMesh(mesh)
            }
        };
        self
    }

    /// The shape's name as in scene files: `plane`, `ball`, `cuboid`, `capsule`, `trimesh`.
    #[must_use]
    pub fn shape_name(&self) -> &'static str {
        match self.shape {
            Shape::Plane { .. } => "plane",
            Shape::Ball { .. } => "ball",
            Shape::Cuboid { .. } => "cuboid",
            Shape::Capsule { .. } => "capsule",
            Shape::TriMesh(_) => "trimesh",
        }
    }

    /// Checks that the collider can be used: finite positions, a unit plane
    /// normal, positive radii and extents, a non-negative finite friction.
    /// The fallible constructors already check their fields; this catches a
    /// ball or a plane built with bad numbers, or fields edited afterwards.
    ///
    /// # Errors
    /// [`ClothError::BadCollider`] naming the shape and the field.
    pub fn check(&self) -> Result<()> {
        let name = self.shape_name();
        if !(self.friction >= 0.0 && self.friction.is_finite()) {
            return Err(bad(
                name,
                "friction",
                "non-negative and finite",
                self.friction.to_string(),
            ));
        }
        match &self.shape {
            Shape::Plane { point, normal } => {
                check_finite_vec(name, "point", point)?;
                // False for a NaN normal too.
                let unit = (normal.norm() - 1.0).abs() <= 1e-9;
                if !unit {
                    return Err(bad(name, "normal", "a unit vector", vec_text(normal)));
                }
            }
            Shape::Ball { center, radius } => {
                check_finite_vec(name, "center", center)?;
                check_positive(name, "radius", *radius)?;
            }
            Shape::Cuboid {
                half_extents,
                world_from_local,
            } => {
                Self::cuboid(*half_extents, *world_from_local)?;
            }
            Shape::Capsule { a, b, radius } => {
                Self::capsule(*a, *b, *radius)?;
            }
            Shape::TriMesh(mesh) => check_pose(name, &mesh.world_from_local)?,
        }
        Ok(())
    }

    /// Whether every point within `margin` m of `x` is certainly outside the
    /// collider, by a bounding ball (a cheap test that spares the exact query
    /// for particles far from a mesh, a box or a capsule; always `false` for
    /// the analytic plane and ball).
    fn clearly_outside(&self, x: &Vector3<f64>, margin: f64) -> bool {
        let (center, radius) = match &self.shape {
            Shape::Plane { .. } | Shape::Ball { .. } => return false,
            Shape::Cuboid {
                half_extents,
                world_from_local,
            } => (world_from_local.translation.vector, half_extents.norm()),
            Shape::Capsule { a, b, radius } => ((a + b) / 2.0, (b - a).norm() / 2.0 + radius),
            Shape::TriMesh(mesh) => {
                let (c, r) = mesh.bound;
                ((mesh.world_from_local * Point3::from(c)).coords, r)
            }
        };
        (x - center).norm() > radius + margin
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
            Shape::Cuboid {
                half_extents,
                world_from_local: iso,
            } => {
                let local = iso.inverse_transform_vector(&(x - iso.translation.vector));
                let (phi, n) = geometry::cuboid_signed_distance(half_extents, &local);
                (phi, iso.rotation * n)
            }
            Shape::Capsule { a, b, radius } => geometry::capsule_signed_distance(a, b, *radius, x),
            Shape::TriMesh(mesh) => mesh.signed_distance(x),
        }
    }

    /// The first point where the segment `origin → origin + motion` (m) meets
    /// the surface, for an origin outside: the fraction of `motion` travelled
    /// and the unit normal facing the origin.
    fn ray(&self, origin: &Vector3<f64>, motion: &Vector3<f64>) -> Option<Hit> {
        match &self.shape {
            // A half-space has no far side: the signed distance is exact.
            Shape::Plane { .. } => None,
            Shape::Ball { center, radius } => {
                // |o + s m − c|² = r², smallest root in [0, 1].
                let oc = origin - center;
                let a = motion.norm_squared();
                let b = oc.dot(motion);
                let c = oc.norm_squared() - radius * radius;
                let disc = b * b - a * c;
                if a == 0.0 || disc < 0.0 {
                    return None;
                }
                let s = (-b - disc.sqrt()) / a;
                if !(0.0..=1.0).contains(&s) {
                    return None;
                }
                let normal = (oc + s * motion).try_normalize(0.0)?;
                Some(Hit {
                    fraction: s,
                    normal,
                })
            }
            Shape::Cuboid {
                half_extents,
                world_from_local: iso,
            } => {
                let local_origin = iso.inverse_transform_vector(&(origin - iso.translation.vector));
                let local_motion = iso.inverse_transform_vector(motion);
                let hit = geometry::cuboid_ray(half_extents, &local_origin, &local_motion)?;
                Some(Hit {
                    normal: iso.rotation * hit.normal,
                    ..hit
                })
            }
            Shape::Capsule { a, b, radius } => geometry::capsule_ray(a, b, *radius, origin, motion),
            Shape::TriMesh(mesh) => mesh.ray(origin, motion),
        }
    }

    /// The signed distance (m, negative when penetrating) and outward unit
    /// normal of a particle's predicted position `end`, given that it moves in
    /// a straight line from `start` over the step (the preview).
    ///
    /// Equal to [`signed_distance`](Self::signed_distance)`(end)` unless the
    /// path enters the collider from outside (or from the surface, within
    /// [`SURFACE_TOLERANCE`]) and the closest surface of `end` faces away from
    /// the entry (it crossed a thin part, or passed right through): then it is
    /// the distance of `end` to the plane tangent to the surface at the entry
    /// point, with that plane's normal, so that pushing `end` out along the
    /// normal keeps the particle on the side it came from. Nothing tunnels,
    /// however fast it moves; a path that only dips under a curved surface (a
    /// particle sliding over a ball) is judged by its end alone.
    #[must_use]
    pub fn swept_distance(&self, start: &Vector3<f64>, end: &Vector3<f64>) -> (f64, Vector3<f64>) {
        let (phi_end, n_end) = self.signed_distance(end);
        let motion = end - start;
        let reach = motion.norm();
        // Every point of the path is within `reach` of `end`: none can touch
        // the surface when `end` is further outside than that.
        if phi_end > reach || reach == 0.0 || matches!(self.shape, Shape::Plane { .. }) {
            return (phi_end, n_end);
        }
        let (phi_start, n_start) = self.signed_distance(start);
        if phi_start < -SURFACE_TOLERANCE || phi_start > reach {
            // Already inside (only the closest surface can free it), or too far to reach.
            return (phi_end, n_end);
        }
        let hit = if phi_start <= SURFACE_TOLERANCE {
            // Resting on the surface: the path enters (if at all) where it starts.
            Hit {
                fraction: 0.0,
                normal: n_start,
            }
        } else {
            match self.ray(start, &motion) {
                Some(hit) => hit,
                None => return (phi_end, n_end),
            }
        };
        // The closest surface of `end` faces away from the entry: it crossed a
        // thin part or passed right through. Facing the same way, the path only
        // dipped under a curved surface (a chord of a ball) or `end` is inside
        // near where it entered, and the closest surface is the right one.
        let facing = n_end.dot(&hit.normal);
        let crossed = if phi_end < 0.0 {
            facing <= 0.0
        } else {
            facing < 0.0
        };
        if !crossed {
            return (phi_end, n_end);
        }
        let entry = start + hit.fraction * motion;
        ((end - entry).dot(&hit.normal).min(0.0), hit.normal)
    }
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
    fn closed_means_every_edge_once_each_way() {
        // A tetrahedron, outward.
        let tet = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
        assert!(is_closed(&tet));
        assert!(!is_closed(&tet[..3]), "a missing face opens it");
        let flipped = [[0, 1, 2], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
        assert!(
            !is_closed(&flipped),
            "a flipped face runs an edge twice one way"
        );
    }

    #[test]
    fn ball_ray_hits_the_near_side_within_the_segment() {
        let ball = Collider::ball(Vector3::zeros(), 1.0);
        let hit = ball
            .ray(&Vector3::new(0.0, 3.0, 0.0), &Vector3::new(0.0, -4.0, 0.0))
            .unwrap();
        approx::assert_relative_eq!(hit.fraction, 0.5, epsilon = 1e-15);
        approx::assert_relative_eq!(hit.normal, Vector3::y(), epsilon = 1e-15);
        assert!(
            ball.ray(&Vector3::new(0.0, 3.0, 0.0), &Vector3::new(0.0, -1.5, 0.0))
                .is_none(),
            "the segment ends before the ball"
        );
    }

    #[test]
    fn transformed_moves_every_shape_alike() {
        let iso = Isometry3::new(Vector3::new(1.0, 2.0, 3.0), Vector3::new(0.2, -0.4, 0.1));
        let x = Vector3::new(0.3, 0.1, -0.2);
        let moved = (iso * Point3::from(x)).coords;
        let tri = vec![Vector3::zeros(), Vector3::x(), Vector3::z()];
        let shapes = [
            Collider::plane(Vector3::zeros(), Vector3::new(0.0, 1.0, 0.2)),
            Collider::ball(Vector3::new(0.1, 0.0, 0.0), 0.5),
            Collider::cuboid(Vector3::new(0.4, 0.2, 0.3), Isometry3::identity()).unwrap(),
            Collider::capsule(Vector3::zeros(), Vector3::y(), 0.2).unwrap(),
            Collider::trimesh(tri, vec![[0, 2, 1]]).unwrap(),
        ];
        for c in shapes {
            let (phi, n) = c.signed_distance(&x);
            let (phi_moved, n_moved) = c.clone().transformed(&iso).signed_distance(&moved);
            approx::assert_relative_eq!(phi_moved, phi, epsilon = 1e-12);
            approx::assert_relative_eq!(n_moved, iso.rotation * n, epsilon = 1e-12);
        }
    }
}

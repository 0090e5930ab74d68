//! The parry queries behind the cuboid, capsule and triangle-mesh colliders.
//!
//! This is the one module that sees parry's math types (glam-based `DVec3` in
//! parry 0.31): everything enters and leaves as nalgebra `Vector3<f64>`, in
//! the shape's local frame (the caller applies the pose). When parry changes
//! its math types again, this file absorbs the change.

use nalgebra::Vector3;
use parry3d_f64::math::Vector;
use parry3d_f64::query::{PointQuery as _, PointQueryWithLocation as _, Ray, RayCast as _};
use parry3d_f64::shape::{
    Capsule, Cuboid, Segment, Shape as _, TriMesh, TriMeshBuilderError, TriMeshFlags,
};

/// Distances below this are "on the surface" (m): there the direction from the
/// surface to the point is undefined and the shape's own normal is used.
pub(crate) const ON_SURFACE: f64 = 1e-12;

fn to_parry(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x, v.y, v.z)
}

fn from_parry(v: Vector) -> Vector3<f64> {
    Vector3::new(v.x, v.y, v.z)
}

/// A ray hit: the fraction of the ray's direction travelled (dimensionless,
/// `0..=1` for a segment) and the unit surface normal facing the ray's origin.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Hit {
    pub(crate) fraction: f64,
    pub(crate) normal: Vector3<f64>,
}

/// A unit normal facing the ray origin: parry's normal, flipped if it points along the ray.
fn facing(normal: Vector, dir: &Vector3<f64>) -> Option<Vector3<f64>> {
    let n = from_parry(normal).try_normalize(0.0)?;
    Some(if n.dot(dir) > 0.0 { -n } else { n })
}

/// Signed distance (m, negative inside) and outward unit normal of a point
/// `local` (m, cuboid frame) to the cuboid of `half_extents` (m) centred at the origin.
pub(crate) fn cuboid_signed_distance(
    half_extents: &Vector3<f64>,
    local: &Vector3<f64>,
) -> (f64, Vector3<f64>) {
    let cuboid = Cuboid::new(to_parry(half_extents));
    let x = to_parry(local);
    let (proj, feature) = cuboid.project_local_point_and_get_feature(x);
    let d = from_parry(x - proj.point);
    let dist = d.norm();
    let sign = if proj.is_inside { -1.0 } else { 1.0 };
    if dist > ON_SURFACE {
        return (sign * dist, sign * d / dist);
    }
    let n = cuboid
        .feature_normal_at_point(0, feature, proj.point)
        .and_then(|n| from_parry(n).try_normalize(0.0))
        .unwrap_or_else(|| largest_axis(local, half_extents));
    (sign * dist, n)
}

/// The face normal of the cuboid face whose plane `local` is relatively closest to.
fn largest_axis(local: &Vector3<f64>, half_extents: &Vector3<f64>) -> Vector3<f64> {
    let ratio = local.component_div(half_extents);
    let i = ratio.iamax();
    let mut n = Vector3::zeros();
    n[i] = ratio[i].signum();
    n
}

/// The first hit of the segment `origin → origin + dir` (cuboid frame, m)
/// with the cuboid's surface, for an origin outside.
pub(crate) fn cuboid_ray(
    half_extents: &Vector3<f64>,
    origin: &Vector3<f64>,
    dir: &Vector3<f64>,
) -> Option<Hit> {
    let cuboid = Cuboid::new(to_parry(half_extents));
    let ray = Ray::new(to_parry(origin), to_parry(dir));
    let hit = cuboid.cast_local_ray_and_get_normal(&ray, 1.0, true)?;
    Some(Hit {
        fraction: hit.time_of_impact,
        normal: facing(hit.normal, dir)?,
    })
}

/// Signed distance (m, negative inside) and outward unit normal of `x` (m) to
/// the capsule of axis `a → b` (m) and `radius` (m).
pub(crate) fn capsule_signed_distance(
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    radius: f64,
    x: &Vector3<f64>,
) -> (f64, Vector3<f64>) {
    let capsule = Capsule::new(to_parry(a), to_parry(b), radius);
    let p = to_parry(x);
    let proj = capsule.project_local_point(p, false);
    let dist = from_parry(p - proj.point).norm();
    let sign = if proj.is_inside { -1.0 } else { 1.0 };
    // The normal at the surface point is the direction from the axis to it,
    // defined even where the point itself is on the surface or on the axis.
    let axis = Segment::new(to_parry(a), to_parry(b))
        .project_local_point(proj.point, true)
        .point;
    let n = from_parry(proj.point - axis)
        .try_normalize(0.0)
        .unwrap_or_else(Vector3::y);
    (sign * dist, n)
}

/// The first hit of the segment `origin → origin + dir` (m) with the capsule's
/// surface, for an origin outside.
pub(crate) fn capsule_ray(
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    radius: f64,
    origin: &Vector3<f64>,
    dir: &Vector3<f64>,
) -> Option<Hit> {
    let capsule = Capsule::new(to_parry(a), to_parry(b), radius);
    let ray = Ray::new(to_parry(origin), to_parry(dir));
    let hit = capsule.cast_local_ray_and_get_normal(&ray, 1.0, true)?;
    Some(Hit {
        fraction: hit.time_of_impact,
        normal: facing(hit.normal, dir)?,
    })
}

/// The closest point of a triangle mesh to a query point.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MeshProjection {
    /// Distance to the surface (m, ≥ 0).
    pub(crate) distance: f64,
    /// Whether the point is behind the surface, by the angle-weighted
    /// pseudo-normal of the closest feature (the triangle's, an edge's or a vertex's).
    pub(crate) behind: bool,
    /// Unit normal at the closest point, on the front (outward) side.
    pub(crate) normal: Vector3<f64>,
}

/// A parry triangle mesh with pseudo-normals (for the behind test) and a BVH.
#[derive(Clone)]
pub(crate) struct MeshGeometry {
    mesh: TriMesh,
}

impl std::fmt::Debug for MeshGeometry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MeshGeometry")
            .field("n_triangles", &self.mesh.num_triangles())
            .finish()
    }
}

impl MeshGeometry {
    /// Builds the mesh; vertices (m, local frame) and triangles must already be
    /// checked (finite, indices in range, non-degenerate).
    pub(crate) fn new(
        vertices: &[Vector3<f64>],
        triangles: &[[u32; 3]],
    ) -> Result<Self, TriMeshBuilderError> {
        let vertices = vertices.iter().map(to_parry).collect();
        let mesh = TriMesh::with_flags(vertices, triangles.to_vec(), TriMeshFlags::ORIENTED)?;
        Ok(Self { mesh })
    }

    /// The closest point of the mesh to `local` (m, mesh frame).
    pub(crate) fn project(&self, local: &Vector3<f64>) -> MeshProjection {
        let x = to_parry(local);
        let (proj, (triangle, _)) = self.mesh.project_local_point_and_get_location(x, false);
        let d = from_parry(x - proj.point);
        let distance = d.norm();
        let face = || {
            self.mesh
                .triangle(triangle)
                .normal()
                .map_or_else(Vector3::y, from_parry)
        };
        let normal = if distance > ON_SURFACE {
            if proj.is_inside {
                -d / distance
            } else {
                d / distance
            }
        } else {
            face()
        };
        MeshProjection {
            distance,
            behind: proj.is_inside,
            normal,
        }
    }

    /// The first hit of the segment `origin → origin + dir` (m, mesh frame)
    /// with any triangle, from either side.
    pub(crate) fn ray(&self, origin: &Vector3<f64>, dir: &Vector3<f64>) -> Option<Hit> {
        let ray = Ray::new(to_parry(origin), to_parry(dir));
        let hit = self.mesh.cast_local_ray_and_get_normal(&ray, 1.0, true)?;
        Some(Hit {
            fraction: hit.time_of_impact,
            normal: facing(hit.normal, dir)?,
        })
    }
}

//! Cloth meshes: the grid builder, OBJ triangle meshes, and the vertex numbering.
//!
//! A grid of `nx × nz` vertices lies in its local x–z plane: vertex (col, row)
//! has index `row * nx + col`, col along +x, row along +z (the numbering of
//! marker files). `world_from_local` places it in the world.

use std::collections::BTreeSet;
use std::io::BufRead;

use nalgebra::{Isometry3, Point3, Vector3};

use crate::error::{ClothError, Result};

/// Mass of one particle by default (kg): 1 g, as in the reference scenes.
pub const DEFAULT_PARTICLE_MASS: f64 = 1e-3;

/// The largest grid built by default (the field `GridCloth::max_particles`): 1 000 000
/// particles, a 1000 × 1000 grid, 11 times the largest grid the solver is measured on
/// (300 × 300, 1.8 s per Newton step). Raise the limit to go further.
pub const DEFAULT_MAX_PARTICLES: usize = 1_000_000;

/// The most particles any cloth can have, whatever its limit says: vertex indices are `u32`.
pub const MAX_VERTICES: usize = u32::MAX as usize;

/// A cloth ready to be added to a world: a particle per vertex, a distance
/// constraint per unique edge, and the pinned (static) vertices.
#[derive(Clone, Debug, Default)]
pub struct ClothMesh {
    /// Vertex positions in the world (m).
    pub positions: Vec<Vector3<f64>>,
    /// Mass of each vertex's particle (kg).
    pub masses: Vec<f64>,
    /// Unique edges as vertex pairs, smaller index first, sorted.
    pub edges: Vec<[u32; 2]>,
    /// Triangles (for rendering and export), vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// Pinned vertices, sorted and unique.
    pub pinned: Vec<u32>,
}

/// Anything that can produce a [`ClothMesh`]: a [`GridCloth`] or a mesh itself.
pub trait BuildMesh {
    /// Builds (and checks) the mesh.
    ///
    /// # Errors
    /// [`ClothError`] when the description cannot make a mesh (see the implementor).
    fn build_mesh(&self) -> Result<ClothMesh>;
}

impl BuildMesh for ClothMesh {
    fn build_mesh(&self) -> Result<ClothMesh> {
        Ok(self.clone())
    }
}

impl ClothMesh {
    /// Reads an OBJ triangle (or polygon) mesh: `v x y z` lines become
    /// particles of `particle_mass` kg, each face's edges become unique
    /// constraints (polygons are fanned into triangles). Face indices count from 1;
    /// negative ones count back from the last vertex defined so far (`-1` is the last),
    /// as OBJ allows. Other lines are ignored.
    ///
    /// # Errors
    /// [`ClothError::Obj`] for a malformed line, [`ClothError::ObjIndex`] (with the line
    /// and the index as written) for a face index that names no vertex defined before
    /// the face, [`ClothError::EmptyMesh`] when there are no faces.
    pub fn from_obj(reader: impl BufRead, particle_mass: f64) -> Result<Self> {
        check_positive("particle_mass", particle_mass)?;
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for (k, line) in reader.lines().enumerate() {
            let line_no = k + 1;
            let line = line.map_err(|e| ClothError::Obj {
                line: line_no,
                message: e.to_string(),
            })?;
            let mut words = line.split_whitespace();
            match words.next() {
                Some("v") => {
                    let mut xyz = [0.0; 3];
                    for c in &mut xyz {
                        let w = words.next().ok_or_else(|| ClothError::Obj {
                            line: line_no,
                            message: "expected 3 coordinates after 'v'".into(),
                        })?;
                        *c = w.parse::<f64>().map_err(|_| ClothError::Obj {
                            line: line_no,
                            message: format!("expected a number, found '{w}'"),
                        })?;
                        if !c.is_finite() {
                            return Err(ClothError::Obj {
                                line: line_no,
                                message: format!("coordinate '{w}' is not finite"),
                            });
                        }
                    }
                    positions.push(Vector3::new(xyz[0], xyz[1], xyz[2]));
                }
                Some("f") => {
                    let mut face = Vec::new();
                    for w in words {
                        let first = w.split('/').next().unwrap_or("");
                        let idx: i64 = first.parse().map_err(|_| ClothError::Obj {
                            line: line_no,
                            message: format!("expected a vertex index, found '{w}'"),
                        })?;
                        // 1-based; negative counts back from the last vertex so far (-1).
                        let n = positions.len() as i64;
                        let zero_based = if idx < 0 { n + idx } else { idx - 1 };
                        if zero_based < 0 || zero_based >= n {
                            return Err(ClothError::ObjIndex {
                                line: line_no,
                                index: idx,
                                n_vertices: positions.len(),
                                path: None,
                            });
                        }
                        face.push(zero_based as u32);
                    }
                    if face.len() < 3 {
                        return Err(ClothError::Obj {
                            line: line_no,
                            message: format!(
                                "a face needs at least 3 vertices, found {}",
                                face.len()
                            ),
                        });
                    }
                    for k in 1..face.len() - 1 {
                        triangles.push([face[0], face[k], face[k + 1]]);
                    }
                }
                _ => {}
            }
        }
        let mut edges = BTreeSet::new();
        for t in &triangles {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                if a != b {
                    edges.insert([a.min(b), a.max(b)]);
                }
            }
        }
        let mesh = Self {
            masses: vec![particle_mass; positions.len()],
            positions,
            edges: edges.into_iter().collect(),
            triangles,
            pinned: Vec::new(),
        };
        mesh.check()?;
        Ok(mesh)
    }

    /// Pins a vertex (makes its particle static).
    ///
    /// # Errors
    /// [`ClothError::VertexOutOfRange`] when the vertex does not exist.
    pub fn pin(&mut self, vertex: u32) -> Result<()> {
        if vertex as usize >= self.positions.len() {
            return Err(ClothError::VertexOutOfRange {
                vertex: vertex as usize,
                n_vertices: self.positions.len(),
            });
        }
        if let Err(at) = self.pinned.binary_search(&vertex) {
            self.pinned.insert(at, vertex);
        }
        Ok(())
    }

    /// Checks what a world needs: particles and edges exist, indices are in
    /// range, edges have length, masses are positive. An edge between two pins is allowed:
    /// it is not a constraint ([`ClothWorld::add_cloth`](crate::ClothWorld::add_cloth)
    /// leaves it out), so whole rows, borders and regions can be pinned.
    ///
    /// # Errors
    /// The first problem found, as a typed [`ClothError`].
    pub fn check(&self) -> Result<()> {
        let n = self.positions.len();
        if n == 0 || self.edges.is_empty() {
            return Err(ClothError::EmptyMesh {
                n_particles: n,
                n_edges: self.edges.len(),
            });
        }
        if self.masses.len() != n {
            return Err(ClothError::BadParameter {
                name: "masses",
                expected: "one mass per vertex",
                value: self.masses.len() as f64,
            });
        }
        for (i, p) in self.positions.iter().enumerate() {
            if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
                return Err(ClothError::NonFinite {
                    particle: i as u32,
                    what: "position",
                    x: p.x,
                    y: p.y,
                    z: p.z,
                });
            }
        }
        for &m in &self.masses {
            check_positive("particle mass", m)?;
        }
        for &v in &self.pinned {
            if v as usize >= n {
                return Err(ClothError::VertexOutOfRange {
                    vertex: v as usize,
                    n_vertices: n,
                });
            }
        }
        for &[a, b] in &self.edges {
            for v in [a, b] {
                if v as usize >= n {
                    return Err(ClothError::VertexOutOfRange {
                        vertex: v as usize,
                        n_vertices: n,
                    });
                }
            }
            if a == b {
                return Err(ClothError::DegenerateEdge { a });
            }
            if (self.positions[a as usize] - self.positions[b as usize]).norm() <= 0.0 {
                return Err(ClothError::ZeroLengthEdge { a, b });
            }
        }
        Ok(())
    }
}

/// Which edges of a grid become constraints.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GridEdges {
    /// Both diagonals of each cell.
    pub shear: bool,
    /// Edges skipping one vertex along x and z.
    pub bend: bool,
}

/// A builder for a rectangular grid cloth of `nx × nz` vertices with
/// structural edges (and optional shear and bend edges).
///
/// # Example
/// ```
/// use modelgap_cloth::{BuildMesh, GridCloth};
/// let mesh = GridCloth::new(30, 30, 1.0 / 29.0).pin(0).build_mesh()?;
/// assert_eq!((mesh.positions.len(), mesh.edges.len()), (900, 1740));
/// # Ok::<(), modelgap_cloth::ClothError>(())
/// ```
#[derive(Clone, Debug)]
#[must_use]
pub struct GridCloth {
    /// Vertices along local x (columns).
    pub nx: usize,
    /// Vertices along local z (rows).
    pub nz: usize,
    /// Distance between neighbouring vertices (m).
    pub spacing: f64,
    /// Mass of each particle (kg); default [`DEFAULT_PARTICLE_MASS`].
    pub particle_mass: f64,
    /// Extra edges beyond the structural ones; default none.
    pub edges: GridEdges,
    /// Placement of the grid's local frame in the world; default identity.
    pub world_from_local: Isometry3<f64>,
    /// Pinned vertices (indices `row * nx + col`).
    pub pinned: Vec<u32>,
    /// The most particles (`nx × nz`) [`build_mesh`](BuildMesh::build_mesh) accepts, checked
    /// before anything is allocated; default [`DEFAULT_MAX_PARTICLES`] (1 000 000). Values
    /// past [`MAX_VERTICES`] act as [`MAX_VERTICES`].
    pub max_particles: usize,
}

impl GridCloth {
    /// A flat grid of `nx × nz` vertices, `spacing` m apart, 1 g per particle,
    /// structural edges only, at the origin.
    pub fn new(nx: usize, nz: usize, spacing: f64) -> Self {
        Self {
            nx,
            nz,
            spacing,
            particle_mass: DEFAULT_PARTICLE_MASS,
            edges: GridEdges::default(),
            world_from_local: Isometry3::identity(),
            pinned: Vec::new(),
            max_particles: DEFAULT_MAX_PARTICLES,
        }
    }

    /// Sets the most particles the grid may have (the field `max_particles`).
    pub fn max_particles(mut self, n: usize) -> Self {
        self.max_particles = n;
        self
    }

    /// The number of vertices, `nx × nz`, checked: at least 2 × 2 and at most
    /// `max_particles` (and [`MAX_VERTICES`]).
    ///
    /// # Errors
    /// [`ClothError::BadGrid`] for fewer than 2 × 2 vertices,
    /// [`ClothError::TooManyParticles`] past the limit.
    pub fn n_vertices(&self) -> Result<usize> {
        grid_size(self.nx, self.nz, self.max_particles)
    }

    /// The index of vertex (col, row): `row * nx + col`.
    #[must_use]
    pub fn vertex(&self, col: usize, row: usize) -> u32 {
        (row * self.nx + col) as u32
    }

    /// Sets the mass of each particle (kg).
    pub fn particle_mass(mut self, kg: f64) -> Self {
        self.particle_mass = kg;
        self
    }

    /// Adds both diagonals of each cell as constraints.
    pub fn shear(mut self, on: bool) -> Self {
        self.edges.shear = on;
        self
    }

    /// Adds edges skipping one vertex along x and z as constraints.
    pub fn bend(mut self, on: bool) -> Self {
        self.edges.bend = on;
        self
    }

    /// Places the grid in the world.
    pub fn world_from_local(mut self, iso: Isometry3<f64>) -> Self {
        self.world_from_local = iso;
        self
    }

    /// Pins vertex `vertex` (index `row * nx + col`).
    pub fn pin(mut self, vertex: u32) -> Self {
        self.pinned.push(vertex);
        self
    }

    /// Pins every vertex of row `row` (all columns).
    pub fn pin_row(mut self, row: usize) -> Self {
        for col in 0..self.nx {
            self.pinned.push((row * self.nx + col) as u32);
        }
        self
    }
}

impl BuildMesh for GridCloth {
    /// # Errors
    /// [`ClothError::BadGrid`] for fewer than 2 × 2 vertices,
    /// [`ClothError::TooManyParticles`] for more than
    /// `max_particles` (checked before anything is allocated),
    /// [`ClothError::BadParameter`] for a non-positive spacing or mass,
    /// and [`ClothError::VertexOutOfRange`] for a pin past the grid. Pins may be
    /// neighbours (a whole row): the edge between them is not a constraint.
    fn build_mesh(&self) -> Result<ClothMesh> {
        let (nx, nz) = (self.nx, self.nz);
        self.n_vertices()?;
        check_positive("spacing", self.spacing)?;
        check_positive("particle_mass", self.particle_mass)?;
        let idx = |col: usize, row: usize| (row * nx + col) as u32;
        let mut positions = Vec::with_capacity(nx * nz);
        for row in 0..nz {
            for col in 0..nx {
                let local = Point3::new(col as f64 * self.spacing, 0.0, row as f64 * self.spacing);
                positions.push((self.world_from_local * local).coords);
            }
        }
        let mut edges = Vec::new();
        for row in 0..nz {
            for col in 0..nx {
                if col + 1 < nx {
                    edges.push([idx(col, row), idx(col + 1, row)]);
                }
                if row + 1 < nz {
                    edges.push([idx(col, row), idx(col, row + 1)]);
                }
                if self.edges.shear && col + 1 < nx && row + 1 < nz {
                    edges.push([idx(col, row), idx(col + 1, row + 1)]);
                    edges.push([idx(col + 1, row), idx(col, row + 1)]);
                }
                if self.edges.bend {
                    if col + 2 < nx {
                        edges.push([idx(col, row), idx(col + 2, row)]);
                    }
                    if row + 2 < nz {
                        edges.push([idx(col, row), idx(col, row + 2)]);
                    }
                }
            }
        }
        let mut triangles = Vec::with_capacity(2 * (nx - 1) * (nz - 1));
        for row in 0..nz - 1 {
            for col in 0..nx - 1 {
                triangles.push([idx(col, row), idx(col, row + 1), idx(col + 1, row)]);
                triangles.push([idx(col + 1, row), idx(col, row + 1), idx(col + 1, row + 1)]);
            }
        }
        let mut mesh = ClothMesh {
            masses: vec![self.particle_mass; positions.len()],
            positions,
            edges,
            triangles,
            pinned: Vec::new(),
        };
        for &v in &self.pinned {
            mesh.pin(v)?;
        }
        mesh.check()?;
        Ok(mesh)
    }
}

/// `nx × nz`, checked: at least 2 × 2, at most `max_particles` (and [`MAX_VERTICES`]).
pub(crate) fn grid_size(nx: usize, nz: usize, max_particles: usize) -> Result<usize> {
    if nx < 2 || nz < 2 {
        return Err(ClothError::BadGrid { nx, nz });
    }
    let limit = max_particles.min(MAX_VERTICES);
    match nx.checked_mul(nz) {
        Some(n) if n <= limit => Ok(n),
        _ => Err(ClothError::TooManyParticles { nx, nz, limit }),
    }
}

fn check_positive(name: &'static str, value: f64) -> Result<()> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(ClothError::BadParameter {
            name,
            expected: "positive and finite",
            value,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_numbering_is_row_major_with_col_along_x() {
        let g = GridCloth::new(4, 3, 0.5);
        let mesh = g.build_mesh().unwrap();
        assert_eq!(g.vertex(3, 2), 11);
        assert_eq!(
            mesh.positions[g.vertex(1, 0) as usize],
            Vector3::new(0.5, 0.0, 0.0)
        );
        assert_eq!(
            mesh.positions[g.vertex(0, 1) as usize],
            Vector3::new(0.0, 0.0, 0.5)
        );
    }

    #[test]
    fn structural_edge_count_matches_the_paper() {
        let mesh = GridCloth::new(30, 30, 1.0 / 29.0).build_mesh().unwrap();
        assert_eq!(mesh.edges.len(), 1740);
        let more = GridCloth::new(3, 3, 1.0)
            .shear(true)
            .bend(true)
            .build_mesh()
            .unwrap();
        assert_eq!(more.edges.len(), 12 + 8 + 6);
    }

    #[test]
    fn transform_places_the_grid() {
        let iso = Isometry3::translation(1.0, 2.0, 3.0);
        let mesh = GridCloth::new(2, 2, 1.0)
            .world_from_local(iso)
            .build_mesh()
            .unwrap();
        assert_eq!(mesh.positions[3], Vector3::new(2.0, 2.0, 4.0));
    }

    #[test]
    fn a_whole_row_can_be_pinned_and_a_pin_past_the_grid_is_an_error() {
        let mesh = GridCloth::new(3, 3, 1.0).pin_row(0).build_mesh().unwrap();
        assert_eq!(mesh.pinned, vec![0, 1, 2]);
        // The mesh keeps every edge; the world leaves the pinned ones out.
        assert_eq!(mesh.edges.len(), 12);
        let err = GridCloth::new(3, 3, 1.0).pin(9).build_mesh().unwrap_err();
        assert!(matches!(
            err,
            ClothError::VertexOutOfRange {
                vertex: 9,
                n_vertices: 9
            }
        ));
        let err = GridCloth::new(1, 3, 1.0).build_mesh().unwrap_err();
        assert!(matches!(err, ClothError::BadGrid { .. }));
        let err = GridCloth::new(2, 2, 0.0).build_mesh().unwrap_err();
        assert!(matches!(
            err,
            ClothError::BadParameter {
                name: "spacing",
                ..
            }
        ));
    }

    #[test]
    fn obj_quads_become_unique_edges() {
        let text = "# a square of two triangles\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 2 3\nf 1/1 3/3 4/4\n";
        let mesh = ClothMesh::from_obj(text.as_bytes(), 0.01).unwrap();
        assert_eq!(mesh.positions.len(), 4);
        assert_eq!(mesh.edges, vec![[0, 1], [0, 2], [0, 3], [1, 2], [2, 3]]);
        assert_eq!(mesh.triangles.len(), 2);
    }

    /// Issue 11: OBJ's negative (relative) indices count back from the last vertex so far.
    #[test]
    fn obj_negative_indices_count_back_from_the_last_vertex() {
        let relative = "v 0 0 0\nv 1 0 0\nv 1 0 1\nf -3 -2 -1\nv 0 0 1\nf -4 -2 -1\n";
        let absolute = "v 0 0 0\nv 1 0 0\nv 1 0 1\nf 1 2 3\nv 0 0 1\nf 1 3 4\n";
        let a = ClothMesh::from_obj(relative.as_bytes(), 0.01).unwrap();
        let b = ClothMesh::from_obj(absolute.as_bytes(), 0.01).unwrap();
        assert_eq!(a.triangles, b.triangles);
        assert_eq!(a.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    }

    /// Issue 11: an index out of range names its line and the index as written (-9 was
    /// reported as "vertex 9").
    #[test]
    fn obj_index_out_of_range_names_line_and_index_as_written() {
        let text = "# square\nv 0 0 0\nv 1 0 0\nv 1 0 1\n\nf 1 2 -9\n";
        let err = ClothMesh::from_obj(text.as_bytes(), 0.01).unwrap_err();
        assert_eq!(
            err.to_string(),
            "OBJ line 6: expected a face vertex index from 1 to 3 or from -3 to -1 (3 vertices \
             defined so far), found -9"
        );
        let err = err.with_path(std::path::Path::new("cloth.obj"));
        assert!(err.to_string().ends_with("found -9 in cloth.obj"), "{err}");
        let err = ClothMesh::from_obj("f 0 1 2\n".as_bytes(), 0.01).unwrap_err();
        assert!(
            err.to_string()
                .contains("of a vertex defined before the face (none is), found 0"),
            "{err}"
        );
    }

    /// Issue 11: a grid past its particle limit is refused before anything is allocated
    /// (10¹⁰ particles aborted the process).
    #[test]
    fn grid_past_its_particle_limit_is_refused_before_allocating() {
        let err = GridCloth::new(100_000, 100_000, 0.01)
            .build_mesh()
            .unwrap_err();
        assert!(matches!(
            err,
            ClothError::TooManyParticles {
                nx: 100_000,
                nz: 100_000,
                limit: DEFAULT_MAX_PARTICLES
            }
        ));
        assert_eq!(
            err.to_string(),
            "expected at most 1000000 particles (`max_particles`), found a 100000 x 100000 \
             grid of 10000000000 particles"
        );
        // Overflowing nx × nz is the same error, not a panic.
        let err = GridCloth::new(usize::MAX, 3, 0.01)
            .max_particles(usize::MAX)
            .n_vertices()
            .unwrap_err();
        assert!(matches!(err, ClothError::TooManyParticles { limit, .. } if limit == MAX_VERTICES));
        // The limit can be lowered and raised.
        let small = GridCloth::new(4, 4, 0.1).max_particles(15);
        assert!(matches!(
            small.build_mesh(),
            Err(ClothError::TooManyParticles { limit: 15, .. })
        ));
        assert_eq!(small.max_particles(16).n_vertices().unwrap(), 16);
    }

    #[test]
    fn obj_errors_are_typed() {
        let err = ClothMesh::from_obj("v 0 0\n".as_bytes(), 0.01).unwrap_err();
        assert!(matches!(err, ClothError::Obj { line: 1, .. }));
        let err = ClothMesh::from_obj("v 0 0 0\nf 1 2 3\n".as_bytes(), 0.01).unwrap_err();
        assert!(matches!(
            err,
            ClothError::ObjIndex {
                line: 2,
                index: 2,
                n_vertices: 1,
                ..
            }
        ));
        let err = ClothMesh::from_obj("v 0 0 0\n".as_bytes(), 0.01).unwrap_err();
        assert!(matches!(
            err,
            ClothError::EmptyMesh {
                n_particles: 1,
                n_edges: 0
            }
        ));
        let err = ClothMesh::from_obj("v 0 0 0\nv 0 0 0\nv 1 0 0\nf 1 2 3\n".as_bytes(), 0.01)
            .unwrap_err();
        assert!(matches!(err, ClothError::ZeroLengthEdge { a: 0, b: 1 }));
    }
}

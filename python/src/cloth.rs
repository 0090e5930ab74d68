//! Wrappers of modelgap-cloth (re-exported by `modelgap.cloth`): [`PyClothMesh`] (grid, numpy
//! or OBJ meshes), [`PyCollider`], [`PySolverParams`], [`PyClothWorld`] (the step, state as
//! numpy, kinematic pins, marker recording), [`PyStepReport`], [`PyMarkerRecording`],
//! [`PyScene`] and its [`PyClothRun`].

use std::path::PathBuf;

use modelgap::cloth::markers::{read_markers_path, write_markers_path};
use modelgap::cloth::model::{markers_to_recording, recording_to_markers, simulate_markers};
use modelgap::cloth::solver::Fallback;
use modelgap::cloth::trajectory::{MarkerSelection, RunOptions, run_scene, write_run_path};
use modelgap::cloth::{
    BuildMesh as _, ClothError, ClothId, ClothMesh, ClothModel, ClothWorld, Collider, GridCloth,
    Integrator, MarkerRecording, Method, PinPath, PredictSettings, Scene, Shape, SolverParams,
    StepReport, kinematic, scenes,
};
use modelgap::math::Vector3;
use modelgap::{Effect, Model};
use numpy::ndarray::{Array1, Array3};
use numpy::{IntoPyArray as _, PyArray1, PyArray2, PyArray3, PyArrayDyn, PyArrayMethods as _};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple, PyType};

use crate::convert::{
    array1, detached, index_list_from_py, index_rows_from_py, points_from_py, points_to_array,
    rows_to_array2, run_watched, vec_from_py, vec3_from_py,
};
use crate::core_api::{PyEffect, PyRecording};
use crate::errors::{cloth_err, data_error, to_py_err};

/// Registers the cloth classes and functions (re-exported by `modelgap.cloth`).
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyClothMesh>()?;
    m.add_class::<PyCollider>()?;
    m.add_class::<PySolverParams>()?;
    m.add_class::<PyStepReport>()?;
    m.add_class::<PyClothWorld>()?;
    m.add_class::<PyMarkerRecording>()?;
    m.add_class::<PyScene>()?;
    m.add_class::<PyClothRun>()?;
    m.add_class::<PyClothModel>()?;
    m.add_function(wrap_pyfunction!(scene, m)?)?;
    m.add_function(wrap_pyfunction!(scene_names, m)?)?;
    Ok(())
}

/// Checks that a number is positive and finite (`what` names it in the error).
fn positive(what: &str, value: f64) -> PyResult<f64> {
    if value > 0.0 && value.is_finite() {
        Ok(value)
    } else {
        Err(data_error(format!(
            "{what} must be positive and finite, found {value}"
        )))
    }
}

/// Pins each vertex of `pins` on `mesh`.
fn pin_all(mesh: &mut ClothMesh, pins: &[u32]) -> PyResult<()> {
    for &v in pins {
        mesh.pin(v).map_err(cloth_err)?;
    }
    Ok(())
}

/// Unique edges (smaller index first, sorted) of triangles.
fn triangle_edges(triangles: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let mut edges: Vec<[u32; 2]> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .filter(|(a, b)| a != b)
        .map(|(a, b)| [a.min(b), a.max(b)])
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// A cloth mesh before it enters a world: a particle per vertex, a distance constraint per
/// edge, the triangles, the pinned (static) vertices. Particles weigh ``particle_mass`` kg
/// (default 1 g, the crate's default, written out so that the signature shows it).
///
/// Build one with ``ClothMesh(vertices, triangles)`` (numpy ``(n, 3)`` floats in m and
/// ``(m, 3)`` integer vertex indices; each triangle side becomes a constraint),
/// ``ClothMesh.grid(nx, nz, spacing)`` or ``ClothMesh.load_obj(path)``. Raises ``DataError``
/// (a ``ValueError``) naming the vertex, edge or OBJ line for a mesh that cannot work.
#[pyclass(name = "ClothMesh", module = "modelgap.cloth")]
#[derive(Clone)]
pub struct PyClothMesh {
    inner: ClothMesh,
}

impl PyClothMesh {
    fn checked(mut inner: ClothMesh, pins: &[u32]) -> PyResult<Self> {
        pin_all(&mut inner, pins)?;
        inner.check().map_err(cloth_err)?;
        Ok(Self { inner })
    }
}

#[pymethods]
impl PyClothMesh {
    #[new]
    #[pyo3(signature = (vertices, triangles, *, particle_mass = 0.001, pins = None))]
    fn new(
        vertices: &Bound<'_, PyAny>,
        triangles: &Bound<'_, PyAny>,
        particle_mass: f64,
        pins: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let positions = points_from_py(vertices, "vertices")?;
        let triangles = index_rows_from_py::<3>(triangles, "triangles")?;
        positive("particle_mass", particle_mass)?;
        let n = positions.len();
        if let Some(v) = triangles.iter().flatten().find(|&&v| v as usize >= n) {
            return Err(cloth_err(ClothError::VertexOutOfRange {
                vertex: *v as usize,
                n_vertices: n,
            }));
        }
        let pins = match pins {
            Some(p) => index_list_from_py(p, "pins")?,
            None => Vec::new(),
        };
        let mesh = ClothMesh {
            masses: vec![particle_mass; n],
            edges: triangle_edges(&triangles),
            positions,
            triangles,
            pinned: Vec::new(),
        };
        Self::checked(mesh, &pins)
    }

    /// A flat grid of ``nx × nz`` vertices ``spacing`` m apart in the x–z plane (vertex
    /// ``row * nx + col`` at ``origin + (col, 0, row) * spacing``), structural edges, plus
    /// both cell diagonals with ``shear`` and edges skipping a vertex with ``bend``.
    #[staticmethod]
    #[pyo3(signature = (nx, nz, spacing, *, particle_mass = 0.001, pins = None, shear = false, bend = false, origin = None))]
    #[allow(clippy::too_many_arguments)] // keyword-only options of the Python API
    fn grid(
        nx: usize,
        nz: usize,
        spacing: f64,
        particle_mass: f64,
        pins: Option<&Bound<'_, PyAny>>,
        shear: bool,
        bend: bool,
        origin: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let mut grid = GridCloth::new(nx, nz, spacing)
            .particle_mass(particle_mass)
            .shear(shear)
            .bend(bend);
        if let Some(o) = origin {
            let o = vec3_from_py(o, "origin")?;
            grid = grid.world_from_local(nalgebra::Isometry3::translation(o.x, o.y, o.z));
        }
        if let Some(p) = pins {
            for v in index_list_from_py(p, "pins")? {
                grid = grid.pin(v);
            }
        }
        Ok(Self {
            inner: grid.build_mesh().map_err(cloth_err)?,
        })
    }

    /// Reads an OBJ file: ``v`` lines become particles, faces' sides constraints. Raises
    /// ``DataError`` naming the line for a malformed file.
    #[staticmethod]
    #[pyo3(signature = (path, *, particle_mass = 0.001, pins = None))]
    fn load_obj(
        py: Python<'_>,
        path: PathBuf,
        particle_mass: f64,
        pins: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let pins = match pins {
            Some(p) => index_list_from_py(p, "pins")?,
            None => Vec::new(),
        };
        let mesh = detached(py, move || {
            let file = std::fs::File::open(&path).map_err(|source| ClothError::Io {
                source,
                path: path.clone(),
            })?;
            ClothMesh::from_obj(std::io::BufReader::new(file), particle_mass)
                .map_err(|e| in_file(e, &path))
        })?
        .map_err(cloth_err)?;
        Self::checked(mesh, &pins)
    }

    /// Reads OBJ text (as ``load_obj`` reads a file).
    #[staticmethod]
    #[pyo3(signature = (text, *, particle_mass = 0.001, pins = None))]
    fn from_obj(text: &str, particle_mass: f64, pins: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let pins = match pins {
            Some(p) => index_list_from_py(p, "pins")?,
            None => Vec::new(),
        };
        let mesh = ClothMesh::from_obj(text.as_bytes(), particle_mass).map_err(cloth_err)?;
        Self::checked(mesh, &pins)
    }

    /// Pins a vertex (makes its particle static). Raises ``DataError`` for a vertex past the
    /// mesh. Neighbouring pins are allowed: the edge between them is not a constraint.
    fn pin(&mut self, vertex: &Bound<'_, PyAny>) -> PyResult<()> {
        let v = index_list_from_py(&PyTuple::new(vertex.py(), [vertex])?.into_any(), "vertex")?;
        let mut mesh = self.inner.clone();
        pin_all(&mut mesh, &v)?;
        mesh.check().map_err(cloth_err)?;
        self.inner = mesh;
        Ok(())
    }

    /// Number of vertices (particles).
    #[getter]
    fn n_vertices(&self) -> usize {
        self.inner.positions.len()
    }
    /// Number of edges (distance constraints).
    #[getter]
    fn n_edges(&self) -> usize {
        self.inner.edges.len()
    }
    /// Vertex positions (m), a fresh ``(n, 3)`` float64 array.
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        points_to_array(py, &self.inner.positions)
    }
    /// Particle masses (kg), a fresh ``(n,)`` float64 array.
    #[getter]
    fn masses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array1(py, &self.inner.masses)
    }
    /// Edges as vertex pairs, a fresh ``(k, 2)`` int64 array.
    #[getter]
    fn edges<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        rows_to_array2(py, &widen(&self.inner.edges))
    }
    /// Triangles, a fresh ``(m, 3)`` int64 array.
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        rows_to_array2(py, &widen(&self.inner.triangles))
    }
    /// The pinned vertices, sorted.
    #[getter]
    fn pinned(&self) -> Vec<u32> {
        self.inner.pinned.clone()
    }

    /// Restores a pickled mesh (see ``__reduce__``).
    #[staticmethod]
    fn _from_parts(
        vertices: &Bound<'_, PyAny>,
        masses: &Bound<'_, PyAny>,
        edges: &Bound<'_, PyAny>,
        triangles: &Bound<'_, PyAny>,
        pinned: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let mesh = ClothMesh {
            positions: points_from_py(vertices, "vertices")?,
            masses: vec_from_py(masses, "masses")?,
            edges: index_rows_from_py::<2>(edges, "edges")?,
            triangles: index_rows_from_py::<3>(triangles, "triangles")?,
            pinned: index_list_from_py(pinned, "pinned")?,
        };
        mesh.check().map_err(cloth_err)?;
        Ok(Self { inner: mesh })
    }

    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let me = slf.borrow();
        let args = PyTuple::new(
            py,
            [
                me.vertices(py).into_any(),
                me.masses(py).into_any(),
                me.edges(py).into_any(),
                me.triangles(py).into_any(),
                me.pinned().into_pyobject(py)?.into_any(),
            ],
        )?;
        Ok((slf.get_type().getattr("_from_parts")?, args))
    }

    fn __repr__(&self) -> String {
        format!(
            "<ClothMesh vertices={} edges={} triangles={} pinned={}>",
            self.inner.positions.len(),
            self.inner.edges.len(),
            self.inner.triangles.len(),
            self.inner.pinned.len()
        )
    }
}

/// A read error of an OBJ file with the file named (OBJ errors carry only a line).
fn in_file(e: ClothError, path: &std::path::Path) -> ClothError {
    match e {
        ClothError::Obj { line, message } => ClothError::Obj {
            line,
            message: format!("{message} in {}", path.display()),
        },
        other => other.with_path(path),
    }
}

/// Index rows as `i64` (numpy's default integer).
fn widen<const K: usize>(rows: &[[u32; K]]) -> Vec<[i64; K]> {
    rows.iter().map(|r| r.map(i64::from)).collect()
}

/// A rotation from an axis × angle vector (rad), as scene files write it.
fn rotation_from_py(obj: Option<&Bound<'_, PyAny>>) -> PyResult<nalgebra::UnitQuaternion<f64>> {
    Ok(match obj {
        Some(r) => nalgebra::UnitQuaternion::from_scaled_axis(vec3_from_py(r, "rotation")?),
        None => nalgebra::UnitQuaternion::identity(),
    })
}

/// A static collider: a shape and a Coulomb friction coefficient.
///
/// ``Collider.plane(point, normal)`` (the half-space behind the plane is solid),
/// ``Collider.ball(center, radius)``, ``Collider.cuboid(half_extents)``,
/// ``Collider.capsule(a, b, radius)`` or ``Collider.trimesh(vertices, triangles)``;
/// ``friction=`` sets the Coulomb coefficient. Raises ``DataError`` naming the shape and the
/// field for numbers that cannot work.
#[pyclass(name = "Collider", module = "modelgap.cloth", frozen)]
#[derive(Clone)]
pub struct PyCollider {
    inner: Collider,
}

impl PyCollider {
    fn checked(inner: Collider, friction: f64) -> PyResult<Self> {
        let inner = inner.friction(friction);
        inner.check().map_err(cloth_err)?;
        Ok(Self { inner })
    }
}

#[pymethods]
impl PyCollider {
    /// The half-space behind the plane through ``point`` (m) with outward ``normal``
    /// (normalised here; it must not be zero).
    #[staticmethod]
    #[pyo3(signature = (point, normal, *, friction = 0.0))]
    fn plane(point: &Bound<'_, PyAny>, normal: &Bound<'_, PyAny>, friction: f64) -> PyResult<Self> {
        let point = vec3_from_py(point, "point")?;
        let normal = vec3_from_py(normal, "normal")?;
        if normal.norm() == 0.0 {
            return Err(data_error(
                "plane collider: `normal` must not be zero: it gives the plane's outward direction",
            ));
        }
        Self::checked(Collider::plane(point, normal), friction)
    }

    /// A solid ball of ``radius`` m at ``center`` (m).
    #[staticmethod]
    #[pyo3(signature = (center, radius, *, friction = 0.0))]
    fn ball(center: &Bound<'_, PyAny>, radius: f64, friction: f64) -> PyResult<Self> {
        let center = vec3_from_py(center, "center")?;
        Self::checked(Collider::ball(center, radius), friction)
    }

    /// A solid box of ``half_extents`` (m, along its local axes) centred at ``center`` (m)
    /// and turned by ``rotation`` (an axis × angle vector, rad).
    #[staticmethod]
    #[pyo3(signature = (half_extents, *, center = None, rotation = None, friction = 0.0))]
    fn cuboid(
        half_extents: &Bound<'_, PyAny>,
        center: Option<&Bound<'_, PyAny>>,
        rotation: Option<&Bound<'_, PyAny>>,
        friction: f64,
    ) -> PyResult<Self> {
        let half = vec3_from_py(half_extents, "half_extents")?;
        let center = match center {
            Some(c) => vec3_from_py(c, "center")?,
            None => Vector3::zeros(),
        };
        let pose = nalgebra::Isometry3::from_parts(center.into(), rotation_from_py(rotation)?);
        Self::checked(Collider::cuboid(half, pose).map_err(cloth_err)?, friction)
    }

    /// A solid capsule: the points within ``radius`` m of the segment ``a``–``b`` (m).
    #[staticmethod]
    #[pyo3(signature = (a, b, radius, *, friction = 0.0))]
    fn capsule(
        a: &Bound<'_, PyAny>,
        b: &Bound<'_, PyAny>,
        radius: f64,
        friction: f64,
    ) -> PyResult<Self> {
        let a = vec3_from_py(a, "a")?;
        let b = vec3_from_py(b, "b")?;
        Self::checked(
            Collider::capsule(a, b, radius).map_err(cloth_err)?,
            friction,
        )
    }

    /// A triangle mesh of ``vertices`` (``(n, 3)``, m) and ``triangles`` (``(m, 3)``
    /// vertex indices, counter-clockwise seen from outside): a solid when closed, a surface
    /// of ``shell_thickness`` m (default the crate's) when open.
    #[staticmethod]
    #[pyo3(signature = (vertices, triangles, *, shell_thickness = None, friction = 0.0))]
    fn trimesh(
        vertices: &Bound<'_, PyAny>,
        triangles: &Bound<'_, PyAny>,
        shell_thickness: Option<f64>,
        friction: f64,
    ) -> PyResult<Self> {
        let v = points_from_py(vertices, "vertices")?;
        let t = index_rows_from_py::<3>(triangles, "triangles")?;
        let c = match shell_thickness {
            Some(s) => Collider::trimesh_with_shell(v, t, s),
            None => Collider::trimesh(v, t),
        }
        .map_err(cloth_err)?;
        Self::checked(c, friction)
    }

    /// ``"plane"``, ``"ball"``, ``"cuboid"``, ``"capsule"`` or ``"trimesh"``.
    #[getter]
    fn shape(&self) -> &'static str {
        self.inner.shape_name()
    }

    /// The shape's numbers (m): ``point`` and ``normal`` of a plane, ``center`` and
    /// ``radius`` of a ball, ``half_extents``, ``center`` and ``rotation`` (axis × angle,
    /// rad) of a cuboid, ``a``, ``b`` and ``radius`` of a capsule, ``vertices`` (local),
    /// ``triangles``, ``closed`` and ``shell_thickness`` of a triangle mesh.
    #[getter]
    fn geometry<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let xyz = |v: &Vector3| [v.x, v.y, v.z];
        match &self.inner.shape {
            Shape::Plane { point, normal } => {
                d.set_item("point", xyz(point))?;
                d.set_item("normal", xyz(normal))?;
            }
            Shape::Ball { center, radius } => {
                d.set_item("center", xyz(center))?;
                d.set_item("radius", *radius)?;
            }
            Shape::Cuboid {
                half_extents,
                world_from_local,
            } => {
                d.set_item("half_extents", xyz(half_extents))?;
                d.set_item("center", xyz(&world_from_local.translation.vector))?;
                d.set_item("rotation", xyz(&world_from_local.rotation.scaled_axis()))?;
            }
            Shape::Capsule { a, b, radius } => {
                d.set_item("a", xyz(a))?;
                d.set_item("b", xyz(b))?;
                d.set_item("radius", *radius)?;
            }
            Shape::TriMesh(mesh) => {
                d.set_item("vertices", points_to_array(py, mesh.vertices()))?;
                d.set_item("triangles", rows_to_array2(py, &widen(mesh.triangles())))?;
                d.set_item("closed", mesh.is_closed())?;
                d.set_item("shell_thickness", mesh.shell_thickness())?;
            }
            _ => {}
        }
        Ok(d)
    }

    /// Coulomb friction coefficient (dimensionless).
    #[getter]
    fn friction(&self) -> f64 {
        self.inner.friction
    }

    /// The same collider with another friction coefficient.
    fn with_friction(&self, friction: f64) -> PyResult<Self> {
        Self::checked(self.inner.clone(), friction)
    }

    /// Signed distance of ``point`` to the surface (m, negative inside).
    fn signed_distance(&self, point: &Bound<'_, PyAny>) -> PyResult<f64> {
        let x = vec3_from_py(point, "point")?;
        Ok(self.inner.signed_distance(&x).0)
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyCollider>()
            .is_ok_and(|o| o.get().inner == self.inner)
    }

    fn __repr__(&self) -> String {
        let v = |v: &Vector3| format!("({}, {}, {})", v.x, v.y, v.z);
        let geometry = match &self.inner.shape {
            Shape::Plane { point, normal } => format!("point={} normal={}", v(point), v(normal)),
            Shape::Ball { center, radius } => format!("center={} radius={radius}", v(center)),
            Shape::Cuboid {
                half_extents,
                world_from_local,
            } => format!(
                "half_extents={} center={}",
                v(half_extents),
                v(&world_from_local.translation.vector)
            ),
            Shape::Capsule { a, b, radius } => {
                format!("a={} b={} radius={radius}", v(a), v(b))
            }
            Shape::TriMesh(mesh) => format!(
                "vertices={} triangles={}",
                mesh.vertices().len(),
                mesh.triangles().len()
            ),
            _ => String::new(),
        };
        format!(
            "<Collider {} {geometry} friction={}>",
            self.inner.shape_name(),
            self.inner.friction
        )
    }
}

fn method_name(m: Method) -> &'static str {
    match m {
        Method::Newton => "newton",
        Method::Strips => "strips",
        _ => "gauss-seidel",
    }
}

fn integrator_name(i: Integrator) -> &'static str {
    match i {
        Integrator::Bdf2 => "bdf2",
        _ => "impulse",
    }
}

fn parse_integrator(s: &str) -> PyResult<Integrator> {
    match s {
        "impulse" => Ok(Integrator::Impulse),
        "bdf2" => Ok(Integrator::Bdf2),
        _ => Err(data_error(format!(
            "integrator must be \"impulse\" or \"bdf2\", found \"{s}\""
        ))),
    }
}

fn parse_method(s: &str) -> PyResult<Method> {
    match s {
        "gauss-seidel" | "gauss_seidel" => Ok(Method::GaussSeidel),
        "newton" => Ok(Method::Newton),
        "strips" => Ok(Method::Strips),
        _ => Err(data_error(format!(
            "method must be \"newton\", \"gauss-seidel\" or \"strips\", found \"{s}\""
        ))),
    }
}

/// What pickling stores of solver parameters, in the constructor's order.
type ParamsState = (String, f64, usize, [f64; 3], usize, bool, f64, f64, String);

/// Parameters of the cloth solver (a value: change one with ``replace``).
///
/// ``method`` is ``"newton"`` (a global solve, the default), ``"gauss-seidel"`` (the
/// paper's any-time iteration) or ``"strips"`` (the paper's acyclic strips); ``stretch_tolerance`` the allowed relative stretch (default 1e-4, 0.01 %);
/// ``max_iterations`` the limit per step (running out is reported, not raised);
/// ``gravity`` in m/s²; ``velocity_iterations`` sweeps of the velocity part;
/// ``warm_start`` reuses the last step's impulses; ``refactor_ratio`` (Newton),
/// ``contact_tolerance`` (m, allowed penetration) and ``integrator`` (``"impulse"``, the
/// paper's step, or ``"bdf2"``, second order).
#[pyclass(name = "SolverParams", module = "modelgap.cloth", frozen)]
#[derive(Clone)]
pub struct PySolverParams {
    inner: SolverParams,
}

impl PySolverParams {
    fn state(&self) -> ParamsState {
        let p = &self.inner;
        (
            method_name(p.method).to_owned(),
            p.stretch_tolerance,
            p.max_iterations,
            [p.gravity.x, p.gravity.y, p.gravity.z],
            p.velocity_iterations,
            p.warm_start,
            p.refactor_ratio,
            p.contact_tolerance,
            integrator_name(p.integrator).to_owned(),
        )
    }
}

#[pymethods]
impl PySolverParams {
    #[new]
    #[pyo3(signature = (*, method = "newton", stretch_tolerance = 1e-4, max_iterations = 1000, gravity = None, velocity_iterations = 0, warm_start = true, refactor_ratio = 0.3, contact_tolerance = 1e-4, integrator = "impulse"))]
    #[allow(clippy::too_many_arguments)] // keyword-only options of the Python API
    fn new(
        method: &str,
        stretch_tolerance: f64,
        max_iterations: usize,
        gravity: Option<&Bound<'_, PyAny>>,
        velocity_iterations: usize,
        warm_start: bool,
        refactor_ratio: f64,
        contact_tolerance: f64,
        integrator: &str,
    ) -> PyResult<Self> {
        let defaults = SolverParams::default();
        if max_iterations == 0 {
            return Err(data_error("max_iterations must be at least 1, found 0"));
        }
        if !(refactor_ratio > 0.0 && refactor_ratio < 1.0) {
            return Err(data_error(format!(
                "refactor_ratio must be in (0, 1), found {refactor_ratio}"
            )));
        }
        Ok(Self {
            inner: SolverParams {
                stretch_tolerance: positive("stretch_tolerance", stretch_tolerance)?,
                max_iterations,
                method: parse_method(method)?,
                gravity: match gravity {
                    Some(g) => vec3_from_py(g, "gravity")?,
                    None => defaults.gravity,
                },
                velocity_iterations,
                warm_start,
                refactor_ratio,
                contact_tolerance: positive("contact_tolerance", contact_tolerance)?,
                integrator: parse_integrator(integrator)?,
                ..defaults
            },
        })
    }

    /// The same parameters with the given ones changed (same keywords as the constructor).
    #[pyo3(signature = (**changes))]
    fn replace(slf: &Bound<'_, Self>, changes: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let py = slf.py();
        let kwargs = slf.get().kwargs(py)?;
        if let Some(changes) = changes {
            for (k, v) in changes.iter() {
                if !kwargs.contains(&k)? {
                    return Err(data_error(format!(
                        "SolverParams has no parameter `{k}`; parameters: {}",
                        kwargs.keys().str()?
                    )));
                }
                kwargs.set_item(k, v)?;
            }
        }
        slf.get_type()
            .call((), Some(&kwargs))?
            .cast_into::<PySolverParams>()
            .map(|b| b.get().clone())
            .map_err(Into::into)
    }

    /// The parameters as a dict of the constructor's keywords.
    fn kwargs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (method, tol, max_it, g, vel, warm, ratio, contact, integrator) = self.state();
        let d = PyDict::new(py);
        d.set_item("method", method)?;
        d.set_item("stretch_tolerance", tol)?;
        d.set_item("max_iterations", max_it)?;
        d.set_item("gravity", g)?;
        d.set_item("velocity_iterations", vel)?;
        d.set_item("warm_start", warm)?;
        d.set_item("refactor_ratio", ratio)?;
        d.set_item("contact_tolerance", contact)?;
        d.set_item("integrator", integrator)?;
        Ok(d)
    }

    /// ``"newton"``, ``"gauss-seidel"`` or ``"strips"``.
    #[getter]
    fn method(&self) -> &'static str {
        method_name(self.inner.method)
    }
    /// Allowed relative stretch at the end of a converged step.
    #[getter]
    fn stretch_tolerance(&self) -> f64 {
        self.inner.stretch_tolerance
    }
    /// Iteration limit per step.
    #[getter]
    fn max_iterations(&self) -> usize {
        self.inner.max_iterations
    }
    /// Gravity (m/s²).
    #[getter]
    fn gravity(&self) -> (f64, f64, f64) {
        let g = self.inner.gravity;
        (g.x, g.y, g.z)
    }
    /// Sweeps of the velocity part per step.
    #[getter]
    fn velocity_iterations(&self) -> usize {
        self.inner.velocity_iterations
    }
    /// Whether a step starts from the last step's impulses.
    #[getter]
    fn warm_start(&self) -> bool {
        self.inner.warm_start
    }
    /// Newton: refactor when an iteration shrinks the stretch by less than this factor.
    #[getter]
    fn refactor_ratio(&self) -> f64 {
        self.inner.refactor_ratio
    }
    /// Allowed penetration into colliders (m).
    #[getter]
    fn contact_tolerance(&self) -> f64 {
        self.inner.contact_tolerance
    }
    /// ``"impulse"`` (the paper's step) or ``"bdf2"`` (second order).
    #[getter]
    fn integrator(&self) -> &'static str {
        integrator_name(self.inner.integrator)
    }

    /// Restores pickled parameters (see ``__reduce__``).
    #[staticmethod]
    #[allow(clippy::too_many_arguments)] // the pickled tuple, in order
    fn _from_state(
        py: Python<'_>,
        method: &str,
        stretch_tolerance: f64,
        max_iterations: usize,
        gravity: [f64; 3],
        velocity_iterations: usize,
        warm_start: bool,
        refactor_ratio: f64,
        contact_tolerance: f64,
        integrator: &str,
    ) -> PyResult<Self> {
        let g = gravity.into_pyobject(py)?;
        Self::new(
            method,
            stretch_tolerance,
            max_iterations,
            Some(&g),
            velocity_iterations,
            warm_start,
            refactor_ratio,
            contact_tolerance,
            integrator,
        )
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, ParamsState)> {
        Ok((slf.get_type().getattr("_from_state")?, slf.get().state()))
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PySolverParams>()
            .is_ok_and(|o| o.get().inner == self.inner)
    }

    fn __repr__(&self) -> String {
        let p = &self.inner;
        format!(
            "<SolverParams method={} stretch_tolerance={:e} max_iterations={} gravity=({}, {}, {})>",
            method_name(p.method),
            p.stretch_tolerance,
            p.max_iterations,
            p.gravity.x,
            p.gravity.y,
            p.gravity.z
        )
    }
}

/// What pickling stores of a step report: steps, then the report's fields in order.
type ReportState = (
    usize,
    usize,
    f64,
    bool,
    usize,
    usize,
    usize,
    f64,
    String,
    Option<String>,
    bool,
    (Option<f64>, bool),
);

/// A fallback as a short code (for pickling) and back.
fn fallback_code(f: Option<Fallback>) -> Option<String> {
    f.map(|f| {
        match f {
            Fallback::NewtonUnavailable => "newton-unavailable",
            _ => "no-constraints",
        }
        .to_owned()
    })
}

fn fallback_of(code: Option<&str>) -> Option<Fallback> {
    match code? {
        "newton-unavailable" => Some(Fallback::NewtonUnavailable),
        _ => Some(Fallback::NoConstraints),
    }
}

/// What ``ClothWorld.step`` did over its steps: summed iterations, the worst stretch,
/// converged only if every step converged.
#[pyclass(name = "StepReport", module = "modelgap.cloth", frozen)]
#[derive(Clone)]
pub struct PyStepReport {
    inner: StepReport,
    steps: usize,
}

#[pymethods]
impl PyStepReport {
    /// Steps taken.
    #[getter]
    fn steps(&self) -> usize {
        self.steps
    }
    /// Iterations used, summed over the steps (Gauss–Seidel sweeps or Newton solves).
    #[getter]
    fn iterations(&self) -> usize {
        self.inner.iterations
    }
    /// Largest relative stretch of any constraint at the end of any step.
    #[getter]
    fn max_stretch(&self) -> f64 {
        self.inner.max_stretch
    }
    /// Whether every step met its tolerances.
    #[getter]
    fn converged(&self) -> bool {
        self.inner.converged
    }
    /// Numeric factorisations (Newton only).
    #[getter]
    fn factorizations(&self) -> usize {
        self.inner.factorizations
    }
    /// Gauss–Seidel sweeps after a failed Newton step (Newton only).
    #[getter]
    fn fallback_sweeps(&self) -> usize {
        self.inner.fallback_sweeps
    }
    /// Most particles in contact with a collider in one step.
    #[getter]
    fn n_contacts(&self) -> usize {
        self.inner.n_contacts
    }
    /// Deepest penetration into a collider at the end of a step (m).
    #[getter]
    fn max_penetration(&self) -> f64 {
        self.inner.max_penetration
    }
    /// The method the last step ran (``newton``, ``gauss-seidel`` or ``strips``): not the
    /// one asked for when it fell back.
    #[getter]
    fn method(&self) -> &'static str {
        method_name(self.inner.method_used)
    }
    /// Why a step ran another method than the one asked for (the first such step), or
    /// ``None``.
    #[getter]
    fn fallback(&self) -> Option<String> {
        self.inner.fallback.map(|f| f.to_string())
    }
    /// Whether a step stopped because its error stopped falling: the stretch tolerance
    /// is below what it can reach (``ClothWorld.stagnation`` says the level).
    #[getter]
    fn stagnated(&self) -> bool {
        self.inner.stagnated
    }
    /// The tolerance held instead of the requested one after a step stagnated (the
    /// largest over the steps), or ``None``.
    #[getter]
    fn relaxed_tolerance(&self) -> Option<f64> {
        self.inner.relaxed_tolerance
    }
    /// Whether a step asked to be BDF2 (``integrator = "bdf2"`` in its scene) did not
    /// converge as BDF2 and was taken again as the paper's impulse step.
    #[getter]
    fn first_order(&self) -> bool {
        self.inner.first_order
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, ReportState)> {
        let r = &slf.get().inner;
        Ok((
            slf.get_type().getattr("_from_state")?,
            (
                slf.get().steps,
                r.iterations,
                r.max_stretch,
                r.converged,
                r.factorizations,
                r.fallback_sweeps,
                r.n_contacts,
                r.max_penetration,
                method_name(r.method_used).to_owned(),
                fallback_code(r.fallback),
                r.stagnated,
                (r.relaxed_tolerance, r.first_order),
            ),
        ))
    }

    /// Restores a pickled report (see ``__reduce__``).
    #[staticmethod]
    #[allow(clippy::too_many_arguments)] // the pickled tuple, in order
    fn _from_state(
        steps: usize,
        iterations: usize,
        max_stretch: f64,
        converged: bool,
        factorizations: usize,
        fallback_sweeps: usize,
        n_contacts: usize,
        max_penetration: f64,
        method: &str,
        fallback: Option<&str>,
        stagnated: bool,
        relaxed_and_first_order: (Option<f64>, bool),
    ) -> PyResult<Self> {
        let (relaxed_tolerance, first_order) = relaxed_and_first_order;
        Ok(Self {
            inner: StepReport {
                iterations,
                max_stretch,
                converged,
                factorizations,
                fallback_sweeps,
                n_contacts,
                max_penetration,
                method_used: parse_method(method)?,
                fallback: fallback_of(fallback),
                stagnated,
                relaxed_tolerance,
                first_order,
            },
            steps,
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "<StepReport steps={} iterations={} max_stretch={:.2e} converged={}>",
            self.steps,
            self.inner.iterations,
            self.inner.max_stretch,
            if self.inner.converged {
                "True"
            } else {
                "False"
            }
        )
    }
}

/// All cloths and colliders of a simulation, stepped together.
///
/// ``world = ClothWorld(SolverParams(...))``; ``cloth = world.add_cloth(mesh)`` returns the
/// cloth's id (0, 1, …); ``world.step(100, dt=0.01)`` returns a ``StepReport``;
/// ``world.positions(cloth)`` a fresh ``(n, 3)`` float64 array. Stepping releases the GIL,
/// stops on Ctrl-C between steps and reports ``progress(done, total)``.
#[pyclass(name = "ClothWorld", module = "modelgap.cloth")]
pub struct PyClothWorld {
    inner: ClothWorld,
    n_cloths: u32,
}

impl PyClothWorld {
    fn id(&self, cloth: u32) -> PyResult<ClothId> {
        if cloth < self.n_cloths {
            Ok(ClothId(cloth))
        } else {
            Err(cloth_err(ClothError::UnknownCloth {
                id: cloth,
                n_cloths: self.n_cloths as usize,
            }))
        }
    }

    /// The world's particle indices of a cloth's vertices.
    fn particle_range(&self, cloth: u32) -> PyResult<std::ops::Range<usize>> {
        let id = self.id(cloth)?;
        let n = self.inner.positions(id).len();
        let first = self.inner.particle(id, 0).map_err(cloth_err)?.index();
        Ok(first..first + n)
    }

    /// Replaces a column of a cloth (positions or velocities) from a `(n, 3)` array.
    fn set_column(
        &mut self,
        cloth: u32,
        values: &Bound<'_, PyAny>,
        what: &'static str,
    ) -> PyResult<()> {
        let range = self.particle_range(cloth)?;
        let label = if what == "position" {
            "positions"
        } else {
            "velocities"
        };
        let v = points_from_py(values, label)?;
        if v.len() != range.len() {
            return Err(data_error(format!(
                "{label} must be (n, 3) = ({}, 3), one row per vertex of cloth {cloth}, found ({}, 3)",
                range.len(),
                v.len()
            )));
        }
        if let Some((k, p)) = v
            .iter()
            .enumerate()
            .find(|(_, p)| !p.iter().all(|c| c.is_finite()))
        {
            return Err(cloth_err(ClothError::NonFinite {
                particle: (range.start + k) as u32,
                what,
                x: p.x,
                y: p.y,
                z: p.z,
            }));
        }
        let ps = self.inner.particles_mut();
        let column = if what == "position" {
            &mut ps.positions
        } else {
            &mut ps.velocities
        };
        column[range].copy_from_slice(&v);
        Ok(())
    }
}

/// Steps `world` `steps` times, calling `after_step(done)` after each, stopping early when
/// `watch` says so; returns the merged report and the steps done.
fn step_watched(
    world: &mut ClothWorld,
    steps: usize,
    dt: f64,
    watch: &crate::convert::Watch,
    mut after_step: impl FnMut(&ClothWorld, usize) -> Result<(), ClothError>,
) -> Result<(StepReport, usize), ClothError> {
    let mut total = StepReport {
        converged: true,
        ..StepReport::default()
    };
    (watch.progress)(0, steps);
    for done in 1..=steps {
        if watch.cancel.is_cancelled() {
            return Ok((total, done - 1));
        }
        total = total.merge(world.step(dt)?);
        after_step(world, done)?;
        (watch.progress)(done, steps);
    }
    Ok((total, steps))
}

#[pymethods]
impl PyClothWorld {
    #[new]
    #[pyo3(signature = (params = None))]
    fn new(params: Option<&Bound<'_, PySolverParams>>) -> Self {
        let params = params.map_or_else(SolverParams::default, |p| p.get().inner.clone());
        Self {
            inner: ClothWorld::new(params),
            n_cloths: 0,
        }
    }

    /// Adds a cloth (a particle per vertex, a constraint per edge with its current length as
    /// rest length, except edges between two pinned vertices) and returns its id.
    fn add_cloth(&mut self, mesh: &Bound<'_, PyClothMesh>) -> PyResult<u32> {
        let id = self
            .inner
            .add_cloth(mesh.borrow().inner.clone())
            .map_err(cloth_err)?;
        self.n_cloths = id.0 + 1;
        Ok(id.0)
    }

    /// Adds a static collider and returns its id.
    fn add_collider(&mut self, collider: &Bound<'_, PyCollider>) -> u32 {
        self.inner.add_collider(collider.get().inner.clone()).0
    }

    /// Makes pinned ``vertex`` of ``cloth`` follow the path through ``points`` (``(k, 3)``,
    /// m) at times ``t`` (``(k,)``, s, strictly increasing): linear between points, held
    /// before the first and after the last. Raises ``DataError`` for a dynamic vertex.
    fn add_kinematic_pin(
        &mut self,
        cloth: u32,
        vertex: usize,
        t: &Bound<'_, PyAny>,
        points: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let id = self.id(cloth)?;
        let path = PinPath::new(vec_from_py(t, "t")?, points_from_py(points, "points")?)
            .map_err(cloth_err)?;
        self.inner
            .add_kinematic_pin(id, vertex, path)
            .map_err(cloth_err)?;
        Ok(())
    }

    /// Makes every pinned vertex of ``cloth`` whose id is in ``markers`` follow the recorded
    /// positions (recording time = world time); returns how many pins follow them.
    fn follow_markers(
        &mut self,
        cloth: u32,
        markers: &Bound<'_, PyMarkerRecording>,
    ) -> PyResult<usize> {
        let id = self.id(cloth)?;
        kinematic::follow_markers(&mut self.inner, id, &markers.get().inner).map_err(cloth_err)
    }

    /// Advances the world ``steps`` steps of ``dt`` seconds. The GIL is released; Ctrl-C
    /// (or an exception from ``progress(done, total)``) stops it between steps, and the
    /// steps done stay done. Running out of iterations is reported (``converged=False``),
    /// not raised.
    #[pyo3(signature = (steps = 1, *, dt = 1.0 / 60.0, progress = None))]
    fn step(
        &mut self,
        py: Python<'_>,
        steps: usize,
        dt: f64,
        progress: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyStepReport> {
        let world = &mut self.inner;
        let (report, done) = run_watched(py, progress, move |watch| {
            step_watched(world, steps, dt, &watch, |_, _| Ok(()))
        })?
        .map_err(cloth_err)?;
        Ok(PyStepReport {
            inner: report,
            steps: done,
        })
    }

    /// Steps like ``step`` and records the positions of vertices ``ids`` of ``cloth`` (all
    /// when None) at the start and after every ``every`` steps (and after the last) as a
    /// ``MarkerRecording`` whose time is the world's time.
    #[pyo3(signature = (steps, *, dt = 1.0 / 60.0, cloth = 0, ids = None, every = 1, progress = None))]
    #[allow(clippy::too_many_arguments)] // keyword-only options of the Python API
    fn record(
        &mut self,
        py: Python<'_>,
        steps: usize,
        dt: f64,
        cloth: u32,
        ids: Option<&Bound<'_, PyAny>>,
        every: usize,
        progress: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyMarkerRecording> {
        let id = self.id(cloth)?;
        let n = self.inner.positions(id).len();
        let ids = match ids {
            Some(ids) => index_list_from_py(ids, "ids")?,
            None => (0..n as u32).collect(),
        };
        if let Some(&bad) = ids.iter().find(|&&i| i as usize >= n) {
            return Err(cloth_err(ClothError::VertexOutOfRange {
                vertex: bad as usize,
                n_vertices: n,
            }));
        }
        if every == 0 {
            return Err(data_error("every must be at least 1, found 0"));
        }
        let world = &mut self.inner;
        let frame = |w: &ClothWorld| -> Vec<[f64; 3]> {
            let x = w.positions(id);
            ids.iter()
                .map(|&i| {
                    let p = x[i as usize];
                    [p.x, p.y, p.z]
                })
                .collect()
        };
        let rec = run_watched(py, progress, |watch| {
            let mut t = vec![world.time()];
            let mut frames = vec![frame(world)];
            step_watched(world, steps, dt, &watch, |w, done| {
                if done % every == 0 || done == steps {
                    t.push(w.time());
                    frames.push(frame(w));
                }
                Ok(())
            })?;
            MarkerRecording::new(t, ids.clone(), frames)
        })?
        .map_err(cloth_err)?;
        Ok(PyMarkerRecording { inner: rec })
    }

    /// The positions of a cloth's vertices (m), a fresh ``(n, 3)`` float64 array.
    #[pyo3(signature = (cloth = 0))]
    fn positions<'py>(&self, py: Python<'py>, cloth: u32) -> PyResult<Bound<'py, PyArray2<f64>>> {
        Ok(points_to_array(py, self.inner.positions(self.id(cloth)?)))
    }

    /// The velocities of a cloth's vertices (m/s), a fresh ``(n, 3)`` float64 array.
    #[pyo3(signature = (cloth = 0))]
    fn velocities<'py>(&self, py: Python<'py>, cloth: u32) -> PyResult<Bound<'py, PyArray2<f64>>> {
        Ok(points_to_array(py, self.inner.velocities(self.id(cloth)?)))
    }

    /// Sets the positions of a cloth's vertices from an ``(n, 3)`` array (m) between steps.
    #[pyo3(signature = (positions, cloth = 0))]
    fn set_positions(&mut self, positions: &Bound<'_, PyAny>, cloth: u32) -> PyResult<()> {
        self.set_column(cloth, positions, "position")
    }

    /// Sets the velocities of a cloth's vertices from an ``(n, 3)`` array (m/s).
    #[pyo3(signature = (velocities, cloth = 0))]
    fn set_velocities(&mut self, velocities: &Bound<'_, PyAny>, cloth: u32) -> PyResult<()> {
        self.set_column(cloth, velocities, "velocity")
    }

    /// A cloth's triangles, a fresh ``(m, 3)`` int64 array of vertex indices.
    #[pyo3(signature = (cloth = 0))]
    fn triangles<'py>(&self, py: Python<'py>, cloth: u32) -> PyResult<Bound<'py, PyArray2<i64>>> {
        Ok(rows_to_array2(
            py,
            &widen(self.inner.triangles(self.id(cloth)?)),
        ))
    }

    /// The inverse masses of a cloth's particles (1/kg; 0 for pinned vertices).
    #[pyo3(signature = (cloth = 0))]
    fn inv_masses<'py>(&self, py: Python<'py>, cloth: u32) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let r = self.particle_range(cloth)?;
        Ok(array1(py, &self.inner.particles().inv_mass[r]))
    }

    /// The largest relative stretch of a cloth's constraints now.
    #[pyo3(signature = (cloth = 0))]
    fn max_stretch(&self, cloth: u32) -> PyResult<f64> {
        Ok(self.inner.max_stretch(self.id(cloth)?))
    }

    /// The total momentum of all particles (kg m/s), a fresh ``(3,)`` array.
    fn momentum<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let p = self.inner.particles().momentum();
        Array1::from(vec![p.x, p.y, p.z]).into_pyarray(py)
    }

    /// Simulated time (s).
    #[getter]
    fn time(&self) -> f64 {
        self.inner.time()
    }
    /// Number of cloths.
    #[getter]
    fn n_cloths(&self) -> u32 {
        self.n_cloths
    }
    /// Number of particles over all cloths.
    #[getter]
    fn n_particles(&self) -> usize {
        self.inner.particles().len()
    }
    /// Number of distance constraints over all cloths.
    #[getter]
    fn n_constraints(&self) -> usize {
        self.inner.constraints().len()
    }
    /// The colliders, in the order added.
    #[getter]
    fn colliders(&self) -> Vec<PyCollider> {
        self.inner
            .colliders()
            .iter()
            .map(|c| PyCollider { inner: c.clone() })
            .collect()
    }
    /// Number of kinematic pins.
    #[getter]
    fn n_kinematic_pins(&self) -> usize {
        self.inner.kinematic_pins().len()
    }
    /// The warning when a step found the stretch tolerance out of reach (the level reached
    /// and the one held since), or ``None``.
    #[getter]
    fn stagnation(&self) -> Option<String> {
        self.inner.stagnation().map(ToString::to_string)
    }
    /// The solver parameters (assign a new ``SolverParams`` to change them between steps).
    #[getter]
    fn get_params(&self) -> PySolverParams {
        PySolverParams {
            inner: self.inner.params().clone(),
        }
    }
    #[setter]
    fn set_params(&mut self, params: &Bound<'_, PySolverParams>) {
        *self.inner.params_mut() = params.get().inner.clone();
    }

    fn __repr__(&self) -> String {
        format!(
            "<ClothWorld cloths={} particles={} constraints={} colliders={} time={} s>",
            self.n_cloths,
            self.inner.particles().len(),
            self.inner.constraints().len(),
            self.inner.colliders().len(),
            self.inner.time()
        )
    }
}

/// A marker recording as numpy: times, ids, positions.
type MarkerArrays<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray3<f64>>,
);

/// The positions of chosen mesh vertices (markers) over time: measured or simulated.
///
/// ``MarkerRecording(t, ids, positions)`` with ``t`` ``(n_frames,)`` s, ``ids`` the vertex
/// indices and ``positions`` ``(n_frames, n_markers, 3)`` m; ``MarkerRecording.load(path)``
/// reads ``.csv`` (``t,id,x,y,z``) or ``.mcap`` (topic ``/markers``). Arrays read from it
/// are fresh copies.
#[pyclass(name = "MarkerRecording", module = "modelgap.cloth", frozen)]
#[derive(Clone)]
pub struct PyMarkerRecording {
    pub(crate) inner: MarkerRecording,
}

impl PyMarkerRecording {
    fn positions_array<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let p = self.inner.positions();
        let a = Array3::from_shape_fn(
            (self.inner.n_frames(), self.inner.n_markers(), 3),
            |(f, m, c)| p[f][m][c],
        );
        a.into_pyarray(py)
    }

    fn ids_array<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let ids: Vec<i64> = self.inner.ids().iter().map(|&i| i64::from(i)).collect();
        PyArray1::from_vec(py, ids)
    }
}

#[pymethods]
impl PyMarkerRecording {
    #[new]
    fn new(
        t: &Bound<'_, PyAny>,
        ids: &Bound<'_, PyAny>,
        positions: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let t = vec_from_py(t, "t")?;
        let ids = index_list_from_py(ids, "ids")?;
        let np = positions.py().import("numpy")?;
        let arr = np
            .call_method1("asarray", (positions, np.getattr("float64")?))?
            .cast_into::<PyArrayDyn<f64>>()?;
        let ro = arr.readonly();
        let view = ro.as_array();
        let shape = view.shape().to_vec();
        if !(shape.len() == 3 && shape[0] == t.len() && shape[1] == ids.len() && shape[2] == 3) {
            return Err(data_error(format!(
                "positions must be (n_frames, n_markers, 3) = ({}, {}, 3), found shape {shape:?}",
                t.len(),
                ids.len()
            )));
        }
        let frames: Vec<Vec<[f64; 3]>> = view
            .outer_iter()
            .map(|frame| frame.outer_iter().map(|p| [p[0], p[1], p[2]]).collect())
            .collect();
        Ok(Self {
            inner: MarkerRecording::new(t, ids, frames).map_err(cloth_err)?,
        })
    }

    /// Reads a ``.csv`` or ``.mcap`` marker file. Raises ``DataError`` naming the line (or
    /// message), the field and the file.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let rec = detached(py, move || read_markers_path(&path))?.map_err(cloth_err)?;
        Ok(Self { inner: rec })
    }

    /// Writes the recording as ``.csv`` or (zstd) ``.mcap``, chosen by the extension.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let rec = &self.inner;
        detached(py, move || write_markers_path(rec, &path))?.map_err(cloth_err)
    }

    /// ``(t, ids, positions)``: ``(n_frames,)`` s, ``(n_markers,)`` int64 vertex ids,
    /// ``(n_frames, n_markers, 3)`` m.
    fn to_numpy<'py>(&self, py: Python<'py>) -> MarkerArrays<'py> {
        (
            array1(py, self.inner.t()),
            self.ids_array(py),
            self.positions_array(py),
        )
    }

    /// Frame times (s), a fresh array.
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array1(py, self.inner.t())
    }
    /// Marker ids (vertex indices), a fresh int64 array.
    #[getter]
    fn ids<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        self.ids_array(py)
    }
    /// Positions (m), a fresh ``(n_frames, n_markers, 3)`` array.
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        self.positions_array(py)
    }
    /// Number of frames.
    #[getter]
    fn n_frames(&self) -> usize {
        self.inner.n_frames()
    }
    /// Number of markers.
    #[getter]
    fn n_markers(&self) -> usize {
        self.inner.n_markers()
    }

    /// The positions of marker ``id`` in every frame, a fresh ``(n_frames, 3)`` array.
    /// Raises ``DataError`` for an id not recorded.
    fn track<'py>(&self, py: Python<'py>, id: u32) -> PyResult<Bound<'py, PyArray2<f64>>> {
        match self.inner.track(id) {
            Some(rows) => Ok(rows_to_array2(py, &rows)),
            None => {
                let ids = self.inner.ids();
                let mut listed: Vec<String> = ids.iter().take(10).map(u32::to_string).collect();
                if ids.len() > listed.len() {
                    listed.push(format!("… ({} in all)", ids.len()));
                }
                Err(data_error(format!(
                    "marker {id} is not recorded; recorded ids: {}",
                    listed.join(", ")
                )))
            }
        }
    }

    /// The markers as a ``modelgap.Recording`` with signals ``m{id}.x``, ``m{id}.y``,
    /// ``m{id}.z`` (m): what ``compare`` and ``explain`` hold a ``ClothModel`` against.
    fn to_recording(&self) -> PyResult<PyRecording> {
        Ok(markers_to_recording(&self.inner).map_err(cloth_err)?.into())
    }

    /// Markers from a ``Recording`` with signals ``m{id}.x|y|z`` (others are ignored).
    #[staticmethod]
    fn from_recording(rec: &Bound<'_, PyRecording>) -> PyResult<Self> {
        Ok(Self {
            inner: recording_to_markers(&rec.get().inner).map_err(cloth_err)?,
        })
    }

    fn __len__(&self) -> usize {
        self.inner.n_frames()
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyMarkerRecording>()
            .is_ok_and(|o| o.get().inner == self.inner)
    }

    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyType>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let (t, ids, positions) = slf.get().to_numpy(py);
        let args = PyTuple::new(py, [t.into_any(), ids.into_any(), positions.into_any()])?;
        Ok((slf.get_type(), args))
    }

    fn __repr__(&self) -> String {
        let t = self.inner.t();
        format!(
            "<MarkerRecording frames={} markers={} t={}..{} s>",
            self.inner.n_frames(),
            self.inner.n_markers(),
            t.first().copied().unwrap_or(0.0),
            t.last().copied().unwrap_or(0.0)
        )
    }
}

/// A cloth scene: a grid cloth, colliders, solver parameters, a step and a duration.
///
/// ``modelgap.cloth.scene("corner")`` (``corner``, ``two-corners``, ``drape``: the paper's
/// 30 × 30 mesh), ``Scene.load(path)`` (a TOML scene file) or ``Scene.from_toml(text)``;
/// ``resized(nx, nz)`` for a smaller grid, ``world()`` to step it yourself, ``run()`` to
/// run it and record its frames.
#[pyclass(name = "Scene", module = "modelgap.cloth", frozen)]
#[derive(Clone)]
pub struct PyScene {
    pub(crate) inner: Scene,
}

#[pymethods]
impl PyScene {
    /// Reads a scene file (TOML). Raises ``DataError`` naming the file and the field.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let scene = detached(py, move || Scene::from_path(&path))?.map_err(cloth_err)?;
        Ok(Self { inner: scene })
    }

    /// A scene from TOML text; ``label`` names it in errors.
    #[staticmethod]
    #[pyo3(signature = (text, label = "scene"))]
    fn from_toml(text: &str, label: &str) -> PyResult<Self> {
        Ok(Self {
            inner: Scene::from_toml(text, label).map_err(cloth_err)?,
        })
    }

    /// Short name.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }
    /// What it shows.
    #[getter]
    fn description(&self) -> &str {
        &self.inner.description
    }
    /// Simulated time (s).
    #[getter]
    fn duration(&self) -> f64 {
        self.inner.duration
    }
    /// Step size (s).
    #[getter]
    fn dt(&self) -> f64 {
        self.inner.dt
    }
    /// Steps of ``dt`` that cover ``duration``.
    #[getter]
    fn n_steps(&self) -> usize {
        self.inner.n_steps()
    }
    /// Grid vertices along x and z: ``(nx, nz)``.
    #[getter]
    fn grid(&self) -> (usize, usize) {
        (self.inner.cloth.nx, self.inner.cloth.nz)
    }
    /// Distance between neighbouring grid vertices (m).
    #[getter]
    fn spacing(&self) -> f64 {
        self.inner.cloth.spacing
    }
    /// Pinned vertices.
    #[getter]
    fn pins(&self) -> Vec<u32> {
        self.inner.cloth.pinned.clone()
    }
    /// The colliders.
    #[getter]
    fn colliders(&self) -> Vec<PyCollider> {
        self.inner
            .colliders
            .iter()
            .map(|c| PyCollider { inner: c.clone() })
            .collect()
    }
    /// The solver parameters.
    #[getter]
    fn params(&self) -> PySolverParams {
        PySolverParams {
            inner: self.inner.params.clone(),
        }
    }

    /// The same scene with other solver parameters.
    fn with_params(&self, params: &Bound<'_, PySolverParams>) -> Self {
        let mut inner = self.inner.clone();
        inner.params = params.get().inner.clone();
        Self { inner }
    }

    /// The same scene with another duration (s).
    fn with_duration(&self, duration: f64) -> PyResult<Self> {
        let mut inner = self.inner.clone();
        inner.duration = positive("duration", duration)?;
        Ok(Self { inner })
    }

    /// The same scene on a grid of ``nx × nz`` vertices over the same width; pins move to
    /// the nearest vertex at the same relative place.
    fn resized(&self, nx: usize, nz: usize) -> PyResult<Self> {
        Ok(Self {
            inner: self.inner.resized(nx, nz).map_err(cloth_err)?,
        })
    }

    /// The scene's mesh (as the world gets it).
    fn mesh(&self) -> PyResult<PyClothMesh> {
        Ok(PyClothMesh {
            inner: self.inner.cloth.build_mesh().map_err(cloth_err)?,
        })
    }

    /// A world holding the scene (cloth id 0); pinned vertices whose ids are in ``markers``
    /// follow that recording. The scene's effects (drag, damping, point masses, ...) are
    /// not in it: ``run()`` and ``ClothModel`` step with them.
    #[pyo3(signature = (markers = None))]
    fn world(&self, markers: Option<&Bound<'_, PyMarkerRecording>>) -> PyResult<PyClothWorld> {
        let markers = markers.map(|m| &m.get().inner);
        let (world, cloth) = self.inner.build_with_markers(markers).map_err(cloth_err)?;
        Ok(PyClothWorld {
            inner: world,
            n_cloths: cloth.0 + 1,
        })
    }

    /// Runs the scene from its start for ``duration`` (s, default the scene's) and records
    /// ``markers`` (every vertex by default or with ``"all"``, a list of vertex ids, or
    /// ``"none"`` for statistics only) at ``rate`` frames per second (default every step). The GIL is released; Ctrl-C is
    /// raised when the run ends (step a ``world()`` to stop between steps).
    #[pyo3(signature = (*, duration = None, rate = None, markers = None))]
    fn run(
        &self,
        py: Python<'_>,
        duration: Option<f64>,
        rate: Option<f64>,
        markers: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyClothRun> {
        let selection = match markers {
            None => MarkerSelection::All,
            Some(m) => match m.extract::<String>() {
                Ok(s) if s == "all" => MarkerSelection::All,
                Ok(s) if s == "none" => MarkerSelection::None,
                Ok(s) => {
                    return Err(data_error(format!(
                        "markers must be \"all\", \"none\" or a list of vertex ids, found \"{s}\""
                    )));
                }
                Err(_) => MarkerSelection::Ids(index_list_from_py(m, "markers")?),
            },
        };
        let options = RunOptions {
            duration,
            rate,
            markers: selection,
            ..RunOptions::default()
        };
        let scene = &self.inner;
        let run = detached(py, move || run_scene(scene, &options))?.map_err(cloth_err)?;
        Ok(PyClothRun { inner: run })
    }

    /// The scene as the text of a scene file (``Scene.from_toml`` reads it back). The
    /// solver's method and limits are not part of a scene file.
    fn to_toml(&self) -> PyResult<String> {
        self.inner.to_toml().map_err(cloth_err)
    }

    /// Restores a pickled scene (see ``__reduce__``): its file text and solver parameters.
    #[staticmethod]
    fn _from_state(text: &str, label: &str, params: &Bound<'_, PySolverParams>) -> PyResult<Self> {
        let mut inner = Scene::from_toml(text, label).map_err(cloth_err)?;
        inner.params = params.get().inner.clone();
        Ok(Self { inner })
    }

    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (String, String, PySolverParams))> {
        let me = slf.get();
        Ok((
            slf.get_type().getattr("_from_state")?,
            (me.to_toml()?, me.inner.name.clone(), me.params()),
        ))
    }

    fn __repr__(&self) -> String {
        format!(
            "<Scene {} grid={}x{} pins={:?} colliders={} dt={} s duration={} s>",
            self.inner.name,
            self.inner.cloth.nx,
            self.inner.cloth.nz,
            self.inner.cloth.pinned,
            self.inner.colliders.len(),
            self.inner.dt,
            self.inner.duration
        )
    }
}

/// A scene's run: the recorded frames, the mesh and what the solver did.
#[pyclass(name = "ClothRun", module = "modelgap.cloth", frozen)]
pub struct PyClothRun {
    inner: modelgap::cloth::trajectory::ClothRun,
}

#[pymethods]
impl PyClothRun {
    /// The scene's name.
    #[getter]
    fn scene(&self) -> &str {
        &self.inner.scene
    }
    /// The recorded markers (None when no markers were recorded).
    #[getter]
    fn markers(&self) -> Option<PyMarkerRecording> {
        self.inner
            .markers
            .clone()
            .map(|inner| PyMarkerRecording { inner })
    }
    /// Every vertex's position in each recorded frame (m), a fresh
    /// ``(n_frames, n_vertices, 3)`` array.
    #[getter]
    fn frames<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let f = &self.inner.mesh_frames;
        let n = f.first().map_or(0, Vec::len);
        Array3::from_shape_fn((f.len(), n, 3), |(i, v, c)| f[i][v][c]).into_pyarray(py)
    }
    /// The mesh's triangles, a fresh ``(m, 3)`` int64 array.
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        rows_to_array2(py, &widen(&self.inner.triangles))
    }
    /// The mesh's edges, a fresh ``(k, 2)`` int64 array.
    #[getter]
    fn edges<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        rows_to_array2(py, &widen(&self.inner.edges))
    }
    /// What the solver did: ``steps``, ``dt``, ``max_stretch``, ``total_iterations``,
    /// ``max_iterations``, ``mean_iterations``, ``unconverged_steps``, ``n_particles``,
    /// ``n_constraints``.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.inner.stats;
        let d = PyDict::new(py);
        d.set_item("steps", s.steps)?;
        d.set_item("dt", s.dt)?;
        d.set_item("max_stretch", s.max_stretch)?;
        d.set_item("total_iterations", s.total_iterations)?;
        d.set_item("max_iterations", s.max_iterations)?;
        d.set_item("mean_iterations", s.mean_iterations())?;
        d.set_item("unconverged_steps", s.unconverged_steps)?;
        d.set_item("n_particles", s.n_particles)?;
        d.set_item("n_constraints", s.n_constraints)?;
        Ok(d)
    }

    /// Writes the run: marker CSV (``.csv``) or MCAP with the mesh for Foxglove (``.mcap``).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let run = &self.inner;
        detached(py, move || write_run_path(run, &path))?.map_err(cloth_err)
    }

    fn __repr__(&self) -> String {
        let s = &self.inner.stats;
        format!(
            "<ClothRun {} steps={} frames={} max_stretch={:.2e} mean_iterations={:.1} unconverged_steps={}>",
            self.inner.scene,
            s.steps,
            self.inner.mesh_frames.len(),
            s.max_stretch,
            s.mean_iterations(),
            s.unconverged_steps
        )
    }
}

/// A reference scene by name: ``corner``, ``two-corners`` or ``drape``.
#[pyfunction]
fn scene(name: &str) -> PyResult<PyScene> {
    Ok(PyScene {
        inner: scenes::by_name(name).map_err(cloth_err)?,
    })
}

/// The names of the reference scenes.
#[pyfunction(name = "scenes")]
fn scene_names() -> Vec<String> {
    scenes::all().into_iter().map(|s| s.name).collect()
}

/// What pickling stores of a cloth model: the scene file text and label, the solver
/// parameters, the simulation settings (method, tolerance, iteration limit, step divisor)
/// and the effects built in (JSON).
type ClothModelState = (
    String,
    String,
    PySolverParams,
    (String, Option<f64>, usize, usize),
    String,
);

/// A cloth scene as a model of marker recordings: what ``modelgap.compare``,
/// ``modelgap.explain`` and ``modelgap.fix`` hold against a ``Recording`` of marker signals
/// ``m{id}.x|y|z`` (``MarkerRecording.to_recording()``).
///
/// ``ClothModel(scene)`` or ``ClothModel.load(path)`` (a scene file); ``method``,
/// ``stretch_tolerance`` (None: the scene's), ``max_iterations`` and ``step_divisor`` set
/// how it simulates. It predicts by running the scene from its start (simulated time 0 is
/// recording time 0). Its candidate effects: air drag, skin friction, wind, damping,
/// bending (the quadratic bending rigidity, N m), stretch compliance (warp and weft apart
/// when the scene sets them apart), the cloth's mass, a point mass, collider friction, and
/// per ``[[materials]]`` region ``R`` of the scene its compliance, bending and damping
/// (``compliance@R``, ``bending@R``, ``damping@R``). ``with_effects`` returns a new model.
#[pyclass(name = "ClothModel", module = "modelgap.cloth", frozen)]
pub struct PyClothModel {
    /// The model as built, before `effects`.
    base: ClothModel,
    /// Effects built in on top of `base`, in order.
    effects: Vec<Effect>,
    /// `base` with `effects`: what the loop works on.
    model: std::sync::Arc<dyn Model>,
    /// The scene with `effects` applied.
    scene: Scene,
}

impl PyClothModel {
    fn build(base: ClothModel, effects: Vec<Effect>) -> PyResult<Self> {
        let pairs: Vec<(&modelgap::Candidate, &[f64])> = effects
            .iter()
            .map(|e| (&e.candidate, e.values.as_slice()))
            .collect();
        let scene = base.edited(&pairs).map_err(cloth_err)?;
        let model: std::sync::Arc<dyn Model> = if effects.is_empty() {
            std::sync::Arc::new(base.clone())
        } else {
            std::sync::Arc::from(base.with_effects(&effects).map_err(to_py_err)?)
        };
        Ok(Self {
            base,
            effects,
            model,
            scene,
        })
    }

    /// The loop's model.
    pub fn model(&self) -> std::sync::Arc<dyn Model> {
        self.model.clone()
    }

    /// The class of a model loaded by the library ([`modelgap::load::load`]).
    pub fn from_model(m: ClothModel) -> PyResult<Self> {
        Self::build(m, Vec::new())
    }

    fn settings_state(&self) -> (String, Option<f64>, usize, usize) {
        let s = self.base.settings();
        (
            method_name(s.method).to_owned(),
            s.stretch_tolerance,
            s.max_iterations,
            s.step_divisor,
        )
    }
}

/// Simulation settings from the Python keywords.
fn predict_settings(
    method: &str,
    stretch_tolerance: Option<f64>,
    max_iterations: usize,
    step_divisor: usize,
) -> PyResult<PredictSettings> {
    if let Some(tol) = stretch_tolerance {
        positive("stretch_tolerance", tol)?;
    }
    if max_iterations == 0 {
        return Err(data_error("max_iterations must be at least 1, found 0"));
    }
    if step_divisor == 0 {
        return Err(data_error("step_divisor must be at least 1, found 0"));
    }
    Ok(PredictSettings {
        method: parse_method(method)?,
        stretch_tolerance,
        max_iterations,
        step_divisor,
        ..PredictSettings::default()
    })
}

#[pymethods]
impl PyClothModel {
    #[new]
    #[pyo3(signature = (scene, *, method = "newton", stretch_tolerance = None, max_iterations = 200, step_divisor = 1))]
    fn new(
        scene: &Bound<'_, PyScene>,
        method: &str,
        stretch_tolerance: Option<f64>,
        max_iterations: usize,
        step_divisor: usize,
    ) -> PyResult<Self> {
        let settings = predict_settings(method, stretch_tolerance, max_iterations, step_divisor)?;
        let base = ClothModel::new(scene.get().inner.clone()).with_settings(settings);
        Self::build(base, Vec::new())
    }

    /// A model of the scene file at ``path`` (simulated with the default settings).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let base = detached(py, move || ClothModel::from_path(&path))?.map_err(cloth_err)?;
        Self::build(base, Vec::new())
    }

    /// A model of a reference scene by name, optionally resized to ``nx × nz`` vertices.
    #[staticmethod]
    #[pyo3(signature = (name, nx = None, nz = None))]
    fn from_scene(name: &str, nx: Option<usize>, nz: Option<usize>) -> PyResult<Self> {
        let mut scene = scenes::by_name(name).map_err(cloth_err)?;
        if nx.is_some() || nz.is_some() {
            let nx = nx.unwrap_or(scene.cloth.nx);
            let nz = nz.unwrap_or(scene.cloth.nz);
            scene = scene.resized(nx, nz).map_err(cloth_err)?;
        }
        Self::build(ClothModel::new(scene), Vec::new())
    }

    /// A new model with the effects (from ``Explanation.effects``) built in.
    fn with_effects(&self, effects: Vec<PyRef<'_, PyEffect>>) -> PyResult<Self> {
        let mut all = self.effects.clone();
        all.extend(effects.iter().map(|e| e.inner.clone()));
        Self::build(self.base.clone(), all)
    }

    /// The model's name (the scene's).
    #[getter]
    fn name(&self) -> String {
        self.model.name()
    }

    /// The scene with the effects built in.
    #[getter]
    fn scene(&self) -> PyScene {
        PyScene {
            inner: self.scene.clone(),
        }
    }

    /// The effects built in so far.
    #[getter]
    fn effects(&self) -> Vec<PyEffect> {
        self.effects
            .iter()
            .map(|e| PyEffect { inner: e.clone() })
            .collect()
    }

    /// How it simulates: ``method``, ``stretch_tolerance``, ``max_iterations``,
    /// ``step_divisor``.
    #[getter]
    fn settings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (method, tol, max_it, divisor) = self.settings_state();
        let d = PyDict::new(py);
        d.set_item("method", method)?;
        d.set_item("stretch_tolerance", tol)?;
        d.set_item("max_iterations", max_it)?;
        d.set_item("step_divisor", divisor)?;
        Ok(d)
    }

    /// The outputs it predicts: ``m{id}.x``, ``m{id}.y``, ``m{id}.z`` for every vertex.
    #[getter]
    fn outputs(&self) -> Vec<String> {
        self.model.outputs()
    }

    /// The candidate effects explain fits: dicts with ``id``, ``name``, ``kind``,
    /// ``acts_on`` and ``params`` (names).
    fn candidates<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        crate::bond::candidate_dicts(py, &self.model.candidates())
    }

    /// Runs the model's scene (effects included) from its start and records vertices
    /// ``ids`` (all when None) at times ``t`` (s): a ``MarkerRecording``. The GIL is
    /// released.
    #[pyo3(signature = (t, ids = None))]
    fn simulate(
        &self,
        py: Python<'_>,
        t: &Bound<'_, PyAny>,
        ids: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyMarkerRecording> {
        let t = vec_from_py(t, "t")?;
        let ids = match ids {
            Some(ids) => index_list_from_py(ids, "ids")?,
            None => (0..(self.scene.cloth.nx * self.scene.cloth.nz) as u32).collect(),
        };
        let scene = &self.scene;
        let settings = self.base.settings();
        let rec = detached(py, move || {
            simulate_markers(scene, &ids, &t, settings, None)
        })?
        .map_err(cloth_err)?;
        Ok(PyMarkerRecording { inner: rec })
    }

    /// The model as a scene file (TOML), headed by a comment per effect built in.
    fn to_toml(&self) -> PyResult<String> {
        match self.model.to_file_text() {
            Some(text) => Ok(text),
            None => self.scene.to_toml().map_err(cloth_err),
        }
    }

    /// Restores a pickled model (see ``__reduce__``).
    #[staticmethod]
    fn _from_state(
        text: &str,
        label: &str,
        params: &Bound<'_, PySolverParams>,
        settings: (String, Option<f64>, usize, usize),
        effects: &str,
    ) -> PyResult<Self> {
        let mut scene = Scene::from_toml(text, label).map_err(cloth_err)?;
        scene.params = params.get().inner.clone();
        let (method, tol, max_it, divisor) = settings;
        let settings = predict_settings(&method, tol, max_it, divisor)?;
        let effects: Vec<Effect> = serde_json::from_str(effects)
            .map_err(|e| data_error(format!("not the JSON of a list of effects: {e}")))?;
        Self::build(ClothModel::new(scene).with_settings(settings), effects)
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, ClothModelState)> {
        let me = slf.get();
        let base = me.base.scene();
        let effects = serde_json::to_string(&me.effects).map_err(|e| data_error(e.to_string()))?;
        Ok((
            slf.get_type().getattr("_from_state")?,
            (
                base.to_toml().map_err(cloth_err)?,
                base.name.clone(),
                PySolverParams {
                    inner: base.params.clone(),
                },
                me.settings_state(),
                effects,
            ),
        ))
    }

    fn __repr__(&self) -> String {
        format!(
            "<ClothModel {} grid={}x{} effects={} method={}>",
            self.scene.name,
            self.scene.cloth.nx,
            self.scene.cloth.nz,
            self.effects.len(),
            method_name(self.base.settings().method)
        )
    }
}

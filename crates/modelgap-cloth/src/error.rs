//! Errors of the cloth crate.

use std::path::{Path, PathBuf};

use modelgap_core::{CoreError, Location};

/// Everything that can go wrong while building or stepping cloth. Each variant
/// carries the particles, lines or values a user needs to fix the input.
///
/// Running out of solver iterations is not an error: the step report says
/// `converged: false` and the state stays usable.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ClothError {
    /// An edge joins two particles at the same place, so it has no direction.
    #[error(
        "edge {a}-{b} has zero rest length; an edge must join particles at different positions"
    )]
    ZeroLengthEdge {
        /// First particle of the edge (index in its mesh or world).
        a: u32,
        /// Second particle of the edge.
        b: u32,
    },
    /// An edge refers to itself (a = b).
    #[error("edge {a}-{a} joins a particle to itself")]
    DegenerateEdge {
        /// The particle.
        a: u32,
    },
    /// A position or velocity is NaN or infinite.
    #[error("particle {particle} has a non-finite {what}: [{x}, {y}, {z}]")]
    NonFinite {
        /// The particle (index in the world).
        particle: u32,
        /// `position` or `velocity`.
        what: &'static str,
        /// x component.
        x: f64,
        /// y component.
        y: f64,
        /// z component.
        z: f64,
    },
    /// The time step is not positive and finite.
    #[error("time step must be positive and finite, found {dt} s")]
    BadTimeStep {
        /// The step given (s).
        dt: f64,
    },
    /// A mesh has no particles or no edges.
    #[error("mesh is empty: {n_particles} particles, {n_edges} edges")]
    EmptyMesh {
        /// Number of particles.
        n_particles: usize,
        /// Number of edges.
        n_edges: usize,
    },
    /// A vertex index is out of range (a pin, an edge or an OBJ face).
    #[error("vertex {vertex} is out of range: the mesh has {n_vertices} vertices")]
    VertexOutOfRange {
        /// The index given.
        vertex: usize,
        /// The number of vertices.
        n_vertices: usize,
    },
    /// A numeric parameter is out of its range.
    #[error("parameter '{name}' must be {expected}, found {value}")]
    BadParameter {
        /// The parameter.
        name: &'static str,
        /// What it must be, e.g. "positive and finite".
        expected: &'static str,
        /// The value given.
        value: f64,
    },
    /// A grid cloth is too small.
    #[error("a grid cloth needs at least 2 x 2 vertices, found {nx} x {nz}")]
    BadGrid {
        /// Vertices along x.
        nx: usize,
        /// Vertices along z.
        nz: usize,
    },
    /// A cloth id that this world did not hand out.
    #[error("unknown cloth id {id} (the world has {n_cloths} cloths)")]
    UnknownCloth {
        /// The id given.
        id: u32,
        /// The number of cloths.
        n_cloths: usize,
    },
    /// An OBJ file line cannot be read.
    #[error("OBJ line {line}: {message}")]
    Obj {
        /// 1-based line number.
        line: usize,
        /// What was expected and found.
        message: String,
    },
    /// A scene file cannot be read.
    #[error("scene '{scene}': {message}")]
    Scene {
        /// The scene's name or file name.
        scene: String,
        /// What is wrong.
        message: String,
    },
    /// A file cannot be read.
    #[error("cannot read {}: {source}", path.display())]
    Io {
        /// The underlying error.
        source: std::io::Error,
        /// The file.
        path: PathBuf,
    },
    /// A value of a marker file or recording cannot be used.
    #[error("expected {expected} for `{field}` at {at}, found {found}{}", in_path(.path))]
    MarkerField {
        /// Where: a CSV line, an MCAP message or a frame (sample) of a recording.
        at: Location,
        /// The column or JSON field (`t`, `id`, `x`, `ids`, `positions`, …).
        field: String,
        /// What was expected.
        expected: String,
        /// What was found.
        found: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },
    /// Marker frames are not in strictly increasing time.
    #[error(
        "marker time is not strictly increasing at {at}: {t} s after {t_prev} s{}",
        in_path(.path)
    )]
    MarkerTime {
        /// The frame (CSV line, MCAP message or sample) that is not later than its predecessor.
        at: Location,
        /// The previous frame's time (s).
        t_prev: f64,
        /// The offending time (s).
        t: f64,
        /// The file, when known.
        path: Option<PathBuf>,
    },
    /// A marker file has no header `t,id,x,y,z`, or a different one.
    #[error("expected the header `t,id,x,y,z`, found {found}{}", in_path(.path))]
    MarkerHeader {
        /// The header found (quoted), or `no header`.
        found: String,
        /// The file, when known.
        path: Option<PathBuf>,
    },
    /// A marker recording has no frames.
    #[error("expected at least one marker frame, found none{}", in_path(.path))]
    NoMarkerFrames {
        /// The file, when known.
        path: Option<PathBuf>,
    },
    /// A prescribed pin path cannot be used.
    #[error("pin path point {index}: {message}")]
    BadPinPath {
        /// The point (0-based).
        index: usize,
        /// What was expected and found.
        message: String,
    },
    /// A kinematic pin was asked for a vertex that is not pinned (static).
    #[error("vertex {vertex} is not pinned; only pinned (static) vertices can follow a path")]
    NotPinned {
        /// The vertex (index in its mesh).
        vertex: usize,
    },
    /// A collider cannot be built: a field is out of range or its mesh is malformed.
    #[error("{shape} collider: `{field}` must be {expected}, found {found}")]
    BadCollider {
        /// The shape: `plane`, `ball`, `cuboid`, `capsule` or `trimesh`.
        shape: &'static str,
        /// The field, with an index for a mesh's vertex or triangle (`triangles[3]`).
        field: String,
        /// What it must be.
        expected: String,
        /// What was given.
        found: String,
    },
    /// An OBJ face refers to a vertex that is not defined (yet): OBJ indices count from 1,
    /// and negative ones count back from the last vertex defined so far (−1 is the last).
    #[error(
        "OBJ line {line}: expected a face vertex index {}, found {index}{}",
        obj_range(*.n_vertices),
        in_path(.path)
    )]
    ObjIndex {
        /// 1-based line number of the face.
        line: usize,
        /// The index as written in the file.
        index: i64,
        /// Vertices defined before the face.
        n_vertices: usize,
        /// The file, when known.
        path: Option<PathBuf>,
    },
    /// A field of a scene file is out of its range.
    #[error("scene '{scene}': {field} must be {expected}, found {found}")]
    SceneField {
        /// The scene's name or file name.
        scene: String,
        /// The field, as written in the file (`gravity`, `cloth.pins[2]`, …).
        field: String,
        /// What it must be.
        expected: String,
        /// What was given.
        found: String,
    },
    /// A field of a scene file cannot be used; the error names its line.
    #[error("scene '{scene}' line {line}, `{field}`: {message}")]
    SceneAt {
        /// The scene's name or file name.
        scene: String,
        /// The 1-based line of the field.
        line: usize,
        /// The field, as written in the file (`pins.attach[0].rows[1]`).
        field: String,
        /// What was expected and found.
        message: String,
    },
    /// A scene pins the same vertex twice.
    #[error(
        "scene '{scene}': vertex {vertex} is pinned twice, by {first} and by {second}; \
         expected each vertex pinned once"
    )]
    DuplicatePin {
        /// The scene's name or file name.
        scene: String,
        /// The vertex (index `row * nx + col`).
        vertex: u32,
        /// Where it is pinned first (`cloth.pins[0]`, `pins.paths[1].vertex`).
        first: String,
        /// Where it is pinned again.
        second: String,
    },
    /// A grid has more particles than its limit allows (checked before anything is
    /// allocated; see the field `max_particles` of [`GridCloth`](crate::GridCloth)).
    #[error(
        "expected at most {limit} particles (`max_particles`), found a {nx} x {nz} grid of {} \
         particles",
        u128::from(*.nx as u64) * u128::from(*.nz as u64)
    )]
    TooManyParticles {
        /// Vertices along x.
        nx: usize,
        /// Vertices along z.
        nz: usize,
        /// The limit (particles).
        limit: usize,
    },
    /// A run needs more steps than its limit allows (checked before the run starts; see
    /// [`RunLimits::max_steps`](crate::trajectory::RunLimits::max_steps)).
    #[error(
        "expected at most {limit} steps (`max_steps`), found {} (duration {} s / dt {} s)",
        num(*.steps),
        num(*.duration),
        num(*.dt)
    )]
    TooManySteps {
        /// The steps the run needs: `duration / dt`, rounded.
        steps: f64,
        /// Simulated time (s).
        duration: f64,
        /// Step size (s).
        dt: f64,
        /// The limit (steps).
        limit: usize,
    },
    /// A run would record more frames than its memory limit allows (checked before the run
    /// starts; see [`RunLimits::max_frame_bytes`](crate::trajectory::RunLimits::max_frame_bytes)).
    #[error(
        "expected recorded frames within {limit} bytes (`max_frame_bytes`), found {frames} \
         frames x {positions} positions x 24 bytes = {bytes} bytes ({:.1} GiB); record fewer \
         frames (a lower rate) or fewer markers",
        *.bytes as f64 / f64::from(1u32 << 30)
    )]
    TooMuchFrameMemory {
        /// Frames the run would record.
        frames: u64,
        /// Positions per frame (every vertex, plus the markers).
        positions: u64,
        /// `frames × positions × 24` bytes.
        bytes: u128,
        /// The limit (bytes).
        limit: u64,
    },
    /// A step left a non-finite (NaN or infinite, or overflowed) position, velocity or
    /// stretch: the simulation diverged. The world holds that step's state.
    #[error(
        "simulation diverged at step {step} (t = {} s): expected a finite {quantity}{}, \
         found {value}",
        num(*.time),
        .particle.map(|p| format!(" of particle {p}")).unwrap_or_default()
    )]
    Diverged {
        /// The step (counted from 1 over the world's life).
        step: usize,
        /// Simulated time at the end of the step (s).
        time: f64,
        /// `position`, `velocity` or `stretch`.
        quantity: &'static str,
        /// The particle (index in the world) of a position or velocity.
        particle: Option<u32>,
        /// The value found: a vector `[x, y, z]`, or a stretch and its edge (`inf on edge 4-7`).
        value: String,
    },
    /// A run was cancelled through its cancel flag (Ctrl-C) between two steps.
    #[error("run cancelled after step {step} of {steps}")]
    Cancelled {
        /// Steps done.
        step: usize,
        /// Steps the run would have taken.
        steps: usize,
    },
    /// An error of modelgap-core: MCAP files, their topics, their time.
    #[error(transparent)]
    Core(#[from] CoreError),
}

impl ClothError {
    /// The same error with `path` as the file it is about (for marker errors, OBJ face
    /// indices and core errors; other variants are returned unchanged).
    #[must_use]
    pub fn with_path(self, file: &Path) -> Self {
        let set = |path: Option<PathBuf>| path.or_else(|| Some(file.to_path_buf()));
        match self {
            Self::MarkerField {
                at,
                field,
                expected,
                found,
                path,
            } => Self::MarkerField {
                at,
                field,
                expected,
                found,
                path: set(path),
            },
            Self::MarkerTime {
                at,
                t_prev,
                t,
                path,
            } => Self::MarkerTime {
                at,
                t_prev,
                t,
                path: set(path),
            },
            Self::MarkerHeader { found, path } => Self::MarkerHeader {
                found,
                path: set(path),
            },
            Self::NoMarkerFrames { path } => Self::NoMarkerFrames { path: set(path) },
            Self::ObjIndex {
                line,
                index,
                n_vertices,
                path,
            } => Self::ObjIndex {
                line,
                index,
                n_vertices,
                path: set(path),
            },
            Self::Core(e) => Self::Core(e.with_path(file)),
            other => other,
        }
    }
}

/// ` in <path>` when the path is known, else nothing.
fn in_path(path: &Option<PathBuf>) -> String {
    path.as_ref()
        .map(|p| format!(" in {}", p.display()))
        .unwrap_or_default()
}

/// A number for a message: plain when it reads well, in exponent form when very large or
/// small (`1e200`, not two hundred zeros).
pub(crate) fn num(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && a.is_finite() && !(1e-4..1e7).contains(&a) {
        format!("{v:e}")
    } else {
        v.to_string()
    }
}

/// The valid face indices of an OBJ file with `n` vertices defined so far.
fn obj_range(n: usize) -> String {
    if n == 0 {
        "of a vertex defined before the face (none is)".to_owned()
    } else {
        format!("from 1 to {n} or from -{n} to -1 ({n} vertices defined so far)")
    }
}

/// `Result` with [`ClothError`] as the error type.
pub type Result<T, E = ClothError> = std::result::Result<T, E>;

//! Errors of the cloth crate.

use std::path::PathBuf;

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
    /// An edge joins two static particles; no impulse can move either.
    #[error("edge {a}-{b} joins two static particles; at least one end must be dynamic")]
    StaticEdge {
        /// First particle of the edge.
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
}

/// `Result` with [`ClothError`] as the error type.
pub type Result<T, E = ClothError> = std::result::Result<T, E>;

//! Reference scenes, shared by tests, benches and examples, stored as TOML
//! files in the crate's `scenes/` folder.
//!
//! All three are the paper's mesh: 30 × 30 particles on a 1 m square, 1 g per
//! particle, structural edges only (1740 constraints), starting flat and
//! horizontal in the x–z plane, gravity 9.81 m/s², `h` = 0.01 s for 3 s,
//! tolerance 1e-4: [`corner`] (pinned at vertex 0), [`two_corners`] (vertices
//! 0 and 29, the ends of row 0), [`drape`] (no pins, dropped from 0.5 m above
//! a fixed ball of radius 0.3 m with friction 0.3).
//!
//! A scene file:
//!
//! ```toml
//! name = "corner"
//! description = "..."
//! duration = 3.0            # s
//! dt = 0.01                 # s
//! stretch_tolerance = 1e-4  # relative
//! gravity = [0.0, -9.81, 0.0]   # m/s^2, magnitude at most 1000 (solver::MAX_GRAVITY)
//! integrator = "impulse"    # optional: "impulse" (the paper's step, first order) or
//!                           # "bdf2" (second order; solver::Integrator)
//!
//! [cloth]
//! nx = 30
//! nz = 30
//! size = 1.0                # m, the grid spans size x size * (nz - 1) / (nx - 1)
//! particle_mass = 0.001     # kg
//! origin = [0.0, 0.0, 0.0]  # m, position of vertex 0
//! rotation = [0.0, 0.0, 0.0] # optional, rad: axis x angle turning the grid's x-z plane
//!                           # (about vertex 0); [1.5708, 0, 0] hangs rows along -y
//! pins = [0]                # vertex indices row * nx + col
//! shear = false             # optional
//! bend = false              # optional
//! compliance = 0.0          # optional, m/N per constraint (0: inextensible)
//! warp_compliance = 0.0     # optional, m/N, links along a row (instead of compliance)
//! weft_compliance = 0.0     # optional, m/N, links along a column (instead of compliance)
//! bending_rigidity = 0.0    # optional, N m, quadratic bending (crate::bending)
//! bend_stiffness = 0.0      # optional, N/m, springs on the bend pairs (crate::forces)
//! damping = 0.0             # optional, 1/s, velocity damping -c m v
//!
//! [air]                     # optional: aerodynamic drag per triangle (crate::forces)
//! density = 1.225           # kg/m^3, optional
//! drag_coefficient = 1.0    # dimensionless, on the velocity across the sheet (optional, 0)
//! skin_friction = 0.0       # optional, dimensionless, on the velocity along the sheet
//! wind = [0.0, 0.0, 0.0]    # m/s, optional
//!
//! [[materials]]             # optional, any number: a region with its own material
//! name = "hem"              # (crate::material); later entries win where they overlap
//! rows = [28, 29]           # and/or vertices, cols, regions, border, as [[pins.attach]]
//! compliance = 0.002        # any of compliance, warp_compliance, weft_compliance,
//! bending_rigidity = 1e-4   # bending_rigidity, damping
//!
//! [[point_masses]]          # optional, any number: extra mass at a vertex
//! vertex = 899
//! mass = 0.01               # kg
//!
//! [[colliders]]             # optional, any number; each has a shape and its fields
//! shape = "ball"            # a solid ball
//! center = [0.5, 0.0, 0.5]  # m
//! radius = 0.3              # m
//! friction = 0.3            # optional, Coulomb coefficient (default 0)
//!
//! [[colliders]]
//! shape = "plane"           # the half-space behind a plane
//! point = [0.0, -1.0, 0.0]  # m
//! normal = [0.0, 1.0, 0.0]  # outward, normalised when read
//!
//! [[colliders]]
//! shape = "cuboid"          # a solid box
//! center = [0.5, -0.2, 0.5] # m
//! half_extents = [0.3, 0.05, 0.3]  # m, along the box's axes
//! rotation = [0.0, 0.0, 0.0]       # optional, rad: rotation axis * angle
//!
//! [[colliders]]
//! shape = "capsule"         # the points within radius of the segment a-b
//! a = [0.0, -0.2, 0.5]      # m
//! b = [1.0, -0.2, 0.5]      # m
//! radius = 0.05             # m
//!
//! [[colliders]]
//! shape = "trimesh"         # triangles counter-clockwise seen from outside
//! vertices = [[0.0, -0.5, 0.0], [1.0, -0.5, 0.0], [1.0, -0.5, 1.0], [0.0, -0.5, 1.0]]  # m
//! triangles = [[0, 2, 1], [0, 3, 2]]   # vertex indices
//! # obj = "table.obj"       # or: an OBJ file (relative to the scene file) instead
//! translation = [0.0, 0.0, 0.0]        # optional, m
//! rotation = [0.0, 0.0, 0.0]           # optional, rad: rotation axis * angle
//! shell_thickness = 0.01    # optional, m: an open mesh is a surface; a point up to
//!                           # this far behind it penetrates (a closed mesh is a solid)
//!
//! [pins]                    # optional: pins that move (kinematic pins)
//! from_markers = false      # pinned vertices whose ids appear in a marker
//!                           # recording follow the recorded positions
//! markers = "run.csv"       # that recording (.csv or .mcap, relative to the scene file)
//!
//! [[pins.paths]]            # any number: a vertex (pinned by this) following a path
//! vertex = 29
//! path = [[0.0, 0.983, 0.0, 0.0], [1.0, 1.5, 0.0, 0.0]]  # [t (s), x, y, z (m)], linear
//!
//! [[rails]]                 # any number: a moving frame, named once (crate::rail)
//! name = "top"
//! translation = ["0.03 * sin(2 * pi * 0.4 * t)", "0", "0"]  # m, or rows [t, x, y, z]
//! rotation = ["0", "0", "0"]  # optional, rad, axis x angle about `origin` (optional)
//!
//! [[pins.attach]]           # any number: vertices (pinned by this) riding a rail
//! rail = "top"
//! rows = [0]                # and/or cols, vertices, regions [[c0, r0, c1, r1]], border
//! ```
//!
//! Pins may be neighbours (a whole row, a border): the edge between two pins is not a
//! constraint. See [`crate::rail::file`] for every field of `[[rails]]` and
//! `[[pins.attach]]`; their errors name the line.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Vector3};
use serde::Deserialize;
use toml::Spanned;

use crate::contact::{Collider, Shape};
use crate::error::{ClothError, Result, num};
use crate::forces::{AIR_DENSITY, ClothEffects, ClothForces, PointMass};
use crate::kinematic::{PinPath, follow_markers};
use crate::markers::{MarkerRecording, read_markers_path};
use crate::material::{MaterialFile, write_materials};
use crate::mesh::GridCloth;
use crate::rail::file::{AttachFile, RailFile, Reader};
use crate::rail::{Rail, RailPins};
use crate::solver::{Integrator, MAX_GRAVITY, SolverParams};
use crate::world::{ClothId, ClothWorld};

const CORNER: &str = include_str!("../scenes/corner.toml");
const TWO_CORNERS: &str = include_str!("../scenes/two-corners.toml");
const DRAPE: &str = include_str!("../scenes/drape.toml");

/// A reference scene: one grid cloth, colliders, solver parameters, a step and a duration.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Short name (`corner`, `two-corners`, `drape`).
    pub name: String,
    /// One line saying what it shows.
    pub description: String,
    /// Simulated time (s).
    pub duration: f64,
    /// Step size (s).
    pub dt: f64,
    /// Solver parameters (tolerance and gravity from the file, the rest default).
    pub params: SolverParams,
    /// The cloth.
    pub cloth: GridCloth,
    /// Static colliders.
    pub colliders: Vec<Collider>,
    /// Pinned vertices that follow prescribed paths: (vertex index, path). Each vertex is
    /// also in the cloth's pins.
    pub pin_paths: Vec<(u32, PinPath)>,
    /// Rails: moving frames named once ([`crate::rail`]).
    pub rails: Vec<Rail>,
    /// Vertices riding the rails, each set naming its rail. Each vertex is also in the
    /// cloth's pins.
    pub rail_pins: Vec<RailPins>,
    /// Whether pinned vertices whose ids appear in a marker recording follow the recorded
    /// positions (see [`build`](Self::build)).
    pub pins_from_markers: bool,
    /// The marker recording of `pins_from_markers` (`.csv` or `.mcap`); a relative path in
    /// a scene file is resolved against the file's folder by [`from_path`](Self::from_path).
    pub pin_markers: Option<PathBuf>,
    /// Physical terms beyond gravity: drag, wind, damping, bending, compliance, point
    /// masses (see [`crate::forces`]); none by default.
    pub effects: ClothEffects,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: String,
    #[serde(default)]
    description: String,
    duration: f64,
    dt: f64,
    stretch_tolerance: Option<f64>,
    gravity: Option<[f64; 3]>,
    integrator: Option<String>,
    cloth: ClothFile,
    #[serde(default)]
    colliders: Vec<ColliderFile>,
    #[serde(default)]
    pins: PinsFile,
    air: Option<AirFile>,
    #[serde(default)]
    point_masses: Vec<PointMass>,
    #[serde(default)]
    rails: Vec<RailFile>,
    #[serde(default)]
    materials: Vec<MaterialFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AirFile {
    density: Option<f64>,
    #[serde(default)]
    drag_coefficient: f64,
    #[serde(default)]
    skin_friction: f64,
    #[serde(default)]
    wind: [f64; 3],
}

#[derive(Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct PinsFile {
    #[serde(default)]
    from_markers: bool,
    markers: Option<PathBuf>,
    #[serde(default)]
    paths: Vec<PathFile>,
    #[serde(default)]
    attach: Vec<AttachFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PathFile {
    vertex: u32,
    path: Vec<[f64; 4]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ClothFile {
    nx: usize,
    nz: usize,
    size: f64,
    particle_mass: Option<f64>,
    #[serde(default)]
    origin: [f64; 3],
    #[serde(default)]
    rotation: [f64; 3],
    #[serde(default)]
    pins: Vec<u32>,
    #[serde(default)]
    shear: bool,
    #[serde(default)]
    bend: bool,
    #[serde(default)]
    compliance: f64,
    #[serde(default)]
    bend_stiffness: f64,
    #[serde(default)]
    damping: f64,
    warp_compliance: Option<Spanned<f64>>,
    weft_compliance: Option<Spanned<f64>>,
    bending_rigidity: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, tag = "shape", rename_all = "lowercase")]
enum ColliderFile {
    Ball {
        center: [f64; 3],
        radius: f64,
        #[serde(default)]
        friction: f64,
    },
    Plane {
        point: [f64; 3],
        normal: [f64; 3],
        #[serde(default)]
        friction: f64,
    },
    Cuboid {
        center: [f64; 3],
        half_extents: [f64; 3],
        /// Rotation vector: axis times angle (rad).
        #[serde(default)]
        rotation: [f64; 3],
        #[serde(default)]
        friction: f64,
    },
    Capsule {
        a: [f64; 3],
        b: [f64; 3],
        radius: f64,
        #[serde(default)]
        friction: f64,
    },
    TriMesh {
        #[serde(default)]
        vertices: Vec<[f64; 3]>,
        #[serde(default)]
        triangles: Vec<[u32; 3]>,
        /// An OBJ file instead of `vertices` and `triangles`.
        obj: Option<PathBuf>,
        #[serde(default)]
        translation: [f64; 3],
        /// Rotation vector: axis times angle (rad).
        #[serde(default)]
        rotation: [f64; 3],
        shell_thickness: Option<f64>,
        #[serde(default)]
        friction: f64,
    },
}

/// The mesh of an OBJ file (`path` relative to `dir` when given).
fn read_obj_mesh(
    path: &Path,
    dir: Option<&Path>,
) -> std::result::Result<crate::mesh::ClothMesh, String> {
    let path = match dir {
        Some(dir) if path.is_relative() => dir.join(path),
        _ => path.to_path_buf(),
    };
    let file = std::fs::File::open(&path).map_err(|source| {
        ClothError::Io {
            source,
            path: path.clone(),
        }
        .to_string()
    })?;
    crate::mesh::ClothMesh::from_obj(
        std::io::BufReader::new(file),
        crate::mesh::DEFAULT_PARTICLE_MASS,
    )
    .map_err(|e| match e {
        e @ ClothError::ObjIndex { .. } => e.with_path(&path).to_string(),
        e => format!("{e} in {}", path.display()),
    })
}

/// The scene file's colliders (an `obj` file relative to `dir` when given); an error
/// names the collider's index and field.
fn colliders_from_file(
    colliders: &[ColliderFile],
    dir: Option<&Path>,
) -> std::result::Result<Vec<Collider>, String> {
    let pose = |translation: [f64; 3], rotation: [f64; 3]| {
        Isometry3::new(Vector3::from(translation), Vector3::from(rotation))
    };
    let mut out = Vec::with_capacity(colliders.len());
    for (k, c) in colliders.iter().enumerate() {
        let built = match c {
            ColliderFile::Ball {
                center,
                radius,
                friction,
            } => Ok(Collider::ball(Vector3::from(*center), *radius).friction(*friction)),
            ColliderFile::Plane {
                point,
                normal,
                friction,
            } => {
                let n = Vector3::from(*normal);
                if n.iter().all(|c| c.is_finite()) && n.norm() > 0.0 {
                    Ok(Collider::plane(Vector3::from(*point), n).friction(*friction))
                } else {
                    Err(ClothError::BadCollider {
                        shape: "plane",
                        field: "normal".into(),
                        expected: "non-zero and finite".into(),
                        found: format!("{normal:?}"),
                    })
                }
            }
            ColliderFile::Cuboid {
                center,
                half_extents,
                rotation,
                friction,
            } => Collider::cuboid(Vector3::from(*half_extents), pose(*center, *rotation))
                .map(|c| c.friction(*friction)),
            ColliderFile::Capsule {
                a,
                b,
                radius,
                friction,
            } => Collider::capsule(Vector3::from(*a), Vector3::from(*b), *radius)
                .map(|c| c.friction(*friction)),
            ColliderFile::TriMesh {
                vertices,
                triangles,
                obj,
                translation,
                rotation,
                shell_thickness,
                friction,
            } => {
                let (vertices, triangles) = match obj {
                    Some(_) if !vertices.is_empty() || !triangles.is_empty() => {
                        return Err(format!(
                            "colliders[{k}]: a trimesh takes either `obj` or `vertices` and \
                             `triangles`, found both"
                        ));
                    }
                    Some(path) => {
                        let mesh =
                            read_obj_mesh(path, dir).map_err(|e| format!("colliders[{k}]: {e}"))?;
                        (mesh.positions, mesh.triangles)
                    }
                    None => (
                        vertices.iter().map(|v| Vector3::from(*v)).collect(),
                        triangles.clone(),
                    ),
                };
                Collider::trimesh_with_shell(
                    vertices,
                    triangles,
                    shell_thickness.unwrap_or(crate::contact::DEFAULT_SHELL_THICKNESS),
                )
            }
            .map(|c| {
                c.transformed(&pose(*translation, *rotation))
                    .friction(*friction)
            }),
        };
        let collider = built
            .and_then(|c| c.check().map(|()| c))
            .map_err(|e| format!("colliders[{k}]: {e}"))?;
        out.push(collider);
    }
    Ok(out)
}

/// The largest length or coordinate a scene file may hold (m): 1000 km. A grid far
/// beyond it loses its spacing in the rounding of its positions.
pub const MAX_SCENE_LENGTH: f64 = 1e6;

/// A scene-file field out of its range, before the scene's label is attached.
struct FieldError {
    field: String,
    expected: String,
    found: String,
}

impl FieldError {
    fn new(field: &str, expected: impl Into<String>, found: impl Into<String>) -> Self {
        Self {
            field: field.to_owned(),
            expected: expected.into(),
            found: found.into(),
        }
    }

    fn in_scene(self, label: &str) -> ClothError {
        ClothError::SceneField {
            scene: label.to_owned(),
            field: self.field,
            expected: self.expected,
            found: self.found,
        }
    }
}

/// `[x, y, z]` as written in a scene file.
fn triple(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]))
}

/// The numbers and sizes of a scene file, each checked where it enters.
/// The integrator a scene file names (`integrator`).
fn integrator(name: &str) -> std::result::Result<Integrator, FieldError> {
    match name {
        "impulse" => Ok(Integrator::Impulse),
        "bdf2" => Ok(Integrator::Bdf2),
        _ => Err(FieldError::new(
            "integrator",
            "\"impulse\" (the paper's step) or \"bdf2\" (second order)",
            format!("{name:?}"),
        )),
    }
}

fn check_fields(file: &SceneFile) -> std::result::Result<(), FieldError> {
    let positive = |field: &str, v: f64| {
        if v > 0.0 && v.is_finite() {
            Ok(())
        } else {
            Err(FieldError::new(field, "positive and finite", num(v)))
        }
    };
    positive("dt", file.dt)?;
    positive("duration", file.duration)?;
    if let Some(tol) = file.stretch_tolerance {
        positive("stretch_tolerance", tol)?;
    }
    if let Some(name) = &file.integrator {
        integrator(name)?;
    }
    if let Some(g) = file.gravity {
        let magnitude = crate::solver::magnitude(&Vector3::from(g));
        if magnitude.is_nan() || magnitude > MAX_GRAVITY {
            return Err(FieldError::new(
                "gravity",
                format!("finite and at most {MAX_GRAVITY} m/s^2 in magnitude"),
                format!("{} (magnitude {} m/s^2)", triple(g), num(magnitude)),
            ));
        }
    }
    let c = &file.cloth;
    if c.nx < 2 || c.nz < 2 {
        return Err(FieldError::new(
            "cloth.nx x cloth.nz",
            "at least 2 x 2 vertices",
            format!("{} x {}", c.nx, c.nz),
        ));
    }
    positive("cloth.size", c.size)?;
    if c.size > MAX_SCENE_LENGTH {
        return Err(FieldError::new(
            "cloth.size",
            format!("at most {MAX_SCENE_LENGTH} m"),
            num(c.size),
        ));
    }
    if let Some(m) = c.particle_mass {
        positive("cloth.particle_mass", m)?;
    }
    if !c.origin.iter().all(|v| v.abs() <= MAX_SCENE_LENGTH) {
        return Err(FieldError::new(
            "cloth.origin",
            format!("finite coordinates of at most {MAX_SCENE_LENGTH} m"),
            triple(c.origin),
        ));
    }
    if !c.rotation.iter().all(|v| v.is_finite()) {
        return Err(FieldError::new(
            "cloth.rotation",
            "finite (rad, axis x angle)",
            triple(c.rotation),
        ));
    }
    Ok(())
}

impl Scene {
    /// Reads a scene from TOML text; `label` names it in errors.
    ///
    /// Every field is checked where it enters, and an error names it (`gravity`,
    /// `cloth.pins[2]`, `colliders[1]`): `dt`, `duration`, `cloth.size` and tolerances
    /// positive and finite; lengths and coordinates (`cloth.size`, `cloth.origin`) at most
    /// [`MAX_SCENE_LENGTH`] m; gravity finite and at most
    /// [`MAX_GRAVITY`] m/s²; masses positive and finite; pins
    /// on the grid, each vertex pinned once. The size of the grid is checked when it is
    /// built (the field `max_particles` of [`GridCloth`]).
    ///
    /// # Errors
    /// [`ClothError::Scene`] for malformed TOML or unknown fields, or a collider that cannot
    /// be built (the message names it, `colliders[2]`, and its field);
    /// [`ClothError::SceneField`] for a field out of its range;
    /// [`ClothError::DuplicatePin`] for a vertex pinned twice (in `cloth.pins`,
    /// `pins.paths` or `pins.attach`); [`ClothError::SceneAt`], naming the line and the
    /// field, for a bad `[[rails]]`, `[[pins.attach]]` or `[[materials]]` entry (an unknown
    /// rail name, a vertex, row or column past the grid, a malformed row of samples or
    /// expression, a material region named twice or without vertices, a negative or
    /// non-finite material value) or a negative `cloth.warp_compliance`,
    /// `cloth.weft_compliance` or `cloth.bending_rigidity`.
    pub fn from_toml(text: &str, label: &str) -> Result<Self> {
        Self::from_toml_in(text, label, None)
    }

    /// As [`from_toml`](Self::from_toml), with relative file names in the scene (a
    /// trimesh collider's `obj`) resolved against `dir`.
    fn from_toml_in(text: &str, label: &str, dir: Option<&Path>) -> Result<Self> {
        let bad = |message: String| ClothError::Scene {
            scene: label.to_string(),
            message,
        };
        let file: SceneFile = toml::from_str(text).map_err(|e| bad(e.to_string()))?;
        let in_scene = |e: FieldError| e.in_scene(label);
        check_fields(&file).map_err(in_scene)?;
        let mut params = SolverParams::default();
        if let Some(tol) = file.stretch_tolerance {
            params.stretch_tolerance = tol;
        }
        if let Some(g) = file.gravity {
            params.gravity = Vector3::from(g);
        }
        if let Some(name) = &file.integrator {
            params.integrator = integrator(name).map_err(in_scene)?;
        }
        let c = &file.cloth;
        let [ox, oy, oz] = c.origin;
        let mut cloth = GridCloth::new(c.nx, c.nz, c.size / (c.nx - 1) as f64)
            .shear(c.shear)
            .bend(c.bend)
            .world_from_local(Isometry3::new(
                Vector3::new(ox, oy, oz),
                Vector3::from(c.rotation),
            ));
        if let Some(m) = c.particle_mass {
            cloth = cloth.particle_mass(m);
        }
        // Saturates for absurd sizes, which building the grid refuses with its limit.
        let n_vertices = c.nx.saturating_mul(c.nz);
        // Where each pinned vertex is pinned, to refuse a second pin.
        let mut pinned_at: BTreeMap<u32, String> = BTreeMap::new();
        let mut pin_once = |vertex: u32, at: String| match pinned_at.get(&vertex) {
            Some(first) => Err(ClothError::DuplicatePin {
                scene: label.to_string(),
                vertex,
                first: first.clone(),
                second: at,
            }),
            None => {
                pinned_at.insert(vertex, at);
                Ok(())
            }
        };
        for (k, &p) in c.pins.iter().enumerate() {
            let field = format!("cloth.pins[{k}]");
            if p as usize >= n_vertices {
                return Err(in_scene(FieldError::new(
                    &field,
                    format!(
                        "a vertex of the {} x {} grid (below {n_vertices})",
                        c.nx, c.nz
                    ),
                    p.to_string(),
                )));
            }
            pin_once(p, field)?;
            cloth = cloth.pin(p);
        }
        let mut pin_paths = Vec::with_capacity(file.pins.paths.len());
        for (k, p) in file.pins.paths.iter().enumerate() {
            let field = format!("pins.paths[{k}].vertex");
            if p.vertex as usize >= n_vertices {
                return Err(in_scene(FieldError::new(
                    &field,
                    format!("below {n_vertices} (the grid's vertices)"),
                    p.vertex.to_string(),
                )));
            }
            let path = PinPath::from_rows(&p.path)
                .map_err(|e| bad(format!("pins.paths[{k}] (vertex {}): {e}", p.vertex)))?;
            pin_once(p.vertex, field)?;
            cloth = cloth.pin(p.vertex);
            pin_paths.push((p.vertex, path));
        }
        let reader = Reader { text, label };
        let n_steps = (file.duration / file.dt).round().min(1e5) as usize;
        let times: Vec<f64> = (0..=n_steps).map(|k| k as f64 * file.dt).collect();
        let rails = reader.rails(&file.rails, &times)?;
        let mut rail_pins = Vec::with_capacity(file.pins.attach.len());
        for (set, vertices, at) in reader.attachments(&file.pins.attach, &rails, (c.nx, c.nz))? {
            for v in vertices {
                pin_once(v, format!("{at} (rail \"{}\")", set.rail))?;
                cloth = cloth.pin(v);
            }
            rail_pins.push(set);
        }
        let mut effects = effects_from_file(&file, n_vertices).map_err(in_scene)?;
        let value = |v: &Option<Spanned<f64>>, field: &str, unit: &str| {
            reader.non_negative(v.as_ref(), field, unit)
        };
        effects.warp_compliance = value(&c.warp_compliance, "cloth.warp_compliance", "m/N")?;
        effects.weft_compliance = value(&c.weft_compliance, "cloth.weft_compliance", "m/N")?;
        effects.bending_rigidity =
            value(&c.bending_rigidity, "cloth.bending_rigidity", "N m")?.unwrap_or(0.0);
        effects.materials = reader.materials(&file.materials, (c.nx, c.nz))?;
        let colliders = colliders_from_file(&file.colliders, dir).map_err(bad)?;
        Ok(Self {
            name: file.name,
            description: file.description,
            duration: file.duration,
            dt: file.dt,
            params,
            cloth,
            colliders,
            pin_paths,
            rails,
            rail_pins,
            pins_from_markers: file.pins.from_markers,
            pin_markers: file.pins.markers,
            effects,
        })
    }

    /// Reads a scene file.
    ///
    /// # Errors
    /// [`ClothError::Io`] when the file cannot be read, else as [`from_toml`](Self::from_toml).
    pub fn from_path(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|source| ClothError::Io {
            source,
            path: path.to_path_buf(),
        })?;
        let mut scene = Self::from_toml_in(&text, &path.display().to_string(), path.parent())?;
        if let Some(markers) = scene.pin_markers.take() {
            scene.pin_markers = Some(match path.parent() {
                Some(dir) if markers.is_relative() => dir.join(markers),
                _ => markers,
            });
        }
        Ok(scene)
    }

    /// The same scene on a grid of `nx × nz` vertices over the same width: pins (static and
    /// moving) go to the nearest vertex of the new grid at the same relative place, so
    /// `two-corners` keeps its two corners; the rows, columns and regions riding a rail stay
    /// whole rows, columns and regions at the same relative place.
    ///
    /// # Errors
    ///
    /// [`ClothError::BadGrid`] for fewer than 2 × 2 vertices,
    /// [`ClothError::TooManyParticles`] for more than the cloth's `max_particles`.
    pub fn resized(&self, nx: usize, nz: usize) -> Result<Self> {
        let old = &self.cloth;
        crate::mesh::grid_size(nx, nz, old.max_particles)?;
        let (ox, oz) = (old.nx.max(2), old.nz.max(2));
        let map = |v: u32| -> u32 {
            let (col, row) = (v as usize % ox, v as usize / ox);
            let scale = |i: usize, n_old: usize, n_new: usize| {
                ((i as f64) * (n_new - 1) as f64 / (n_old - 1) as f64).round() as usize
            };
            (scale(row, oz, nz) * nx + scale(col, ox, nx)) as u32
        };
        let mut scene = self.clone();
        scene.cloth.nx = nx;
        scene.cloth.nz = nz;
        scene.cloth.spacing = old.spacing * (ox - 1) as f64 / (nx - 1) as f64;
        let on_rails: Vec<u32> = self
            .rail_pins
            .iter()
            .flat_map(|p| p.vertices.resolve(old.nx, old.nz))
            .collect();
        scene.cloth.pinned = old
            .pinned
            .iter()
            .filter(|v| !on_rails.contains(v))
            .map(|&v| map(v))
            .collect();
        for (v, _) in &mut scene.pin_paths {
            *v = map(*v);
        }
        for r in &mut scene.effects.materials {
            r.vertices = r.vertices.resized((ox, oz), (nx, nz), map);
        }
        for p in &mut scene.rail_pins {
            p.vertices = p.vertices.resized((ox, oz), (nx, nz), map);
            scene.cloth.pinned.extend(p.vertices.resolve(nx, nz));
        }
        scene.cloth.pinned.sort_unstable();
        scene.cloth.pinned.dedup();
        Ok(scene)
    }

    /// The scene as the text of a scene file (the format of the [module docs](self)),
    /// which [`from_toml`](Self::from_toml) reads back to the same scene. Effect fields
    /// appear only when set. The grid's placement is written as its `origin` (a scene file
    /// holds no rotation); the solver's method and limits are not part of a scene file.
    ///
    /// # Errors
    /// [`ClothError::Scene`] for a collider shape the scene format cannot hold.
    pub fn to_toml(&self) -> Result<String> {
        use std::fmt::Write as _;
        let num = |v: f64| format!("{v:?}");
        let vec3 = |v: &Vector3<f64>| format!("[{}, {}, {}]", num(v.x), num(v.y), num(v.z));
        let text = |t: &str| serde_json::to_string(t).unwrap_or_else(|_| "\"\"".into());
        let mut out = String::new();
        let c = &self.cloth;
        let mut path_vertices: Vec<u32> = self.pin_paths.iter().map(|(v, _)| *v).collect();
        for p in &self.rail_pins {
            path_vertices.extend(p.vertices.resolve(c.nx, c.nz));
        }
        let mut pins: Vec<u32> = c
            .pinned
            .iter()
            .copied()
            .filter(|v| !path_vertices.contains(v))
            .collect();
        pins.sort_unstable();
        pins.dedup();
        let fx = &self.effects.forces;
        // Writing to a String cannot fail.
        let _ = writeln!(out, "name = {}", text(&self.name));
        let _ = writeln!(out, "description = {}", text(&self.description));
        let _ = writeln!(out, "duration = {}  # s", num(self.duration));
        let _ = writeln!(out, "dt = {}  # s", num(self.dt));
        let _ = writeln!(
            out,
            "stretch_tolerance = {}  # relative",
            num(self.params.stretch_tolerance)
        );
        let _ = writeln!(out, "gravity = {}  # m/s^2", vec3(&self.params.gravity));
        if self.params.integrator == Integrator::Bdf2 {
            let _ = writeln!(out, "integrator = \"bdf2\"  # second order");
        }
        let _ = writeln!(out, "\n[cloth]");
        let _ = writeln!(out, "nx = {}", c.nx);
        let _ = writeln!(out, "nz = {}", c.nz);
        let _ = writeln!(
            out,
            "size = {}  # m",
            num(c.spacing * (c.nx.max(2) - 1) as f64)
        );
        let _ = writeln!(out, "particle_mass = {}  # kg", num(c.particle_mass));
        let _ = writeln!(
            out,
            "origin = {}  # m",
            vec3(&c.world_from_local.translation.vector)
        );
        let rotation = c.world_from_local.rotation.scaled_axis();
        if rotation != Vector3::zeros() {
            let _ = writeln!(out, "rotation = {}  # rad, axis x angle", vec3(&rotation));
        }
        let pins: Vec<String> = pins.iter().map(u32::to_string).collect();
        let _ = writeln!(out, "pins = [{}]", pins.join(", "));
        let _ = writeln!(out, "shear = {}", c.edges.shear);
        let _ = writeln!(out, "bend = {}", c.edges.bend);
        if self.effects.compliance != 0.0 {
            let _ = writeln!(
                out,
                "compliance = {}  # m/N per constraint",
                num(self.effects.compliance)
            );
        }
        for (field, value) in [
            ("warp_compliance", self.effects.warp_compliance),
            ("weft_compliance", self.effects.weft_compliance),
        ] {
            if let Some(v) = value {
                let _ = writeln!(out, "{field} = {}  # m/N per link", num(v));
            }
        }
        if self.effects.bending_rigidity != 0.0 {
            let _ = writeln!(
                out,
                "bending_rigidity = {}  # N m, quadratic bending",
                num(self.effects.bending_rigidity)
            );
        }
        if fx.bend_stiffness != 0.0 {
            let _ = writeln!(
                out,
                "bend_stiffness = {}  # N/m on the bend pairs",
                num(fx.bend_stiffness)
            );
        }
        if fx.damping != 0.0 {
            let _ = writeln!(out, "damping = {}  # 1/s", num(fx.damping));
        }
        if fx.drag_coefficient != 0.0 || fx.skin_friction != 0.0 || fx.wind != Vector3::zeros() {
            let _ = writeln!(out, "\n[air]");
            let _ = writeln!(out, "density = {}  # kg/m^3", num(fx.air_density));
            let _ = writeln!(out, "drag_coefficient = {}", num(fx.drag_coefficient));
            if fx.skin_friction != 0.0 {
                let _ = writeln!(out, "skin_friction = {}", num(fx.skin_friction));
            }
            let _ = writeln!(out, "wind = {}  # m/s", vec3(&fx.wind));
        }
        write_materials(&mut out, &self.effects.materials);
        for p in &self.effects.point_masses {
            let _ = writeln!(out, "\n[[point_masses]]");
            let _ = writeln!(out, "vertex = {}", p.vertex);
            let _ = writeln!(out, "mass = {}  # kg", num(p.mass));
        }
        for collider in &self.colliders {
            let _ = writeln!(out, "\n[[colliders]]");
            match &collider.shape {
                Shape::Ball { center, radius } => {
                    let _ = writeln!(out, "shape = \"ball\"");
                    let _ = writeln!(out, "center = {}", vec3(center));
                    let _ = writeln!(out, "radius = {}", num(*radius));
                }
                Shape::Plane { point, normal } => {
                    let _ = writeln!(out, "shape = \"plane\"");
                    let _ = writeln!(out, "point = {}", vec3(point));
                    let _ = writeln!(out, "normal = {}", vec3(normal));
                }
                Shape::Cuboid {
                    half_extents,
                    world_from_local,
                } => {
                    let _ = writeln!(out, "shape = \"cuboid\"");
                    let _ = writeln!(
                        out,
                        "center = {}  # m",
                        vec3(&world_from_local.translation.vector)
                    );
                    let _ = writeln!(out, "half_extents = {}  # m", vec3(half_extents));
                    let _ = writeln!(
                        out,
                        "rotation = {}  # rad, axis * angle",
                        vec3(&world_from_local.rotation.scaled_axis())
                    );
                }
                Shape::Capsule { a, b, radius } => {
                    let _ = writeln!(out, "shape = \"capsule\"");
                    let _ = writeln!(out, "a = {}  # m", vec3(a));
                    let _ = writeln!(out, "b = {}  # m", vec3(b));
                    let _ = writeln!(out, "radius = {}  # m", num(*radius));
                }
                Shape::TriMesh(mesh) => {
                    let iso = mesh.world_from_local();
                    let _ = writeln!(out, "shape = \"trimesh\"");
                    let vertices: Vec<String> = mesh.vertices().iter().map(vec3).collect();
                    let _ = writeln!(out, "vertices = [{}]  # m", vertices.join(", "));
                    let triangles: Vec<String> = mesh
                        .triangles()
                        .iter()
                        .map(|t| format!("[{}, {}, {}]", t[0], t[1], t[2]))
                        .collect();
                    let _ = writeln!(out, "triangles = [{}]", triangles.join(", "));
                    let _ = writeln!(out, "translation = {}  # m", vec3(&iso.translation.vector));
                    let _ = writeln!(
                        out,
                        "rotation = {}  # rad, axis * angle",
                        vec3(&iso.rotation.scaled_axis())
                    );
                    if let Some(t) = mesh.shell_thickness() {
                        let _ = writeln!(out, "shell_thickness = {}  # m", num(t));
                    }
                }
                #[allow(unreachable_patterns)] // Shape is non-exhaustive: new shapes land here
                other => {
                    return Err(ClothError::Scene {
                        scene: self.name.clone(),
                        message: format!("cannot write collider shape {other:?} to a scene file"),
                    });
                }
            }
            let _ = writeln!(out, "friction = {}", num(collider.friction));
        }
        crate::rail::file::write_rails(&mut out, &self.rails);
        if self.pins_from_markers
            || self.pin_markers.is_some()
            || !self.pin_paths.is_empty()
            || !self.rail_pins.is_empty()
        {
            let _ = writeln!(out, "\n[pins]");
            let _ = writeln!(out, "from_markers = {}", self.pins_from_markers);
            if let Some(m) = &self.pin_markers {
                let _ = writeln!(out, "markers = {}", text(&m.display().to_string()));
            }
            for (v, path) in &self.pin_paths {
                let _ = writeln!(out, "\n[[pins.paths]]");
                let _ = writeln!(out, "vertex = {v}");
                let rows: Vec<String> = path
                    .t()
                    .iter()
                    .zip(path.points())
                    .map(|(t, p)| {
                        format!("[{}, {}, {}, {}]", num(*t), num(p.x), num(p.y), num(p.z))
                    })
                    .collect();
                let _ = writeln!(out, "path = [{}]", rows.join(", "));
            }
            crate::rail::file::write_attachments(&mut out, &self.rail_pins);
        }
        Ok(out)
    }

    /// The number of steps of `dt` that cover `duration`.
    #[must_use]
    pub fn n_steps(&self) -> usize {
        (self.duration / self.dt).round() as usize
    }

    /// A world holding the scene's cloth and colliders, and the cloth's id.
    /// Its kinematic pins follow their paths and rails, and with `pins_from_markers` the pinned
    /// vertices in the `pin_markers` recording follow it. The scene's effects are not in
    /// it: [`SceneWorld`](crate::scene_world::SceneWorld) adds them and steps with them.
    ///
    /// # Errors
    /// The cloth's errors (see [`ClothWorld::add_cloth`]); with `pins_from_markers`, the
    /// recording's read errors, or [`ClothError::Scene`] when no recording is named.
    pub fn build(&self) -> Result<(ClothWorld, ClothId)> {
        self.build_with_markers(None)
    }

    /// Like [`build`](Self::build), but pinned vertices whose ids appear in `markers` (when
    /// given, whatever `pins_from_markers` says) follow that recording instead of the
    /// scene's `pin_markers` file.
    ///
    /// # Errors
    /// As [`build`](Self::build).
    pub fn build_with_markers(
        &self,
        markers: Option<&MarkerRecording>,
    ) -> Result<(ClothWorld, ClothId)> {
        let mut world = ClothWorld::new(self.params.clone());
        let cloth = world.add_cloth(self.cloth.clone())?;
        for c in &self.colliders {
            world.add_collider(c.clone());
        }
        for (v, path) in &self.pin_paths {
            world.add_kinematic_pin(cloth, *v as usize, path.clone())?;
        }
        let rails: Vec<std::sync::Arc<Rail>> = self
            .rails
            .iter()
            .cloned()
            .map(std::sync::Arc::new)
            .collect();
        for p in &self.rail_pins {
            let Some(rail) = rails.iter().find(|r| r.name == p.rail) else {
                return Err(ClothError::Scene {
                    scene: self.name.clone(),
                    message: format!(
                        "vertices ride rail \"{}\", which the scene does not name",
                        p.rail
                    ),
                });
            };
            for v in p.vertices.resolve(self.cloth.nx, self.cloth.nz) {
                world.attach_to_rail(cloth, v as usize, std::sync::Arc::clone(rail))?;
            }
        }
        let loaded;
        let recording = match (markers, &self.pin_markers) {
            (Some(rec), _) => Some(rec),
            (None, Some(path)) if self.pins_from_markers => {
                loaded = read_markers_path(path)?;
                Some(&loaded)
            }
            (None, None) if self.pins_from_markers => {
                return Err(ClothError::Scene {
                    scene: self.name.clone(),
                    message: "pins.from_markers needs pins.markers (a .csv or .mcap file) \
                              or a recording passed to build_with_markers"
                        .into(),
                });
            }
            _ => None,
        };
        if let Some(rec) = recording {
            follow_markers(&mut world, cloth, rec)?;
        }
        Ok((world, cloth))
    }
}

/// The effect fields of a scene file, checked: the error names the field.
fn effects_from_file(
    file: &SceneFile,
    n_vertices: usize,
) -> std::result::Result<ClothEffects, FieldError> {
    let non_negative = |field: &str, v: f64| {
        if v >= 0.0 && v.is_finite() {
            Ok(v)
        } else {
            Err(FieldError::new(field, "non-negative and finite", num(v)))
        }
    };
    let c = &file.cloth;
    let mut forces = ClothForces {
        damping: non_negative("cloth.damping", c.damping)?,
        bend_stiffness: non_negative("cloth.bend_stiffness", c.bend_stiffness)?,
        ..ClothForces::default()
    };
    if let Some(air) = &file.air {
        forces.drag_coefficient = non_negative("air.drag_coefficient", air.drag_coefficient)?;
        forces.skin_friction = non_negative("air.skin_friction", air.skin_friction)?;
        let density = air.density.unwrap_or(AIR_DENSITY);
        if !(density > 0.0 && density.is_finite()) {
            return Err(FieldError::new(
                "air.density",
                "positive and finite",
                num(density),
            ));
        }
        forces.air_density = density;
        if !air.wind.iter().all(|w| w.is_finite()) {
            return Err(FieldError::new("air.wind", "finite", triple(air.wind)));
        }
        forces.wind = Vector3::from(air.wind);
    }
    for (k, p) in file.point_masses.iter().enumerate() {
        if p.vertex as usize >= n_vertices {
            return Err(FieldError::new(
                &format!("point_masses[{k}].vertex"),
                format!("below {n_vertices} (the grid's vertices)"),
                p.vertex.to_string(),
            ));
        }
        if !(p.mass > 0.0 && p.mass.is_finite()) {
            return Err(FieldError::new(
                &format!("point_masses[{k}].mass"),
                "positive and finite (kg)",
                num(p.mass),
            ));
        }
    }
    Ok(ClothEffects {
        forces,
        compliance: non_negative("cloth.compliance", c.compliance)?,
        warp_compliance: None,
        weft_compliance: None,
        bending_rigidity: 0.0,
        materials: Vec::new(),
        point_masses: file.point_masses.clone(),
    })
}

fn bundled(text: &str, label: &str) -> Scene {
    match Scene::from_toml(text, label) {
        Ok(scene) => scene,
        // The bundled files are fixed and parsed by this module's tests.
        Err(e) => panic!("bundled scene {label} is invalid: {e}"),
    }
}

/// The cloth hanging from one corner (vertex 0).
#[must_use]
pub fn corner() -> Scene {
    bundled(CORNER, "corner.toml")
}

/// The cloth held by the two corners of one edge (vertices 0 and 29).
#[must_use]
pub fn two_corners() -> Scene {
    bundled(TWO_CORNERS, "two-corners.toml")
}

/// The cloth dropped onto a ball.
#[must_use]
pub fn drape() -> Scene {
    bundled(DRAPE, "drape.toml")
}

/// All reference scenes, in the order corner, two-corners, drape.
#[must_use]
pub fn all() -> Vec<Scene> {
    vec![corner(), two_corners(), drape()]
}

/// A reference scene by name (`corner`, `two-corners`, `drape`).
///
/// # Errors
/// [`ClothError::Scene`] for an unknown name.
pub fn by_name(name: &str) -> Result<Scene> {
    match name {
        "corner" => Ok(corner()),
        "two-corners" | "two_corners" => Ok(two_corners()),
        "drape" => Ok(drape()),
        _ => Err(ClothError::Scene {
            scene: name.to_string(),
            message: "unknown scene (known: corner, two-corners, drape)".into(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::BuildMesh as _;

    #[test]
    fn bundled_scenes_are_the_papers_mesh() {
        for scene in all() {
            let mesh = scene.cloth.build_mesh().unwrap();
            assert_eq!(
                (mesh.positions.len(), mesh.edges.len()),
                (900, 1740),
                "{}",
                scene.name
            );
            assert_eq!(scene.n_steps(), 300);
            approx::assert_relative_eq!(scene.params.stretch_tolerance, 1e-4);
            approx::assert_relative_eq!(mesh.masses[0], 1e-3);
            approx::assert_relative_eq!(
                mesh.positions[899].x - mesh.positions[0].x,
                1.0,
                epsilon = 1e-12
            );
        }
        assert_eq!(corner().cloth.pinned, vec![0]);
        assert_eq!(two_corners().cloth.pinned, vec![0, 29]);
        assert_eq!(drape().colliders.len(), 1);
        assert!(by_name("nope").is_err());
    }

    #[test]
    fn scene_errors_name_the_problem() {
        let err = Scene::from_toml(
            "name = 'x'\nduration = 1.0\ndt = 0.0\n[cloth]\nnx = 2\nnz = 2\nsize = 1.0\n",
            "x",
        )
        .unwrap_err();
        assert!(err.to_string().contains("dt must be positive"), "{err}");
        let err = Scene::from_toml("name = 'x'\n", "x").unwrap_err();
        assert!(matches!(err, ClothError::Scene { .. }));
    }

    #[test]
    fn the_integrator_is_read_written_back_and_a_wrong_one_named() {
        let base = "name = 'x'\nduration = 1.0\ndt = 0.01\n";
        let cloth = "[cloth]\nnx = 2\nnz = 2\nsize = 1.0\n";
        let scene = Scene::from_toml(&format!("{base}{cloth}"), "x").unwrap();
        assert_eq!(scene.params.integrator, Integrator::Impulse);
        assert!(!scene.to_toml().unwrap().contains("integrator"));
        let text = format!("{base}integrator = \"bdf2\"\n{cloth}");
        let scene = Scene::from_toml(&text, "x").unwrap();
        assert_eq!(scene.params.integrator, Integrator::Bdf2);
        let back = Scene::from_toml(&scene.to_toml().unwrap(), "x").unwrap();
        assert_eq!(back.params.integrator, Integrator::Bdf2);
        let text = format!("{base}integrator = \"rk4\"\n{cloth}");
        let err = Scene::from_toml(&text, "x").unwrap_err().to_string();
        assert!(
            err.contains("integrator") && err.contains("\"rk4\"") && err.contains("bdf2"),
            "{err}"
        );
    }
}

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
//! gravity = [0.0, -9.81, 0.0]
//!
//! [cloth]
//! nx = 30
//! nz = 30
//! size = 1.0                # m, the grid spans size x size * (nz - 1) / (nx - 1)
//! particle_mass = 0.001     # kg
//! origin = [0.0, 0.0, 0.0]  # m, position of vertex 0
//! pins = [0]                # vertex indices row * nx + col
//! shear = false             # optional
//! bend = false              # optional
//!
//! [[colliders]]             # optional, any number
//! shape = "ball"            # or "plane" with point = [..] and normal = [..]
//! center = [0.5, 0.0, 0.5]
//! radius = 0.3
//! friction = 0.3
//!
//! [pins]                    # optional: pins that move (kinematic pins)
//! from_markers = false      # pinned vertices whose ids appear in a marker
//!                           # recording follow the recorded positions
//! markers = "run.csv"       # that recording (.csv or .mcap, relative to the scene file)
//!
//! [[pins.paths]]            # any number: a vertex (pinned by this) following a path
//! vertex = 29
//! path = [[0.0, 0.983, 0.0, 0.0], [1.0, 1.5, 0.0, 0.0]]  # [t (s), x, y, z (m)], linear
//! ```

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Vector3};
use serde::Deserialize;

use crate::contact::Collider;
use crate::error::{ClothError, Result};
use crate::kinematic::{PinPath, follow_markers};
use crate::markers::{MarkerRecording, read_markers_path};
use crate::mesh::GridCloth;
use crate::solver::SolverParams;
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
    /// Whether pinned vertices whose ids appear in a marker recording follow the recorded
    /// positions (see [`build`](Self::build)).
    pub pins_from_markers: bool,
    /// The marker recording of `pins_from_markers` (`.csv` or `.mcap`); a relative path in
    /// a scene file is resolved against the file's folder by [`from_path`](Self::from_path).
    pub pin_markers: Option<PathBuf>,
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
    cloth: ClothFile,
    #[serde(default)]
    colliders: Vec<ColliderFile>,
    #[serde(default)]
    pins: PinsFile,
}

#[derive(Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct PinsFile {
    #[serde(default)]
    from_markers: bool,
    markers: Option<PathBuf>,
    #[serde(default)]
    paths: Vec<PathFile>,
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
    pins: Vec<u32>,
    #[serde(default)]
    shear: bool,
    #[serde(default)]
    bend: bool,
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
}

impl Scene {
    /// Reads a scene from TOML text; `label` names it in errors.
    ///
    /// # Errors
    /// [`ClothError::Scene`] for malformed TOML, unknown fields, or
    /// non-positive `dt`, `duration`, `size` or tolerance.
    pub fn from_toml(text: &str, label: &str) -> Result<Self> {
        let bad = |message: String| ClothError::Scene {
            scene: label.to_string(),
            message,
        };
        let file: SceneFile = toml::from_str(text).map_err(|e| bad(e.to_string()))?;
        for (what, v) in [
            ("dt", file.dt),
            ("duration", file.duration),
            ("cloth.size", file.cloth.size),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(bad(format!(
                    "{what} must be positive and finite, found {v}"
                )));
            }
        }
        if file.cloth.nx < 2 || file.cloth.nz < 2 {
            return Err(bad(format!(
                "a grid needs at least 2 x 2 vertices, found {} x {}",
                file.cloth.nx, file.cloth.nz
            )));
        }
        let mut params = SolverParams::default();
        if let Some(tol) = file.stretch_tolerance {
            if !(tol > 0.0 && tol.is_finite()) {
                return Err(bad(format!(
                    "stretch_tolerance must be positive, found {tol}"
                )));
            }
            params.stretch_tolerance = tol;
        }
        if let Some(g) = file.gravity {
            params.gravity = Vector3::from(g);
        }
        let c = &file.cloth;
        let [ox, oy, oz] = c.origin;
        let mut cloth = GridCloth::new(c.nx, c.nz, c.size / (c.nx - 1) as f64)
            .shear(c.shear)
            .bend(c.bend)
            .world_from_local(Isometry3::translation(ox, oy, oz));
        if let Some(m) = c.particle_mass {
            cloth = cloth.particle_mass(m);
        }
        for &p in &c.pins {
            cloth = cloth.pin(p);
        }
        let n_vertices = c.nx * c.nz;
        let mut pin_paths = Vec::with_capacity(file.pins.paths.len());
        for (k, p) in file.pins.paths.iter().enumerate() {
            if p.vertex as usize >= n_vertices {
                return Err(bad(format!(
                    "pins.paths[{k}].vertex must be below {n_vertices} (the grid's vertices), found {}",
                    p.vertex
                )));
            }
            let path = PinPath::from_rows(&p.path)
                .map_err(|e| bad(format!("pins.paths[{k}] (vertex {}): {e}", p.vertex)))?;
            cloth = cloth.pin(p.vertex);
            pin_paths.push((p.vertex, path));
        }
        let colliders =
            file.colliders
                .iter()
                .map(|c| match *c {
                    ColliderFile::Ball {
                        center,
                        radius,
                        friction,
                    } => Collider::ball(Vector3::from(center), radius).friction(friction),
                    ColliderFile::Plane {
                        point,
                        normal,
                        friction,
                    } => Collider::plane(Vector3::from(point), Vector3::from(normal))
                        .friction(friction),
                })
                .collect();
        Ok(Self {
            name: file.name,
            description: file.description,
            duration: file.duration,
            dt: file.dt,
            params,
            cloth,
            colliders,
            pin_paths,
            pins_from_markers: file.pins.from_markers,
            pin_markers: file.pins.markers,
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
        let mut scene = Self::from_toml(&text, &path.display().to_string())?;
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
    /// `two-corners` keeps its two corners.
    ///
    /// # Errors
    ///
    /// [`ClothError::BadGrid`] for fewer than 2 × 2 vertices.
    pub fn resized(&self, nx: usize, nz: usize) -> Result<Self> {
        if nx < 2 || nz < 2 {
            return Err(ClothError::BadGrid { nx, nz });
        }
        let old = &self.cloth;
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
        scene.cloth.pinned = old.pinned.iter().map(|&v| map(v)).collect();
        scene.cloth.pinned.sort_unstable();
        scene.cloth.pinned.dedup();
        for (v, _) in &mut scene.pin_paths {
            *v = map(*v);
        }
        Ok(scene)
    }

    /// The number of steps of `dt` that cover `duration`.
    #[must_use]
    pub fn n_steps(&self) -> usize {
        (self.duration / self.dt).round() as usize
    }

    /// A world holding the scene's cloth and colliders, and the cloth's id.
    /// Its kinematic pins follow their paths, and with `pins_from_markers` the pinned
    /// vertices in the `pin_markers` recording follow it.
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
}

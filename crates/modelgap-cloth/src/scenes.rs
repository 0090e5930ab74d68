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
//! ```

use std::path::Path;

use nalgebra::{Isometry3, Vector3};
use serde::Deserialize;

use crate::contact::Collider;
use crate::error::{ClothError, Result};
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
        Self::from_toml(&text, &path.display().to_string())
    }

    /// The number of steps of `dt` that cover `duration`.
    #[must_use]
    pub fn n_steps(&self) -> usize {
        (self.duration / self.dt).round() as usize
    }

    /// A world holding the scene's cloth and colliders, and the cloth's id.
    ///
    /// # Errors
    /// The cloth's errors (see [`ClothWorld::add_cloth`]).
    pub fn build(&self) -> Result<(ClothWorld, ClothId)> {
        let mut world = ClothWorld::new(self.params.clone());
        let cloth = world.add_cloth(self.cloth.clone())?;
        for c in &self.colliders {
            world.add_collider(c.clone());
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

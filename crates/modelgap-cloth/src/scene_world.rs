//! [`SceneWorld`]: a scene's world with the scene's effects in it — stretch
//! compliance (per link, from the materials of [`crate::material`]) and point
//! masses set once, drag, wind, damping and bending springs applied as forces
//! at every step, and quadratic bending ([`crate::bending`]) integrated
//! implicitly over every step. The one way a scene is stepped: `cloth
//! run` ([`crate::trajectory::run_scene`]) and the measurement loop's
//! predictions ([`crate::model::simulate_markers`]) both go through it, so a
//! scene file that `fix` wrote with an `[air]` table runs with its drag
//! everywhere.

use nalgebra::Vector3;

use crate::bending::{ImplicitBending, QuadraticBending};
use crate::error::Result;
use crate::forces::{BendPair, ClothForces, grid_bend_pairs};
use crate::markers::MarkerRecording;
use crate::scenes::Scene;
use crate::solver::StepReport;
use crate::world::{ClothId, ClothWorld};

/// A scene's world with its effects, ready to step (see the [module docs](self)).
#[derive(Debug)]
pub struct SceneWorld {
    /// The world (its parameters may be changed before the first step).
    pub world: ClothWorld,
    /// The scene's cloth in it.
    pub cloth: ClothId,
    forces: ClothForces,
    /// Each vertex's damping rate (1/s) when it differs between vertices
    /// (`forces.damping` is 0 then).
    damping: Option<Vec<f64>>,
    /// Quadratic bending, when any vertex has a rigidity.
    bending: Option<ImplicitBending>,
    nx: usize,
    nz: usize,
    /// Filled at the first step, from the state then (rest lengths of the
    /// bend pairs, particle masses).
    geometry: Option<Geometry>,
}

/// What the forces need of the cloth, taken at the first step.
#[derive(Debug)]
struct Geometry {
    first: usize,
    masses: Vec<f64>,
    triangles: Vec<[u32; 3]>,
    bend: Vec<BendPair>,
    out: Vec<Vector3<f64>>,
}

impl SceneWorld {
    /// Builds the scene's world ([`Scene::build_with_markers`]) and puts its
    /// compliance and point masses in.
    ///
    /// # Errors
    /// The scene's build errors; [`crate::ClothError::VertexOutOfRange`] for
    /// a point mass past the grid.
    pub fn new(scene: &Scene, pins: Option<&MarkerRecording>) -> Result<SceneWorld> {
        let (mut world, cloth) = scene.build_with_markers(pins)?;
        let effects = &scene.effects;
        let (nx, nz) = (scene.cloth.nx, scene.cloth.nz);
        let materials = effects.vertex_materials(nx, nz);
        if effects.materials.is_empty() && !effects.compliance_is_anisotropic() {
            if effects.compliance > 0.0 {
                world.set_compliance(cloth, effects.compliance)?;
            }
        } else if materials.any_compliance() {
            world.set_link_compliance(cloth, |a, b| materials.link_compliance(a, b))?;
        }
        for pm in &effects.point_masses {
            let particle = world.particle(cloth, pm.vertex as usize)?;
            let k = world.particles().inv_mass[particle.index()];
            if k > 0.0 {
                world.set_particle_mass(particle, 1.0 / k + pm.mass)?;
            }
        }
        let mut forces = effects.forces.clone();
        let damping = match materials.uniform_damping() {
            Some(c) => {
                forces.damping = c;
                None
            }
            None => {
                forces.damping = 0.0;
                Some(materials.damping.clone())
            }
        };
        let bending = if materials.any_bending() {
            let mut b = QuadraticBending::new(world.positions(cloth), world.triangles(cloth));
            b.set_vertex_stiffness(&materials.bending);
            Some(ImplicitBending::new(b, &cloth_masses(&world, cloth)?))
        } else {
            None
        };
        Ok(SceneWorld {
            world,
            cloth,
            forces,
            damping,
            bending,
            nx: scene.cloth.nx,
            nz: scene.cloth.nz,
            geometry: None,
        })
    }

    /// The positions of the cloth's vertices (m).
    #[must_use]
    pub fn positions(&self) -> &[Vector3<f64>] {
        self.world.positions(self.cloth)
    }

    /// One step of `h` seconds with the scene's forces evaluated at its start.
    ///
    /// # Errors
    /// The step's errors ([`ClothWorld::step`]).
    pub fn step(&mut self, h: f64) -> Result<StepReport> {
        if !self.forces.is_none() || self.damping.is_some() || self.bending.is_some() {
            let (world, cloth) = (&mut self.world, self.cloth);
            let g = match &mut self.geometry {
                Some(g) => g,
                None => {
                    let first = world.particle(cloth, 0)?.index();
                    let n = world.positions(cloth).len();
                    let masses = cloth_masses(world, cloth)?;
                    let bend = if self.forces.bend_stiffness > 0.0 {
                        grid_bend_pairs(self.nx, self.nz, world.positions(cloth))
                    } else {
                        Vec::new()
                    };
                    self.geometry.insert(Geometry {
                        first,
                        masses,
                        triangles: world.triangles(cloth).to_vec(),
                        bend,
                        out: vec![Vector3::zeros(); n],
                    })
                }
            };
            self.forces.evaluate(
                world.positions(cloth),
                world.velocities(cloth),
                &g.masses,
                &g.triangles,
                &g.bend,
                &mut g.out,
            );
            if let Some(rates) = &self.damping {
                let v = world.velocities(cloth);
                for (((f, v), m), c) in g.out.iter_mut().zip(v).zip(&g.masses).zip(rates) {
                    *f -= c * m * v;
                }
            }
            if let Some(bending) = &mut self.bending {
                let gravity = world.params().gravity;
                bending.add_step_forces(
                    h,
                    world.positions(cloth),
                    world.velocities(cloth),
                    &gravity,
                    &mut g.out,
                )?;
            }
            let n = g.out.len();
            world.external_forces_mut()[g.first..g.first + n].copy_from_slice(&g.out);
        }
        self.world.step(h)
    }
}

/// The mass of each of a cloth's vertices (kg; 0 for a pinned one).
fn cloth_masses(world: &ClothWorld, cloth: ClothId) -> Result<Vec<f64>> {
    let first = world.particle(cloth, 0)?.index();
    let n = world.positions(cloth).len();
    Ok(world.particles().inv_mass[first..first + n]
        .iter()
        .map(|&k| if k > 0.0 { 1.0 / k } else { 0.0 })
        .collect())
}

#[cfg(test)]
mod tests {
    use crate::model::{PredictSettings, simulate_markers};
    use crate::scenes;
    use crate::solver::Method;
    use crate::trajectory::{MarkerSelection, RunOptions, run_scene};

    /// A scene file with an `[air]` table (as `fix` writes one) runs with its drag in
    /// `cloth run` as in the loop's predictions; it once ran without it.
    #[test]
    fn a_run_and_a_prediction_step_the_same_effects() {
        let mut scene = scenes::corner().resized(6, 6).unwrap();
        scene.duration = 0.2;
        scene.effects.forces.drag_coefficient = 0.8;
        scene.effects.forces.damping = 0.5;
        let run = run_scene(
            &scene,
            &RunOptions {
                markers: MarkerSelection::Ids(vec![35]),
                ..RunOptions::default()
            },
        )
        .unwrap();
        let markers = run.markers.unwrap();
        let settings = PredictSettings {
            method: Method::Newton,
            max_iterations: scene.params.max_iterations,
            ..PredictSettings::default()
        };
        let predicted = simulate_markers(&scene, &[35], markers.t(), &settings, None).unwrap();
        let last = markers.positions().last().unwrap()[0];
        let same = predicted.positions().last().unwrap()[0];
        for k in 0..3 {
            assert!((last[k] - same[k]).abs() < 1e-9, "{last:?} vs {same:?}");
        }
        // Without the effects the free corner falls elsewhere.
        let mut bare = scene.clone();
        bare.effects = Default::default();
        let free = run_scene(
            &bare,
            &RunOptions {
                markers: MarkerSelection::Ids(vec![35]),
                ..RunOptions::default()
            },
        )
        .unwrap()
        .markers
        .unwrap();
        let other = free.positions().last().unwrap()[0];
        assert!((other[1] - last[1]).abs() > 1e-3, "{other:?} vs {last:?}");
    }
}

//! Running a scene and keeping its trajectory: marker frames, the mesh, the solver's
//! statistics; and writing it as marker CSV or as an MCAP file Foxglove shows in 3D.
//!
//! The MCAP file holds three topics: [`MARKERS_TOPIC`](crate::markers::MARKERS_TOPIC) (the
//! marker frames, readable with [`read_markers_mcap`](crate::markers::read_markers_mcap)),
//! [`CLOTH_TOPIC`] (a `foxglove.SceneUpdate` per frame: the mesh as a triangle list and its
//! edges as a line list, in frame [`WORLD_FRAME`]) and [`TF_TOPIC`] (one static
//! `foxglove.FrameTransform` from `world` to the simulation's frame `cloth`). The
//! simulation is y-up and Foxglove is z-up: the primitives' pose (and the transform) turn
//! +y into +z, so gravity points down on screen.
//!
//! # Example
//!
//! ```
//! use modelgap_cloth::scenes;
//! use modelgap_cloth::trajectory::{MarkerSelection, RunOptions, run_scene};
//!
//! let scene = scenes::corner().resized(6, 6)?;
//! let options = RunOptions { duration: Some(0.1), markers: MarkerSelection::Ids(vec![0, 35]), ..RunOptions::default() };
//! let run = run_scene(&scene, &options)?;
//! assert_eq!(run.stats.steps, 10);
//! let markers = run.markers.as_ref().map(|m| (m.n_frames(), m.n_markers()));
//! assert_eq!(markers, Some((11, 2)));
//! # Ok::<(), modelgap_cloth::ClothError>(())
//! ```

use crate::scene_world::SceneWorld;
use std::io::{BufWriter, Seek, Write};
use std::path::Path;
use std::sync::Arc;

use modelgap_core::fit::Cancel;
use modelgap_core::io::Format;
use modelgap_core::io::atomic::{AtomicFile, commit_buffered};
use modelgap_core::io::mcap::{McapCompression, McapWriter};

use crate::error::{ClothError, Result};
use crate::markers::{
    MarkerRecording, add_markers_channel, write_markers_csv_path, write_markers_frame,
};
use crate::mesh::BuildMesh as _;
use crate::scenes::Scene;

/// The MCAP topic of the cloth's `foxglove.SceneUpdate` messages.
pub const CLOTH_TOPIC: &str = "/cloth";

/// The MCAP topic of the static `foxglove.FrameTransform`.
pub const TF_TOPIC: &str = "/tf";

/// The frame the cloth's scene entities are drawn in.
pub const WORLD_FRAME: &str = "world";

/// The simulation's own (y-up) frame, a child of [`WORLD_FRAME`].
pub const CLOTH_FRAME: &str = "cloth";

/// Which vertices a run records as markers.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum MarkerSelection {
    /// Every vertex, ids 0, 1, … (the default).
    #[default]
    All,
    /// These vertices, in this order.
    Ids(Vec<u32>),
    /// Nothing: statistics only (benchmarks).
    None,
}

/// The most steps a run takes by default ([`RunLimits::max_steps`]): 10 000 000, 28 hours
/// of simulated time at the reference scenes' 0.01 s, and hours of computing at their 1 to
/// 2 ms per step.
pub const DEFAULT_MAX_STEPS: usize = 10_000_000;

/// The most memory the recorded frames of a run take by default
/// ([`RunLimits::max_frame_bytes`]): 2 GiB.
pub const DEFAULT_MAX_FRAME_BYTES: u64 = 2 << 30;

/// Bytes of one recorded position: three `f64`.
pub const POSITION_BYTES: u64 = 24;

/// Limits a run checks before it starts (and before it allocates anything), so that a
/// mistyped step or duration ends in an error instead of an allocation failure. The
/// particle limit is the cloth's own, the field `max_particles` of
/// [`GridCloth`](crate::GridCloth) (default 1 000 000).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RunLimits {
    /// The most steps (`duration / dt`, rounded); default [`DEFAULT_MAX_STEPS`] (10 000 000).
    pub max_steps: usize,
    /// The most bytes of recorded frames: frames × (vertices + markers) ×
    /// [`POSITION_BYTES`]; default [`DEFAULT_MAX_FRAME_BYTES`] (2 GiB). Runs that record
    /// nothing ([`MarkerSelection::None`]) are not limited by it.
    pub max_frame_bytes: u64,
}

impl Default for RunLimits {
    fn default() -> Self {
        Self {
            max_steps: DEFAULT_MAX_STEPS,
            max_frame_bytes: DEFAULT_MAX_FRAME_BYTES,
        }
    }
}

/// What [`run_scene`] runs and records.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Simulated time (s); default the scene's duration.
    pub duration: Option<f64>,
    /// Frames per second recorded (Hz), rounded to a whole number of steps per frame (at
    /// least one); default one frame per step.
    pub rate: Option<f64>,
    /// The vertices recorded as markers; default all.
    pub markers: MarkerSelection,
    /// Steps and memory the run may take; default [`RunLimits::default`].
    pub limits: RunLimits,
    /// A flag checked between steps: once set, the run stops with
    /// [`ClothError::Cancelled`] (the CLI sets it on Ctrl-C); default none.
    pub cancel: Option<Arc<Cancel>>,
}

/// What a run's solver did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunStats {
    /// Particles in the world.
    pub n_particles: usize,
    /// Distance constraints in the world.
    pub n_constraints: usize,
    /// Steps taken.
    pub steps: usize,
    /// Step size (s).
    pub dt: f64,
    /// Largest relative stretch at the end of any step (dimensionless).
    pub max_stretch: f64,
    /// Iterations summed over all steps.
    pub total_iterations: usize,
    /// Most iterations of one step.
    pub max_iterations: usize,
    /// Steps that ran out of iterations before every constraint held.
    pub unconverged_steps: usize,
    /// Steps that ran Gauss–Seidel instead of the scene's method because it
    /// could not run ([`StepReport::fallback`](crate::StepReport::fallback)).
    pub fallback_steps: usize,
}

impl RunStats {
    /// Simulated time (s).
    #[must_use]
    pub fn simulated(&self) -> f64 {
        self.steps as f64 * self.dt
    }

    /// Mean iterations per step (0 without steps).
    #[must_use]
    pub fn mean_iterations(&self) -> f64 {
        if self.steps == 0 {
            0.0
        } else {
            self.total_iterations as f64 / self.steps as f64
        }
    }
}

/// A scene's run: the recorded frames, the mesh, the statistics.
#[derive(Clone, Debug, PartialEq)]
pub struct ClothRun {
    /// The scene's name.
    pub scene: String,
    /// The recorded markers (`None` with [`MarkerSelection::None`]).
    pub markers: Option<MarkerRecording>,
    /// Every vertex's position (m) in each recorded frame (empty with
    /// [`MarkerSelection::None`]).
    pub mesh_frames: Vec<Vec<[f64; 3]>>,
    /// The mesh's triangles (vertex indices).
    pub triangles: Vec<[u32; 3]>,
    /// The mesh's edges (vertex indices), one per constraint.
    pub edges: Vec<[u32; 2]>,
    /// What the solver did.
    pub stats: RunStats,
}

/// Runs a scene from its start for `options.duration` (or the scene's), recording frames,
/// with the scene's effects — drag, wind, damping, bending, compliance, point masses — as
/// the measurement loop predicts it ([`SceneWorld`]).
///
/// The limits are checked before anything is built: the grid's particles
/// ([`GridCloth`](crate::GridCloth)'s `max_particles`), the steps and the memory of the
/// recorded frames ([`RunLimits`]).
///
/// # Errors
///
/// [`ClothError::BadParameter`] for a non-positive or non-finite duration or rate;
/// [`ClothError::TooManyParticles`], [`ClothError::TooManySteps`] or
/// [`ClothError::TooMuchFrameMemory`] past a limit; [`ClothError::VertexOutOfRange`] for a
/// selected marker past the mesh; [`ClothError::Cancelled`] when `options.cancel` is set
/// between two steps; the scene's and the steps' errors ([`Scene::build`],
/// [`ClothWorld::step`](crate::ClothWorld::step), which ends a diverged run with
/// [`ClothError::Diverged`]).
pub fn run_scene(scene: &Scene, options: &RunOptions) -> Result<ClothRun> {
    let duration = options.duration.unwrap_or(scene.duration);
    check_positive("duration", duration)?;
    let dt = scene.dt;
    check_positive("dt", dt)?;
    let limits = &options.limits;
    let steps = (duration / dt).round();
    // The cast below comes after this check (it would saturate, and NaN would become 0).
    if steps.is_nan() || steps > limits.max_steps as f64 {
        return Err(ClothError::TooManySteps {
            steps,
            duration,
            dt,
            limit: limits.max_steps,
        });
    }
    let n_steps = steps as usize;
    let stride = match options.rate {
        Some(rate) => {
            check_positive("rate", rate)?;
            // Saturates for a rate far below one frame per run: then only the ends are kept.
            ((1.0 / rate / dt).round() as usize).max(1)
        }
        None => 1,
    };
    let n_vertices = scene.cloth.n_vertices()?;
    let n_markers = match &options.markers {
        MarkerSelection::All => Some(n_vertices),
        MarkerSelection::Ids(ids) => {
            if let Some(&bad) = ids.iter().find(|&&id| id as usize >= n_vertices) {
                return Err(ClothError::VertexOutOfRange {
                    vertex: bad as usize,
                    n_vertices,
                });
            }
            Some(ids.len())
        }
        MarkerSelection::None => None,
    };
    if let Some(n_markers) = n_markers {
        // The start, every stride-th step, and the last step.
        let frames = (n_steps / stride + 2) as u64;
        let positions = (n_vertices + n_markers) as u64;
        let bytes = u128::from(frames) * u128::from(positions) * u128::from(POSITION_BYTES);
        if bytes > u128::from(limits.max_frame_bytes) {
            return Err(ClothError::TooMuchFrameMemory {
                frames,
                positions,
                bytes,
                limit: limits.max_frame_bytes,
            });
        }
    }
    let mesh = scene.cloth.build_mesh()?;
    // The scene with its effects (compliance, point masses, drag, damping, bending).
    let mut sw = SceneWorld::new(scene, None)?;
    let ids: Option<Vec<u32>> = match &options.markers {
        MarkerSelection::All => Some((0..n_vertices as u32).collect()),
        MarkerSelection::Ids(ids) => Some(ids.clone()),
        MarkerSelection::None => None,
    };
    let mut stats = RunStats {
        n_particles: sw.world.particles().len(),
        n_constraints: sw.world.constraints().len(),
        dt,
        ..RunStats::default()
    };
    let mut t = Vec::new();
    let mut mesh_frames: Vec<Vec<[f64; 3]>> = Vec::new();
    let mut record = |step: usize, positions: &[nalgebra::Vector3<f64>]| {
        if ids.is_some() {
            t.push(step as f64 * dt);
            mesh_frames.push(positions.iter().map(|p| [p.x, p.y, p.z]).collect());
        }
    };
    record(0, sw.positions());
    for step in 1..=n_steps {
        if options.cancel.as_ref().is_some_and(|c| c.is_cancelled()) {
            return Err(ClothError::Cancelled {
                step: step - 1,
                steps: n_steps,
            });
        }
        let report = sw.step(dt)?;
        stats.steps = step;
        stats.total_iterations += report.iterations;
        stats.max_iterations = stats.max_iterations.max(report.iterations);
        stats.max_stretch = stats.max_stretch.max(report.max_stretch);
        stats.unconverged_steps += usize::from(!report.converged);
        stats.fallback_steps += usize::from(report.fallback.is_some());
        if step % stride == 0 || step == n_steps {
            record(step, sw.positions());
        }
    }
    let markers = match &ids {
        Some(ids) => {
            let frames = mesh_frames
                .iter()
                .map(|frame| ids.iter().map(|&id| frame[id as usize]).collect())
                .collect();
            Some(MarkerRecording::new(t, ids.clone(), frames)?)
        }
        None => None,
    };
    Ok(ClothRun {
        scene: scene.name.clone(),
        markers,
        mesh_frames,
        triangles: mesh.triangles,
        edges: mesh.edges,
        stats,
    })
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

/// Writes a run as MCAP: markers, the mesh as `foxglove.SceneUpdate`, a static
/// `foxglove.FrameTransform` (see the [module docs](self)).
///
/// # Errors
///
/// [`ClothError::NoMarkerFrames`] for a run without recorded frames; [`ClothError::Core`]
/// when writing fails.
pub fn write_run_mcap<W: Write + Seek>(
    run: &ClothRun,
    writer: W,
    compression: McapCompression,
) -> Result<W> {
    let Some(markers) = &run.markers else {
        return Err(ClothError::NoMarkerFrames { path: None });
    };
    let mut out = McapWriter::new(writer, compression)?;
    let tf = out.add_json_channel(
        TF_TOPIC,
        "foxglove.FrameTransform",
        &object_schema("foxglove.FrameTransform"),
    )?;
    let scene = out.add_json_channel(
        CLOTH_TOPIC,
        "foxglove.SceneUpdate",
        &object_schema("foxglove.SceneUpdate"),
    )?;
    let channel = add_markers_channel(&mut out)?;
    let t0 = markers.t()[0];
    out.write_json(tf, 0.0, &frame_transform(0.0))?;
    let triangle_indices: Vec<u32> = run.triangles.iter().flatten().copied().collect();
    let edge_indices: Vec<u32> = run.edges.iter().flatten().copied().collect();
    for ((&t, frame), mesh) in markers
        .t()
        .iter()
        .zip(markers.positions())
        .zip(&run.mesh_frames)
    {
        let update = scene_update(&run.scene, t - t0, mesh, &triangle_indices, &edge_indices);
        out.write_json(scene, t - t0, &update)?;
        write_markers_frame(&mut out, channel, t - t0, markers.ids(), frame)?;
    }
    Ok(out.finish()?)
}

/// Writes a run to a file by extension: `.csv` the markers ([`write_markers_csv_path`]),
/// `.mcap` everything ([`write_run_mcap`], zstd).
///
/// # Errors
///
/// [`ClothError::Core`] for another extension (nothing is written) or when writing fails;
/// [`ClothError::NoMarkerFrames`] for a run without recorded frames.
pub fn write_run_path(run: &ClothRun, path: &Path) -> Result<()> {
    let format = Format::from_path(path)?;
    let Some(markers) = &run.markers else {
        return Err(ClothError::NoMarkerFrames {
            path: Some(path.to_path_buf()),
        });
    };
    match format {
        Format::Csv => write_markers_csv_path(markers, path),
        Format::Mcap => {
            let file = AtomicFile::create(path)?;
            let w = write_run_mcap(run, BufWriter::new(file), McapCompression::Zstd)
                .map_err(|e| e.with_path(path))?;
            Ok(commit_buffered(w)?)
        }
    }
}

/// A minimal JSON schema naming a Foxglove message type (Foxglove picks the panel by the
/// schema name; the fields are those of its published schemas).
fn object_schema(title: &str) -> serde_json::Value {
    serde_json::json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": title,
        "type": "object",
    })
}

/// A Foxglove `Time`: whole seconds and nanoseconds.
fn time(t: f64) -> serde_json::Value {
    let ns = (t.max(0.0) * 1e9).round() as u64;
    serde_json::json!({ "sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000 })
}

/// Turns the simulation's +y (up) into Foxglove's +z (up): +90° about x.
fn y_up_to_z_up() -> serde_json::Value {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    serde_json::json!({ "x": h, "y": 0.0, "z": 0.0, "w": h })
}

fn frame_transform(t: f64) -> serde_json::Value {
    serde_json::json!({
        "timestamp": time(t),
        "parent_frame_id": WORLD_FRAME,
        "child_frame_id": CLOTH_FRAME,
        "translation": { "x": 0.0, "y": 0.0, "z": 0.0 },
        "rotation": y_up_to_z_up(),
    })
}

fn scene_update(
    name: &str,
    t: f64,
    mesh: &[[f64; 3]],
    triangle_indices: &[u32],
    edge_indices: &[u32],
) -> serde_json::Value {
    let points: Vec<serde_json::Value> = mesh
        .iter()
        .map(|&[x, y, z]| serde_json::json!({ "x": x, "y": y, "z": z }))
        .collect();
    let pose = serde_json::json!({
        "position": { "x": 0.0, "y": 0.0, "z": 0.0 },
        "orientation": y_up_to_z_up(),
    });
    let triangles = serde_json::json!({
        "pose": pose,
        "points": points,
        "color": { "r": 0.25, "g": 0.55, "b": 0.9, "a": 0.85 },
        "colors": [],
        "indices": triangle_indices,
    });
    let lines = serde_json::json!({
        "type": 2, // LINE_LIST: each pair of indices is a segment
        "pose": pose,
        "thickness": 1.0,
        "scale_invariant": true,
        "points": points,
        "color": { "r": 0.1, "g": 0.1, "b": 0.2, "a": 1.0 },
        "colors": [],
        "indices": edge_indices,
    });
    serde_json::json!({
        "deletions": [],
        "entities": [{
            "timestamp": time(t),
            "frame_id": WORLD_FRAME,
            "id": "cloth",
            "lifetime": { "sec": 0, "nsec": 0 },
            "frame_locked": false,
            "metadata": [{ "key": "scene", "value": name }],
            "arrows": [],
            "cubes": [],
            "spheres": [],
            "cylinders": [],
            "lines": [lines],
            "triangles": [triangles],
            "texts": [],
            "models": [],
        }],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes;

    /// Issue 12: a run counts the steps that fell back to Gauss–Seidel.
    #[test]
    fn run_stats_count_the_steps_that_fell_back() {
        let scene = scenes::corner().resized(6, 6).unwrap();
        let options = RunOptions {
            duration: Some(5.0 * scene.dt),
            markers: MarkerSelection::None,
            ..RunOptions::default()
        };
        let normal = run_scene(&scene, &options).unwrap().stats;
        assert_eq!((normal.steps, normal.fallback_steps), (5, 0));
        // Newton's solver cannot be built on this thread (see `newton::FailBuilds`).
        let _fail = crate::newton::FailBuilds::new();
        let fell_back = run_scene(&scene, &options).unwrap().stats;
        assert_eq!((fell_back.steps, fell_back.fallback_steps), (5, 5));
    }
}

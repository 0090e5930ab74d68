//! Running a scene and keeping its trajectory: marker frames, the mesh, the solver's
//! statistics; and writing it as marker CSV or as an MCAP file Foxglove shows in 3D.
//!
//! The MCAP file holds three topics: [`MARKERS_TOPIC`](crate::markers::MARKERS_TOPIC) (the
//! marker frames, readable with [`read_markers_mcap`](crate::markers::read_markers_mcap)),
//! [`CLOTH_TOPIC`] (a `foxglove.SceneUpdate` per frame: the mesh as a triangle list and its
//! edges as a line list, in the simulation's frame [`CLOTH_FRAME`], identity poses,
//! coordinates rounded to [`DRAWN_DECIMALS`]) and [`TF_TOPIC`] (one static
//! `foxglove.FrameTransform` from [`WORLD_FRAME`] to [`CLOTH_FRAME`]). The simulation is y-up
//! and Foxglove is z-up: the transform, and nothing else, turns +y into +z, so gravity
//! points down on screen. Both Foxglove channels carry Foxglove's published JSON Schemas
//! ([`modelgap_core::io::foxglove`]).
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
use modelgap_core::io::foxglove::{
    Color, FrameTransform, KeyValuePair, LinePrimitive, LineType, Pose, Quaternion, SceneEntity,
    SceneUpdate, Time, TriangleListPrimitive, Vector3, add_frame_transform_channel,
    add_scene_update_channel, write_message,
};
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

/// Foxglove's fixed frame (z-up), the parent of [`CLOTH_FRAME`].
pub const WORLD_FRAME: &str = "world";

/// The simulation's own (y-up) frame, a child of [`WORLD_FRAME`]: every scene entity of
/// modelgap's cloth files is drawn in it.
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
    /// Steps of a BDF2 scene taken again as the paper's impulse step
    /// ([`StepReport::first_order`](crate::StepReport::first_order)).
    pub first_order_steps: usize,
    /// Where the scene's stretch tolerance proved out of reach, and the level held
    /// instead ([`crate::Stagnation`]; its text is the warning to show); `None` when
    /// every step could reach it.
    pub stagnation: Option<crate::Stagnation>,
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
        stats.first_order_steps += usize::from(report.first_order);
        stats.stagnation = sw.world.stagnation().copied();
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
    let tf = add_frame_transform_channel(&mut out, TF_TOPIC)?;
    let scene = add_scene_update_channel(&mut out, CLOTH_TOPIC)?;
    let channel = add_markers_channel(&mut out)?;
    let t0 = markers.t()[0];
    write_message(&mut out, tf, 0.0, &cloth_frame_transform())?;
    let triangle_indices: Vec<u32> = run.triangles.iter().flatten().copied().collect();
    let edge_indices: Vec<u32> = run.edges.iter().flatten().copied().collect();
    for ((&t, frame), mesh) in markers
        .t()
        .iter()
        .zip(markers.positions())
        .zip(&run.mesh_frames)
    {
        let update = scene_update(&run.scene, t - t0, mesh, &triangle_indices, &edge_indices);
        write_message(&mut out, scene, t - t0, &update)?;
        write_markers_frame(&mut out, channel, t - t0, markers.ids(), frame)?;
    }
    Ok(out.finish()?)
}

/// Writes a run to a file by extension: `.csv` the markers ([`write_markers_csv_path`]),
/// `.mcap` everything ([`write_run_mcap`], zstd).
///
/// # Errors
///
/// [`ClothError::Core`] for another extension or Parquet (nothing is written) or when
/// writing fails; [`ClothError::NoMarkerFrames`] for a run without recorded frames.
pub fn write_run_path(run: &ClothRun, path: &Path) -> Result<()> {
    let format = Format::for_writing(path)?;
    let Some(markers) = &run.markers else {
        return Err(ClothError::NoMarkerFrames {
            path: Some(path.to_path_buf()),
        });
    };
    match format {
        Format::Parquet => Err(modelgap_core::io::parquet_read_only(path).into()),
        Format::Csv => write_markers_csv_path(markers, path),
        Format::Mcap => {
            let file = AtomicFile::create(path)?;
            let w = write_run_mcap(run, BufWriter::new(file), McapCompression::Zstd)
                .map_err(|e| e.with_path(path))?;
            Ok(commit_buffered(w)?)
        }
    }
}

/// Coordinates drawn in Foxglove (the mesh, the measured markers as spheres) are rounded to
/// this many decimals of a metre: 0.1 mm, a tenth of the markers' noise in the reference
/// recordings and far below what a 3D view shows. The [`MARKERS_TOPIC`](crate::markers::MARKERS_TOPIC)
/// frames, which read back as data, are written exactly.
pub const DRAWN_DECIMALS: u8 = 4;

/// The static transform from [`WORLD_FRAME`] (Foxglove's z-up) to [`CLOTH_FRAME`] (the
/// simulation's y-up): +90° about x, so +y of the simulation is +z on screen. Every entity
/// of modelgap's cloth files is drawn in [`CLOTH_FRAME`] with identity poses; this transform
/// is the only rotation in them.
pub(crate) fn cloth_frame_transform() -> FrameTransform {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    FrameTransform {
        timestamp: Time::default(),
        parent_frame_id: WORLD_FRAME.to_owned(),
        child_frame_id: CLOTH_FRAME.to_owned(),
        translation: Vector3::ZERO,
        rotation: Quaternion {
            x: h,
            y: 0.0,
            z: 0.0,
            w: h,
        },
    }
}

/// The mesh vertices as points in [`CLOTH_FRAME`], rounded to [`DRAWN_DECIMALS`].
pub(crate) fn drawn_points(mesh: &[[f64; 3]]) -> Vec<Vector3> {
    mesh.iter()
        .map(|&p| Vector3::rounded(p, DRAWN_DECIMALS))
        .collect()
}

fn scene_update(
    name: &str,
    t: f64,
    mesh: &[[f64; 3]],
    triangle_indices: &[u32],
    edge_indices: &[u32],
) -> SceneUpdate {
    let points = drawn_points(mesh);
    let mut entity = SceneEntity::new(t, CLOTH_FRAME, "cloth");
    entity.metadata.push(KeyValuePair::new("scene", name));
    entity.lines.push(LinePrimitive {
        kind: LineType::List,
        pose: Pose::IDENTITY,
        thickness: 1.0,
        scale_invariant: true,
        points: points.clone(),
        color: Color::opaque([0.1, 0.1, 0.2]),
        colors: Vec::new(),
        indices: edge_indices.to_vec(),
    });
    entity.triangles.push(TriangleListPrimitive {
        pose: Pose::IDENTITY,
        points,
        color: Color::with_alpha([0.25, 0.55, 0.9], 0.85),
        colors: Vec::new(),
        indices: triangle_indices.to_vec(),
    });
    SceneUpdate {
        deletions: Vec::new(),
        entities: vec![entity],
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use modelgap_core::io::json_schema::Strictness;
    use modelgap_core::io::mcap::{check_messages, read_topic_messages};
    use serde_json::Value;

    use super::*;
    use crate::scenes;

    /// Every message of a cloth MCAP file validates, complete, against its channel's schema
    /// (Foxglove's published ones for the scene and the transform), `n_scene_topics`
    /// topics hold scene updates, and the file has one frame convention: every entity in
    /// [`CLOTH_FRAME`] with unrotated primitives, the rotation only in the one transform on
    /// [`TF_TOPIC`], from [`WORLD_FRAME`].
    pub(crate) fn assert_foxglove_file(bytes: &[u8], n_scene_topics: usize) {
        let checked = check_messages(bytes, Strictness::Complete).unwrap();
        let scene_topics: Vec<&str> = checked
            .iter()
            .filter(|c| c.schema == "foxglove.SceneUpdate")
            .map(|c| c.topic.as_str())
            .collect();
        assert_eq!(scene_topics.len(), n_scene_topics, "{checked:?}");
        for topic in scene_topics {
            for m in read_topic_messages(bytes, topic).unwrap() {
                let update: Value = serde_json::from_slice(&m.data).unwrap();
                for entity in update["entities"].as_array().unwrap() {
                    assert_eq!(entity["frame_id"], CLOTH_FRAME, "{topic}");
                    for kind in ["spheres", "lines", "triangles"] {
                        for p in entity[kind].as_array().unwrap() {
                            let q = &p["pose"]["orientation"];
                            assert_eq!(
                                (&q["x"], &q["y"], &q["z"], &q["w"]),
                                (&0.0.into(), &0.0.into(), &0.0.into(), &1.0.into()),
                                "{topic} {kind}"
                            );
                            if kind != "spheres" {
                                assert_eq!(
                                    p["pose"]["position"],
                                    serde_json::json!({"x": 0.0, "y": 0.0, "z": 0.0})
                                );
                            }
                        }
                    }
                }
            }
        }
        let tf = read_topic_messages(bytes, TF_TOPIC).unwrap();
        assert_eq!(tf.len(), 1);
        let tf: Value = serde_json::from_slice(&tf[0].data).unwrap();
        assert_eq!(
            (&tf["parent_frame_id"], &tf["child_frame_id"]),
            (&WORLD_FRAME.into(), &CLOTH_FRAME.into())
        );
    }

    #[test]
    fn a_run_file_validates_with_one_frame_convention_and_rounded_points() {
        let scene = scenes::corner().resized(6, 6).unwrap();
        let options = RunOptions {
            duration: Some(0.1),
            ..RunOptions::default()
        };
        let run = run_scene(&scene, &options).unwrap();
        let bytes = write_run_mcap(
            &run,
            std::io::Cursor::new(Vec::new()),
            McapCompression::Zstd,
        )
        .unwrap()
        .into_inner();
        assert_foxglove_file(&bytes, 1);
        let first = &read_topic_messages(&bytes, CLOTH_TOPIC).unwrap()[0];
        let update: Value = serde_json::from_slice(&first.data).unwrap();
        for p in update["entities"][0]["triangles"][0]["points"]
            .as_array()
            .unwrap()
        {
            for c in ["x", "y", "z"] {
                let text = p[c].to_string();
                let decimals = text.split('.').nth(1).map_or(0, str::len);
                assert!(decimals <= usize::from(DRAWN_DECIMALS), "{text}");
            }
        }
        // The markers, data, read back exactly.
        let back = crate::markers::read_markers_mcap(&bytes).unwrap();
        assert_eq!(back.positions(), run.markers.as_ref().unwrap().positions());
    }

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

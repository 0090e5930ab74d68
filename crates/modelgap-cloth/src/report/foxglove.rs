//! The cloth comparison as MCAP for Foxglove's 3D and Plot panels: the model's mesh
//! coloured by the marker error at each frame, the measured markers as spheres (both
//! `foxglove.SceneUpdate`), a `/tf` frame, and the error per marker as flat JSON.

use modelgap_core::io::atomic::{AtomicFile, commit_buffered};
use std::io::{BufWriter, Seek, Write};
use std::path::Path;

use modelgap_core::CoreError;
use modelgap_core::io::foxglove::{
    Color, KeyValuePair, Pose, SceneEntity, SceneUpdate, SpherePrimitive, TriangleListPrimitive,
    Vector3, add_frame_transform_channel, add_scene_update_channel, round_to, write_message,
};
use modelgap_core::io::mcap::{ChannelId, McapCompression, McapWriter, number_object_schema};
use serde_json::{Value, json};

use super::ClothComparison;
use super::map::{error_colour, interpolate, nice_ceiling, vertex_weights};
use crate::error::{ClothError, Result};
use crate::markers::{MarkerRecording, add_markers_channel, write_markers_frame};
use crate::trajectory::{
    CLOTH_FRAME, DRAWN_DECIMALS, TF_TOPIC, cloth_frame_transform, drawn_points,
};

/// Topic of the model's mesh coloured by error (`foxglove.SceneUpdate`), model as given.
pub const CLOTH_ERROR_TOPIC: &str = "/cloth_error";
/// Topic of the mesh coloured by error with the effect added.
pub const CLOTH_ERROR_AFTER_TOPIC: &str = "/cloth_error_after";
/// Topic of the 3D error per marker and its RMS (`{"m12": 0.004, …, "rms": 0.003}`, m).
pub const MARKER_ERROR_TOPIC: &str = "/marker_error";
/// Topic of the error per marker with the effect added.
pub const MARKER_ERROR_AFTER_TOPIC: &str = "/marker_error_after";
/// Topic of the measured markers drawn as spheres (`foxglove.SceneUpdate`), once per frame
/// for both models.
pub const MEASURED_MARKERS_TOPIC: &str = "/measured_markers";

/// The errors on [`MARKER_ERROR_TOPIC`] are rounded to this many decimals of a metre: 1 µm,
/// the resolution of the marker recordings.
pub const ERROR_DECIMALS: u8 = 6;

/// Diameter of a measured marker's sphere (m).
const MARKER_DIAMETER: f64 = 0.012;

/// What [`write_error_mcap`] writes.
#[derive(Clone, Copy, Debug)]
pub struct ErrorMcap<'a> {
    /// The scene's name, in the entities' metadata.
    pub scene: &'a str,
    /// The mesh's triangles (vertex indices).
    pub triangles: &'a [[u32; 3]],
    /// The measured markers, one frame per time of the comparisons.
    pub measured: &'a MarkerRecording,
    /// The model as given against the markers.
    pub before: &'a ClothComparison,
    /// The model's mesh (every vertex, m) at each frame of `before`.
    pub mesh_before: &'a [Vec<[f64; 3]>],
    /// The model with the effect added and its mesh, when there is one.
    pub after: Option<(&'a ClothComparison, &'a [Vec<[f64; 3]>])>,
}

/// Writes a cloth comparison as MCAP: [`TF_TOPIC`] (a static `foxglove.FrameTransform` from
/// `world` to the y-up frame `cloth`, the file's only rotation), [`CLOTH_ERROR_TOPIC`] (per
/// frame a `foxglove.SceneUpdate`: the model's mesh with one colour per vertex, blue where it
/// meets the markers and red where it is off by the colour scale's top or more),
/// [`MEASURED_MARKERS_TOPIC`] (per frame the measured markers as small spheres),
/// [`MARKER_ERROR_TOPIC`] (the 3D distance per marker and its RMS, m, rounded to
/// [`ERROR_DECIMALS`], for the Plot panel), the measured markers as data on `/markers`, and
/// with `after` the same on [`CLOTH_ERROR_AFTER_TOPIC`] and [`MARKER_ERROR_AFTER_TOPIC`].
/// Scene entities are in frame `cloth` with identity poses, their coordinates rounded to
/// [`DRAWN_DECIMALS`]; the Foxglove channels carry Foxglove's published schemas. Times start
/// at 0.
///
/// # Errors
///
/// [`ClothError::Core`] when the frame counts of the recording, the comparisons and the
/// meshes differ, a mesh frame misses vertices, or writing fails.
pub fn write_error_mcap<W: Write + Seek>(m: &ErrorMcap<'_>, writer: W) -> Result<W> {
    validate(m)?;
    let n_vertices = m.before.nx * m.before.nz;
    let weights = vertex_weights(m.before);
    let scale = nice_ceiling(m.before.markers.iter().map(|x| x.rms).fold(0.0, f64::max));
    let mut out = McapWriter::new(writer, McapCompression::Zstd)?;
    let tf = add_frame_transform_channel(&mut out, TF_TOPIC)?;
    let mut streams: Vec<Stream<'_>> = Vec::new();
    let names: Vec<String> = m
        .before
        .markers
        .iter()
        .map(|x| format!("m{}", x.id))
        .chain(std::iter::once("rms".to_owned()))
        .collect();
    let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let mut sides = vec![(
        m.before,
        m.mesh_before,
        CLOTH_ERROR_TOPIC,
        MARKER_ERROR_TOPIC,
        "model as given",
    )];
    if let Some((a, mesh)) = m.after {
        sides.push((
            a,
            mesh,
            CLOTH_ERROR_AFTER_TOPIC,
            MARKER_ERROR_AFTER_TOPIC,
            "with the effect added",
        ));
    }
    for (c, mesh, scene_topic, error_topic, label) in sides {
        let scene = add_scene_update_channel(&mut out, scene_topic)?;
        let error = out.add_json_channel(
            error_topic,
            "modelgap.MarkerError",
            &number_object_schema("modelgap.MarkerError", &name_refs),
        )?;
        streams.push(Stream {
            comparison: c,
            mesh,
            scene,
            error,
            label,
        });
    }
    let measured_scene = add_scene_update_channel(&mut out, MEASURED_MARKERS_TOPIC)?;
    let markers = add_markers_channel(&mut out)?;
    let t0 = m.measured.t()[0];
    let indices: Vec<u32> = m.triangles.iter().flatten().copied().collect();
    let legend = format!("blue 0 mm to red {} mm", scale * 1e3);
    write_message(&mut out, tf, 0.0, &cloth_frame_transform())?;
    for (k, (&t, frame)) in m
        .measured
        .t()
        .iter()
        .zip(m.measured.positions())
        .enumerate()
    {
        let t = t - t0;
        for &Stream {
            comparison: c,
            mesh,
            scene,
            error,
            label,
        } in &streams
        {
            let per_marker: Vec<f64> = c.markers.iter().map(|x| x.distance[k]).collect();
            let values = interpolate(&weights, &per_marker);
            let mut entity = SceneEntity::new(t, CLOTH_FRAME, "model mesh coloured by error");
            entity.metadata = vec![
                KeyValuePair::new("scene", m.scene),
                KeyValuePair::new("model", label),
                KeyValuePair::new("colour scale", legend.as_str()),
            ];
            entity.triangles.push(TriangleListPrimitive {
                pose: Pose::IDENTITY,
                points: drawn_points(&mesh[k][..n_vertices]),
                color: Color::opaque([0.5, 0.5, 0.5]),
                colors: values
                    .iter()
                    .map(|&v| Color::opaque(error_colour(colour_step(v / scale))))
                    .collect(),
                indices: indices.clone(),
            });
            let update = SceneUpdate {
                deletions: Vec::new(),
                entities: vec![entity],
            };
            write_message(&mut out, scene, t, &update)?;
            let mut fields: serde_json::Map<String, Value> = c
                .markers
                .iter()
                .map(|x| {
                    (
                        format!("m{}", x.id),
                        json!(round_to(x.distance[k], ERROR_DECIMALS)),
                    )
                })
                .collect();
            fields.insert(
                "rms".to_owned(),
                json!(round_to(c.error_over_time[k], ERROR_DECIMALS)),
            );
            out.write_json(error, t, &Value::Object(fields))?;
        }
        write_message(
            &mut out,
            measured_scene,
            t,
            &measured_update(m.scene, t, frame),
        )?;
        write_markers_frame(&mut out, markers, t, m.measured.ids(), frame)?;
    }
    Ok(out.finish()?)
}

/// Steps of the colour scale: the error is drawn to 2 % of the scale's top (51 colours),
/// finer than a colour is read and a third fewer bytes than colours to 0.01.
const COLOUR_STEPS: f64 = 50.0;

/// A fraction of the colour scale rounded to a step of [`COLOUR_STEPS`].
fn colour_step(fraction: f64) -> f64 {
    (fraction * COLOUR_STEPS).round() / COLOUR_STEPS
}

/// The measured markers of one frame as spheres in frame `cloth`.
fn measured_update(scene: &str, t: f64, frame: &[[f64; 3]]) -> SceneUpdate {
    let mut entity = SceneEntity::new(t, CLOTH_FRAME, "measured markers");
    entity.metadata.push(KeyValuePair::new("scene", scene));
    entity.spheres = frame
        .iter()
        .map(|&p| SpherePrimitive {
            pose: Pose::at(Vector3::rounded(p, DRAWN_DECIMALS)),
            size: Vector3::splat(MARKER_DIAMETER),
            color: Color::opaque([0.1, 0.1, 0.1]),
        })
        .collect();
    SceneUpdate {
        deletions: Vec::new(),
        entities: vec![entity],
    }
}

/// One side of the comparison (the model as given, or with the effect) and its channels.
struct Stream<'a> {
    comparison: &'a ClothComparison,
    mesh: &'a [Vec<[f64; 3]>],
    scene: ChannelId,
    error: ChannelId,
    label: &'static str,
}

/// Writes [`write_error_mcap`] to a file (created or truncated), the path in every error.
///
/// # Errors
///
/// As [`write_error_mcap`], plus [`ClothError::Core`] when the file cannot be created.
pub fn write_error_mcap_path(m: &ErrorMcap<'_>, path: &Path) -> Result<()> {
    validate(m).map_err(|e| e.with_path(path))?;
    let file = AtomicFile::create(path)?;
    let w = write_error_mcap(m, BufWriter::new(file)).map_err(|e| e.with_path(path))?;
    Ok(commit_buffered(w)?)
}

fn validate(m: &ErrorMcap<'_>) -> Result<()> {
    let n = m.measured.n_frames();
    let n_vertices = m.before.nx * m.before.nz;
    let bad = |reason: String| -> ClothError {
        CoreError::InvalidArgument {
            name: "cloth error mcap",
            reason,
        }
        .into()
    };
    let mut sides = vec![("before", m.before, m.mesh_before)];
    if let Some((a, mesh)) = m.after {
        sides.push(("after", a, mesh));
    }
    for (label, c, mesh) in sides {
        if c.t.len() != n || mesh.len() != n {
            return Err(bad(format!(
                "{label}: the recording has {n} frames, the comparison {} and the mesh {}",
                c.t.len(),
                mesh.len()
            )));
        }
        if let Some(k) = mesh.iter().position(|f| f.len() < n_vertices) {
            return Err(bad(format!(
                "{label}: mesh frame {k} has {} vertices, the grid {n_vertices}",
                mesh[k].len()
            )));
        }
        if c.markers.len() != m.before.markers.len() {
            return Err(bad(format!(
                "{label}: {} markers, the model as given {}",
                c.markers.len(),
                m.before.markers.len()
            )));
        }
    }
    Ok(())
}

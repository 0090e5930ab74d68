//! The cloth comparison as MCAP for Foxglove's 3D and Plot panels: the model's mesh
//! coloured by the marker error at each frame (`foxglove.SceneUpdate`, JSON), the measured
//! markers, a `/tf` frame, and the error per marker as flat JSON.

use modelgap_core::io::atomic::{AtomicFile, commit_buffered};
use std::io::{BufWriter, Seek, Write};
use std::path::Path;

use modelgap_core::CoreError;
use modelgap_core::io::mcap::{ChannelId, McapCompression, McapWriter, number_object_schema};
use serde_json::{Value, json};

use super::ClothComparison;
use super::map::{error_colour, interpolate, nice_ceiling, vertex_weights};
use crate::error::{ClothError, Result};
use crate::markers::{MarkerRecording, add_markers_channel, write_markers_frame};
use crate::trajectory::{CLOTH_FRAME, TF_TOPIC, WORLD_FRAME};

/// Topic of the model's mesh coloured by error (`foxglove.SceneUpdate`), model as given.
pub const CLOTH_ERROR_TOPIC: &str = "/cloth_error";
/// Topic of the mesh coloured by error with the effect added.
pub const CLOTH_ERROR_AFTER_TOPIC: &str = "/cloth_error_after";
/// Topic of the 3D error per marker and its RMS (`{"m12": 0.004, …, "rms": 0.003}`, m).
pub const MARKER_ERROR_TOPIC: &str = "/marker_error";
/// Topic of the error per marker with the effect added.
pub const MARKER_ERROR_AFTER_TOPIC: &str = "/marker_error_after";

/// Coordinates are written rounded to this (m): 1 µm, far below any marker noise.
const POSITION_QUANTUM: f64 = 1e-6;

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
/// `world` to the y-up frame `cloth`), [`CLOTH_ERROR_TOPIC`] (per frame a
/// `foxglove.SceneUpdate`: the model's mesh with one colour per vertex, blue where it meets
/// the markers and red where it is off by the colour scale's top or more, and the measured
/// markers as small spheres), [`MARKER_ERROR_TOPIC`] (the 3D distance per marker and its RMS,
/// m, for the Plot panel), the measured markers on `/markers`, and with `after` the same
/// on [`CLOTH_ERROR_AFTER_TOPIC`] and [`MARKER_ERROR_AFTER_TOPIC`]. Times start at 0.
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
    let schema = |title: &str| {
        json!({
            "$schema": "https://json-schema.org/draft/2020-12/schema",
            "title": title,
            "type": "object",
        })
    };
    let tf = out.add_json_channel(
        TF_TOPIC,
        "foxglove.FrameTransform",
        &schema("foxglove.FrameTransform"),
    )?;
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
        let scene = out.add_json_channel(
            scene_topic,
            "foxglove.SceneUpdate",
            &schema("foxglove.SceneUpdate"),
        )?;
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
    let markers = add_markers_channel(&mut out)?;
    let t0 = m.measured.t()[0];
    out.write_json(tf, 0.0, &frame_transform())?;
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
            let update = scene_update(m, t, &mesh[k][..n_vertices], &values, scale, frame, label);
            out.write_json(scene, t, &update)?;
            let mut fields: serde_json::Map<String, Value> = c
                .markers
                .iter()
                .map(|x| (format!("m{}", x.id), json!(x.distance[k])))
                .collect();
            fields.insert("rms".to_owned(), json!(c.error_over_time[k]));
            out.write_json(error, t, &Value::Object(fields))?;
        }
        write_markers_frame(&mut out, markers, t, m.measured.ids(), frame)?;
    }
    Ok(out.finish()?)
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

/// A Foxglove `Time`: whole seconds and nanoseconds.
fn time(t: f64) -> Value {
    let ns = (t.max(0.0) * 1e9).round() as u64;
    json!({ "sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000 })
}

/// Turns the simulation's +y (up) into Foxglove's +z (up): +90° about x.
fn y_up_to_z_up() -> Value {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    json!({ "x": h, "y": 0.0, "z": 0.0, "w": h })
}

fn frame_transform() -> Value {
    json!({
        "timestamp": time(0.0),
        "parent_frame_id": WORLD_FRAME,
        "child_frame_id": CLOTH_FRAME,
        "translation": { "x": 0.0, "y": 0.0, "z": 0.0 },
        "rotation": y_up_to_z_up(),
    })
}

fn point(p: [f64; 3]) -> Value {
    let q = |v: f64| (v / POSITION_QUANTUM).round() * POSITION_QUANTUM;
    json!({ "x": q(p[0]), "y": q(p[1]), "z": q(p[2]) })
}

fn rgba(c: [f64; 3], a: f64) -> Value {
    let q = |v: f64| (v * 1000.0).round() / 1000.0;
    json!({ "r": q(c[0]), "g": q(c[1]), "b": q(c[2]), "a": a })
}

fn scene_update(
    m: &ErrorMcap<'_>,
    t: f64,
    mesh: &[[f64; 3]],
    values: &[f64],
    scale: f64,
    measured: &[[f64; 3]],
    label: &str,
) -> Value {
    let pose = json!({
        "position": { "x": 0.0, "y": 0.0, "z": 0.0 },
        "orientation": y_up_to_z_up(),
    });
    let points: Vec<Value> = mesh.iter().map(|&p| point(p)).collect();
    let colors: Vec<Value> = values
        .iter()
        .map(|&v| rgba(error_colour(v / scale), 1.0))
        .collect();
    let indices: Vec<u32> = m.triangles.iter().flatten().copied().collect();
    let triangles = json!({
        "pose": pose,
        "points": points,
        "color": rgba([0.5, 0.5, 0.5], 1.0),
        "colors": colors,
        "indices": indices,
    });
    let spheres: Vec<Value> = measured
        .iter()
        .map(|&p| {
            json!({
                "pose": {
                    "position": point(p),
                    "orientation": { "x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0 },
                },
                "size": { "x": 0.012, "y": 0.012, "z": 0.012 },
                "color": rgba([0.1, 0.1, 0.1], 1.0),
            })
        })
        .collect();
    let measured_entity = json!({
        "timestamp": time(t),
        "frame_id": CLOTH_FRAME,
        "id": "measured markers",
        "lifetime": { "sec": 0, "nsec": 0 },
        "frame_locked": false,
        "metadata": [{ "key": "scene", "value": m.scene }],
        "arrows": [], "cubes": [], "spheres": spheres, "cylinders": [], "lines": [],
        "triangles": [], "texts": [], "models": [],
    });
    let mesh_entity = json!({
        "timestamp": time(t),
        "frame_id": WORLD_FRAME,
        "id": "model mesh coloured by error",
        "lifetime": { "sec": 0, "nsec": 0 },
        "frame_locked": false,
        "metadata": [
            { "key": "scene", "value": m.scene },
            { "key": "model", "value": label },
            { "key": "colour scale", "value": format!("blue 0 mm to red {} mm", scale * 1e3) },
        ],
        "arrows": [], "cubes": [], "spheres": [], "cylinders": [], "lines": [],
        "triangles": [triangles], "texts": [], "models": [],
    });
    json!({ "deletions": [], "entities": [mesh_entity, measured_entity] })
}

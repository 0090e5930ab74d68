//! Foxglove's own message types, as JSON with their published JSON Schemas: what modelgap's
//! MCAP files show in Foxglove's 3D panel ([`SceneUpdate`]) and the frame they are drawn in
//! ([`FrameTransform`]).
//!
//! # The schemas
//!
//! [`SCENE_UPDATE_SCHEMA`] and [`FRAME_TRANSFORM_SCHEMA`] are the published schemas of
//! `foxglove.SceneUpdate` and `foxglove.FrameTransform`, the text of
//! `schemas/jsonschema/SceneUpdate.json` (commit `d41940ba10614a1b657b7024b795c3d9462e1aaa`,
//! 42 453 characters) and `schemas/jsonschema/FrameTransform.json` (commit
//! `ad820c517cf4af715cb788a814250d75e46c711e`, 1 784 characters) of
//! <https://github.com/foxglove/schemas> (MIT licence), the schemas of the
//! `@foxglove/schemas` package. Channels added with [`add_scene_update_channel`] and
//! [`add_frame_transform_channel`] carry them with the insignificant whitespace taken out
//! ([`minify_json`]; 19 981 and 1 156 bytes), so each file holds the same JSON value.
//!
//! The newer copies in `foxglove/foxglove-sdk` add `"required"` lists and a `lineage` field
//! given only as `{"$ref": "LineageInfo.json"}`, a field without a `type`, which Foxglove's
//! JSON Schema reader (`parseJsonSchema` of `@foxglove/mcap-support`) refuses ("Unsupported
//! type"); the files written here use the earlier schemas, which every Foxglove reads. Their
//! `required` lists ask for every field, and so does the check of the messages written here
//! ([`check_message`](crate::io::json_schema::check_message) with
//! [`Strictness::Complete`](crate::io::json_schema::Strictness::Complete)).
//!
//! # The messages
//!
//! The types below serialise to exactly the fields of the schema, all of them present
//! (primitive kinds modelgap does not draw are written as empty arrays). Coordinates are
//! `f64` and written as given; round them first ([`round_to`]) to keep files small.

use std::io::{Seek, Write};

use serde::{Serialize, Serializer};

use crate::error::Result;
use crate::io::mcap::{ChannelId, McapWriter};

/// The schema name of a scene update.
pub const SCENE_UPDATE: &str = "foxglove.SceneUpdate";

/// The schema name of a transform between two frames.
pub const FRAME_TRANSFORM: &str = "foxglove.FrameTransform";

/// The published JSON Schema of `foxglove.SceneUpdate` (see the [module docs](self)).
pub const SCENE_UPDATE_SCHEMA: &str = include_str!("SceneUpdate.json");

/// The published JSON Schema of `foxglove.FrameTransform` (see the [module docs](self)).
pub const FRAME_TRANSFORM_SCHEMA: &str = include_str!("FrameTransform.json");

/// The published schema of a Foxglove message type this module writes, by schema name.
#[must_use]
pub fn published_schema(name: &str) -> Option<&'static str> {
    match name {
        SCENE_UPDATE => Some(SCENE_UPDATE_SCHEMA),
        FRAME_TRANSFORM => Some(FRAME_TRANSFORM_SCHEMA),
        _ => None,
    }
}

/// Adds a `foxglove.SceneUpdate` channel on `topic`, with the published schema.
///
/// # Errors
///
/// As [`McapWriter::add_channel_with_schema_text`].
pub fn add_scene_update_channel<W: Write + Seek>(
    writer: &mut McapWriter<W>,
    topic: &str,
) -> Result<ChannelId> {
    writer.add_channel_with_schema_text(topic, SCENE_UPDATE, &minify_json(SCENE_UPDATE_SCHEMA))
}

/// Adds a `foxglove.FrameTransform` channel on `topic`, with the published schema.
///
/// # Errors
///
/// As [`McapWriter::add_channel_with_schema_text`].
pub fn add_frame_transform_channel<W: Write + Seek>(
    writer: &mut McapWriter<W>,
    topic: &str,
) -> Result<ChannelId> {
    writer.add_channel_with_schema_text(
        topic,
        FRAME_TRANSFORM,
        &minify_json(FRAME_TRANSFORM_SCHEMA),
    )
}

/// JSON text with the whitespace between tokens taken out (strings and key order kept): the
/// same JSON value in fewer bytes. Text that is not JSON comes out with its whitespace
/// outside strings removed, no more.
#[must_use]
pub fn minify_json(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut in_string = false;
    let mut escaped = false;
    for c in text.chars() {
        if in_string {
            out.push(c);
            if escaped {
                escaped = false;
            } else if c == '\\' {
                escaped = true;
            } else if c == '"' {
                in_string = false;
            }
        } else if c == '"' {
            in_string = true;
            out.push(c);
        } else if !c.is_ascii_whitespace() {
            out.push(c);
        }
    }
    out
}

/// `v` rounded to `decimals` decimal places, written back as the `f64` nearest to that
/// decimal (so JSON prints at most `decimals` places: 0.1667, not 0.16670000000000001);
/// −0 becomes 0. `decimals` is at most 15; non-finite values pass through.
#[must_use]
pub fn round_to(v: f64, decimals: u8) -> f64 {
    let scale = 10f64.powi(i32::from(decimals.min(15)));
    // Dividing a whole number by an exact power of ten rounds once, to the nearest f64.
    let r = (v * scale).round() / scale;
    if r == 0.0 { 0.0 } else { r }
}

/// A Foxglove `time`: whole seconds and nanoseconds since the file's zero.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Time {
    /// Whole seconds.
    pub sec: u64,
    /// Nanoseconds, 0 to 999 999 999.
    pub nsec: u32,
}

impl Time {
    /// The time `t` seconds after zero, rounded to a nanosecond; negative or NaN times are 0.
    #[must_use]
    pub fn from_seconds(t: f64) -> Self {
        // Saturating casts: NaN and negatives give 0, huge values the largest time.
        let ns = (t * 1e9).round() as u64;
        Self {
            sec: ns / 1_000_000_000,
            nsec: (ns % 1_000_000_000) as u32,
        }
    }
}

/// A Foxglove `duration` (an entity's lifetime; zero: until replaced or deleted).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Duration {
    /// Whole seconds.
    pub sec: i64,
    /// Nanoseconds, 0 to 999 999 999.
    pub nsec: u32,
}

/// `foxglove.Vector3` (and `foxglove.Point3`, which has the same fields).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

impl Vector3 {
    /// The zero vector.
    pub const ZERO: Self = Self {
        x: 0.0,
        y: 0.0,
        z: 0.0,
    };

    /// A point from `[x, y, z]`, each coordinate rounded to `decimals` places ([`round_to`]).
    #[must_use]
    pub fn rounded(p: [f64; 3], decimals: u8) -> Self {
        Self {
            x: round_to(p[0], decimals),
            y: round_to(p[1], decimals),
            z: round_to(p[2], decimals),
        }
    }

    /// The same length `s` along each axis (a sphere's diameter, for example).
    #[must_use]
    pub const fn splat(s: f64) -> Self {
        Self { x: s, y: s, z: s }
    }
}

/// `foxglove.Quaternion`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Quaternion {
    /// No rotation.
    pub const IDENTITY: Self = Self {
        x: 0.0,
        y: 0.0,
        z: 0.0,
        w: 1.0,
    };
}

/// `foxglove.Pose`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Pose {
    /// Position.
    pub position: Vector3,
    /// Orientation.
    pub orientation: Quaternion,
}

impl Pose {
    /// At the frame's origin, not rotated: the pose of every primitive modelgap writes
    /// (positions are in the entity's frame).
    pub const IDENTITY: Self = Self {
        position: Vector3::ZERO,
        orientation: Quaternion::IDENTITY,
    };

    /// At `position`, not rotated.
    #[must_use]
    pub const fn at(position: Vector3) -> Self {
        Self {
            position,
            orientation: Quaternion::IDENTITY,
        }
    }
}

/// `foxglove.Color`, each channel 0 to 1.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Color {
    /// Red.
    pub r: f64,
    /// Green.
    pub g: f64,
    /// Blue.
    pub b: f64,
    /// Alpha (opacity).
    pub a: f64,
}

impl Color {
    /// Opaque `rgb`, each channel rounded to two decimals (101 levels, finer than a colour
    /// map needs).
    #[must_use]
    pub fn opaque(rgb: [f64; 3]) -> Self {
        Self {
            r: round_to(rgb[0], 2),
            g: round_to(rgb[1], 2),
            b: round_to(rgb[2], 2),
            a: 1.0,
        }
    }

    /// `rgb` with opacity `a`, channels rounded to two decimals.
    #[must_use]
    pub fn with_alpha(rgb: [f64; 3], a: f64) -> Self {
        Self {
            a: round_to(a, 2),
            ..Self::opaque(rgb)
        }
    }
}

/// `foxglove.KeyValuePair`: an entity's metadata entry.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct KeyValuePair {
    /// Key (unique within an entity).
    pub key: String,
    /// Value.
    pub value: String,
}

impl KeyValuePair {
    /// A metadata entry.
    #[must_use]
    pub fn new(key: impl Into<String>, value: impl Into<String>) -> Self {
        Self {
            key: key.into(),
            value: value.into(),
        }
    }
}

/// `foxglove.SpherePrimitive`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SpherePrimitive {
    /// Centre (and orientation).
    pub pose: Pose,
    /// Diameter along each axis.
    pub size: Vector3,
    /// Colour.
    pub color: Color,
}

/// How a [`LinePrimitive`] joins its points (`foxglove.LineType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineType {
    /// 0–1, 1–2, …
    Strip,
    /// 0–1, 1–2, …, n–0.
    Loop,
    /// Separate segments 0–1, 2–3, …
    List,
}

impl Serialize for LineType {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_u8(match self {
            Self::Strip => 0,
            Self::Loop => 1,
            Self::List => 2,
        })
    }
}

/// `foxglove.LinePrimitive`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LinePrimitive {
    /// How the points are joined.
    #[serde(rename = "type")]
    pub kind: LineType,
    /// Origin of the points.
    pub pose: Pose,
    /// Thickness: pixels when `scale_invariant`, else in the frame's units.
    pub thickness: f64,
    /// Whether `thickness` is in screen pixels.
    pub scale_invariant: bool,
    /// Points.
    pub points: Vec<Vector3>,
    /// Colour of the whole line (unless `colors` is given).
    pub color: Color,
    /// One colour per point, or none.
    pub colors: Vec<Color>,
    /// Indices into `points` (empty: the points in order).
    pub indices: Vec<u32>,
}

/// `foxglove.TriangleListPrimitive`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TriangleListPrimitive {
    /// Origin of the points.
    pub pose: Pose,
    /// Vertices.
    pub points: Vec<Vector3>,
    /// Colour of the whole surface (unless `colors` is given).
    pub color: Color,
    /// One colour per vertex, or none.
    pub colors: Vec<Color>,
    /// Three indices into `points` per triangle (empty: the points in threes).
    pub indices: Vec<u32>,
}

/// The primitive kinds modelgap does not draw, written as the empty arrays the schema has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoPrimitives;

impl Serialize for NoPrimitives {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_seq(std::iter::empty::<()>())
    }
}

/// `foxglove.SceneEntity`: primitives drawn together in one frame, replacing any earlier
/// entity with the same `id` on the topic.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneEntity {
    /// Time of the entity.
    pub timestamp: Time,
    /// The frame its poses are in.
    pub frame_id: String,
    /// Identifier, unique on the topic.
    pub id: String,
    /// When it disappears (zero: when replaced).
    pub lifetime: Duration,
    /// Whether it follows `frame_id` when that frame moves.
    pub frame_locked: bool,
    /// Metadata shown when the entity is selected.
    pub metadata: Vec<KeyValuePair>,
    /// Not drawn by modelgap.
    pub arrows: NoPrimitives,
    /// Not drawn by modelgap.
    pub cubes: NoPrimitives,
    /// Spheres.
    pub spheres: Vec<SpherePrimitive>,
    /// Not drawn by modelgap.
    pub cylinders: NoPrimitives,
    /// Lines.
    pub lines: Vec<LinePrimitive>,
    /// Triangle lists.
    pub triangles: Vec<TriangleListPrimitive>,
    /// Not drawn by modelgap.
    pub texts: NoPrimitives,
    /// Not drawn by modelgap.
    pub models: NoPrimitives,
}

impl SceneEntity {
    /// An entity without primitives at `t` seconds in `frame_id`, kept until replaced.
    #[must_use]
    pub fn new(t: f64, frame_id: &str, id: &str) -> Self {
        Self {
            timestamp: Time::from_seconds(t),
            frame_id: frame_id.to_owned(),
            id: id.to_owned(),
            lifetime: Duration::default(),
            frame_locked: false,
            metadata: Vec::new(),
            arrows: NoPrimitives,
            cubes: NoPrimitives,
            spheres: Vec::new(),
            cylinders: NoPrimitives,
            lines: Vec::new(),
            triangles: Vec::new(),
            texts: NoPrimitives,
            models: NoPrimitives,
        }
    }
}

/// `foxglove.SceneEntityDeletion` (none are written; the type completes the message).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct SceneEntityDeletion {
    /// Entities older than this are deleted.
    pub timestamp: Time,
    /// 0: the entity `id`; 1: all entities on the topic.
    #[serde(rename = "type")]
    pub kind: u8,
    /// The entity to delete when `kind` is 0.
    pub id: String,
}

/// `foxglove.SceneUpdate`: entities to add or replace, and deletions.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SceneUpdate {
    /// Entities to delete.
    pub deletions: Vec<SceneEntityDeletion>,
    /// Entities to add or replace.
    pub entities: Vec<SceneEntity>,
}

/// `foxglove.FrameTransform`: where the child frame sits in its parent.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameTransform {
    /// Time from which the transform holds.
    pub timestamp: Time,
    /// The parent frame.
    pub parent_frame_id: String,
    /// The child frame.
    pub child_frame_id: String,
    /// The child's origin in the parent frame.
    pub translation: Vector3,
    /// The child's orientation in the parent frame.
    pub rotation: Quaternion,
}

/// Writes a Foxglove message (any of the types above) as JSON on `channel` at `t` seconds.
///
/// # Errors
///
/// As [`McapWriter::write_json`]; [`CoreError::McapWrite`](crate::CoreError::McapWrite)
/// when the message does not serialise (a non-finite number: JSON has none).
pub fn write_message<W: Write + Seek, M: Serialize>(
    writer: &mut McapWriter<W>,
    channel: ChannelId,
    t: f64,
    message: &M,
) -> Result<()> {
    let value = serde_json::to_value(message).map_err(|e| crate::CoreError::McapWrite {
        reason: format!("a Foxglove message does not serialise: {e}"),
        path: None,
    })?;
    if let Some(reason) = non_finite(&value) {
        return Err(crate::CoreError::McapWrite { reason, path: None });
    }
    writer.write_json(channel, t, &value)
}

/// serde_json writes NaN and infinities as `null`, which no schema number accepts: say so.
fn non_finite(value: &serde_json::Value) -> Option<String> {
    match value {
        serde_json::Value::Null => {
            Some("a Foxglove message holds a non-finite number (JSON has none)".to_owned())
        }
        serde_json::Value::Array(items) => items.iter().find_map(non_finite),
        serde_json::Value::Object(map) => map.values().find_map(non_finite),
        _ => None,
    }
}

#[cfg(test)]
mod tests;

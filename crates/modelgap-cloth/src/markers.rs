//! Marker recordings: the measured (or simulated) positions of chosen mesh vertices over
//! time, and their CSV and MCAP files.
//!
//! A marker's id is the vertex index in the scene's mesh (`row * nx + col` for a grid).
//!
//! - **CSV**: the header `t,id,x,y,z`, then one row per marker per frame; rows of one frame
//!   share their `t` and follow each other. Lines whose first non-blank character is `#`
//!   are comments; blank lines are skipped (both count for line numbers); cells are trimmed.
//!   Later frames may list their markers in any order; they are put in the first frame's
//!   order. Writing uses Rust's shortest round-trip `Display` of `f64`, so write → read
//!   gives back the same recording, bit for bit.
//! - **MCAP**: topic [`MARKERS_TOPIC`], one JSON message per frame,
//!   `{"ids": [..], "positions": [x0, y0, z0, x1, …]}`; a frame's time is its `log_time`
//!   relative to the first frame (written as `t - t[0]`, rounded to whole nanoseconds).
//!
//! Readers check what they read: finite numbers, strictly increasing time, the same ids in
//! every frame, each id once. Errors name the line (CSV, from 1) or message (MCAP, from 0),
//! the field, what was expected and found, and the file last.
//!
//! # Example
//!
//! ```
//! use modelgap_cloth::markers::{MarkerRecording, read_markers_csv, write_markers_csv};
//!
//! let rec = MarkerRecording::new(
//!     vec![0.0, 0.01],
//!     vec![0, 29],
//!     vec![
//!         vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
//!         vec![[0.0, -0.001, 0.0], [1.0, -0.001, 0.0]],
//!     ],
//! )?;
//! let mut text = Vec::new();
//! write_markers_csv(&rec, &mut text)?;
//! assert_eq!(read_markers_csv(text.as_slice())?, rec);
//! # Ok::<(), modelgap_cloth::ClothError>(())
//! ```

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Read, Seek, Write};
use std::path::Path;

use modelgap_core::io::atomic::{AtomicFile, commit_buffered};
use modelgap_core::io::mcap::{
    ChannelId, McapCompression, McapWriter, TopicMessage, read_topic_messages,
};
use modelgap_core::{CoreError, Location};

use crate::error::{ClothError, Result};

/// The MCAP topic of marker frames.
pub const MARKERS_TOPIC: &str = "/markers";

/// The schema name of the marker channel.
pub const MARKERS_SCHEMA_NAME: &str = "modelgap.Markers";

/// The CSV header of a marker file.
pub const MARKERS_CSV_HEADER: &str = "t,id,x,y,z";

/// Nanoseconds per second (for the 1 ns spacing check of MCAP frames).
const NS_PER_S: f64 = 1e9;

/// The positions of a set of markers (mesh vertices) over time: one frame per time, one
/// position per marker in every frame.
///
/// Built only through [`new`](Self::new) (or the readers), so it always holds: time finite
/// and strictly increasing, ids unique, every frame a finite position per id.
#[derive(Clone, Debug, PartialEq)]
pub struct MarkerRecording {
    t: Vec<f64>,
    ids: Vec<u32>,
    positions: Vec<Vec<[f64; 3]>>,
}

impl MarkerRecording {
    /// A recording from frame times (s), marker ids (vertex indices) and positions (m) per
    /// frame, per marker in the order of `ids`.
    ///
    /// # Errors
    ///
    /// [`ClothError::NoMarkerFrames`] when `t` is empty; [`ClothError::MarkerField`] (at the
    /// frame, as [`Location::Sample`]) for no ids, a repeated id, a frame count or a frame
    /// length that does not match, a non-finite time or coordinate;
    /// [`ClothError::MarkerTime`] when time does not strictly increase.
    pub fn new(t: Vec<f64>, ids: Vec<u32>, positions: Vec<Vec<[f64; 3]>>) -> Result<Self> {
        if t.is_empty() {
            return Err(ClothError::NoMarkerFrames { path: None });
        }
        if ids.is_empty() {
            return Err(field_error(
                Location::Sample(0),
                "ids",
                "at least one marker id",
                "none",
            ));
        }
        let mut seen = BTreeMap::new();
        for (k, &id) in ids.iter().enumerate() {
            if let Some(first) = seen.insert(id, k) {
                return Err(field_error(
                    Location::Sample(0),
                    "ids",
                    "each id once",
                    &format!("id {id} at positions {first} and {k}"),
                ));
            }
        }
        if positions.len() != t.len() {
            return Err(field_error(
                Location::Sample(positions.len().min(t.len())),
                "positions",
                &format!("one frame per time ({})", t.len()),
                &format!("{} frames", positions.len()),
            ));
        }
        for (k, (&tk, frame)) in t.iter().zip(&positions).enumerate() {
            if !tk.is_finite() {
                return Err(field_error(
                    Location::Sample(k),
                    "t",
                    "a finite time",
                    &tk.to_string(),
                ));
            }
            if k > 0 && tk <= t[k - 1] {
                return Err(ClothError::MarkerTime {
                    at: Location::Sample(k),
                    t_prev: t[k - 1],
                    t: tk,
                    path: None,
                });
            }
            if frame.len() != ids.len() {
                return Err(field_error(
                    Location::Sample(k),
                    "positions",
                    &format!("{} markers (one per id)", ids.len()),
                    &format!("{} markers", frame.len()),
                ));
            }
            for (p, &id) in frame.iter().zip(&ids) {
                for (c, axis) in p.iter().zip(["x", "y", "z"]) {
                    if !c.is_finite() {
                        return Err(field_error(
                            Location::Sample(k),
                            &format!("{axis} of marker {id}"),
                            "a finite coordinate",
                            &c.to_string(),
                        ));
                    }
                }
            }
        }
        Ok(Self { t, ids, positions })
    }

    /// Frame times (s), strictly increasing.
    #[must_use]
    pub fn t(&self) -> &[f64] {
        &self.t
    }

    /// Marker ids (vertex indices), unique, in the order of each frame's positions.
    #[must_use]
    pub fn ids(&self) -> &[u32] {
        &self.ids
    }

    /// Positions (m) per frame, per marker in the order of [`ids`](Self::ids).
    #[must_use]
    pub fn positions(&self) -> &[Vec<[f64; 3]>] {
        &self.positions
    }

    /// The number of frames (at least 1).
    #[must_use]
    pub fn n_frames(&self) -> usize {
        self.t.len()
    }

    /// The number of markers (at least 1).
    #[must_use]
    pub fn n_markers(&self) -> usize {
        self.ids.len()
    }

    /// Where marker `id` sits in [`ids`](Self::ids), if it is recorded.
    #[must_use]
    pub fn marker_index(&self, id: u32) -> Option<usize> {
        self.ids.iter().position(|&i| i == id)
    }

    /// The positions (m) of marker `id` in every frame, if it is recorded.
    #[must_use]
    pub fn track(&self, id: u32) -> Option<Vec<[f64; 3]>> {
        let k = self.marker_index(id)?;
        Some(self.positions.iter().map(|frame| frame[k]).collect())
    }

    /// Times, ids and positions, moved out.
    #[must_use]
    pub fn into_parts(self) -> (Vec<f64>, Vec<u32>, Vec<Vec<[f64; 3]>>) {
        (self.t, self.ids, self.positions)
    }
}

fn field_error(at: Location, field: &str, expected: &str, found: &str) -> ClothError {
    ClothError::MarkerField {
        at,
        field: field.to_owned(),
        expected: expected.to_owned(),
        found: found.to_owned(),
        path: None,
    }
}

/// The rows of one frame while a CSV file is read: (id, position, line).
struct CsvFrame {
    t: f64,
    line: usize,
    rows: Vec<(u32, [f64; 3], usize)>,
}

/// Reads a marker recording from CSV text (see the [module docs](self)).
///
/// # Errors
///
/// [`ClothError::MarkerHeader`] for a missing or different header;
/// [`ClothError::MarkerField`] (with the line) for a row without 5 cells, a cell that is not
/// a (finite) number or an id, an id repeated in a frame, missing from it or not in the
/// first frame; [`ClothError::MarkerTime`] when a frame's time is earlier than the previous
/// one; [`ClothError::NoMarkerFrames`] when there are no rows; [`ClothError::Core`] when the
/// text cannot be read or is not UTF-8.
pub fn read_markers_csv(reader: impl Read) -> Result<MarkerRecording> {
    read_csv(reader, None)
}

/// Reads marker CSV text; with `n_vertices`, an id of no vertex (`id >= n_vertices`) is
/// refused at its line.
fn read_csv(reader: impl Read, n_vertices: Option<usize>) -> Result<MarkerRecording> {
    let mut reader = BufReader::new(reader);
    let mut buf = Vec::new();
    let mut line_no = 0usize;
    let mut header = false;
    let mut current: Option<CsvFrame> = None;
    let mut frames = FrameSet::default();
    loop {
        buf.clear();
        let n = reader
            .read_until(b'\n', &mut buf)
            .map_err(|e| CoreError::io(e, None))?;
        if n == 0 {
            break;
        }
        line_no += 1;
        let line = std::str::from_utf8(&buf).map_err(|_| CoreError::NotUtf8 {
            line: line_no,
            path: None,
        })?;
        let line = if line_no == 1 {
            line.strip_prefix('\u{feff}').unwrap_or(line)
        } else {
            line
        };
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if !header {
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            if cells != ["t", "id", "x", "y", "z"] {
                return Err(ClothError::MarkerHeader {
                    found: format!("`{line}` at line {line_no}"),
                    path: None,
                });
            }
            header = true;
            continue;
        }
        let (t, id, p) = parse_row(line, line_no)?;
        check_vertex(id, n_vertices, Location::Line(line_no), "id")?;
        match current.as_mut() {
            Some(frame) if t.to_bits() == frame.t.to_bits() => frame.rows.push((id, p, line_no)),
            Some(frame) if t < frame.t => {
                return Err(ClothError::MarkerTime {
                    at: Location::Line(line_no),
                    t_prev: frame.t,
                    t,
                    path: None,
                });
            }
            _ => {
                if let Some(done) = current.take() {
                    frames.push_csv(done)?;
                }
                current = Some(CsvFrame {
                    t,
                    line: line_no,
                    rows: vec![(id, p, line_no)],
                });
            }
        }
    }
    if !header {
        return Err(ClothError::MarkerHeader {
            found: "no header".to_owned(),
            path: None,
        });
    }
    if let Some(done) = current.take() {
        frames.push_csv(done)?;
    }
    frames.finish()
}

/// Reads a marker CSV file; like [`read_markers_csv`], with the path in every error.
///
/// # Errors
///
/// As [`read_markers_csv`], plus [`ClothError::Core`] when the file cannot be opened.
pub fn read_markers_csv_path(path: &Path) -> Result<MarkerRecording> {
    read_csv_path(path, None)
}

fn read_csv_path(path: &Path, n_vertices: Option<usize>) -> Result<MarkerRecording> {
    let file = File::open(path).map_err(|e| CoreError::io(e, Some(path)))?;
    read_csv(file, n_vertices).map_err(|e| e.with_path(path))
}

/// [`ClothError::MarkerField`] at `at` when `id` is no vertex of a mesh of `n_vertices`.
fn check_vertex(id: u32, n_vertices: Option<usize>, at: Location, field: &str) -> Result<()> {
    match n_vertices {
        Some(n) if id as usize >= n => Err(field_error(
            at,
            field,
            &if n == 0 {
                "a vertex of the mesh (it has none)".to_owned()
            } else {
                format!("a vertex of the mesh (0 to {})", n - 1)
            },
            &format!("marker id {id}"),
        )),
        _ => Ok(()),
    }
}

/// Writes a marker recording as CSV text: the header `t,id,x,y,z`, then one row per marker
/// per frame, markers in the order of [`MarkerRecording::ids`].
///
/// # Errors
///
/// [`ClothError::Core`] when writing fails.
pub fn write_markers_csv(recording: &MarkerRecording, writer: impl Write) -> Result<()> {
    let io = |e| ClothError::Core(CoreError::io(e, None));
    let mut w = BufWriter::new(writer);
    writeln!(w, "{MARKERS_CSV_HEADER}").map_err(io)?;
    for (t, frame) in recording.t.iter().zip(&recording.positions) {
        for (id, [x, y, z]) in recording.ids.iter().zip(frame) {
            // `{}` on f64 prints the shortest decimal that parses back to the same bits.
            writeln!(w, "{t},{id},{x},{y},{z}").map_err(io)?;
        }
    }
    w.flush().map_err(io)
}

/// Writes a marker recording to a CSV file (created or truncated); like
/// [`write_markers_csv`], with the path in every error.
///
/// # Errors
///
/// As [`write_markers_csv`], plus [`ClothError::Core`] when the file cannot be created.
pub fn write_markers_csv_path(recording: &MarkerRecording, path: &Path) -> Result<()> {
    let mut file = AtomicFile::create(path)?;
    write_markers_csv(recording, &mut file).map_err(|e| e.with_path(path))?;
    Ok(file.commit()?)
}

fn parse_row(line: &str, line_no: usize) -> Result<(f64, u32, [f64; 3])> {
    let cells: Vec<&str> = line.split(',').map(str::trim).collect();
    if cells.len() != 5 {
        return Err(field_error(
            Location::Line(line_no),
            "row",
            "5 cells `t,id,x,y,z`",
            &format!("{} cells", cells.len()),
        ));
    }
    let number = |k: usize, name: &str| -> Result<f64> {
        let text = cells[k];
        let v: f64 = text.parse().map_err(|_| {
            field_error(
                Location::Line(line_no),
                name,
                "a number",
                &format!("`{text}`"),
            )
        })?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(field_error(
                Location::Line(line_no),
                name,
                "a finite number",
                &format!("`{text}`"),
            ))
        }
    };
    let t = number(0, "t")?;
    let id: u32 = cells[1].parse().map_err(|_| {
        field_error(
            Location::Line(line_no),
            "id",
            "a vertex index (a whole number from 0)",
            &format!("`{}`", cells[1]),
        )
    })?;
    Ok((t, id, [number(2, "x")?, number(3, "y")?, number(4, "z")?]))
}

/// Frames as they are read: the first frame fixes the ids and their order.
#[derive(Default)]
struct FrameSet {
    t: Vec<f64>,
    ids: Vec<u32>,
    index: BTreeMap<u32, usize>,
    positions: Vec<Vec<[f64; 3]>>,
}

impl FrameSet {
    /// Adds a frame given as (id, position, location) in any order; `at` locates the frame.
    fn push(&mut self, t: f64, at: Location, rows: &[(u32, [f64; 3], Location)]) -> Result<()> {
        if self.t.is_empty() {
            if rows.is_empty() {
                return Err(field_error(at, "ids", "at least one marker id", "none"));
            }
            let mut frame = Vec::with_capacity(rows.len());
            for &(id, p, row_at) in rows {
                if let Some(&k) = self.index.get(&id) {
                    return Err(repeated(id, row_at, rows[k].2));
                }
                self.index.insert(id, self.ids.len());
                self.ids.push(id);
                frame.push(p);
            }
            self.positions.push(frame);
            self.t.push(t);
            return Ok(());
        }
        let mut frame: Vec<Option<([f64; 3], Location)>> = vec![None; self.ids.len()];
        for &(id, p, row_at) in rows {
            let Some(&k) = self.index.get(&id) else {
                return Err(field_error(
                    row_at,
                    "id",
                    "one of the first frame's ids",
                    &format!("id {id}"),
                ));
            };
            if let Some((_, first)) = frame[k] {
                return Err(repeated(id, row_at, first));
            }
            frame[k] = Some((p, row_at));
        }
        let mut out = Vec::with_capacity(frame.len());
        for (k, slot) in frame.into_iter().enumerate() {
            let Some((p, _)) = slot else {
                return Err(field_error(
                    at,
                    "id",
                    "every id of the first frame in each frame",
                    &format!("id {} missing from the frame at t = {t} s", self.ids[k]),
                ));
            };
            out.push(p);
        }
        self.positions.push(out);
        self.t.push(t);
        Ok(())
    }

    fn push_csv(&mut self, frame: CsvFrame) -> Result<()> {
        let rows: Vec<(u32, [f64; 3], Location)> = frame
            .rows
            .into_iter()
            .map(|(id, p, line)| (id, p, Location::Line(line)))
            .collect();
        self.push(frame.t, Location::Line(frame.line), &rows)
    }

    fn finish(self) -> Result<MarkerRecording> {
        if self.t.is_empty() {
            return Err(ClothError::NoMarkerFrames { path: None });
        }
        MarkerRecording::new(self.t, self.ids, self.positions)
    }
}

fn repeated(id: u32, at: Location, first: Location) -> ClothError {
    field_error(
        at,
        "id",
        "each id once per frame",
        &format!("id {id} again (first at {first})"),
    )
}

/// The JSON schema of a marker frame message.
#[must_use]
pub fn markers_schema() -> serde_json::Value {
    serde_json::json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": MARKERS_SCHEMA_NAME,
        "description": "positions of mesh vertices (ids) in one frame, x y z per id, in m",
        "type": "object",
        "properties": {
            "ids": { "type": "array", "items": { "type": "integer", "minimum": 0 } },
            "positions": { "type": "array", "items": { "type": "number" } },
        },
        "required": ["ids", "positions"],
    })
}

/// Adds the [`MARKERS_TOPIC`] channel to an MCAP writer (for files that hold more than
/// markers; [`write_markers_mcap`] does it for a markers-only file).
///
/// # Errors
///
/// [`ClothError::Core`] when the channel cannot be written.
pub fn add_markers_channel<W: Write + Seek>(writer: &mut McapWriter<W>) -> Result<ChannelId> {
    Ok(writer.add_json_channel(MARKERS_TOPIC, MARKERS_SCHEMA_NAME, &markers_schema())?)
}

/// Writes one marker frame at `t` seconds (the file's time: relative to its first frame).
///
/// # Errors
///
/// [`ClothError::Core`] for a negative or non-finite `t`, or when writing fails.
pub fn write_markers_frame<W: Write + Seek>(
    writer: &mut McapWriter<W>,
    channel: ChannelId,
    t: f64,
    ids: &[u32],
    positions: &[[f64; 3]],
) -> Result<()> {
    let flat: Vec<f64> = positions.iter().flatten().copied().collect();
    let message = serde_json::json!({ "ids": ids, "positions": flat });
    Ok(writer.write_json(channel, t, &message)?)
}

/// Writes a marker recording as MCAP: one message per frame on [`MARKERS_TOPIC`], the first
/// at `log_time` 0.
///
/// # Errors
///
/// [`ClothError::MarkerField`] when two frames are less than 1 ns apart (MCAP's time
/// resolution); [`ClothError::Core`] when writing fails.
pub fn write_markers_mcap<W: Write + Seek>(
    recording: &MarkerRecording,
    writer: W,
    compression: McapCompression,
) -> Result<W> {
    let t0 = recording.t[0];
    let mut prev_ns = None;
    for (k, &t) in recording.t.iter().enumerate() {
        let ns = ((t - t0) * NS_PER_S).round();
        if prev_ns.is_some_and(|p| ns <= p) {
            return Err(field_error(
                Location::Sample(k),
                "t",
                "frames at least 1 ns apart (mcap's time resolution)",
                &format!("{t} s"),
            ));
        }
        prev_ns = Some(ns);
    }
    let mut out = McapWriter::new(writer, compression)?;
    let channel = add_markers_channel(&mut out)?;
    for (&t, frame) in recording.t.iter().zip(&recording.positions) {
        write_markers_frame(&mut out, channel, t - t0, &recording.ids, frame)?;
    }
    Ok(out.finish()?)
}

/// Writes a marker recording to a zstd-compressed MCAP file (created or truncated); like
/// [`write_markers_mcap`], with the path in every error.
///
/// # Errors
///
/// As [`write_markers_mcap`], plus [`ClothError::Core`] when the file cannot be created.
pub fn write_markers_mcap_path(recording: &MarkerRecording, path: &Path) -> Result<()> {
    let file = AtomicFile::create(path)?;
    let w = write_markers_mcap(recording, BufWriter::new(file), McapCompression::Zstd)
        .map_err(|e| e.with_path(path))?;
    Ok(commit_buffered(w)?)
}

/// Reads a marker recording from the [`MARKERS_TOPIC`] messages of MCAP data in memory.
/// Time starts at 0 (the first frame's `log_time`).
///
/// # Errors
///
/// [`ClothError::Core`] for corrupt or truncated data, a missing topic, a non-JSON encoding
/// or a repeated `log_time`; [`ClothError::MarkerField`] (with the message index) for a
/// message that is not `{"ids": [..], "positions": [..]}` with whole-number ids and three
/// finite numbers per id, or whose ids differ from the first frame's.
pub fn read_markers_mcap(bytes: &[u8]) -> Result<MarkerRecording> {
    read_mcap(bytes, None)
}

/// Reads marker MCAP data; with `n_vertices`, an id of no vertex is refused at its message.
fn read_mcap(bytes: &[u8], n_vertices: Option<usize>) -> Result<MarkerRecording> {
    let messages = read_topic_messages(bytes, MARKERS_TOPIC)?;
    let mut frames = FrameSet::default();
    for message in &messages {
        let rows = parse_message(message)?;
        for (k, &(id, _, at)) in rows.iter().enumerate() {
            check_vertex(id, n_vertices, at, &format!("ids[{k}]"))?;
        }
        frames.push(message.t, Location::Message(message.index), &rows)?;
    }
    frames.finish()
}

/// Reads a marker recording from an MCAP file; like [`read_markers_mcap`], with the path in
/// every error.
///
/// # Errors
///
/// As [`read_markers_mcap`], plus [`ClothError::Core`] when the file cannot be read.
pub fn read_markers_mcap_path(path: &Path) -> Result<MarkerRecording> {
    read_mcap_path(path, None)
}

fn read_mcap_path(path: &Path, n_vertices: Option<usize>) -> Result<MarkerRecording> {
    let bytes = std::fs::read(path).map_err(|e| CoreError::io(e, Some(path)))?;
    read_mcap(&bytes, n_vertices).map_err(|e| e.with_path(path))
}

/// Reads a marker recording from a `.csv` or `.mcap` file, by extension.
///
/// # Errors
///
/// [`ClothError::Core`] ([`CoreError::UnknownExtension`]) for another extension, and
/// ([`CoreError::FormatNotSupported`]) for Parquet, which holds signals; otherwise as
/// [`read_markers_csv_path`] or [`read_markers_mcap_path`].
pub fn read_markers_path(path: &Path) -> Result<MarkerRecording> {
    match modelgap_core::io::Format::from_path(path)? {
        modelgap_core::io::Format::Csv => read_markers_csv_path(path),
        modelgap_core::io::Format::Mcap => read_markers_mcap_path(path),
        modelgap_core::io::Format::Parquet => Err(parquet_markers(path)),
    }
}

/// The refusal to read markers from Parquet, which modelgap reads for signals only.
fn parquet_markers(path: &Path) -> ClothError {
    CoreError::FormatNotSupported {
        action: "read markers from",
        format: "parquet",
        reason: "parquet files are read as signals, markers as `t,id,x,y,z` csv or mcap",
        path: Some(path.to_path_buf()),
    }
    .into()
}

/// Reads a marker recording of a mesh of `n_vertices` vertices from a `.csv` or `.mcap`
/// file: like [`read_markers_path`], and an id that is no vertex of the mesh is refused
/// where it first appears (its CSV line or MCAP message), before the frames are compared.
///
/// # Errors
///
/// As [`read_markers_path`]; [`ClothError::MarkerField`] (field `id`, or `ids[k]` in MCAP)
/// for an id of `n_vertices` or more, with the line or message and the file.
pub fn read_markers_path_within(path: &Path, n_vertices: usize) -> Result<MarkerRecording> {
    match modelgap_core::io::Format::from_path(path)? {
        modelgap_core::io::Format::Csv => read_csv_path(path, Some(n_vertices)),
        modelgap_core::io::Format::Mcap => read_mcap_path(path, Some(n_vertices)),
        modelgap_core::io::Format::Parquet => Err(parquet_markers(path)),
    }
}

/// Writes a marker recording to a `.csv` or (zstd) `.mcap` file, by extension.
///
/// # Errors
///
/// [`ClothError::Core`] ([`CoreError::UnknownExtension`], or
/// [`CoreError::FormatNotSupported`] for Parquet) for another extension (nothing is
/// written); otherwise as [`write_markers_csv_path`] or [`write_markers_mcap_path`].
pub fn write_markers_path(recording: &MarkerRecording, path: &Path) -> Result<()> {
    match modelgap_core::io::Format::from_path(path)? {
        modelgap_core::io::Format::Csv => write_markers_csv_path(recording, path),
        modelgap_core::io::Format::Mcap => write_markers_mcap_path(recording, path),
        modelgap_core::io::Format::Parquet => {
            Err(modelgap_core::io::parquet_read_only(path).into())
        }
    }
}

fn parse_message(message: &TopicMessage) -> Result<Vec<(u32, [f64; 3], Location)>> {
    let at = Location::Message(message.index);
    let value: serde_json::Value = serde_json::from_slice(&message.data).map_err(|e| {
        field_error(
            at,
            "message",
            "a json object",
            &format!("invalid json ({e})"),
        )
    })?;
    let Some(object) = value.as_object() else {
        return Err(field_error(
            at,
            "message",
            "a json object",
            &short(&value.to_string()),
        ));
    };
    let array = |name: &str| -> Result<&Vec<serde_json::Value>> {
        match object.get(name) {
            Some(serde_json::Value::Array(items)) => Ok(items),
            Some(other) => Err(field_error(
                at,
                name,
                "an array",
                &short(&other.to_string()),
            )),
            None => Err(field_error(at, name, "an array", "no such field")),
        }
    };
    let ids = array("ids")?;
    let positions = array("positions")?;
    if positions.len() != 3 * ids.len() {
        return Err(field_error(
            at,
            "positions",
            &format!("3 numbers per id ({})", 3 * ids.len()),
            &format!("{} numbers", positions.len()),
        ));
    }
    let mut rows = Vec::with_capacity(ids.len());
    for (k, id) in ids.iter().enumerate() {
        let id = id
            .as_u64()
            .and_then(|v| u32::try_from(v).ok())
            .ok_or_else(|| {
                field_error(
                    at,
                    &format!("ids[{k}]"),
                    "a vertex index (a whole number from 0)",
                    &short(&id.to_string()),
                )
            })?;
        let mut p = [0.0; 3];
        for (c, slot) in p.iter_mut().enumerate() {
            let item = &positions[3 * k + c];
            *slot = item
                .as_f64()
                .filter(|v| item.is_number() && v.is_finite())
                .ok_or_else(|| {
                    field_error(
                        at,
                        &format!("positions[{}]", 3 * k + c),
                        "a finite number",
                        &short(&item.to_string()),
                    )
                })?;
        }
        rows.push((id, p, at));
    }
    Ok(rows)
}

/// Shortens a text for an error message (at most 40 characters).
fn short(text: &str) -> String {
    const MAX_CHARS: usize = 40;
    if text.chars().count() <= MAX_CHARS {
        text.to_owned()
    } else {
        let mut s: String = text.chars().take(MAX_CHARS).collect();
        s.push('…');
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn later_frames_may_list_markers_in_any_order() {
        let text = "t,id,x,y,z\n0,3,1,2,3\n0,5,4,5,6\n# comment\n\n0.5,5,7,8,9\n0.5,3,0,1,2\n";
        let rec = read_markers_csv(text.as_bytes()).unwrap();
        assert_eq!(rec.ids(), &[3, 5]);
        assert_eq!(rec.positions()[1], vec![[0.0, 1.0, 2.0], [7.0, 8.0, 9.0]]);
        assert_eq!(rec.track(5).unwrap()[1], [7.0, 8.0, 9.0]);
    }

    /// Issue 11: an id past the mesh on line 7 was reported as another id on a later line.
    #[test]
    fn an_id_past_the_mesh_is_refused_at_its_own_line() {
        let text = "t,id,x,y,z\n0,0,0,0,0\n0,1,1,0,0\n0,2,2,0,0\n0,3,3,0,0\n0,4000,4,0,0\n\
                    0,5,5,0,0\n0.1,0,0,0,0\n0.1,1,1,0,0\n0.1,2,2,0,0\n0.1,3,3,0,0\n0.1,4,4,0,0\n";
        let e = read_csv(text.as_bytes(), Some(9)).unwrap_err();
        assert_eq!(
            e.to_string(),
            "expected a vertex of the mesh (0 to 8) for `id` at line 6, found marker id 4000"
        );
        // Without a mesh the frames disagree, found later.
        let e = read_csv(text.as_bytes(), None).unwrap_err();
        assert!(
            matches!(
                e,
                ClothError::MarkerField {
                    at: Location::Line(12),
                    ..
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn new_rejects_repeated_ids_and_short_frames() {
        let e = MarkerRecording::new(vec![0.0], vec![1, 1], vec![vec![[0.0; 3]; 2]]).unwrap_err();
        assert!(matches!(e, ClothError::MarkerField { ref field, .. } if field == "ids"));
        let e = MarkerRecording::new(vec![0.0], vec![1, 2], vec![vec![[0.0; 3]]]).unwrap_err();
        assert!(
            matches!(e, ClothError::MarkerField { at: Location::Sample(0), ref field, .. } if field == "positions")
        );
        let e = MarkerRecording::new(vec![0.0, 0.0], vec![1], vec![vec![[0.0; 3]]; 2]).unwrap_err();
        assert!(matches!(
            e,
            ClothError::MarkerTime {
                at: Location::Sample(1),
                ..
            }
        ));
    }
}

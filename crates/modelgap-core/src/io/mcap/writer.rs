//! [`McapWriter`]: JSON channels written to one MCAP file.

use std::io::{BufWriter, Seek, Write};
use std::path::{Path, PathBuf};

use ::mcap::records::MessageHeader;
use ::mcap::{McapError, WriteOptions, Writer};

use super::{MESSAGE_ENCODING, NS_PER_S, SCHEMA_ENCODING, mcap_error_text};
use crate::error::{CoreError, Location, Result};
use crate::io::atomic::{AtomicFile, commit_buffered};

/// How MCAP chunks are compressed when writing. Reading handles all of them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum McapCompression {
    /// No compression.
    None,
    /// Zstandard at level 9: small files, the common choice (the default). Level 9 makes
    /// the demo's cloth comparison 22 % smaller than zstd's default level 3 and still
    /// compresses tens of MB of JSON per second.
    #[default]
    Zstd,
    /// LZ4: faster, larger.
    Lz4,
}

impl McapCompression {
    /// The compression level given to the mcap crate (0: the codec's default).
    fn level(self) -> u32 {
        match self {
            Self::Zstd => 9,
            Self::None | Self::Lz4 => 0,
        }
    }

    fn to_mcap(self) -> Option<::mcap::Compression> {
        match self {
            Self::None => None,
            Self::Zstd => Some(::mcap::Compression::Zstd),
            Self::Lz4 => Some(::mcap::Compression::Lz4),
        }
    }
}

/// A JSON schema (draft 2020-12) for a flat object with one number property per name, all
/// required: the shape of the messages [`write_signals`](super::write_signals) writes.
pub fn number_object_schema(title: &str, names: &[&str]) -> serde_json::Value {
    let properties: serde_json::Map<String, serde_json::Value> = names
        .iter()
        .map(|&name| (name.to_owned(), serde_json::json!({ "type": "number" })))
        .collect();
    serde_json::json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": title,
        "type": "object",
        "properties": properties,
        "required": names,
        "additionalProperties": false,
    })
}

/// A channel of an [`McapWriter`], handed out by [`McapWriter::add_json_channel`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ChannelId(u16);

/// Writes JSON channels to one MCAP file, for Foxglove (measured, model and residual side by
/// side, for example).
///
/// Call [`finish`](Self::finish) to write the summary and footer and see any error. A writer
/// on any stream dropped unfinished still finishes and flushes it (ignoring errors), so data
/// is never silently cut short; a file made with [`McapWriter::create`] is written atomically
/// and appears only after [`McapWriter::finish_file`] (dropped before that, it leaves any
/// earlier file at its path untouched).
///
/// # Example
///
/// ```
/// # use std::io::Cursor;
/// # use modelgap_core::io::mcap::{McapWriter, McapCompression, number_object_schema};
/// let mut writer = McapWriter::new(Cursor::new(Vec::new()), McapCompression::Zstd)?;
/// let schema = number_object_schema("Current", &["i"]);
/// let measured = writer.add_json_channel("/measured", "Current", &schema)?;
/// writer.write_json(measured, 0.001, &serde_json::json!({ "i": 1.25 }))?;
/// let bytes = writer.finish()?.into_inner();
/// assert!(bytes.starts_with(b"\x89MCAP0\r\n"));
/// # Ok::<(), modelgap_core::CoreError>(())
/// ```
pub struct McapWriter<W: Write + Seek = BufWriter<AtomicFile>> {
    /// `None` once finished.
    inner: Option<Writer<W>>,
    /// One sequence counter per channel, indexed by channel id.
    sequences: Vec<u32>,
    path: Option<PathBuf>,
}

impl McapWriter<BufWriter<AtomicFile>> {
    /// Starts an MCAP file at `path`, written atomically: it replaces an
    /// existing file only when [`McapWriter::finish_file`] completes, and a
    /// writer dropped before that leaves the earlier file as it was.
    ///
    /// # Errors
    ///
    /// [`CoreError::Io`] when the file cannot be created; [`CoreError::McapWrite`] when the
    /// MCAP header cannot be written.
    pub fn create(path: &Path, compression: McapCompression) -> Result<Self> {
        let file = AtomicFile::create(path)?;
        let mut writer =
            Self::new(BufWriter::new(file), compression).map_err(|e| e.with_path(path))?;
        writer.path = Some(path.to_path_buf());
        Ok(writer)
    }

    /// Finishes the file and renames it into place.
    ///
    /// # Errors
    ///
    /// As [`McapWriter::finish`], and [`CoreError::Io`] when the file cannot be renamed.
    pub fn finish_file(self) -> Result<()> {
        commit_buffered(self.finish()?)
    }
}

impl<W: Write + Seek> McapWriter<W> {
    /// Starts an MCAP stream on `writer`, chunks compressed with `compression`.
    ///
    /// # Errors
    ///
    /// [`CoreError::McapWrite`] when the MCAP header cannot be written.
    pub fn new(writer: W, compression: McapCompression) -> Result<Self> {
        let inner = WriteOptions::new()
            .compression(compression.to_mcap())
            .compression_level(compression.level())
            .create(writer)
            .map_err(|e| write_error(&e, None))?;
        Ok(Self {
            inner: Some(inner),
            sequences: Vec::new(),
            path: None,
        })
    }

    /// Adds a channel on `topic` whose messages are JSON, described by the JSON schema
    /// `schema_json` named `schema_name`.
    ///
    /// # Errors
    ///
    /// [`CoreError::McapWrite`] when the schema or channel record cannot be written (or the
    /// writer already failed).
    pub fn add_json_channel(
        &mut self,
        topic: &str,
        schema_name: &str,
        schema_json: &serde_json::Value,
    ) -> Result<ChannelId> {
        self.add_channel_with_schema_text(topic, schema_name, &schema_json.to_string())
    }

    /// Adds a channel on `topic` whose messages are JSON, described by the JSON schema
    /// `schema_text` (written as given, byte for byte) named `schema_name`. Channels with the
    /// same schema share one schema record.
    ///
    /// # Errors
    ///
    /// [`CoreError::McapWrite`] when the schema or channel record cannot be written (or the
    /// writer already failed).
    pub fn add_channel_with_schema_text(
        &mut self,
        topic: &str,
        schema_name: &str,
        schema_text: &str,
    ) -> Result<ChannelId> {
        let path = self.path.clone();
        let writer = self.writer()?;
        let schema_id = writer
            .add_schema(schema_name, SCHEMA_ENCODING, schema_text.as_bytes())
            .map_err(|e| write_error(&e, path.as_deref()))?;
        let id = writer
            .add_channel(schema_id, topic, MESSAGE_ENCODING, &Default::default())
            .map_err(|e| write_error(&e, path.as_deref()))?;
        let slot = usize::from(id);
        if self.sequences.len() <= slot {
            self.sequences.resize(slot + 1, 0);
        }
        Ok(ChannelId(id))
    }

    /// Writes one JSON message on `channel` at `log_time_s` seconds (stored as whole
    /// nanoseconds, also as the publish time).
    ///
    /// `serde_json` objects sort their keys; Foxglove does not care about field order.
    ///
    /// # Errors
    ///
    /// [`CoreError::McapTime`] when `log_time_s` is negative, not finite or beyond
    /// `u64::MAX` ns; [`CoreError::McapWrite`] when writing fails or `channel` belongs to
    /// another writer.
    pub fn write_json(
        &mut self,
        channel: ChannelId,
        log_time_s: f64,
        message: &serde_json::Value,
    ) -> Result<()> {
        let log_time_ns = seconds_to_ns(log_time_s).map_err(|reason| CoreError::McapTime {
            at: Location::Message(
                self.sequences
                    .get(usize::from(channel.0))
                    .map_or(0, |&s| s as usize),
            ),
            t: log_time_s,
            reason,
            path: self.path.clone(),
        })?;
        self.write_bytes(channel, log_time_ns, message.to_string().as_bytes())
    }

    /// Finishes the file (summary, footer), flushes it and hands back the underlying writer.
    ///
    /// # Errors
    ///
    /// [`CoreError::McapWrite`] or [`CoreError::Io`] when the end of the file cannot be
    /// written or flushed.
    pub fn finish(mut self) -> Result<W> {
        let path = self.path.clone();
        let mut inner = self.writer_take()?;
        inner
            .finish()
            .map_err(|e| write_error(&e, path.as_deref()))?;
        let mut w = inner.into_inner();
        w.flush().map_err(|e| CoreError::io(e, path.as_deref()))?;
        Ok(w)
    }

    pub(super) fn write_bytes(
        &mut self,
        channel: ChannelId,
        log_time_ns: u64,
        data: &[u8],
    ) -> Result<()> {
        let path = self.path.clone();
        let sequence = match self.sequences.get_mut(usize::from(channel.0)) {
            Some(s) => {
                let current = *s;
                *s = s.wrapping_add(1);
                current
            }
            None => 0,
        };
        let header = MessageHeader {
            channel_id: channel.0,
            sequence,
            log_time: log_time_ns,
            publish_time: log_time_ns,
        };
        self.writer()?
            .write_to_known_channel(&header, data)
            .map_err(|e| write_error(&e, path.as_deref()))
    }

    fn writer(&mut self) -> Result<&mut Writer<W>> {
        let path = self.path.clone();
        self.inner.as_mut().ok_or_else(|| CoreError::McapWrite {
            reason: "the writer is already finished".to_owned(),
            path,
        })
    }

    fn writer_take(&mut self) -> Result<Writer<W>> {
        self.inner.take().ok_or_else(|| CoreError::McapWrite {
            reason: "the writer is already finished".to_owned(),
            path: self.path.clone(),
        })
    }
}

impl<W: Write + Seek> Drop for McapWriter<W> {
    fn drop(&mut self) {
        if let Some(mut inner) = self.inner.take() {
            // Errors cannot be reported from drop; `finish` is the way to see them.
            if inner.finish().is_ok() {
                let _ = inner.into_inner().flush();
            }
        }
    }
}

/// Converts seconds to whole nanoseconds for a `log_time`, or says why it cannot.
pub(super) fn seconds_to_ns(t: f64) -> std::result::Result<u64, &'static str> {
    let ns = (t * NS_PER_S).round();
    if !ns.is_finite() {
        Err("time must be finite")
    } else if ns < 0.0 {
        Err("log time cannot be negative")
    } else if ns >= u64::MAX as f64 {
        Err("time exceeds u64::MAX nanoseconds")
    } else {
        // In range and integral, so the cast is exact.
        Ok(ns as u64)
    }
}

fn write_error(error: &McapError, path: Option<&Path>) -> CoreError {
    CoreError::McapWrite {
        reason: mcap_error_text(error),
        path: path.map(Path::to_path_buf),
    }
}

#[cfg(test)]
mod tests {
    use std::io::Cursor;

    use super::super::{DEFAULT_SIGNAL_TOPIC, read_signals, read_signals_path};
    use super::*;

    #[test]
    fn writer_writes_several_channels_readable_per_topic() {
        let mut w = McapWriter::new(Cursor::new(Vec::new()), McapCompression::Lz4).unwrap();
        let schema = number_object_schema("X", &["x"]);
        let measured = w.add_json_channel("/measured", "X", &schema).unwrap();
        let model = w.add_json_channel("/model", "X", &schema).unwrap();
        assert_ne!(measured, model);
        for k in 0..10u32 {
            let t = f64::from(k) * 0.25;
            w.write_json(measured, t, &serde_json::json!({ "x": f64::from(k) }))
                .unwrap();
            w.write_json(model, t, &serde_json::json!({ "x": -f64::from(k) }))
                .unwrap();
        }
        let bytes = w.finish().unwrap().into_inner();
        let a = read_signals(&bytes, "/measured").unwrap();
        let b = read_signals(&bytes, "/model").unwrap();
        assert_eq!(a.t(), b.t());
        assert_eq!(a.duration(), 2.25);
        assert_eq!(b.values("x").unwrap()[9], -9.0);
    }

    #[test]
    fn writer_rejects_negative_or_nan_log_time() {
        let mut w = McapWriter::new(Cursor::new(Vec::new()), McapCompression::None).unwrap();
        let c = w
            .add_json_channel("/x", "X", &number_object_schema("X", &["x"]))
            .unwrap();
        for t in [-1.0, f64::NAN, f64::INFINITY, 1e20] {
            let e = w
                .write_json(c, t, &serde_json::json!({ "x": 1 }))
                .unwrap_err();
            assert!(matches!(e, CoreError::McapTime { .. }), "{t}");
        }
    }

    #[test]
    fn dropped_writer_still_finishes_its_stream() {
        let mut bytes = Vec::new();
        {
            let mut w =
                McapWriter::new(std::io::Cursor::new(&mut bytes), McapCompression::Zstd).unwrap();
            let c = w
                .add_json_channel("/signals", "X", &number_object_schema("X", &["x"]))
                .unwrap();
            w.write_json(c, 0.0, &serde_json::json!({ "x": 1.0 }))
                .unwrap();
            w.write_json(c, 0.5, &serde_json::json!({ "x": 2.0 }))
                .unwrap();
            // Dropped without finish().
        }
        let rec = super::super::read_signals(&bytes, DEFAULT_SIGNAL_TOPIC).unwrap();
        assert_eq!(rec.values("x").unwrap(), &[1.0, 2.0]);
    }

    #[test]
    fn a_file_dropped_before_finish_file_leaves_the_earlier_file() {
        let dir = std::env::temp_dir().join(format!("modelgap-core-mcap-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("dropped.mcap");
        std::fs::write(&path, b"an earlier file").unwrap();
        {
            let mut w = McapWriter::create(&path, McapCompression::Zstd).unwrap();
            let c = w
                .add_json_channel("/signals", "X", &number_object_schema("X", &["x"]))
                .unwrap();
            w.write_json(c, 0.0, &serde_json::json!({ "x": 1.0 }))
                .unwrap();
            // Dropped without finish_file(): an interrupted run.
        }
        assert_eq!(std::fs::read(&path).unwrap(), b"an earlier file");
        let mut w = McapWriter::create(&path, McapCompression::Zstd).unwrap();
        let c = w
            .add_json_channel("/signals", "X", &number_object_schema("X", &["x"]))
            .unwrap();
        w.write_json(c, 0.0, &serde_json::json!({ "x": 3.0 }))
            .unwrap();
        w.finish_file().unwrap();
        let rec = read_signals_path(&path, DEFAULT_SIGNAL_TOPIC).unwrap();
        assert_eq!(rec.values("x").unwrap(), &[3.0]);
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            1,
            "no temporary file left"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

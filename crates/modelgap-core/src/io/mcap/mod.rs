//! Signals as MCAP: JSON messages on one topic, the form Foxglove's Plot panel plots as is.
//!
//! Each message is a flat JSON object of numbers, one field per signal (channel message
//! encoding `json`, schema encoding `jsonschema`); a sample's time is the message's
//! `log_time` in nanoseconds relative to the first message. This module is the only place
//! where nanoseconds become seconds.
//!
//! Reading sorts messages by `log_time` (files need not be in time order), checks that times
//! strictly increase, and takes the signal names, in order, from the first message's fields.
//! Every later message must have the same fields. Chunk and data-section CRCs are checked and
//! chunk framing is verified before chunk contents are parsed, so a corrupt or truncated
//! file is a [`CoreError::McapCorrupt`], never a panic.
//!
//! [`write_signals`] writes the first sample at `log_time` 0 and each later one at
//! `round((t - t_first) * 1e9)` ns: the absolute start of the recording is not kept (the
//! format's time is relative to the first message), and times round to whole nanoseconds.
//! Reading back therefore gives time starting at 0; a recording whose times are whole
//! nanoseconds from a start at 0 reads back bit for bit.
//!
//! [`McapWriter`] writes any number of JSON channels (measured, model, residual, …) to one
//! file.

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::io::{BufWriter, Seek, Write};
use std::path::Path;

use ::mcap::McapError;
use ::mcap::io::MessageReader;
use ::mcap::sans_io::LinearReaderOptions;
use serde::de::{Deserialize, Deserializer, MapAccess, Visitor};

use crate::error::{CoreError, Location, Result};
use crate::recording::{Recording, Signal};

mod check;
mod topic;
mod writer;

pub use check::{McapCheckError, TopicCheck, check_messages};
pub use topic::{TopicMessage, read_topic_messages};
use writer::seconds_to_ns;
pub use writer::{ChannelId, McapCompression, McapWriter, number_object_schema};

/// The topic signals are read from and written to unless told otherwise.
pub const DEFAULT_SIGNAL_TOPIC: &str = "/signals";

/// The schema encoding of the channels this module writes.
pub const SCHEMA_ENCODING: &str = "jsonschema";

/// The message encoding of the channels this module reads and writes.
pub const MESSAGE_ENCODING: &str = "json";

/// The schema name [`write_signals`] gives its channel.
pub const SIGNALS_SCHEMA_NAME: &str = "modelgap.Signals";

/// Nanoseconds per second.
const NS_PER_S: f64 = 1e9;

/// The longest JSON text quoted in an error message (characters).
const MAX_QUOTED_CHARS: usize = 40;

/// The largest record or decompressed chunk accepted, as a multiple of the file size: a
/// damaged length field then fails fast instead of reserving gigabytes. JSON signal data
/// compresses far less than 1024:1.
const MAX_EXPANSION: usize = 1024;

/// The smallest record length limit (bytes), so small files may still hold large chunks.
const MIN_RECORD_LENGTH_LIMIT: usize = 64 << 20;

fn record_length_limit(file_len: usize) -> usize {
    file_len
        .saturating_mul(MAX_EXPANSION)
        .max(MIN_RECORD_LENGTH_LIMIT)
}

/// Reads a recording from the JSON messages on `topic` of MCAP data in memory.
///
/// Messages on other topics are ignored. Errors name the message by its index among the
/// topic's messages in file order, counted from 0.
///
/// # Errors
///
/// [`CoreError::McapCorrupt`] for truncated or corrupt data; [`CoreError::TopicNotFound`]
/// (listing the topics that have messages) when `topic` has none; [`CoreError::McapEncoding`]
/// when its messages are not JSON; [`CoreError::McapJson`], [`CoreError::McapBadField`],
/// [`CoreError::McapMissingField`], [`CoreError::McapUnexpectedField`] or
/// [`CoreError::DuplicateSignal`] for a bad message; [`CoreError::NonIncreasingTime`] when
/// two messages share a `log_time`; [`CoreError::InvalidSignalName`] for a field named `t`
/// or an empty one.
///
/// # Example
///
/// ```
/// # use std::io::Cursor;
/// # use modelgap_core::{Recording, Signal};
/// # use modelgap_core::io::mcap::{self, McapCompression, DEFAULT_SIGNAL_TOPIC};
/// let rec = Recording::new(vec![0.0, 0.5], vec![Signal::new("i", vec![1.0, 2.0])])?;
/// let mut file = Cursor::new(Vec::new());
/// mcap::write_signals(&rec, &mut file, DEFAULT_SIGNAL_TOPIC, McapCompression::Zstd)?;
/// let back = mcap::read_signals(file.get_ref(), DEFAULT_SIGNAL_TOPIC)?;
/// assert_eq!(back, rec);
/// # Ok::<(), modelgap_core::CoreError>(())
/// ```
pub fn read_signals(bytes: &[u8], topic: &str) -> Result<Recording> {
    // Chunk CRCs are checked before any record inside a chunk is parsed: the mcap crate's
    // chunk parser trusts the lengths inside a chunk, and a damaged length there could make
    // it fail in ways other than an error.
    let options = LinearReaderOptions::default()
        .with_prevalidate_chunk_crcs(true)
        .with_validate_data_section_crc(true)
        .with_record_length_limit(record_length_limit(bytes.len()));
    check_chunk_framing(bytes)?;
    let stream = MessageReader::new_with_options(bytes, options);
    let mut other_topics = BTreeSet::new();
    let mut names: Option<Vec<String>> = None;
    let mut log_times: Vec<u64> = Vec::new();
    let mut columns: Vec<Vec<f64>> = Vec::new();

    for message in stream {
        let message = message.map_err(corrupt)?;
        if message.channel.topic != topic {
            other_topics.insert(message.channel.topic.clone());
            continue;
        }
        if message.channel.message_encoding != MESSAGE_ENCODING {
            return Err(CoreError::McapEncoding {
                topic: topic.to_owned(),
                encoding: message.channel.message_encoding.clone(),
                path: None,
            });
        }
        let index = log_times.len();
        let fields = parse_message(&message.data, index)?;
        match &names {
            None => {
                let first: Vec<String> = fields.iter().map(|(name, _)| name.clone()).collect();
                for name in &first {
                    crate::recording::check_name(name).map_err(|e| match e {
                        CoreError::InvalidSignalName { name, reason, .. } => {
                            CoreError::InvalidSignalName {
                                name,
                                reason,
                                at: Some(Location::Message(index)),
                                path: None,
                            }
                        }
                        other => other,
                    })?;
                }
                columns = fields.iter().map(|&(_, v)| vec![v]).collect();
                names = Some(first);
            }
            Some(names) => {
                for (column, name) in columns.iter_mut().zip(names) {
                    let value = fields
                        .iter()
                        .find(|(field, _)| field == name)
                        .map(|&(_, v)| v)
                        .ok_or_else(|| CoreError::McapMissingField {
                            index,
                            field: name.clone(),
                            path: None,
                        })?;
                    column.push(value);
                }
                if fields.len() != names.len() {
                    // Every name was found and fields are unique, so there is an extra field.
                    if let Some((field, _)) = fields.iter().find(|(f, _)| !names.contains(f)) {
                        return Err(CoreError::McapUnexpectedField {
                            index,
                            field: field.clone(),
                            path: None,
                        });
                    }
                }
            }
        }
        log_times.push(message.log_time);
    }

    let Some(names) = names else {
        return Err(CoreError::TopicNotFound {
            topic: topic.to_owned(),
            available: other_topics.into_iter().collect(),
            path: None,
        });
    };

    // MCAP readers yield messages in file order; sort by log_time (stable, so the error for a
    // repeated time names the later message in file order).
    let mut order: Vec<usize> = (0..log_times.len()).collect();
    order.sort_by_key(|&i| log_times[i]);
    let log_start = log_times[order[0]];
    let seconds = |log_time: u64| (log_time - log_start) as f64 / NS_PER_S;
    for pair in order.windows(2) {
        let (prev, next) = (pair[0], pair[1]);
        if log_times[next] == log_times[prev] {
            return Err(CoreError::NonIncreasingTime {
                at: Location::Message(next),
                t_prev: seconds(log_times[prev]),
                t: seconds(log_times[next]),
                path: None,
            });
        }
    }
    let t = order.iter().map(|&i| seconds(log_times[i])).collect();
    let signals = names
        .into_iter()
        .zip(columns)
        .map(|(name, values)| Signal::new(name, order.iter().map(|&i| values[i]).collect()))
        .collect();
    Recording::new(t, signals)
}

/// Reads a recording from the JSON messages on `topic` of an MCAP file; like
/// [`read_signals`], with the path in every error.
///
/// # Errors
///
/// As [`read_signals`], plus [`CoreError::Io`] when the file cannot be read.
pub fn read_signals_path(path: &Path, topic: &str) -> Result<Recording> {
    let bytes = std::fs::read(path).map_err(|e| CoreError::io(e, Some(path)))?;
    read_signals(&bytes, topic).map_err(|e| e.with_path(path))
}

/// Writes a recording as JSON messages on `topic`, one message per sample, with a JSON
/// schema listing the signals as number properties.
///
/// Time is shifted to start at `log_time` 0 and rounded to whole nanoseconds (see the
/// module docs). The file is always finished (summary and footer written), also on error
/// paths that leave a usable writer. Returns the writer, flushed.
///
/// # Errors
///
/// [`CoreError::McapTime`] when two samples are closer than 1 ns or the recording spans more
/// than `u64::MAX` ns; [`CoreError::McapWrite`] or [`CoreError::Io`] when writing fails.
pub fn write_signals<W: Write + Seek>(
    recording: &Recording,
    writer: W,
    topic: &str,
    compression: McapCompression,
) -> Result<W> {
    let log_times = log_times_ns(recording.t())?;
    let names = recording.names();
    let mut out = McapWriter::new(writer, compression)?;
    let schema = number_object_schema(SIGNALS_SCHEMA_NAME, &names);
    let channel = out.add_json_channel(topic, SIGNALS_SCHEMA_NAME, &schema)?;
    let mut text = String::new();
    for (i, &log_time_ns) in log_times.iter().enumerate() {
        // Written by hand to keep the signals' order (a serde_json map would sort the keys).
        text.clear();
        text.push('{');
        for (k, signal) in recording.signals().iter().enumerate() {
            if k > 0 {
                text.push(',');
            }
            let key = serde_json::Value::from(signal.name.as_str());
            let value = serde_json::Number::from_f64(signal.values[i])
                .map_or_else(|| serde_json::Value::Null, serde_json::Value::Number);
            // Writing into a String cannot fail.
            let _ = write!(text, "{key}:{value}");
        }
        text.push('}');
        out.write_bytes(channel, log_time_ns, text.as_bytes())?;
    }
    out.finish()
}

/// Writes a recording to an MCAP file (created or truncated); like [`write_signals`], with
/// the path in every error.
///
/// # Errors
///
/// As [`write_signals`], plus [`CoreError::Io`] when the file cannot be created.
pub fn write_signals_path(
    recording: &Recording,
    path: &Path,
    topic: &str,
    compression: McapCompression,
) -> Result<()> {
    let file = crate::io::atomic::AtomicFile::create(path)?;
    let w = write_signals(recording, BufWriter::new(file), topic, compression)
        .map_err(|e| e.with_path(path))?;
    crate::io::atomic::commit_buffered(w)
}

/// The log times (ns) of a recording's samples, the first at 0.
fn log_times_ns(t: &[f64]) -> Result<Vec<u64>> {
    let t0 = t.first().copied().unwrap_or(0.0);
    let mut out: Vec<u64> = Vec::with_capacity(t.len());
    for (i, &ti) in t.iter().enumerate() {
        let ns = seconds_to_ns(ti - t0).map_err(|reason| CoreError::McapTime {
            at: Location::Sample(i),
            t: ti,
            reason,
            path: None,
        })?;
        if out.last().is_some_and(|&prev| ns <= prev) {
            return Err(CoreError::McapTime {
                at: Location::Sample(i),
                t: ti,
                reason: "it is less than 1 ns after the previous sample (mcap's time resolution)",
                path: None,
            });
        }
        out.push(ns);
    }
    Ok(out)
}

/// Checks that the records inside every uncompressed chunk fit the chunk exactly.
///
/// The mcap crate (0.26) trusts those lengths and overflows on a damaged one (a panic in
/// debug builds) when the chunk carries no CRC to catch the damage first; this pass over
/// the file's top-level records, which does not parse chunk contents, turns that into an
/// error.
fn check_chunk_framing(bytes: &[u8]) -> Result<()> {
    /// An opcode (1 byte) and a record length (u64, little endian).
    const RECORD_PREFIX: usize = 9;
    for record in ::mcap::read::LinearReader::new(bytes).map_err(corrupt)? {
        let record = record.map_err(corrupt)?;
        let ::mcap::records::Record::Chunk { header, data } = record else {
            continue;
        };
        if !header.compression.is_empty() {
            continue;
        }
        let mut rest: &[u8] = &data;
        while !rest.is_empty() {
            let len = rest
                .get(1..RECORD_PREFIX)
                .and_then(|b| <[u8; 8]>::try_from(b).ok())
                .map(u64::from_le_bytes)
                .and_then(|len| usize::try_from(len).ok())
                .and_then(|len| len.checked_add(RECORD_PREFIX))
                .filter(|&total| total <= rest.len());
            let Some(total) = len else {
                return Err(CoreError::McapCorrupt {
                    reason: "a record overruns its chunk".to_owned(),
                    path: None,
                });
            };
            rest = &rest[total..];
        }
    }
    Ok(())
}

/// Parses a message as a flat JSON object, keeping field order, with every value a number.
fn parse_message(data: &[u8], index: usize) -> Result<Vec<(String, f64)>> {
    let object: OrderedObject = serde_json::from_slice(data).map_err(|e| CoreError::McapJson {
        index,
        reason: e.to_string(),
        path: None,
    })?;
    let mut fields: Vec<(String, f64)> = Vec::with_capacity(object.0.len());
    for (name, value) in object.0 {
        if fields.iter().any(|(n, _)| *n == name) {
            return Err(CoreError::DuplicateSignal {
                name,
                at: Some(Location::Message(index)),
                path: None,
            });
        }
        match value.as_f64() {
            Some(v) if value.is_number() && v.is_finite() => fields.push((name, v)),
            _ => {
                return Err(CoreError::McapBadField {
                    index,
                    field: name,
                    found: shorten(&value.to_string()),
                    path: None,
                });
            }
        }
    }
    Ok(fields)
}

/// A JSON object's entries in document order (serde_json's map would sort them).
struct OrderedObject(Vec<(String, serde_json::Value)>);

impl<'de> Deserialize<'de> for OrderedObject {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        struct ObjectVisitor;

        impl<'de> Visitor<'de> for ObjectVisitor {
            type Value = OrderedObject;

            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a json object")
            }

            fn visit_map<A: MapAccess<'de>>(
                self,
                mut map: A,
            ) -> std::result::Result<Self::Value, A::Error> {
                let mut entries = Vec::with_capacity(map.size_hint().unwrap_or(0));
                while let Some(entry) = map.next_entry::<String, serde_json::Value>()? {
                    entries.push(entry);
                }
                Ok(OrderedObject(entries))
            }
        }

        deserializer.deserialize_map(ObjectVisitor)
    }
}

/// Shortens a text for an error message.
fn shorten(text: &str) -> String {
    if text.chars().count() <= MAX_QUOTED_CHARS {
        text.to_owned()
    } else {
        let mut short: String = text.chars().take(MAX_QUOTED_CHARS).collect();
        short.push('…');
        short
    }
}

/// The text of an mcap error with its causes (the mcap crate keeps I/O details in `source`).
fn mcap_error_text(error: &McapError) -> String {
    let mut text = error.to_string();
    let mut source = std::error::Error::source(error);
    while let Some(cause) = source {
        let _ = write!(text, ": {cause}");
        source = cause.source();
    }
    text
}

fn corrupt(error: McapError) -> CoreError {
    CoreError::McapCorrupt {
        reason: mcap_error_text(&error),
        path: None,
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;
    use std::io::Cursor;

    use ::mcap::records::MessageHeader;
    use ::mcap::{WriteOptions, Writer};

    use super::*;

    /// Times that are whole nanoseconds from 0, so the round trip is exact.
    fn recording(n: u32) -> Recording {
        let t: Vec<f64> = (0..n).map(|k| f64::from(k) / 1000.0).collect();
        let z: Vec<f64> = (0..n).map(|k| (f64::from(k) * 0.37).sin() / 3.0).collect();
        let a: Vec<f64> = (0..n).map(|k| 1e-12 * f64::from(k) - 7.0).collect();
        Recording::new(t, vec![Signal::new("z", z), Signal::new("a", a)]).unwrap()
    }

    fn written(rec: &Recording, compression: McapCompression) -> Vec<u8> {
        let mut file = Cursor::new(Vec::new());
        write_signals(rec, &mut file, DEFAULT_SIGNAL_TOPIC, compression).unwrap();
        file.into_inner()
    }

    fn bits(rec: &Recording) -> Vec<u64> {
        rec.t()
            .iter()
            .chain(rec.signals().iter().flat_map(|s| s.values.iter()))
            .map(|v| v.to_bits())
            .collect()
    }

    /// Writes raw JSON messages with the given log times on one or more topics.
    fn raw_file(messages: &[(&str, u64, &str)]) -> Vec<u8> {
        let mut w = Writer::new(Cursor::new(Vec::new())).unwrap();
        let mut channels = BTreeMap::new();
        for (topic, log_time, data) in messages {
            let id = *channels.entry(*topic).or_insert_with(|| {
                w.add_channel(0, topic, MESSAGE_ENCODING, &BTreeMap::new())
                    .unwrap()
            });
            let header = MessageHeader {
                channel_id: id,
                sequence: 0,
                log_time: *log_time,
                publish_time: *log_time,
            };
            w.write_to_known_channel(&header, data.as_bytes()).unwrap();
        }
        w.finish().unwrap();
        w.into_inner().into_inner()
    }

    #[test]
    fn write_then_read_is_identical_for_every_compression() {
        let rec = recording(500);
        for compression in [
            McapCompression::None,
            McapCompression::Zstd,
            McapCompression::Lz4,
        ] {
            let bytes = written(&rec, compression);
            let back = read_signals(&bytes, DEFAULT_SIGNAL_TOPIC).unwrap();
            assert_eq!(back.names(), vec!["z", "a"], "{compression:?}");
            assert_eq!(bits(&back), bits(&rec), "{compression:?}");
        }
    }

    #[test]
    fn compression_makes_the_file_smaller() {
        let rec = recording(2000);
        let plain = written(&rec, McapCompression::None).len();
        assert!(written(&rec, McapCompression::Zstd).len() < plain);
        assert!(written(&rec, McapCompression::Lz4).len() < plain);
    }

    #[test]
    fn written_file_has_json_schema_listing_the_signals() {
        let bytes = written(&recording(3), McapCompression::Zstd);
        let summary = ::mcap::Summary::read(&bytes).unwrap().unwrap();
        let channel = summary.channels.values().next().unwrap();
        assert_eq!(channel.topic, DEFAULT_SIGNAL_TOPIC);
        assert_eq!(channel.message_encoding, "json");
        let schema = channel.schema.as_ref().unwrap();
        assert_eq!(schema.encoding, "jsonschema");
        let json: serde_json::Value = serde_json::from_slice(&schema.data).unwrap();
        assert_eq!(json["type"], "object");
        assert_eq!(json["properties"]["z"]["type"], "number");
        assert_eq!(json["properties"]["a"]["type"], "number");
    }

    #[test]
    fn recording_starting_late_reads_back_from_zero() {
        let rec = Recording::new(
            vec![5.0, 5.5, 6.0],
            vec![Signal::new("x", vec![1.0, 2.0, 3.0])],
        )
        .unwrap();
        let bytes = written(&rec, McapCompression::None);
        let back = read_signals(&bytes, DEFAULT_SIGNAL_TOPIC).unwrap();
        assert_eq!(back.t(), &[0.0, 0.5, 1.0]);
        assert_eq!(back.values("x").unwrap(), rec.values("x").unwrap());
    }

    #[test]
    fn samples_closer_than_a_nanosecond_cannot_be_written() {
        let rec = Recording::new(vec![0.0, 1e-10], vec![]).unwrap();
        let e = write_signals(
            &rec,
            Cursor::new(Vec::new()),
            DEFAULT_SIGNAL_TOPIC,
            McapCompression::None,
        )
        .unwrap_err();
        assert!(matches!(
            e,
            CoreError::McapTime {
                at: Location::Sample(1),
                ..
            }
        ));
    }

    #[test]
    fn truncated_file_is_a_typed_error() {
        let bytes = written(&recording(300), McapCompression::Zstd);
        for cut in [bytes.len() / 2, bytes.len() - 1, 8, 3, 0] {
            let e = read_signals(&bytes[..cut], DEFAULT_SIGNAL_TOPIC).unwrap_err();
            assert!(matches!(e, CoreError::McapCorrupt { .. }), "cut {cut}: {e}");
        }
    }

    #[test]
    fn flipped_bytes_never_panic_and_flips_in_chunk_data_are_errors() {
        for compression in [
            McapCompression::None,
            McapCompression::Zstd,
            McapCompression::Lz4,
        ] {
            let rec = recording(40);
            let bytes = written(&rec, compression);
            let mut failures = 0;
            for pos in 0..bytes.len() {
                let mut damaged = bytes.clone();
                damaged[pos] ^= 0xff;
                match read_signals(&damaged, DEFAULT_SIGNAL_TOPIC) {
                    Err(_) => failures += 1,
                    // A flip in a field that reading does not check (the summary, the header's
                    // library name) may leave the data intact, but never changes it silently.
                    Ok(back) => assert_eq!(back, rec, "{compression:?} flip at {pos}"),
                }
            }
            // The messages sit in one CRC-checked chunk that takes most of the file.
            assert!(
                failures > bytes.len() / 2,
                "{compression:?}: {failures}/{}",
                bytes.len()
            );
        }
    }

    #[test]
    fn damaged_files_without_crcs_never_panic() {
        // Without chunk CRCs nothing catches a damaged length inside a chunk before the mcap
        // crate parses it; `check_chunk_framing` must.
        for compression in [
            None,
            Some(::mcap::Compression::Zstd),
            Some(::mcap::Compression::Lz4),
        ] {
            let mut w = WriteOptions::new()
                .compression(compression)
                .calculate_chunk_crcs(false)
                .calculate_data_section_crc(false)
                .create(Cursor::new(Vec::new()))
                .unwrap();
            let id = w
                .add_channel(0, "/signals", MESSAGE_ENCODING, &BTreeMap::new())
                .unwrap();
            for k in 0..20u64 {
                let header = MessageHeader {
                    channel_id: id,
                    sequence: 0,
                    log_time: k,
                    publish_time: k,
                };
                w.write_to_known_channel(&header, format!(r#"{{"x": {k}}}"#).as_bytes())
                    .unwrap();
            }
            w.finish().unwrap();
            let bytes = w.into_inner().into_inner();
            let mut overruns = 0;
            for pos in 0..bytes.len() {
                let mut damaged = bytes.clone();
                damaged[pos] ^= 0xff;
                if let Err(CoreError::McapCorrupt { reason, .. }) =
                    read_signals(&damaged, DEFAULT_SIGNAL_TOPIC)
                {
                    overruns += usize::from(reason.contains("overruns"));
                }
            }
            if compression.is_none() {
                assert!(overruns > 0, "no damaged record length was caught");
            }
        }
    }

    #[test]
    fn garbage_is_a_typed_error() {
        let e = read_signals(b"not an mcap file at all", DEFAULT_SIGNAL_TOPIC).unwrap_err();
        assert!(matches!(e, CoreError::McapCorrupt { .. }));
    }

    #[test]
    fn messages_out_of_time_order_are_sorted() {
        let bytes = raw_file(&[
            ("/signals", 2_000_000_000, r#"{"x": 3}"#),
            ("/signals", 1_000_000_000, r#"{"x": 1}"#),
            ("/signals", 1_500_000_000, r#"{"x": 2}"#),
        ]);
        let rec = read_signals(&bytes, "/signals").unwrap();
        assert_eq!(rec.t(), &[0.0, 0.5, 1.0]);
        assert_eq!(rec.values("x").unwrap(), &[1.0, 2.0, 3.0]);
    }

    #[test]
    fn duplicate_log_time_names_the_message() {
        let bytes = raw_file(&[
            ("/signals", 10, r#"{"x": 1}"#),
            ("/signals", 20, r#"{"x": 2}"#),
            ("/signals", 20, r#"{"x": 3}"#),
        ]);
        let e = read_signals(&bytes, "/signals").unwrap_err();
        assert!(matches!(
            e,
            CoreError::NonIncreasingTime {
                at: Location::Message(2),
                ..
            }
        ));
    }

    #[test]
    fn other_topics_are_ignored_and_listed_when_topic_is_missing() {
        let bytes = raw_file(&[
            ("/model", 1, r#"{"x": 9}"#),
            ("/signals", 1, r#"{"x": 1}"#),
            ("/signals", 2, r#"{"x": 2}"#),
            ("/markers", 2, r#"{"ids": []}"#),
        ]);
        let rec = read_signals(&bytes, "/signals").unwrap();
        assert_eq!(rec.values("x").unwrap(), &[1.0, 2.0]);
        let e = read_signals(&bytes, "/nope").unwrap_err();
        assert!(matches!(
            e,
            CoreError::TopicNotFound { ref available, .. } if available == &["/markers", "/model", "/signals"]
        ));
    }

    #[test]
    fn bad_fields_name_message_index_and_field() {
        type Check = fn(&CoreError) -> bool;
        let cases: [(&str, Check); 6] = [
            (
                r#"{"x": null}"#,
                |e| matches!(e, CoreError::McapBadField { index: 1, field, .. } if field == "x"),
            ),
            (r#"{"x": "1.0"}"#, |e| {
                matches!(e, CoreError::McapBadField { index: 1, .. })
            }),
            (
                r#"{"y": 1}"#,
                |e| matches!(e, CoreError::McapMissingField { index: 1, field, .. } if field == "x"),
            ),
            (
                r#"{"x": 1, "y": 2}"#,
                |e| matches!(e, CoreError::McapUnexpectedField { index: 1, field, .. } if field == "y"),
            ),
            (r#"{"x": 1, "x": 2}"#, |e| {
                matches!(
                    e,
                    CoreError::DuplicateSignal {
                        at: Some(Location::Message(1)),
                        ..
                    }
                )
            }),
            (r"[1, 2]", |e| {
                matches!(e, CoreError::McapJson { index: 1, .. })
            }),
        ];
        for (second, check) in cases {
            let bytes = raw_file(&[("/s", 1, r#"{"x": 0}"#), ("/s", 2, second)]);
            let e = read_signals(&bytes, "/s").unwrap_err();
            assert!(check(&e), "{second}: {e}");
        }
    }

    #[test]
    fn field_named_t_is_rejected() {
        let bytes = raw_file(&[("/s", 1, r#"{"t": 0, "x": 1}"#)]);
        let e = read_signals(&bytes, "/s").unwrap_err();
        assert!(matches!(
            e,
            CoreError::InvalidSignalName {
                at: Some(Location::Message(0)),
                ..
            }
        ));
    }

    #[test]
    fn non_json_encoding_is_rejected() {
        let mut w = Writer::new(Cursor::new(Vec::new())).unwrap();
        let id = w.add_channel(0, "/s", "cdr", &BTreeMap::new()).unwrap();
        let header = MessageHeader {
            channel_id: id,
            sequence: 0,
            log_time: 0,
            publish_time: 0,
        };
        w.write_to_known_channel(&header, &[0, 1]).unwrap();
        w.finish().unwrap();
        let bytes = w.into_inner().into_inner();
        let e = read_signals(&bytes, "/s").unwrap_err();
        assert!(matches!(e, CoreError::McapEncoding { ref encoding, .. } if encoding == "cdr"));
    }

    #[test]
    fn path_functions_round_trip_and_put_the_path_in_errors() {
        let dir =
            std::env::temp_dir().join(format!("modelgap-core-mcap-path-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("rec.mcap");
        let rec = recording(20);
        write_signals_path(&rec, &path, "/run", McapCompression::Zstd).unwrap();
        assert_eq!(read_signals_path(&path, "/run").unwrap(), rec);
        let e = read_signals_path(&path, "/other").unwrap_err();
        assert_eq!(e.path(), Some(path.as_path()));
        let e = read_signals_path(&dir.join("missing.mcap"), "/run").unwrap_err();
        assert!(matches!(e, CoreError::Io { .. }));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

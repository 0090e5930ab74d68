//! Every message of an MCAP file checked against its channel's JSON Schema: the test that
//! what modelgap writes is what its schemas (Foxglove's published ones among them) say.

use std::collections::BTreeMap;

use ::mcap::io::MessageReader;
use ::mcap::sans_io::LinearReaderOptions;

use super::{MESSAGE_ENCODING, SCHEMA_ENCODING, check_chunk_framing, corrupt, record_length_limit};
use crate::error::CoreError;
use crate::io::json_schema::{SchemaError, Strictness, check_message};

/// The messages of one topic that [`check_messages`] checked.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TopicCheck {
    /// The topic.
    pub topic: String,
    /// Its schema's name (`foxglove.SceneUpdate`, `modelgap.Markers`, …).
    pub schema: String,
    /// Messages checked.
    pub messages: usize,
    /// Bytes of JSON in those messages.
    pub bytes: usize,
}

/// Why [`check_messages`] refused a file.
#[derive(Debug, thiserror::Error)]
pub enum McapCheckError {
    /// The file does not read.
    #[error(transparent)]
    Read(#[from] CoreError),
    /// A channel has no schema, or one that is not JSON Schema, or messages not in JSON.
    #[error("topic {topic}: {reason}")]
    Channel {
        /// The topic.
        topic: String,
        /// What is wrong.
        reason: String,
    },
    /// A message breaks its schema (or the schema is outside the checked subset).
    #[error("topic {topic} ({schema}), message {index}: {error}")]
    Message {
        /// The topic.
        topic: String,
        /// The schema's name.
        schema: String,
        /// The message's index on its topic, in file order, from 0.
        index: usize,
        /// What is wrong.
        error: SchemaError,
    },
}

/// Checks every message of MCAP data against its channel's JSON Schema (see
/// [`json_schema`](crate::io::json_schema) for the subset understood), and says what it
/// checked per topic, in topic order.
///
/// # Errors
///
/// [`McapCheckError::Read`] for data that does not read as MCAP;
/// [`McapCheckError::Channel`] for a channel without a `jsonschema` schema, whose schema is
/// not JSON, or whose messages are not JSON; [`McapCheckError::Message`] for the first
/// message that breaks its schema.
pub fn check_messages(
    bytes: &[u8],
    strictness: Strictness,
) -> Result<Vec<TopicCheck>, McapCheckError> {
    let options = LinearReaderOptions::default()
        .with_prevalidate_chunk_crcs(true)
        .with_validate_data_section_crc(true)
        .with_record_length_limit(record_length_limit(bytes.len()));
    check_chunk_framing(bytes)?;
    let mut schemas: BTreeMap<u16, serde_json::Value> = BTreeMap::new();
    let mut checked: BTreeMap<String, TopicCheck> = BTreeMap::new();
    for message in MessageReader::new_with_options(bytes, options) {
        let message = message.map_err(corrupt)?;
        let channel = &message.channel;
        let topic = channel.topic.clone();
        let bad = |reason: String| McapCheckError::Channel {
            topic: topic.clone(),
            reason,
        };
        let Some(schema) = &channel.schema else {
            return Err(bad("the channel has no schema".to_owned()));
        };
        if schema.encoding != SCHEMA_ENCODING || channel.message_encoding != MESSAGE_ENCODING {
            return Err(bad(format!(
                "schema encoding `{}` and message encoding `{}`, not jsonschema and json",
                schema.encoding, channel.message_encoding
            )));
        }
        if let std::collections::btree_map::Entry::Vacant(slot) = schemas.entry(schema.id) {
            let parsed = serde_json::from_slice(&schema.data)
                .map_err(|e| bad(format!("its schema {} is not JSON: {e}", schema.name)))?;
            slot.insert(parsed);
        }
        let entry = checked.entry(topic.clone()).or_insert_with(|| TopicCheck {
            topic: topic.clone(),
            schema: schema.name.clone(),
            messages: 0,
            bytes: 0,
        });
        let index = entry.messages;
        let value: serde_json::Value = serde_json::from_slice(&message.data)
            .map_err(|e| bad(format!("message {index} is not JSON: {e}")))?;
        if let Some(schema_value) = schemas.get(&schema.id) {
            check_message(schema_value, &value, strictness).map_err(|error| {
                McapCheckError::Message {
                    topic: topic.clone(),
                    schema: schema.name.clone(),
                    index,
                    error,
                }
            })?;
        }
        entry.messages += 1;
        entry.bytes += message.data.len();
    }
    Ok(checked.into_values().collect())
}

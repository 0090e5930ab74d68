//! The raw JSON messages of one topic, in time order: for readers of message shapes other
//! than flat signal objects (cloth markers, for example).

use std::collections::BTreeSet;

use ::mcap::io::MessageReader;
use ::mcap::sans_io::LinearReaderOptions;

use super::{MESSAGE_ENCODING, NS_PER_S, check_chunk_framing, corrupt, record_length_limit};
use crate::error::{CoreError, Location, Result};

/// One JSON message of a topic, as read by [`read_topic_messages`].
#[derive(Clone, Debug, PartialEq)]
pub struct TopicMessage {
    /// The message's index among the topic's messages in file order, counted from 0 (the
    /// index errors should name, as [`Location::Message`]).
    pub index: usize,
    /// Time (s): the message's `log_time` relative to the topic's earliest message.
    pub t: f64,
    /// The message bytes (JSON text).
    pub data: Vec<u8>,
}

/// Reads the messages on `topic` of MCAP data in memory, sorted by `log_time`, with the same
/// checks as [`read_signals`](super::read_signals): CRCs and chunk framing, JSON message
/// encoding, strictly increasing time. The message contents are not parsed.
///
/// # Errors
///
/// [`CoreError::McapCorrupt`] for truncated or corrupt data; [`CoreError::TopicNotFound`]
/// (listing the topics that have messages) when `topic` has none; [`CoreError::McapEncoding`]
/// when its messages are not JSON; [`CoreError::NonIncreasingTime`] when two messages share a
/// `log_time`.
pub fn read_topic_messages(bytes: &[u8], topic: &str) -> Result<Vec<TopicMessage>> {
    let options = LinearReaderOptions::default()
        .with_prevalidate_chunk_crcs(true)
        .with_validate_data_section_crc(true)
        .with_record_length_limit(record_length_limit(bytes.len()));
    check_chunk_framing(bytes)?;
    let mut other_topics = BTreeSet::new();
    let mut found: Vec<(u64, Vec<u8>)> = Vec::new();
    for message in MessageReader::new_with_options(bytes, options) {
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
        found.push((message.log_time, message.data.into_owned()));
    }
    if found.is_empty() {
        return Err(CoreError::TopicNotFound {
            topic: topic.to_owned(),
            available: other_topics.into_iter().collect(),
            path: None,
        });
    }
    // Stable sort: the error for a repeated time names the later message in file order.
    let mut order: Vec<usize> = (0..found.len()).collect();
    order.sort_by_key(|&i| found[i].0);
    let log_start = found[order[0]].0;
    let seconds = |log_time: u64| (log_time - log_start) as f64 / NS_PER_S;
    for pair in order.windows(2) {
        let (prev, next) = (pair[0], pair[1]);
        if found[next].0 == found[prev].0 {
            return Err(CoreError::NonIncreasingTime {
                at: Location::Message(next),
                t_prev: seconds(found[prev].0),
                t: seconds(found[next].0),
                path: None,
            });
        }
    }
    let mut slots: Vec<Option<(u64, Vec<u8>)>> = found.into_iter().map(Some).collect();
    Ok(order
        .into_iter()
        .filter_map(|index| {
            slots[index].take().map(|(log_time, data)| TopicMessage {
                index,
                t: seconds(log_time),
                data,
            })
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use std::io::Cursor;

    use super::super::{McapCompression, McapWriter, number_object_schema};
    use super::*;

    #[test]
    fn messages_come_back_in_time_order_with_their_file_index() {
        let mut w = McapWriter::new(Cursor::new(Vec::new()), McapCompression::Zstd).unwrap();
        let c = w
            .add_json_channel("/m", "X", &number_object_schema("X", &["x"]))
            .unwrap();
        let other = w
            .add_json_channel("/o", "X", &number_object_schema("X", &["x"]))
            .unwrap();
        w.write_json(c, 2.0, &serde_json::json!({ "x": 2 }))
            .unwrap();
        w.write_json(other, 0.0, &serde_json::json!({ "x": 9 }))
            .unwrap();
        w.write_json(c, 1.5, &serde_json::json!({ "x": 1 }))
            .unwrap();
        let bytes = w.finish().unwrap().into_inner();
        let messages = read_topic_messages(&bytes, "/m").unwrap();
        assert_eq!(messages.len(), 2);
        assert_eq!((messages[0].index, messages[0].t), (1, 0.0));
        assert_eq!((messages[1].index, messages[1].t), (0, 0.5));
        assert_eq!(messages[0].data, br#"{"x":1}"#);
        let e = read_topic_messages(&bytes, "/nope").unwrap_err();
        assert!(matches!(e, CoreError::TopicNotFound { .. }));
        let e = read_topic_messages(&bytes[..bytes.len() / 2], "/m").unwrap_err();
        assert!(matches!(e, CoreError::McapCorrupt { .. }));
    }
}

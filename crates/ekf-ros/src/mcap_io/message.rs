//! What the reader hands out: topics with their types and counts, and raw messages that
//! decode into typed ROS 2 messages on request.

use super::error::MessageError;
use super::{MESSAGE_ENCODING, SCHEMA_ENCODING};
use crate::ros2::{AnyMessage, DecodeError, RosMessage};
use std::path::Path;
use std::sync::Arc;

/// One channel of a bag: a topic and the type its messages have.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChannelInfo {
    /// The bag the channel belongs to (for error messages).
    pub path: Arc<Path>,
    /// Topic name, e.g. `/scan`.
    pub topic: String,
    /// Schema name, e.g. `sensor_msgs/msg/LaserScan`; empty if the channel has no schema.
    pub type_name: String,
    /// Schema encoding, `ros2msg` in ROS 2 bags.
    pub schema_encoding: String,
    /// Message encoding, `cdr` in ROS 2 bags.
    pub message_encoding: String,
}

/// A topic of a bag with its message type and message count.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicInfo {
    /// Topic name.
    pub topic: String,
    /// Schema name, e.g. `nav_msgs/msg/Odometry`.
    pub type_name: String,
    /// Number of messages: from the summary's statistics when the file has them, otherwise
    /// counted by reading the file; in a damaged file, the messages before the damage.
    pub message_count: u64,
}

/// One message as stored: channel, times and the CDR payload.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BagMessage {
    /// The channel the message was published on.
    pub channel: Arc<ChannelInfo>,
    /// Position of the message in delivery order, from 0.
    pub index: u64,
    /// Time the message was recorded (ns).
    pub log_time: u64,
    /// Time the message was published (ns).
    pub publish_time: u64,
    /// The CDR payload, with its encapsulation header.
    pub data: Vec<u8>,
}

impl BagMessage {
    /// The topic name.
    pub fn topic(&self) -> &str {
        &self.channel.topic
    }

    /// Decodes into whichever supported type the channel's schema names.
    pub fn decode(&self) -> Result<AnyMessage, MessageError> {
        self.check_encoding()?;
        AnyMessage::decode(&self.channel.type_name, &self.data).map_err(|e| self.decode_error(e))
    }

    /// Decodes as `T`, failing with [`MessageError::WrongType`] if the topic carries another
    /// type.
    pub fn decode_as<T: RosMessage>(&self) -> Result<T, MessageError> {
        self.check_encoding()?;
        let expected = T::DEF;
        let actual = &self.channel.type_name;
        if !crate::ros2::type_name_matches(expected.name, actual) {
            return Err(MessageError::WrongType {
                path: self.channel.path.to_path_buf(),
                topic: self.channel.topic.clone(),
                index: self.index,
                expected: expected.name,
                actual: actual.clone(),
            });
        }
        T::decode(&self.data).map_err(|e| self.decode_error(e.into()))
    }

    /// Fails unless the channel is `cdr` with a `ros2msg` schema.
    fn check_encoding(&self) -> Result<(), MessageError> {
        let c = &self.channel;
        if c.message_encoding == MESSAGE_ENCODING && c.schema_encoding == SCHEMA_ENCODING {
            return Ok(());
        }
        Err(MessageError::Encoding {
            path: c.path.to_path_buf(),
            topic: c.topic.clone(),
            message_encoding: c.message_encoding.clone(),
            schema_encoding: c.schema_encoding.clone(),
        })
    }

    /// Wraps a decoder error with where the message came from.
    fn decode_error(&self, source: DecodeError) -> MessageError {
        MessageError::Decode {
            path: self.channel.path.to_path_buf(),
            topic: self.channel.topic.clone(),
            index: self.index,
            log_time: self.log_time,
            source,
        }
    }
}

//! Errors of bag reading, writing and typed decoding; each says which file, where in it
//! (byte offset or message index), which topic and what was expected.

use crate::ros2::DecodeError;
use std::path::PathBuf;
use std::sync::Arc;
use thiserror::Error;

/// Log times (ns) that bound the messages of a skipped stretch of a file: the damaged
/// chunk's own first and last message times when the file's index gives them, else the
/// end of the intact chunk before the stretch and the start of the one after it (either
/// unknown when there is none on that side).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct LostRange {
    /// The earliest log time the lost messages can have.
    pub from_ns: Option<u64>,
    /// The latest.
    pub to_ns: Option<u64>,
}

impl std::fmt::Display for LostRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = |t: u64| t as f64 * 1e-9;
        match (self.from_ns, self.to_ns) {
            (Some(a), Some(b)) => write!(
                f,
                "messages logged from {:.3} s to {:.3} s lost",
                s(a),
                s(b)
            ),
            (Some(a), None) => write!(f, "messages logged after {:.3} s lost", s(a)),
            (None, Some(b)) => write!(f, "messages logged before {:.3} s lost", s(b)),
            (None, None) => write!(f, "log times of the lost messages unknown"),
        }
    }
}

/// Why a bag could not be opened or read further.
#[derive(Debug, Error)]
pub enum ReadError {
    /// The file could not be opened or its size read.
    #[error("{path}: cannot open: {source}", path = path.display())]
    Open {
        /// The bag.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The path is not a ROS 2 bag: what it is instead, and what to do.
    #[error("{path}: not a ROS 2 bag (MCAP or sqlite3): {what}; {hint}", path = path.display())]
    NotABag {
        /// The path given.
        path: PathBuf,
        /// What it is.
        what: String,
        /// What to do with it.
        hint: String,
    },
    /// A bag directory's `metadata.yaml` cannot be used.
    #[error("{path}: {message}", path = path.display())]
    Metadata {
        /// The metadata file.
        path: PathBuf,
        /// What is wrong (for YAML errors, with line and column).
        message: String,
    },
    /// SQLite failed on a `.db3` file (it is damaged, locked, or not rosbag2's schema).
    #[error("{path}: sqlite3 bag: {source}", path = path.display())]
    Sqlite {
        /// The storage file.
        path: PathBuf,
        /// SQLite's error.
        #[source]
        source: Arc<rusqlite::Error>,
    },
    /// A row of a `.db3` file is not what rosbag2 writes.
    #[error("{path}: sqlite3 bag: {what}", path = path.display())]
    BadRow {
        /// The storage file.
        path: PathBuf,
        /// What the row has, and what was expected.
        what: String,
    },
    /// Reading the file failed.
    #[error("{path}: read error at byte {offset}: {source}", path = path.display())]
    Io {
        /// The bag.
        path: PathBuf,
        /// Where the read started.
        offset: u64,
        /// The operating system's error.
        #[source]
        source: Arc<std::io::Error>,
    },
    /// The file is truncated or corrupt; everything before `offset` was delivered.
    #[error(
        "{path}: truncated or corrupt MCAP at byte {offset} (after {messages} messages): {source}",
        path = path.display()
    )]
    Corrupt {
        /// The bag.
        path: PathBuf,
        /// Byte offset where the damage was found: the end of the data read so far, or the
        /// start of the chunk that failed.
        offset: u64,
        /// How many messages were delivered before the damage.
        messages: u64,
        /// What the MCAP parser found.
        #[source]
        source: Arc<mcap::McapError>,
    },
    /// A damaged chunk was skipped: its messages are lost, and reading goes on with the
    /// next intact chunk. The only error after which a bag's message stream continues
    /// ([`ReadError::is_skipped_damage`]).
    #[error(
        "{path}: damaged chunk at byte {offset} skipped, reading on after it ({lost}): {source}",
        path = path.display()
    )]
    SkippedChunk {
        /// The bag.
        path: PathBuf,
        /// Where the chunk starts.
        offset: u64,
        /// The log times its messages had.
        lost: LostRange,
        /// What the MCAP parser found.
        #[source]
        source: Arc<mcap::McapError>,
    },
    /// A message refers to a channel or schema the file never defined.
    #[error(
        "{path}: message {index} refers to channel {channel_id}, which the file does not define",
        path = path.display()
    )]
    UnknownChannel {
        /// The bag.
        path: PathBuf,
        /// Index of the message in delivery order.
        index: u64,
        /// The undefined channel id.
        channel_id: u16,
    },
}

impl ReadError {
    /// Whether the stream goes on after this error (a skipped damaged chunk); after any
    /// other error it ends.
    pub fn is_skipped_damage(&self) -> bool {
        matches!(self, ReadError::SkippedChunk { .. })
    }
}

/// Why a message could not be decoded into the type asked for.
#[derive(Debug, Error)]
pub enum MessageError {
    /// The topic carries a different message type.
    #[error(
        "{path}: topic `{topic}` (message {index}): expected {expected}, found {actual}",
        path = path.display()
    )]
    WrongType {
        /// The bag.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// Index of the message in delivery order.
        index: u64,
        /// The type asked for.
        expected: &'static str,
        /// The type the channel's schema names.
        actual: String,
    },
    /// The channel is not CDR-encoded with a `ros2msg` schema.
    #[error(
        "{path}: topic `{topic}` uses message encoding `{message_encoding}` and schema encoding \
         `{schema_encoding}`, expected `cdr` and `ros2msg`",
        path = path.display()
    )]
    Encoding {
        /// The bag.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// The channel's message encoding.
        message_encoding: String,
        /// The schema's encoding.
        schema_encoding: String,
    },
    /// The payload is not a valid message of its type, or the type is not supported.
    #[error(
        "{path}: topic `{topic}` (message {index}, log time {log_time} ns): {source}",
        path = path.display()
    )]
    Decode {
        /// The bag.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// Index of the message in delivery order.
        index: u64,
        /// The message's log time (ns).
        log_time: u64,
        /// What the decoder found.
        #[source]
        source: DecodeError,
    },
}

/// Why a bag could not be written.
#[derive(Debug, Error)]
pub enum WriteError {
    /// The file could not be created.
    #[error("{path}: cannot create: {source}", path = path.display())]
    Create {
        /// The bag.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The MCAP writer failed (I/O or a full channel table).
    #[error("{path}: writing topic `{topic}`: {source}", path = path.display())]
    Mcap {
        /// The bag.
        path: PathBuf,
        /// The topic being written (empty while creating the file).
        topic: String,
        /// The writer's error.
        #[source]
        source: mcap::McapError,
    },
    /// The message could not be encoded.
    #[error("{path}: encoding a message for `{topic}`: {source}", path = path.display())]
    Encode {
        /// The bag.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// The encoder's error.
        #[source]
        source: crate::ros2::CdrError,
    },
    /// The message's stamp is negative, so it has no nanosecond log time.
    #[error(
        "{path}: message for `{topic}` has a negative stamp ({sec} s); log times are unsigned",
        path = path.display()
    )]
    NegativeStamp {
        /// The bag.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// The stamp's seconds.
        sec: i32,
    },
    /// Writing the last chunk, the summary or the footer failed.
    #[error("{path}: finishing the file: {source}", path = path.display())]
    Finish {
        /// The bag.
        path: PathBuf,
        /// The writer's error.
        #[source]
        source: mcap::McapError,
    },
    /// A bag directory's `metadata.yaml` could not be written.
    #[error("{path}: writing the bag's metadata: {source}", path = path.display())]
    Metadata {
        /// The metadata file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The file was written but could not be flushed to disk.
    #[error("{path}: flushing: {source}", path = path.display())]
    Flush {
        /// The bag.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
}

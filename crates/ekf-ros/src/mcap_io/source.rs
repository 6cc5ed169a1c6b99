//! What the message sources share: the size limits that keep corrupt lengths from
//! requesting memory, the message as read, and why a source stopped.

use super::error::LostRange;
use super::message::ChannelInfo;
use mcap::McapError;
use std::io;
use std::sync::Arc;

/// Largest record or decompressed chunk accepted (256 MiB). rosbag2 writes 4 MiB chunks;
/// the cap keeps a corrupt length field from requesting gigabytes of memory.
pub(crate) const MAX_RECORD_BYTES: usize = 256 << 20;

/// Largest piece read from the file at once.
pub(crate) const READ_PIECE: usize = 64 << 10;

/// A message as read, before it is numbered.
pub(crate) struct Raw {
    /// Its channel.
    pub channel: Arc<ChannelInfo>,
    /// Log time (ns).
    pub log_time: u64,
    /// Publish time (ns).
    pub publish_time: u64,
    /// CDR payload.
    pub data: Vec<u8>,
}

/// Why a source stopped, or what it skipped, with the byte offset it had reached.
/// Cloneable, so the damage a recovery pass found can be reported by every stream over
/// the file.
#[derive(Debug, Clone)]
pub(crate) enum SourceError {
    /// A damaged chunk was passed over; the source goes on after it.
    Skipped {
        offset: u64,
        lost: LostRange,
        source: Arc<McapError>,
    },
    /// The parser rejected the data at `offset`.
    Mcap { offset: u64, source: Arc<McapError> },
    /// Reading at `offset` failed.
    Io { offset: u64, source: Arc<io::Error> },
    /// A message named a channel that was never defined.
    UnknownChannel(u16),
}

impl SourceError {
    /// A parser error at `offset`.
    pub fn mcap(offset: u64, source: McapError) -> Self {
        Self::Mcap {
            offset,
            source: Arc::new(source),
        }
    }

    /// A read error at `offset`.
    pub fn io(offset: u64, source: io::Error) -> Self {
        Self::Io {
            offset,
            source: Arc::new(source),
        }
    }
}

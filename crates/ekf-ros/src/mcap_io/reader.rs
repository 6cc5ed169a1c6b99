//! Opening a ROS 2 bag in any form `ros2 bag record` writes (an MCAP file, a sqlite3 `.db3`
//! file, or a bag directory of one or several such files with `metadata.yaml`): its
//! topics with types and counts, and one stream of its messages in log-time order, read
//! incrementally from the files, so memory does not grow with the bag.

use super::error::ReadError;
use super::mcap_file::{McapFile, McapMessages, TopicCounts};
use super::message::{BagMessage, TopicInfo};
use super::sniff::{storage_files, Storage};
use super::source::Raw;
use super::sqlite::{Db3File, Db3Messages};
use std::iter::Peekable;
use std::path::{Path, PathBuf};

/// The order [`Messages`] delivers messages in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MessageOrder {
    /// Non-decreasing log time, ties in file order (and, across the files of a split bag,
    /// in recording order). Used for every chunked MCAP file (all bags `ros2 bag record`
    /// and [`super::BagWriter`] write): through the summary's chunk indexes, or, when the
    /// summary is missing or damaged, through indexes rebuilt by reading the file once at
    /// [`BagReader::open`]; and for sqlite3 files, through their timestamp index.
    LogTime,
    /// The order of the records in the file, with no reordering. Used only for MCAP files
    /// with messages outside chunks, which no chunk index reaches.
    File,
}

/// One storage file of a bag.
#[derive(Debug)]
enum Part {
    Mcap(Box<McapFile>),
    Sqlite(Db3File),
}

impl Part {
    fn counts(&self) -> &TopicCounts {
        match self {
            Part::Mcap(f) => f.counts(),
            Part::Sqlite(f) => f.counts(),
        }
    }

    fn messages(&self) -> Result<PartMessages, ReadError> {
        Ok(match self {
            Part::Mcap(f) => PartMessages::Mcap(Box::new(f.messages()?)),
            Part::Sqlite(f) => PartMessages::Sqlite(Box::new(f.messages()?)),
        })
    }
}

/// A ROS 2 bag opened for reading.
#[derive(Debug)]
pub struct BagReader {
    path: PathBuf,
    parts: Vec<Part>,
    topics: Vec<TopicInfo>,
}

impl BagReader {
    /// Opens the bag at `path` — an MCAP file, a `.db3` file, or a bag directory (or its
    /// `metadata.yaml`) with one or several of them ([`super::sniff`]) — and lists its
    /// topics. An MCAP file whose summary is missing or damaged (a recording cut short) is
    /// read once to rebuild it; its intact part can then be read, and the damage is
    /// reported after its last message. A path that is no bag, or a file without a single
    /// readable channel, is an error naming the file and what it is.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, ReadError> {
        let path = path.as_ref().to_path_buf();
        let parts = storage_files(&path)?
            .into_iter()
            .map(|(file, storage)| match storage {
                Storage::Mcap => McapFile::open(&file).map(|f| Part::Mcap(Box::new(f))),
                Storage::Sqlite => Db3File::open(&file).map(Part::Sqlite),
            })
            .collect::<Result<Vec<_>, _>>()?;
        let mut counts = TopicCounts::new();
        for (key, n) in parts.iter().flat_map(Part::counts) {
            *counts.entry(key.clone()).or_default() += n;
        }
        let topics = counts
            .into_iter()
            .map(|((topic, type_name), message_count)| TopicInfo {
                topic,
                type_name,
                message_count,
            })
            .collect();
        Ok(Self {
            path,
            parts,
            topics,
        })
    }

    /// The path the bag was opened from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Topics sorted by name, each with its type and message count (summed over the
    /// files of a split bag).
    pub fn topics(&self) -> &[TopicInfo] {
        &self.topics
    }

    /// The topics for an error message: `"/odom (nav_msgs/msg/Odometry), /scan (…)"`, or
    /// `"no topics"`.
    pub fn describe_topics(&self) -> String {
        if self.topics.is_empty() {
            return "no topics".to_owned();
        }
        self.topics
            .iter()
            .map(|t| format!("{} ({})", t.topic, t.type_name))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The order [`Self::messages`] delivers messages in.
    pub fn order(&self) -> MessageOrder {
        let in_time = |p: &Part| match p {
            Part::Mcap(f) => f.in_log_time_order(),
            Part::Sqlite(_) => true,
        };
        if self.parts.iter().all(in_time) {
            MessageOrder::LogTime
        } else {
            MessageOrder::File
        }
    }

    /// A new stream over all messages, in [`Self::order`], reading the files
    /// incrementally (one message ahead per file).
    pub fn messages(&self) -> Result<Messages, ReadError> {
        let streams = self
            .parts
            .iter()
            .map(|p| Ok((p.messages()?.peekable(), 0)))
            .collect::<Result<Vec<_>, ReadError>>()?;
        Ok(Messages {
            streams,
            delivered: 0,
            done: false,
        })
    }
}

/// The messages of one storage file.
enum PartMessages {
    Mcap(Box<McapMessages>),
    Sqlite(Box<Db3Messages>),
}

impl Iterator for PartMessages {
    type Item = Result<Raw, ReadError>;

    fn next(&mut self) -> Option<Self::Item> {
        match self {
            PartMessages::Mcap(m) => m.next(),
            PartMessages::Sqlite(m) => m.next(),
        }
    }
}

/// The messages of a bag: the files' streams merged by log time. Yields every message up
/// to the end or the first damage that cannot be read past. A damaged chunk is reported
/// ([`ReadError::SkippedChunk`]) where it was met when the file's index is read, before
/// the first message when the index had to be rebuilt, and reading goes on after it;
/// after any other error the stream yields nothing more.
pub struct Messages {
    /// Each file's stream, with the log time of the last message it delivered (where its
    /// error, if it has one, is placed in the merged order).
    streams: Vec<(Peekable<PartMessages>, u64)>,
    delivered: u64,
    done: bool,
}

impl Iterator for Messages {
    type Item = Result<BagMessage, ReadError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        // The stream whose next item comes first; ties go to the earlier file.
        let (_, index) = self
            .streams
            .iter_mut()
            .enumerate()
            .filter_map(|(i, (stream, last))| match stream.peek()? {
                Ok(raw) => Some((raw.log_time, i)),
                Err(_) => Some((*last, i)),
            })
            .min()?;
        let (stream, last) = &mut self.streams[index];
        match stream.next()? {
            Err(e) => {
                self.done = !e.is_skipped_damage();
                Some(Err(e))
            }
            Ok(Raw {
                channel,
                log_time,
                publish_time,
                data,
            }) => {
                *last = log_time;
                let index = self.delivered;
                self.delivered += 1;
                Some(Ok(BagMessage {
                    channel,
                    index,
                    log_time,
                    publish_time,
                    data,
                }))
            }
        }
    }
}

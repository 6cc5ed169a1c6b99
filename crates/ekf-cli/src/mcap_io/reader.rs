//! Opening a ROS 2 bag: its topics with types and counts, and a stream of its messages
//! read incrementally from the file, so memory does not grow with the file.

use super::error::ReadError;
use super::indexed::IndexedSource;
use super::linear::LinearSource;
use super::message::{BagMessage, TopicInfo};
use super::recover::recover;
use super::source::{Raw, SourceError};
use super::summary;
use mcap::Summary;
use std::collections::BTreeMap;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The order [`Messages`] delivers messages in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MessageOrder {
    /// Non-decreasing log time, ties in file order. Used for every chunked file (all bags
    /// `ros2 bag record` and [`super::BagWriter`] write): through the summary's chunk
    /// indexes, or, when the summary is missing or damaged, through indexes rebuilt by
    /// reading the file once at [`BagReader::open`].
    LogTime,
    /// The order of the records in the file, with no reordering. Used only for files with
    /// messages outside chunks, which no chunk index reaches.
    File,
}

/// An MCAP ROS 2 bag opened for reading.
#[derive(Debug)]
pub struct BagReader {
    path: Arc<Path>,
    file_len: u64,
    /// The file's summary, or one rebuilt by reading the file; `None` for unchunked files.
    summary: Option<Summary>,
    /// Where rebuilding the summary stopped early; reported after the last message.
    damage: Option<SourceError>,
    topics: Vec<TopicInfo>,
}

impl BagReader {
    /// Opens `path` (an MCAP file, or a ROS 2 bag directory with one `.mcap` storage
    /// file; a sqlite3 bag or a text file is named as such, [`super::sniff`]) and lists
    /// its topics. Reads the summary; if the summary is missing or
    /// damaged (a recording cut short), reads the whole file once to rebuild it, checking
    /// every chunk. A damaged file still opens: its intact part can be read, and the
    /// damage is reported after the last message. A damaged file without a single
    /// channel (not MCAP at all, or cut inside its first chunk) is an error naming the
    /// byte offset.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, ReadError> {
        let path: Arc<Path> = Arc::from(super::sniff::mcap_file(path.as_ref())?.as_path());
        let open_error = |source| ReadError::Open {
            path: path.to_path_buf(),
            source,
        };
        let mut file = File::open(&path).map_err(open_error)?;
        let file_len = file.metadata().map_err(open_error)?.len();
        let found =
            summary::read_summary(&mut file, file_len).filter(|s| !s.chunk_indexes.is_empty());
        let (summary, damage, unchunked) = match found {
            Some(summary) => (summary, None, false),
            None => {
                let r = recover(&mut file);
                // Damage and no channel at all: nothing of the file is readable (it is
                // not an MCAP file, or was cut before its first chunk ended), so it does
                // not open.
                if let (Some(damage), true) = (&r.damage, r.summary.channels.is_empty()) {
                    return Err(to_read_error(&path, 0, damage.clone()));
                }
                (r.summary, r.damage, r.unchunked)
            }
        };
        // A rebuilt summary always has statistics; a file's own may lack them.
        let topics = summary.stats.is_some().then(|| summary_topics(&summary));
        let mut bag = Self {
            path,
            file_len,
            // Unchunked files stream front to back, which finds any damage by itself.
            summary: (!unchunked).then_some(summary),
            damage: damage.filter(|_| !unchunked),
            topics: Vec::new(),
        };
        bag.topics = match topics {
            Some(topics) => topics,
            None => bag.count_topics()?,
        };
        Ok(bag)
    }

    /// The file this bag was opened from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Topics sorted by name, each with its type and message count.
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
        if self.summary.is_some() {
            MessageOrder::LogTime
        } else {
            MessageOrder::File
        }
    }

    /// A new stream over all messages, in [`Self::order`], reading the file incrementally.
    pub fn messages(&self) -> Result<Messages, ReadError> {
        let file = File::open(&self.path).map_err(|source| ReadError::Open {
            path: self.path.to_path_buf(),
            source,
        })?;
        let source = match &self.summary {
            Some(summary) => {
                let channels = summary::summary_channels(summary, &self.path);
                let indexed = IndexedSource::new(file, self.file_len, summary, channels)
                    .map_err(|e| to_read_error(&self.path, 0, e))?;
                Source::Indexed(Box::new(indexed))
            }
            None => Source::Linear(Box::new(LinearSource::new(file, Arc::clone(&self.path)))),
        };
        Ok(Messages {
            path: self.path.to_path_buf(),
            source,
            damage: self.damage.clone(),
            delivered: 0,
            done: false,
        })
    }

    /// Counts messages per topic by streaming the file up to its end or its damage.
    fn count_topics(&self) -> Result<Vec<TopicInfo>, ReadError> {
        let mut counts: BTreeMap<(String, String), u64> = BTreeMap::new();
        for message in self.messages()? {
            let Ok(message) = message else { break };
            let key = (
                message.channel.topic.clone(),
                message.channel.type_name.clone(),
            );
            *counts.entry(key).or_default() += 1;
        }
        Ok(into_topics(counts))
    }
}

/// Topics and counts from the summary's statistics (0 for channels they do not list).
fn summary_topics(summary: &Summary) -> Vec<TopicInfo> {
    let no_counts = BTreeMap::new();
    let channel_counts = summary
        .stats
        .as_ref()
        .map_or(&no_counts, |s| &s.channel_message_counts);
    let mut counts: BTreeMap<(String, String), u64> = BTreeMap::new();
    for (id, channel) in &summary.channels {
        let type_name = channel
            .schema
            .as_ref()
            .map(|s| s.name.clone())
            .unwrap_or_default();
        let count = channel_counts.get(id).copied().unwrap_or(0);
        *counts
            .entry((channel.topic.clone(), type_name))
            .or_default() += count;
    }
    into_topics(counts)
}

/// Turns `(topic, type) → count` into a sorted topic list.
fn into_topics(counts: BTreeMap<(String, String), u64>) -> Vec<TopicInfo> {
    counts
        .into_iter()
        .map(|((topic, type_name), message_count)| TopicInfo {
            topic,
            type_name,
            message_count,
        })
        .collect()
}

/// Adds the file and the number of delivered messages to a source's error.
fn to_read_error(path: &Path, delivered: u64, e: SourceError) -> ReadError {
    let path = path.to_path_buf();
    match e {
        SourceError::Mcap { offset, source } => ReadError::Corrupt {
            path,
            offset,
            messages: delivered,
            source,
        },
        SourceError::Io { offset, source } => ReadError::Io {
            path,
            offset,
            source,
        },
        SourceError::UnknownChannel(channel_id) => ReadError::UnknownChannel {
            path,
            index: delivered,
            channel_id,
        },
    }
}

/// Where [`Messages`] gets its messages.
enum Source {
    /// Through the chunk indexes.
    Indexed(Box<IndexedSource>),
    /// Front to back.
    Linear(Box<LinearSource>),
}

/// The messages of a bag. Yields every message up to the end or the first damage; after an
/// error it yields nothing more.
pub struct Messages {
    path: PathBuf,
    source: Source,
    /// Damage found when the bag was opened, yielded after the last message.
    damage: Option<SourceError>,
    delivered: u64,
    done: bool,
}

impl Iterator for Messages {
    type Item = Result<BagMessage, ReadError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let next = match &mut self.source {
            Source::Indexed(s) => s.next(),
            Source::Linear(s) => s.next(),
        };
        match next {
            None => {
                self.done = true;
                let damage = self.damage.take()?;
                Some(Err(to_read_error(&self.path, self.delivered, damage)))
            }
            Some(Err(e)) => {
                self.done = true;
                Some(Err(to_read_error(&self.path, self.delivered, e)))
            }
            Some(Ok(Raw {
                channel,
                log_time,
                publish_time,
                data,
            })) => {
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

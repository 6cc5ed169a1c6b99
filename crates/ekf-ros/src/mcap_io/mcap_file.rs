//! One MCAP storage file of a bag: its summary (read, or rebuilt when the recording was
//! cut short), its topic counts, and a stream of its messages read incrementally.

use super::error::ReadError;
use super::indexed::IndexedSource;
use super::linear::LinearSource;
use super::recover::recover;
use super::source::{Raw, SourceError};
use super::summary;
use mcap::Summary;
use std::collections::{BTreeMap, VecDeque};
use std::fs::File;
use std::path::Path;
use std::sync::Arc;

/// Messages per (topic, type name).
pub(crate) type TopicCounts = BTreeMap<(String, String), u64>;

/// An MCAP file opened for reading.
#[derive(Debug)]
pub(crate) struct McapFile {
    path: Arc<Path>,
    file_len: u64,
    /// The file's summary, or one rebuilt by reading the file; `None` for unchunked files.
    summary: Option<Summary>,
    /// Damage rebuilding the summary read past; reported before the first message.
    skipped: Vec<SourceError>,
    /// Where rebuilding the summary stopped early; reported after the last message.
    damage: Option<SourceError>,
    counts: TopicCounts,
}

impl McapFile {
    /// Opens `path` and counts its topics. Reads the summary; if the summary is missing
    /// or damaged (a recording cut short), reads the whole file once to rebuild it,
    /// checking every chunk. A damaged file still opens: its intact part can be read, and
    /// the damage is reported after the last message. A damaged file without a single
    /// channel (not MCAP at all, or cut inside its first chunk) is an error naming the
    /// byte offset.
    pub fn open(path: &Path) -> Result<Self, ReadError> {
        let path: Arc<Path> = Arc::from(path);
        let open_error = |source| ReadError::Open {
            path: path.to_path_buf(),
            source,
        };
        let mut file = File::open(&path).map_err(open_error)?;
        let file_len = file.metadata().map_err(open_error)?.len();
        let found =
            summary::read_summary(&mut file, file_len).filter(|s| !s.chunk_indexes.is_empty());
        let (summary, skipped, damage, unchunked) = match found {
            Some(summary) => (summary, Vec::new(), None, false),
            None => {
                let r = recover(&mut file);
                // Damage and no channel at all: nothing of the file is readable (it is
                // not an MCAP file, or was cut before its first chunk ended), so it does
                // not open.
                let first_damage = r.skipped.first().or(r.damage.as_ref());
                if let (Some(damage), true) = (first_damage, r.summary.channels.is_empty()) {
                    let damage = match damage {
                        SourceError::Skipped { offset, source, .. } => SourceError::Mcap {
                            offset: *offset,
                            source: Arc::clone(source),
                        },
                        other => other.clone(),
                    };
                    return Err(to_read_error(&path, 0, damage));
                }
                (r.summary, r.skipped, r.damage, r.unchunked)
            }
        };
        // A rebuilt summary always has statistics; a file's own may lack them.
        let counts = summary.stats.is_some().then(|| summary_counts(&summary));
        let mut file = Self {
            path,
            file_len,
            // Unchunked files stream front to back, which finds any damage by itself.
            summary: (!unchunked).then_some(summary),
            skipped: if unchunked { Vec::new() } else { skipped },
            damage: damage.filter(|_| !unchunked),
            counts: TopicCounts::new(),
        };
        file.counts = match counts {
            Some(counts) => counts,
            None => file.count_topics()?,
        };
        Ok(file)
    }

    /// Messages per (topic, type).
    pub fn counts(&self) -> &TopicCounts {
        &self.counts
    }

    /// Whether messages come in log-time order (every chunked file) rather than in file
    /// order (files with messages outside chunks).
    pub fn in_log_time_order(&self) -> bool {
        self.summary.is_some()
    }

    /// A new stream over all messages, reading the file incrementally: in log-time order
    /// through the chunk indexes, or front to back for unchunked files. Yields every
    /// message up to the end or the first damage, then the damage.
    pub fn messages(&self) -> Result<McapMessages, ReadError> {
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
        Ok(McapMessages {
            path: Arc::clone(&self.path),
            source,
            skipped: self.skipped.iter().cloned().collect(),
            damage: self.damage.clone(),
            delivered: 0,
            done: false,
        })
    }

    /// Counts messages per topic by streaming the file up to its end or its damage.
    fn count_topics(&self) -> Result<TopicCounts, ReadError> {
        let mut counts = TopicCounts::new();
        for message in self.messages()? {
            let Ok(message) = message else { break };
            let key = (
                message.channel.topic.clone(),
                message.channel.type_name.clone(),
            );
            *counts.entry(key).or_default() += 1;
        }
        Ok(counts)
    }
}

/// Topic counts from the summary's statistics (0 for channels they do not list).
fn summary_counts(summary: &Summary) -> TopicCounts {
    let no_counts = BTreeMap::new();
    let channel_counts = summary
        .stats
        .as_ref()
        .map_or(&no_counts, |s| &s.channel_message_counts);
    let mut counts = TopicCounts::new();
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
    counts
}

/// Adds the file and the number of delivered messages to a source's error.
fn to_read_error(path: &Path, delivered: u64, e: SourceError) -> ReadError {
    let path = path.to_path_buf();
    match e {
        SourceError::Skipped {
            offset,
            lost,
            source,
        } => ReadError::SkippedChunk {
            path,
            offset,
            lost,
            source,
        },
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

/// Where [`McapMessages`] gets its messages.
enum Source {
    /// Through the chunk indexes.
    Indexed(Box<IndexedSource>),
    /// Front to back.
    Linear(Box<LinearSource>),
}

/// The messages of one MCAP file. After an error it yields nothing more.
pub(crate) struct McapMessages {
    path: Arc<Path>,
    source: Source,
    /// Damage read past when the file was opened, yielded before the first message.
    skipped: VecDeque<SourceError>,
    /// Damage found when the file was opened, yielded after the last message.
    damage: Option<SourceError>,
    delivered: u64,
    done: bool,
}

impl Iterator for McapMessages {
    type Item = Result<Raw, ReadError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        if let Some(skipped) = self.skipped.pop_front() {
            return Some(Err(to_read_error(&self.path, self.delivered, skipped)));
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
                self.done = !matches!(e, SourceError::Skipped { .. });
                Some(Err(to_read_error(&self.path, self.delivered, e)))
            }
            Some(Ok(raw)) => {
                self.delivered += 1;
                Some(Ok(raw))
            }
        }
    }
}

//! One sqlite3 storage file of a ROS 2 bag (`.db3`, the default storage of ROS 2 Foxy and
//! Humble): rosbag2's `topics` table (id, name, type, serialization format) and its
//! `messages` table (topic id, receive timestamp in ns, CDR payload with its
//! encapsulation header, the same bytes an MCAP bag stores). Messages stream in
//! timestamp order a page at a time, so memory does not grow with the file.

use super::error::ReadError;
use super::mcap_file::TopicCounts;
use super::message::ChannelInfo;
use super::source::Raw;
use super::SCHEMA_ENCODING;
use rusqlite::{Connection, OpenFlags};
use std::collections::{HashMap, VecDeque};
use std::path::Path;
use std::sync::Arc;

/// Messages fetched per query: enough to amortise the query, few enough that memory stays
/// small (a page of 4 MB scans is 1 GB only if each scan is 4 MB).
const PAGE_ROWS: usize = 256;

/// The `messages` query, resuming after the last (timestamp, id) delivered. `id` breaks
/// ties in insertion order; rosbag2's `timestamp_idx` serves the order.
const PAGE_QUERY: &str = "SELECT id, topic_id, timestamp, data FROM messages \
                          WHERE (timestamp, id) > (?1, ?2) ORDER BY timestamp, id LIMIT ?3";

/// A `.db3` file opened for reading.
#[derive(Debug)]
pub(crate) struct Db3File {
    path: Arc<Path>,
    channels: Arc<HashMap<i64, Arc<ChannelInfo>>>,
    counts: TopicCounts,
}

impl Db3File {
    /// Opens `path` read-only, reads its topics and counts their messages.
    pub fn open(path: &Path) -> Result<Self, ReadError> {
        let path: Arc<Path> = Arc::from(path);
        let conn = connect(&path)?;
        let sql = |e| sqlite_error(&path, e);
        let tables: i64 = conn
            .query_row(
                "SELECT count(*) FROM sqlite_master WHERE type = 'table' \
                 AND name IN ('topics', 'messages')",
                [],
                |row| row.get(0),
            )
            .map_err(sql)?;
        if tables != 2 {
            return Err(ReadError::NotABag {
                path: path.to_path_buf(),
                what: "a SQLite database without rosbag2's `topics` and `messages` tables".into(),
                hint: "pass a bag written by `ros2 bag record` (storage sqlite3 or mcap)".into(),
            });
        }
        let mut channels = HashMap::new();
        let mut topics = conn
            .prepare("SELECT id, name, type, serialization_format FROM topics")
            .map_err(sql)?;
        let rows = topics
            .query_map([], |row| {
                Ok((row.get::<_, i64>(0)?, row.get(1)?, row.get(2)?, row.get(3)?))
            })
            .map_err(sql)?;
        for row in rows {
            let (id, topic, type_name, message_encoding) = row.map_err(sql)?;
            let info = ChannelInfo {
                path: Arc::clone(&path),
                topic,
                type_name,
                // rosbag2's sqlite3 storage keeps no schema text; its types are ROS 2
                // message definitions, which is what `ros2msg` names in MCAP.
                schema_encoding: SCHEMA_ENCODING.into(),
                message_encoding,
            };
            channels.insert(id, Arc::new(info));
        }
        let mut counts = TopicCounts::new();
        let mut per_topic = conn
            .prepare("SELECT topic_id, count(*) FROM messages GROUP BY topic_id")
            .map_err(sql)?;
        let rows = per_topic
            .query_map([], |row| Ok((row.get::<_, i64>(0)?, row.get::<_, i64>(1)?)))
            .map_err(sql)?;
        for row in rows {
            let (topic_id, count) = row.map_err(sql)?;
            let channel = channels
                .get(&topic_id)
                .ok_or_else(|| unknown_topic(&path, topic_id))?;
            let key = (channel.topic.clone(), channel.type_name.clone());
            *counts.entry(key).or_default() += count.max(0).unsigned_abs();
        }
        // Topics without messages are listed too, as `ros2 bag info` lists them.
        for channel in channels.values() {
            let key = (channel.topic.clone(), channel.type_name.clone());
            counts.entry(key).or_default();
        }
        Ok(Self {
            path,
            channels: Arc::new(channels),
            counts,
        })
    }

    /// Messages per (topic, type).
    pub fn counts(&self) -> &TopicCounts {
        &self.counts
    }

    /// A new stream over all messages in (timestamp, insertion) order, on its own
    /// read-only connection.
    pub fn messages(&self) -> Result<Db3Messages, ReadError> {
        Ok(Db3Messages {
            conn: connect(&self.path)?,
            path: Arc::clone(&self.path),
            channels: Arc::clone(&self.channels),
            after: (i64::MIN, i64::MIN),
            page: VecDeque::new(),
            exhausted: false,
            failed: None,
        })
    }
}

/// Opens `path` read-only (a bag is never changed by reading it).
fn connect(path: &Path) -> Result<Connection, ReadError> {
    Connection::open_with_flags(
        path,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
    .map_err(|e| sqlite_error(path, e))
}

/// Wraps a SQLite error with the file.
fn sqlite_error(path: &Path, source: rusqlite::Error) -> ReadError {
    ReadError::Sqlite {
        path: path.to_path_buf(),
        source: Arc::new(source),
    }
}

/// A message row whose `topic_id` is not in the `topics` table.
fn unknown_topic(path: &Path, topic_id: i64) -> ReadError {
    ReadError::BadRow {
        path: path.to_path_buf(),
        what: format!("messages refer to topic id {topic_id}, which the `topics` table lacks"),
    }
}

/// The messages of one `.db3` file. After an error it yields nothing more.
pub(crate) struct Db3Messages {
    conn: Connection,
    path: Arc<Path>,
    channels: Arc<HashMap<i64, Arc<ChannelInfo>>>,
    /// (timestamp, id) of the last row fetched.
    after: (i64, i64),
    page: VecDeque<Raw>,
    /// No rows are left after [`Self::page`].
    exhausted: bool,
    /// An error met while fetching, yielded once the rows before it are delivered.
    failed: Option<ReadError>,
}

impl Db3Messages {
    /// Fetches the next page of rows after [`Self::after`]; a short page is the last.
    fn fetch(&mut self) -> Result<(), ReadError> {
        let sql = |e| sqlite_error(&self.path, e);
        let mut query = self.conn.prepare(PAGE_QUERY).map_err(sql)?;
        let mut rows = query
            .query((self.after.0, self.after.1, PAGE_ROWS as i64))
            .map_err(sql)?;
        let mut fetched = 0;
        while let Some(row) = rows.next().map_err(sql)? {
            fetched += 1;
            let id: i64 = row.get(0).map_err(sql)?;
            let topic_id: i64 = row.get(1).map_err(sql)?;
            let timestamp: i64 = row.get(2).map_err(sql)?;
            let data: Vec<u8> = row.get(3).map_err(sql)?;
            self.after = (timestamp, id);
            let channel = self
                .channels
                .get(&topic_id)
                .ok_or_else(|| unknown_topic(&self.path, topic_id))?;
            let log_time = u64::try_from(timestamp).map_err(|_| ReadError::BadRow {
                path: self.path.to_path_buf(),
                what: format!(
                    "message row {id} has the negative timestamp {timestamp} ns; \
                     expected nanoseconds since the epoch"
                ),
            })?;
            self.page.push_back(Raw {
                channel: Arc::clone(channel),
                log_time,
                // rosbag2's sqlite3 storage keeps one time, the receive time.
                publish_time: log_time,
                data,
            });
        }
        self.exhausted = fetched < PAGE_ROWS;
        Ok(())
    }
}

impl Iterator for Db3Messages {
    type Item = Result<Raw, ReadError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if let Some(raw) = self.page.pop_front() {
                return Some(Ok(raw));
            }
            if let Some(e) = self.failed.take() {
                self.exhausted = true;
                return Some(Err(e));
            }
            if self.exhausted {
                return None;
            }
            if let Err(e) = self.fetch() {
                self.failed = Some(e);
            }
        }
    }
}

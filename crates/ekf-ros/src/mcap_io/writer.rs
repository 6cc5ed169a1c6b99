//! Writing ROS 2 bags that Foxglove and the ROS 2 tools open: chunked, indexed, with a
//! summary, one channel per (topic, type) registered on first use; as one MCAP file, or
//! as a bag directory (`NAME/NAME_0.mcap` with `NAME/metadata.yaml`) as `ros2 bag record`
//! writes it.

use super::error::WriteError;
use super::metadata::{BagInfo, WrittenBag};
use super::{MESSAGE_ENCODING, PROFILE, SCHEMA_ENCODING};
use crate::ros2::{AnyMessage, CdrError, MsgDef, RosMessage, Stamped};
use mcap::records::MessageHeader;
use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Channel metadata key the `ros2` profile requires.
const QOS_KEY: &str = "offered_qos_profiles";
/// An empty YAML list of offered QoS profiles: `ros2 bag play` then uses its default QoS.
/// A list is what every rosbag2 version parses; its enum spelling changed between distros.
const NO_QOS_PROFILES: &str = "[]";

/// A ROS 2 bag being written. Call [`Self::finish`] to close it and see errors; if it is
/// dropped unfinished (say the caller returned early with an error), `Drop` finishes it
/// best-effort, so the file is still a complete, readable MCAP.
pub struct BagWriter {
    /// The MCAP file.
    path: PathBuf,
    /// The bag directory holding the file and its `metadata.yaml`, if writing one.
    directory: Option<PathBuf>,
    /// `None` once finished.
    inner: Option<mcap::Writer<BufWriter<File>>>,
    /// Channel id and index into `written.topics` per (topic, type name).
    channels: HashMap<(String, &'static str), (u16, usize)>,
    /// Sequence number per channel.
    sequences: HashMap<u16, u32>,
    /// What the metadata says: topics with counts, time span.
    written: WrittenBag,
    /// A second handle on the MCAP file, to sync it to the disk.
    file: File,
    /// Chunks closed by log time ([`Self::close_chunks_every`]).
    chunk_clock: Option<ChunkClock>,
}

/// When the chunk being written is closed.
struct ChunkClock {
    /// Longest log-time span of a chunk (ns).
    every_ns: u64,
    /// Log time of the first message of the open chunk.
    opened_ns: Option<u64>,
}

/// Whether `path` asks for a bag directory: it ends with a path separator, or is an
/// existing directory.
fn is_directory_request(path: &Path) -> bool {
    let text = path.as_os_str().to_string_lossy();
    text.ends_with('/') || text.ends_with(std::path::MAIN_SEPARATOR) || path.is_dir()
}

impl BagWriter {
    /// Creates (or truncates) `path` and writes the MCAP header with profile `ros2`. A
    /// `path` that ends with `/` (or is a directory) is a bag directory, created if
    /// needed, holding `NAME_0.mcap` (NAME: the directory's name) and a `metadata.yaml`
    /// written at once and rewritten with the counts when the bag is finished.
    pub fn create(path: impl AsRef<Path>) -> Result<Self, WriteError> {
        let given = path.as_ref();
        let create_error = |path: &Path, source| WriteError::Create {
            path: path.to_path_buf(),
            source,
        };
        let (directory, path) = if is_directory_request(given) {
            std::fs::create_dir_all(given).map_err(|e| create_error(given, e))?;
            let name = given
                .file_name()
                .map_or("bag".into(), |n| n.to_string_lossy().into_owned());
            (
                Some(given.to_path_buf()),
                given.join(format!("{name}_0.mcap")),
            )
        } else {
            (None, given.to_path_buf())
        };
        let file = File::create(&path).map_err(|e| create_error(&path, e))?;
        let handle = file.try_clone().map_err(|e| create_error(&path, e))?;
        let inner = mcap::WriteOptions::new()
            .profile(PROFILE)
            .create(BufWriter::new(file))
            .map_err(|source| WriteError::Mcap {
                path: path.clone(),
                topic: String::new(),
                source,
            })?;
        let file_name = path.file_name().map(|n| n.to_string_lossy().into_owned());
        let writer = Self {
            path,
            directory,
            inner: Some(inner),
            channels: HashMap::new(),
            sequences: HashMap::new(),
            written: WrittenBag {
                file_name: file_name.unwrap_or_default(),
                ..WrittenBag::default()
            },
            file: handle,
            chunk_clock: None,
        };
        // Written now too, so that a recording killed before it finishes is still a bag
        // directory that readers recognise.
        writer.write_bag_metadata()?;
        Ok(writer)
    }

    /// Closes each chunk once it spans `every_ns` of log time, and syncs the file to the
    /// disk then: a recording killed hard (`kill -9`, a power cut) loses at most the
    /// open chunk, about `every_ns` of messages. The file it leaves has no summary; the
    /// reader rebuilds the index from the chunks (`BagReader::open`). The default, as
    /// rosbag2's, closes chunks by size only (4 MiB), which can hold minutes of a slow
    /// recording.
    pub fn close_chunks_every(&mut self, every_ns: u64) {
        self.chunk_clock = Some(ChunkClock {
            every_ns: every_ns.max(1),
            opened_ns: None,
        });
    }

    /// Writes `metadata.yaml` with what has been written so far, if writing a directory.
    fn write_bag_metadata(&self) -> Result<(), WriteError> {
        let Some(dir) = &self.directory else {
            return Ok(());
        };
        BagInfo::for_written(&self.written)
            .write(dir)
            .map_err(|source| WriteError::Metadata {
                path: dir.join(super::metadata::METADATA_FILE),
                source,
            })
    }

    /// Writes `message` on `topic` with log time = publish time = its header stamp.
    pub fn write<M: RosMessage + Stamped>(
        &mut self,
        topic: &str,
        message: &M,
    ) -> Result<(), WriteError> {
        let stamp = message.header().stamp;
        let time = stamp.to_nanos().ok_or_else(|| WriteError::NegativeStamp {
            path: self.path.clone(),
            topic: topic.to_owned(),
            sec: stamp.sec,
        })?;
        self.write_at(topic, time, message)
    }

    /// Writes `message` on `topic` with log time = publish time = `time_ns`, for messages
    /// without a header (`TFMessage`, `MarkerArray`).
    pub fn write_at<M: RosMessage>(
        &mut self,
        topic: &str,
        time_ns: u64,
        message: &M,
    ) -> Result<(), WriteError> {
        self.write_encoded(topic, M::DEF, time_ns, message.encode())
    }

    /// Writes a message of any supported type on `topic` at `time_ns` (log and publish
    /// time), e.g. one read from another bag.
    pub fn write_any(
        &mut self,
        topic: &str,
        time_ns: u64,
        message: &AnyMessage,
    ) -> Result<(), WriteError> {
        self.write_encoded(topic, message.def(), time_ns, message.encode())
    }

    /// Writes an encoded message of type `def`, registering its channel if new.
    fn write_encoded(
        &mut self,
        topic: &str,
        def: &'static MsgDef,
        time_ns: u64,
        data: Result<Vec<u8>, CdrError>,
    ) -> Result<(), WriteError> {
        let data = data.map_err(|source| WriteError::Encode {
            path: self.path.clone(),
            topic: topic.to_owned(),
            source,
        })?;
        let (channel_id, topic_index) = self.channel(topic, def)?;
        self.written.topics[topic_index].2 += 1;
        let (first, last) = self.written.span.get_or_insert((time_ns, time_ns));
        *first = (*first).min(time_ns);
        *last = (*last).max(time_ns);
        let sequence = self.sequences.entry(channel_id).or_insert(0);
        *sequence = sequence.wrapping_add(1);
        let header = MessageHeader {
            channel_id,
            sequence: *sequence,
            log_time: time_ns,
            publish_time: time_ns,
        };
        let path = &self.path;
        let writer = self.inner.as_mut().ok_or_else(|| finished(path, topic))?;
        if let Some(clock) = &mut self.chunk_clock {
            match clock.opened_ns {
                Some(opened) if time_ns >= opened.saturating_add(clock.every_ns) => {
                    writer
                        .flush()
                        .map_err(|source| mcap_error(path, topic, source))?;
                    self.file.sync_data().map_err(|source| WriteError::Flush {
                        path: path.clone(),
                        source,
                    })?;
                    clock.opened_ns = Some(time_ns);
                }
                Some(_) => {}
                None => clock.opened_ns = Some(time_ns),
            }
        }
        writer
            .write_to_known_channel(&header, &data)
            .map_err(|source| mcap_error(path, topic, source))
    }

    /// Writes an MCAP metadata record `name` with string key/value pairs (provenance,
    /// labels such as a synthetic sensor's parameters).
    pub fn write_metadata(
        &mut self,
        name: &str,
        entries: &[(&str, String)],
    ) -> Result<(), WriteError> {
        let metadata = mcap::records::Metadata {
            name: name.to_owned(),
            metadata: entries
                .iter()
                .map(|(k, v)| ((*k).to_owned(), v.clone()))
                .collect(),
        };
        let path = &self.path;
        let writer = self.inner.as_mut().ok_or_else(|| finished(path, name))?;
        writer
            .write_metadata(&metadata)
            .map_err(|source| mcap_error(path, name, source))
    }

    /// Writes the last chunk, the summary and the footer, and flushes the file.
    pub fn finish(mut self) -> Result<(), WriteError> {
        self.close()
    }

    /// The channel for (`topic`, `def`), registering it and its schema on first use.
    fn channel(&mut self, topic: &str, def: &'static MsgDef) -> Result<(u16, usize), WriteError> {
        let key = (topic.to_owned(), def.name);
        if let Some(&found) = self.channels.get(&key) {
            return Ok(found);
        }
        let path = &self.path;
        let writer = self.inner.as_mut().ok_or_else(|| finished(path, topic))?;
        let schema_id = writer
            .add_schema(def.name, SCHEMA_ENCODING, def.schema_text().as_bytes())
            .map_err(|source| mcap_error(path, topic, source))?;
        let metadata = BTreeMap::from([(QOS_KEY.to_owned(), NO_QOS_PROFILES.to_owned())]);
        let id = writer
            .add_channel(schema_id, topic, MESSAGE_ENCODING, &metadata)
            .map_err(|source| mcap_error(path, topic, source))?;
        let index = self.written.topics.len();
        self.written
            .topics
            .push((topic.to_owned(), def.name.to_owned(), 0));
        self.channels.insert(key, (id, index));
        Ok((id, index))
    }

    /// Finishes the MCAP and flushes, once; later calls do nothing.
    fn close(&mut self) -> Result<(), WriteError> {
        let Some(mut writer) = self.inner.take() else {
            return Ok(());
        };
        writer.finish().map_err(|source| WriteError::Finish {
            path: self.path.clone(),
            source,
        })?;
        writer
            .into_inner()
            .flush()
            .map_err(|source| WriteError::Flush {
                path: self.path.clone(),
                source,
            })?;
        self.write_bag_metadata()
    }
}

impl Drop for BagWriter {
    fn drop(&mut self) {
        // Best effort: errors here have nowhere to go; `finish` reports them.
        let _ = self.close();
    }
}

/// The error for a write after the file was finished.
fn finished(path: &Path, topic: &str) -> WriteError {
    mcap_error(path, topic, mcap::McapError::AttemptedWriteAfterFailure)
}

/// Wraps an MCAP writer error with the file and topic.
fn mcap_error(path: &Path, topic: &str, source: mcap::McapError) -> WriteError {
    WriteError::Mcap {
        path: path.to_path_buf(),
        topic: topic.to_owned(),
        source,
    }
}

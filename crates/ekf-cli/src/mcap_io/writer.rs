//! Writing ROS 2 bags that Foxglove and the ROS 2 tools open: chunked, indexed, with a
//! summary, one channel per (topic, type) registered on first use.

use super::error::WriteError;
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
    path: PathBuf,
    /// `None` once finished.
    inner: Option<mcap::Writer<BufWriter<File>>>,
    /// Channel id per (topic, type name).
    channels: HashMap<(String, &'static str), u16>,
    /// Sequence number per channel.
    sequences: HashMap<u16, u32>,
}

impl BagWriter {
    /// Creates (or truncates) `path` and writes the MCAP header with profile `ros2`.
    pub fn create(path: impl AsRef<Path>) -> Result<Self, WriteError> {
        let path = path.as_ref().to_path_buf();
        let file = File::create(&path).map_err(|source| WriteError::Create {
            path: path.clone(),
            source,
        })?;
        let inner = mcap::WriteOptions::new()
            .profile(PROFILE)
            .create(BufWriter::new(file))
            .map_err(|source| WriteError::Mcap {
                path: path.clone(),
                topic: String::new(),
                source,
            })?;
        Ok(Self {
            path,
            inner: Some(inner),
            channels: HashMap::new(),
            sequences: HashMap::new(),
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
        let channel_id = self.channel(topic, def)?;
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
    fn channel(&mut self, topic: &str, def: &'static MsgDef) -> Result<u16, WriteError> {
        let key = (topic.to_owned(), def.name);
        if let Some(&id) = self.channels.get(&key) {
            return Ok(id);
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
        self.channels.insert(key, id);
        Ok(id)
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
            })
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

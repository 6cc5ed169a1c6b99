//! A ROS 2 bag directory's `metadata.yaml` (`rosbag2_bagfile_information`): read for the
//! storage files a bag has and their order; written beside the bags `ekf` writes into a
//! directory, in format version 8 (what rosbag2 Iron writes; `ros2 bag info` on Humble
//! and later and the `rosbags` package read it).

use super::error::ReadError;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The file name rosbag2 gives a bag directory's metadata.
pub const METADATA_FILE: &str = "metadata.yaml";

/// The metadata format version written.
const WRITTEN_VERSION: u32 = 8;

/// The top-level key of the file (`T` is [`BagInfo`] when read, a reference when written).
#[derive(Debug, Serialize, Deserialize)]
struct MetadataFile<T> {
    rosbag2_bagfile_information: T,
}

/// The part of the metadata that says where the messages are, and what is written.
#[derive(Debug, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct BagInfo {
    /// Format version.
    pub version: u32,
    /// `sqlite3` or `mcap`.
    pub storage_identifier: String,
    /// The storage files, in recording order, relative to the directory (before version 5,
    /// prefixed with the directory's name).
    pub relative_file_paths: Vec<String>,
    /// Time between the first and the last message.
    pub duration: Duration,
    /// Time of the first message.
    pub starting_time: StartingTime,
    /// Messages in the bag.
    pub message_count: u64,
    /// Each topic with its message count.
    pub topics_with_message_count: Vec<TopicWithCount>,
    /// `""`, or `zstd` for a compressed bag.
    pub compression_format: String,
    /// `""` / `NONE`, `FILE` or `MESSAGE`.
    pub compression_mode: String,
    /// Each storage file with its time span and count.
    pub files: Vec<FileInfo>,
    /// User data; none written.
    pub custom_data: Option<BTreeMap<String, String>>,
    /// The ROS distribution that wrote the bag.
    pub ros_distro: String,
}

/// A duration in nanoseconds.
#[derive(Debug, Default, Clone, Copy, Serialize, Deserialize)]
#[serde(default)]
pub struct Duration {
    /// Nanoseconds.
    pub nanoseconds: u64,
}

/// A time in nanoseconds since the epoch.
#[derive(Debug, Default, Clone, Copy, Serialize, Deserialize)]
#[serde(default)]
pub struct StartingTime {
    /// Nanoseconds since the epoch.
    pub nanoseconds_since_epoch: u64,
}

/// A topic and how many messages it has.
#[derive(Debug, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct TopicWithCount {
    /// The topic.
    pub topic_metadata: TopicMetadata,
    /// Its messages.
    pub message_count: u64,
}

/// A topic's name, type and encoding.
#[derive(Debug, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct TopicMetadata {
    /// Topic name.
    pub name: String,
    /// Message type, e.g. `sensor_msgs/msg/LaserScan`.
    #[serde(rename = "type")]
    pub type_name: String,
    /// `cdr`.
    pub serialization_format: String,
    /// The publishers' QoS profiles: written empty (players then use their default QoS).
    /// Not read: its form changed between versions (YAML text, then a list).
    #[serde(skip_deserializing)]
    pub offered_qos_profiles: String,
    /// The type's RIHS01 hash (version 7 and later); written empty.
    pub type_description_hash: String,
}

/// One storage file's span and count.
#[derive(Debug, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct FileInfo {
    /// Path relative to the directory.
    pub path: String,
    /// Time of its first message.
    pub starting_time: StartingTime,
    /// Time between its first and last message.
    pub duration: Duration,
    /// Its messages.
    pub message_count: u64,
}

/// What a writer knows when it finishes: one storage file, its topics and counts, and the
/// log times of the first and last message.
#[derive(Debug, Clone, Default)]
pub struct WrittenBag {
    /// The storage file's name inside the directory.
    pub file_name: String,
    /// Messages per (topic, type), in registration order.
    pub topics: Vec<(String, String, u64)>,
    /// Log times of the first and last message (ns), if any was written.
    pub span: Option<(u64, u64)>,
}

impl BagInfo {
    /// The metadata of a one-file MCAP bag written by `ekf`.
    pub fn for_written(bag: &WrittenBag) -> Self {
        let (start, end) = bag.span.unwrap_or((0, 0));
        let message_count = bag.topics.iter().map(|t| t.2).sum();
        Self {
            version: WRITTEN_VERSION,
            storage_identifier: "mcap".into(),
            relative_file_paths: vec![bag.file_name.clone()],
            duration: Duration {
                nanoseconds: end - start,
            },
            starting_time: StartingTime {
                nanoseconds_since_epoch: start,
            },
            message_count,
            topics_with_message_count: bag
                .topics
                .iter()
                .map(|(name, type_name, count)| TopicWithCount {
                    topic_metadata: TopicMetadata {
                        name: name.clone(),
                        type_name: type_name.clone(),
                        serialization_format: super::MESSAGE_ENCODING.into(),
                        offered_qos_profiles: String::new(),
                        type_description_hash: String::new(),
                    },
                    message_count: *count,
                })
                .collect(),
            compression_format: String::new(),
            compression_mode: String::new(),
            files: vec![FileInfo {
                path: bag.file_name.clone(),
                starting_time: StartingTime {
                    nanoseconds_since_epoch: start,
                },
                duration: Duration {
                    nanoseconds: end - start,
                },
                message_count,
            }],
            custom_data: None,
            ros_distro: "ekf".into(),
        }
    }

    /// Reads `dir/metadata.yaml`; `Ok(None)` if the directory has none (a recording cut
    /// short before rosbag2 wrote it).
    pub fn read(dir: &Path) -> Result<Option<Self>, ReadError> {
        let path = dir.join(METADATA_FILE);
        let text = match std::fs::read_to_string(&path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(source) => return Err(ReadError::Open { path, source }),
        };
        let file: MetadataFile<BagInfo> =
            serde_saphyr::from_str(&text).map_err(|e| ReadError::Metadata {
                path: path.clone(),
                message: e.to_string(),
            })?;
        Ok(Some(file.rosbag2_bagfile_information))
    }

    /// The storage files of the bag in `dir`, in recording order. Fails for a compressed
    /// bag, which is not read.
    pub fn storage_paths(&self, dir: &Path) -> Result<Vec<PathBuf>, ReadError> {
        let mode = self.compression_mode.to_ascii_lowercase();
        if !(mode.is_empty() || mode == "none") {
            return Err(ReadError::Metadata {
                path: dir.join(METADATA_FILE),
                message: format!(
                    "the bag is compressed ({} per {mode}), which is not read; decompress it \
                     with `ros2 bag convert` (output `compression_mode: none`)",
                    self.compression_format
                ),
            });
        }
        // Early versions wrote paths prefixed with the directory's name; the files are
        // always in the directory itself.
        Ok(self
            .relative_file_paths
            .iter()
            .map(|p| dir.join(Path::new(p).file_name().unwrap_or(p.as_ref())))
            .collect())
    }

    /// Writes this metadata to `dir/metadata.yaml`, through a temporary file renamed into
    /// place so that a reader never sees half a file.
    pub fn write(&self, dir: &Path) -> std::io::Result<()> {
        let text = serde_saphyr::to_string(&MetadataFile {
            rosbag2_bagfile_information: self,
        })
        .map_err(std::io::Error::other)?;
        let tmp = dir.join(format!("{METADATA_FILE}.tmp"));
        std::fs::write(&tmp, text)?;
        std::fs::rename(&tmp, dir.join(METADATA_FILE))
    }
}

//! Reading and writing ROS 2 bags: read in every form `ros2 bag record` writes (MCAP,
//! sqlite3 `.db3`, a bag directory with `metadata.yaml` and one or several split files);
//! written as MCAP (profile `ros2`, schemas `ros2msg`, messages `cdr`), the form Foxglove
//! opens, as one file or as a bag directory with `metadata.yaml`.
//!
//! ```
//! use ekf_ros::mcap_io::{BagReader, BagWriter};
//! use ekf_ros::ros2::{sensor_msgs::LaserScan, std_msgs::Header, builtin_interfaces::Time};
//! # let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("run.mcap");
//! let mut writer = BagWriter::create(&path).unwrap();
//! let scan = LaserScan {
//!     header: Header { stamp: Time { sec: 5, nanosec: 0 }, frame_id: "laser".into() },
//!     ranges: vec![1.0, 2.0],
//!     ..LaserScan::default()
//! };
//! writer.write("/scan", &scan).unwrap(); // log time = header stamp
//! writer.finish().unwrap();
//!
//! let bag = BagReader::open(&path).unwrap();
//! assert_eq!(bag.topics()[0].message_count, 1);
//! for message in bag.messages().unwrap() {
//!     let message = message.unwrap();
//!     let scan: LaserScan = message.decode_as().unwrap();
//!     assert_eq!(message.log_time, 5_000_000_000);
//!     assert_eq!(scan.ranges, [1.0, 2.0]);
//! }
//! ```

mod error;
mod guard;
mod indexed;
mod linear;
mod mcap_file;
mod message;
pub mod metadata;
pub mod reader;
mod recover;
mod resync;
pub mod sniff;
mod source;
mod sqlite;
mod summary;
pub mod writer;

pub use error::{LostRange, MessageError, ReadError, WriteError};
pub use message::{BagMessage, ChannelInfo, TopicInfo};
pub use reader::{BagReader, MessageOrder, Messages};
pub use writer::BagWriter;

/// MCAP profile of ROS 2 bags.
pub const PROFILE: &str = "ros2";
/// Schema encoding of ROS 2 bags.
pub const SCHEMA_ENCODING: &str = "ros2msg";
/// Message encoding of ROS 2 bags.
pub const MESSAGE_ENCODING: &str = "cdr";

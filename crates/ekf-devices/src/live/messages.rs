//! Raw device readings as the ROS 2 messages of docs/ARCHITECTURE.md §4, and as the bag messages
//! the filter loop takes: what is recorded is exactly what is fused.

use crate::devices::modbus_base::WheelTicks;
use crate::devices::sick::measured::{range_max, scan_angles};
use crate::devices::sick::{RangeUnit, Variant};
use ekf_ros::config::Config;
use ekf_ros::mcap_io::{ChannelInfo, WriteError};
use ekf_ros::mcap_io::{MESSAGE_ENCODING, SCHEMA_ENCODING};
use ekf_ros::replay::outputs::OutputBag;
use ekf_ros::ros2::builtin_interfaces::Time;
use ekf_ros::ros2::geometry_msgs::{Quaternion, Transform, TransformStamped, Vector3};
use ekf_ros::ros2::sensor_msgs::{JointState, LaserScan, MagneticField};
use ekf_ros::ros2::std_msgs::Header;
use ekf_ros::ros2::tf2_msgs::TFMessage;
use ekf_ros::ros2::{RosMessage, Stamped};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// Horizontal field strength given to a compass bearing recorded as a magnetic field
/// (T): the CMPS03 reports only a bearing, so the magnitude is nominal.
pub const NOMINAL_FIELD_T: f64 = 2.0e-5;

fn header(t_ns: u64, frame_id: &str) -> Header {
    Header {
        stamp: Time::from_nanos(t_ns).unwrap_or_default(),
        frame_id: frame_id.into(),
    }
}

/// `/tf_static`: the laser's mount on the base, from the configuration.
pub fn laser_transform(config: &Config, t_ns: u64) -> TFMessage {
    let m = &config.localizer.laser_mount;
    TFMessage {
        transforms: vec![TransformStamped {
            header: header(t_ns, &config.laser.base_frame),
            child_frame_id: config.devices.laser_frame.clone(),
            transform: Transform {
                translation: Vector3 {
                    x: m.x,
                    y: m.y,
                    z: 0.0,
                },
                rotation: Quaternion::from_yaw(m.theta),
            },
        }],
    }
}

/// A scan of `variant` with ranges in metres.
pub fn laser_scan(
    config: &Config,
    variant: Variant,
    unit: RangeUnit,
    t_ns: u64,
    ranges: Vec<f32>,
) -> LaserScan {
    let (angle_min, angle_max, angle_increment) = scan_angles(variant);
    LaserScan {
        header: header(t_ns, &config.devices.laser_frame),
        angle_min,
        angle_max,
        angle_increment,
        time_increment: 0.0,
        scan_time: 0.0,
        range_min: unit.metres() as f32,
        range_max: range_max(unit),
        ranges,
        intensities: Vec::new(),
    }
}

/// The wheel positions (rad) of the configured joints.
pub fn joint_state(config: &Config, t_ns: u64, ticks: WheelTicks) -> JointState {
    let rad_per_tick = std::f64::consts::TAU / config.devices.ticks_per_revolution;
    JointState {
        header: header(t_ns, &config.laser.base_frame),
        name: vec![
            config.motion.left_joint.clone(),
            config.motion.right_joint.clone(),
        ],
        position: vec![
            ticks.left as f64 * rad_per_tick,
            ticks.right as f64 * rad_per_tick,
        ],
        velocity: Vec::new(),
        effort: Vec::new(),
    }
}

/// A compass bearing (rad, clockwise from magnetic north) as the horizontal field in
/// the robot frame: `bearing = atan2(m_y, m_x)`, as the replay reads it.
pub fn compass(config: &Config, t_ns: u64, bearing: f64) -> MagneticField {
    MagneticField {
        header: header(t_ns, &config.laser.base_frame),
        magnetic_field: Vector3 {
            x: NOMINAL_FIELD_T * bearing.cos(),
            y: NOMINAL_FIELD_T * bearing.sin(),
            z: 0.0,
        },
        magnetic_field_covariance: [0.0; 9],
    }
}

/// Records messages (when recording) and names their channel, one per topic, for the
/// filter loop, which takes each message as it is made.
pub struct Recorder {
    path: Arc<Path>,
    channels: HashMap<String, Arc<ChannelInfo>>,
}

impl Recorder {
    /// A recorder whose bag messages name `path` (the recording, or `live`).
    pub fn new(path: &Path) -> Self {
        Self {
            path: Arc::from(path),
            channels: HashMap::new(),
        }
    }

    /// Records `message` on `topic` at its header stamp (encoding it only if `out` is a
    /// bag to write) and returns where it was recorded, for the filter loop that takes the
    /// message as it is ([`ekf_ros::replay`]'s `Run::handle_decoded`).
    pub fn record<M: RosMessage + Stamped>(
        &mut self,
        out: Option<&mut OutputBag>,
        topic: &str,
        message: &M,
    ) -> Result<Recorded, WriteError> {
        let t_ns = message.header().stamp.to_nanos().unwrap_or(0);
        self.record_at(out, topic, t_ns, message)
    }

    /// As [`Self::record`], at `t_ns` (messages without a header).
    pub fn record_at<M: RosMessage>(
        &mut self,
        out: Option<&mut OutputBag>,
        topic: &str,
        t_ns: u64,
        message: &M,
    ) -> Result<Recorded, WriteError> {
        if let Some(out) = out {
            out.writer().write_at(topic, t_ns, message)?;
        }
        let path = Arc::clone(&self.path);
        let channel = self
            .channels
            .entry(topic.to_owned())
            .or_insert_with(|| {
                Arc::new(ChannelInfo {
                    path,
                    topic: topic.into(),
                    type_name: M::DEF.name.into(),
                    schema_encoding: SCHEMA_ENCODING.into(),
                    message_encoding: MESSAGE_ENCODING.into(),
                })
            })
            .clone();
        Ok(Recorded {
            channel,
            log_time: t_ns,
        })
    }
}

/// Where a message was recorded: its channel and log time.
#[derive(Debug, Clone)]
pub struct Recorded {
    /// The channel (topic and type).
    pub channel: Arc<ChannelInfo>,
    /// The log time (ns): the message's header stamp.
    pub log_time: u64,
}

//! The stamp an input is fused at: its header's, read from the CDR bytes without decoding
//! the message, or its log time.
//!
//! A bag is in log-time order, the time each message reached the recorder; a busy robot
//! computer logs a scan a few hundred milliseconds after the laser took it (its header
//! stamp). Replay hands every input to the time-ordered localizer
//! ([`ekf_fusion::TimedLocalizer`]) with this stamp, which fuses them in stamp order; its
//! warnings still name the log time.
//!
//! The stamp is the header's for the message types with a `std_msgs/Header` first (all
//! the inputs replay fuses), the log time for the others and for a zero header stamp.

use crate::mcap_io::BagMessage;
use crate::ros2::type_name_matches;

/// Message types whose CDR form starts with a `std_msgs/Header`.
const HEADER_FIRST: [&str; 8] = [
    "nav_msgs/msg/Odometry",
    "sensor_msgs/msg/JointState",
    "sensor_msgs/msg/LaserScan",
    "sensor_msgs/msg/Imu",
    "sensor_msgs/msg/MagneticField",
    "sensor_msgs/msg/NavSatFix",
    "geometry_msgs/msg/PoseStamped",
    "geometry_msgs/msg/PoseWithCovarianceStamped",
];

/// The header stamp (ns) of a CDR message whose type starts with a `std_msgs/Header`:
/// after the 4-byte encapsulation header (byte 1: 1 little-endian, 0 big-endian), the
/// `int32 sec` and `uint32 nanosec` of `header.stamp`. `None` if the data is too short,
/// the seconds are negative or the stamp is 0.
pub fn header_stamp(data: &[u8]) -> Option<u64> {
    let little = match data.get(1)? {
        1 => true,
        0 => false,
        _ => return None,
    };
    let word = |at: usize| -> Option<[u8; 4]> { data.get(at..at + 4)?.try_into().ok() };
    let (sec, nanosec) = if little {
        (i32::from_le_bytes(word(4)?), u32::from_le_bytes(word(8)?))
    } else {
        (i32::from_be_bytes(word(4)?), u32::from_be_bytes(word(8)?))
    };
    let ns = u64::try_from(sec).ok()? * 1_000_000_000 + u64::from(nanosec);
    (ns > 0).then_some(ns)
}

/// The time a message is fused at: its header stamp when its type has one
/// (the inputs replay fuses: odometry, joint states, scans, Imu, MagneticField,
/// NavSatFix, poses) and it is set, else its log time.
pub fn stamp_of(message: &BagMessage) -> u64 {
    let typed = HEADER_FIRST
        .iter()
        .any(|t| type_name_matches(t, &message.channel.type_name));
    typed
        .then(|| header_stamp(&message.data))
        .flatten()
        .unwrap_or(message.log_time)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mcap_io::ChannelInfo;
    use std::sync::Arc;

    /// A LaserScan-typed message logged at `log_ms` with header stamp `stamp_ms`.
    fn scan(log_ms: u64, stamp_ms: u64) -> BagMessage {
        let ns = stamp_ms * 1_000_000;
        let mut data = vec![0, 1, 0, 0];
        data.extend_from_slice(&((ns / 1_000_000_000) as i32).to_le_bytes());
        data.extend_from_slice(&((ns % 1_000_000_000) as u32).to_le_bytes());
        BagMessage {
            channel: Arc::new(ChannelInfo {
                path: Arc::from(std::path::Path::new("test.mcap")),
                topic: "/scan".into(),
                type_name: "sensor_msgs/msg/LaserScan".into(),
                schema_encoding: "ros2msg".into(),
                message_encoding: "cdr".into(),
            }),
            index: 0,
            log_time: log_ms * 1_000_000,
            publish_time: log_ms * 1_000_000,
            data,
        }
    }

    #[test]
    fn the_header_stamp_is_read_in_either_byte_order() {
        let mut big = vec![0, 0, 0, 0];
        big.extend_from_slice(&12i32.to_be_bytes());
        big.extend_from_slice(&5u32.to_be_bytes());
        assert_eq!(header_stamp(&big), Some(12_000_000_005));
        assert_eq!(header_stamp(&scan(0, 1500).data), Some(1_500_000_000));
        assert_eq!(header_stamp(&[0, 1, 0, 0, 1]), None, "too short");
        let mut negative = vec![0, 1, 0, 0];
        negative.extend_from_slice(&(-1i32).to_le_bytes());
        negative.extend_from_slice(&0u32.to_le_bytes());
        assert_eq!(header_stamp(&negative), None);
    }
}

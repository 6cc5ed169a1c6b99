//! Measurements fused at their own stamps: a fixed-lag reordering of the log by header
//! stamp.
//!
//! A bag is in log-time order, the time each message reached the recorder. A busy robot
//! computer logs a scan a few hundred milliseconds after the laser took it (its header
//! stamp), after odometry that came later; fused in log order, the scan would meet a
//! state that has moved on. So replay holds each message back until no message stamped
//! before it can still arrive — until a message stamped `max_lag` later has been read —
//! and hands them to the filter in stamp order, each at its stamp (warnings still name
//! the log time). The state then reaches
//! every measurement's stamp by prediction alone, the same estimate robot_localization's
//! rewind-and-re-predict (`smooth_lagged_data`) gives, without a state history. A message
//! stamped before one already handed on arrived more than `max_lag` after a later one: it
//! is too late, dropped and counted. What is held is at most `max_lag` of the log.
//!
//! The stamp is the header's for the message types with a `std_msgs/Header` first (all
//! the inputs replay fuses), the log time for the others and for a zero header stamp.

use crate::mcap_io::BagMessage;
use crate::ros2::type_name_matches;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

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

/// A held message: ordered by stamp, then by the order it was read.
struct Held {
    stamp: u64,
    order: u64,
    message: BagMessage,
}

impl PartialEq for Held {
    fn eq(&self, other: &Self) -> bool {
        (self.stamp, self.order) == (other.stamp, other.order)
    }
}

impl Eq for Held {}

impl PartialOrd for Held {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Held {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        (self.stamp, self.order).cmp(&(other.stamp, other.order))
    }
}

/// The reordering buffer (see the module documentation).
pub struct Reorder {
    lag_ns: u64,
    held: BinaryHeap<Reverse<Held>>,
    read: u64,
    /// Latest stamp read.
    newest: u64,
    /// Stamp of the last message handed on.
    released: Option<u64>,
}

/// What [`Reorder::push`] did with a message that came too late.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TooLate {
    /// Its topic.
    pub topic: String,
    /// Its log time (ns).
    pub log_time: u64,
    /// Its stamp (ns).
    pub stamp: u64,
    /// The stamp of the message handed on before it came (ns).
    pub after: u64,
}

impl Reorder {
    /// A buffer holding messages back by `lag_ns`.
    pub fn new(lag_ns: u64) -> Self {
        Self {
            lag_ns,
            held: BinaryHeap::new(),
            read: 0,
            newest: 0,
            released: None,
        }
    }

    /// Takes a message; refuses it if a message stamped after it was handed on already
    /// (it came more than the lag late, too late to be fused in order).
    pub fn push(&mut self, message: BagMessage) -> Result<(), TooLate> {
        let stamp = stamp_of(&message);
        if let Some(after) = self.released.filter(|&r| stamp < r) {
            return Err(TooLate {
                topic: message.topic().to_owned(),
                log_time: message.log_time,
                stamp,
                after,
            });
        }
        self.newest = self.newest.max(stamp);
        self.held.push(Reverse(Held {
            stamp,
            order: self.read,
            message,
        }));
        self.read += 1;
        Ok(())
    }

    /// The next message whose turn has come, with its stamp ([`stamp_of`]): the earliest
    /// stamp, once a message stamped at least the lag after it has been read.
    pub fn pop_ready(&mut self) -> Option<(u64, BagMessage)> {
        let Reverse(first) = self.held.peek()?;
        if first.stamp.saturating_add(self.lag_ns) > self.newest {
            return None;
        }
        self.pop()
    }

    /// The next message with its stamp, regardless of the lag (at the end of the log).
    pub fn pop(&mut self) -> Option<(u64, BagMessage)> {
        let Reverse(first) = self.held.pop()?;
        self.released = Some(first.stamp);
        Some((first.stamp, first.message))
    }
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

    #[test]
    fn late_messages_come_out_in_stamp_order_at_their_stamps() {
        let mut r = Reorder::new(500_000_000);
        // Logged in this order; the 1000 ms one 350 ms late.
        for (log, stamp) in [(1100, 1100), (1200, 1200), (1350, 1000), (1400, 1400)] {
            r.push(scan(log, stamp)).unwrap();
        }
        assert_eq!(r.pop_ready().map(|m| m.0), None, "1400 - 1000 < 500");
        r.push(scan(1500, 1500)).unwrap();
        let (stamp, first) = r.pop_ready().unwrap();
        assert_eq!((stamp, first.log_time), (1_000_000_000, 1_350_000_000));
        assert_eq!(r.pop_ready().map(|m| m.0), None);
        let rest: Vec<u64> = std::iter::from_fn(|| r.pop())
            .map(|(stamp, _)| stamp / 1_000_000)
            .collect();
        assert_eq!(rest, [1100, 1200, 1400, 1500]);
    }

    #[test]
    fn a_message_older_than_what_was_handed_on_is_refused() {
        let mut r = Reorder::new(100_000_000);
        r.push(scan(1000, 1000)).unwrap();
        r.push(scan(1200, 1200)).unwrap();
        assert!(r.pop_ready().is_some());
        let late = r.push(scan(1300, 900)).unwrap_err();
        assert_eq!(
            late,
            TooLate {
                topic: "/scan".into(),
                log_time: 1_300_000_000,
                stamp: 900_000_000,
                after: 1_000_000_000,
            }
        );
        assert!(
            r.push(scan(1300, 1000)).is_ok(),
            "the same stamp is not late"
        );
    }
}

//! `builtin_interfaces`: the ROS 2 time types every stamped message carries.

use super::schema::MsgDef;
use super::RosMessage;
use serde::{Deserialize, Serialize};

/// `builtin_interfaces/msg/Time`: a point in time as seconds and nanoseconds since the epoch.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Time {
    /// Whole seconds (may be negative on the wire; ROS clocks never are).
    pub sec: i32,
    /// Nanoseconds within the second, `0..1_000_000_000`.
    pub nanosec: u32,
}

impl Time {
    /// The time `ns` nanoseconds after the epoch; `None` if the seconds overflow `i32`.
    pub fn from_nanos(ns: u64) -> Option<Self> {
        let sec = i32::try_from(ns / 1_000_000_000).ok()?;
        Some(Self {
            sec,
            nanosec: (ns % 1_000_000_000) as u32,
        })
    }

    /// Nanoseconds since the epoch; `None` for negative times.
    pub fn to_nanos(self) -> Option<u64> {
        let sec = u64::try_from(self.sec).ok()?;
        Some(sec * 1_000_000_000 + u64::from(self.nanosec))
    }
}

/// `builtin_interfaces/msg/Duration`: a signed span of seconds and nanoseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Duration {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds added to `sec`, `0..1_000_000_000`.
    pub nanosec: u32,
}

/// Definition of `builtin_interfaces/msg/Time`.
pub const TIME: MsgDef = MsgDef {
    name: "builtin_interfaces/msg/Time",
    text: "int32 sec\nuint32 nanosec\n",
    deps: &[],
};

/// Definition of `builtin_interfaces/msg/Duration`.
pub const DURATION: MsgDef = MsgDef {
    name: "builtin_interfaces/msg/Duration",
    text: "int32 sec\nuint32 nanosec\n",
    deps: &[],
};

impl RosMessage for Time {
    const DEF: &'static MsgDef = &TIME;
}

impl RosMessage for Duration {
    const DEF: &'static MsgDef = &DURATION;
}

//! `diagnostic_msgs`: per-update health reports (gate counts, innovations) as key/values.

use super::cdr::string;
use super::schema::MsgDef;
use super::std_msgs::{Header, HEADER};
use super::RosMessage;
use serde::{Deserialize, Serialize};

/// `diagnostic_msgs/msg/KeyValue`: one named value, as text.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct KeyValue {
    /// Name of the value.
    #[serde(with = "string")]
    pub key: String,
    /// The value, formatted as text.
    #[serde(with = "string")]
    pub value: String,
}

/// `diagnostic_msgs/msg/DiagnosticStatus`: the health of one component.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct DiagnosticStatus {
    /// One of [`Self::OK`], [`Self::WARN`], [`Self::ERROR`], [`Self::STALE`].
    pub level: u8,
    /// Component name.
    #[serde(with = "string")]
    pub name: String,
    /// Human-readable summary.
    #[serde(with = "string")]
    pub message: String,
    /// Hardware identifier.
    #[serde(with = "string")]
    pub hardware_id: String,
    /// Details.
    pub values: Vec<KeyValue>,
}

impl DiagnosticStatus {
    /// All is well.
    pub const OK: u8 = 0;
    /// Degraded.
    pub const WARN: u8 = 1;
    /// Failed.
    pub const ERROR: u8 = 2;
    /// No recent data.
    pub const STALE: u8 = 3;
}

/// `diagnostic_msgs/msg/DiagnosticArray`: the statuses reported at one time.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct DiagnosticArray {
    /// Time of the report.
    pub header: Header,
    /// One status per component.
    pub status: Vec<DiagnosticStatus>,
}

/// Definition of `diagnostic_msgs/msg/KeyValue`.
pub const KEY_VALUE: MsgDef = MsgDef {
    name: "diagnostic_msgs/msg/KeyValue",
    text: "string key\nstring value\n",
    deps: &[],
};

/// Definition of `diagnostic_msgs/msg/DiagnosticStatus`.
pub const DIAGNOSTIC_STATUS: MsgDef = MsgDef {
    name: "diagnostic_msgs/msg/DiagnosticStatus",
    text: "byte OK=0\nbyte WARN=1\nbyte ERROR=2\nbyte STALE=3\nbyte level\nstring name\n\
           string message\nstring hardware_id\ndiagnostic_msgs/KeyValue[] values\n",
    deps: &[&KEY_VALUE],
};

/// Definition of `diagnostic_msgs/msg/DiagnosticArray`.
pub const DIAGNOSTIC_ARRAY: MsgDef = MsgDef {
    name: "diagnostic_msgs/msg/DiagnosticArray",
    text: "std_msgs/Header header\ndiagnostic_msgs/DiagnosticStatus[] status\n",
    deps: &[&HEADER, &DIAGNOSTIC_STATUS],
};

impl RosMessage for KeyValue {
    const DEF: &'static MsgDef = &KEY_VALUE;
}
impl RosMessage for DiagnosticStatus {
    const DEF: &'static MsgDef = &DIAGNOSTIC_STATUS;
}
impl RosMessage for DiagnosticArray {
    const DEF: &'static MsgDef = &DIAGNOSTIC_ARRAY;
}

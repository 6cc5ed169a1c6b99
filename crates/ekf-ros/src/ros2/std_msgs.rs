//! `std_msgs`: the message header and colours shared by the other message families.

use super::builtin_interfaces::{Time, TIME};
use super::cdr::string;
use super::schema::MsgDef;
use super::RosMessage;
use serde::{Deserialize, Serialize};

/// `std_msgs/msg/Header`: when and in which frame the data was taken.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// Acquisition time.
    pub stamp: Time,
    /// Coordinate frame the data is expressed in.
    #[serde(with = "string")]
    pub frame_id: String,
}

/// `std_msgs/msg/ColorRGBA`: a colour with components in `[0, 1]`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ColorRGBA {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
    /// Opacity.
    pub a: f32,
}

/// Definition of `std_msgs/msg/Header`.
pub const HEADER: MsgDef = MsgDef {
    name: "std_msgs/msg/Header",
    text: "builtin_interfaces/Time stamp\nstring frame_id\n",
    deps: &[&TIME],
};

/// Definition of `std_msgs/msg/ColorRGBA`.
pub const COLOR_RGBA: MsgDef = MsgDef {
    name: "std_msgs/msg/ColorRGBA",
    text: "float32 r\nfloat32 g\nfloat32 b\nfloat32 a\n",
    deps: &[],
};

impl RosMessage for Header {
    const DEF: &'static MsgDef = &HEADER;
}

impl RosMessage for ColorRGBA {
    const DEF: &'static MsgDef = &COLOR_RGBA;
}

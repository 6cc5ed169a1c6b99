//! `tf2_msgs`: the `/tf` message, a batch of frame transforms.

use super::geometry_msgs::{TransformStamped, TRANSFORM_STAMPED};
use super::schema::MsgDef;
use super::RosMessage;
use serde::{Deserialize, Serialize};

/// `tf2_msgs/msg/TFMessage`: transforms published together on `/tf` or `/tf_static`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TFMessage {
    /// The transforms, each with its own stamp.
    pub transforms: Vec<TransformStamped>,
}

/// Definition of `tf2_msgs/msg/TFMessage`.
pub const TF_MESSAGE: MsgDef = MsgDef {
    name: "tf2_msgs/msg/TFMessage",
    text: "geometry_msgs/TransformStamped[] transforms\n",
    deps: &[&TRANSFORM_STAMPED],
};

impl RosMessage for TFMessage {
    const DEF: &'static MsgDef = &TF_MESSAGE;
}

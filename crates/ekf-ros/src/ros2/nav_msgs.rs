//! `nav_msgs`: odometry, the alternative motion source and a common reference trajectory.

use super::cdr::string;
use super::geometry_msgs::{
    PoseWithCovariance, TwistWithCovariance, POSE_WITH_COVARIANCE, TWIST_WITH_COVARIANCE,
};
use super::schema::MsgDef;
use super::std_msgs::{Header, HEADER};
use super::RosMessage;
use serde::{Deserialize, Serialize};

/// `nav_msgs/msg/Odometry`: pose in `header.frame_id`, twist in `child_frame_id`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Odometry {
    /// Time and the frame of the pose.
    pub header: Header,
    /// The frame of the twist (usually the robot base).
    #[serde(with = "string")]
    pub child_frame_id: String,
    /// Pose estimate with covariance.
    pub pose: PoseWithCovariance,
    /// Velocity estimate with covariance.
    pub twist: TwistWithCovariance,
}

/// Definition of `nav_msgs/msg/Odometry`.
pub const ODOMETRY: MsgDef = MsgDef {
    name: "nav_msgs/msg/Odometry",
    text: "std_msgs/Header header\nstring child_frame_id\n\
           geometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist\n",
    deps: &[&HEADER, &POSE_WITH_COVARIANCE, &TWIST_WITH_COVARIANCE],
};

impl RosMessage for Odometry {
    const DEF: &'static MsgDef = &ODOMETRY;
}

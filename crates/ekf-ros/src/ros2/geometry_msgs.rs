//! `geometry_msgs`: points, orientations, poses, velocities and transforms, with the
//! 6×6 covariances (row-major, order x, y, z, rot x, rot y, rot z) ROS attaches to them.

use super::cdr::string;
use super::schema::MsgDef;
use super::std_msgs::{Header, HEADER};
use super::RosMessage;
use serde::{Deserialize, Serialize};
use serde_big_array::BigArray;

/// `geometry_msgs/msg/Point`: a position (m).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Point {
    /// x (m).
    pub x: f64,
    /// y (m).
    pub y: f64,
    /// z (m).
    pub z: f64,
}

/// `geometry_msgs/msg/Vector3`: a free vector (velocity, acceleration, field…).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x component.
    pub x: f64,
    /// y component.
    pub y: f64,
    /// z component.
    pub z: f64,
}

/// `geometry_msgs/msg/Quaternion`: an orientation; the default is the identity, as in ROS.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w (scalar part).
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Self::from_yaw(0.0)
    }
}

impl Quaternion {
    /// The rotation by `yaw` (rad, counter-clockwise) about z.
    pub fn from_yaw(yaw: f64) -> Self {
        let (s, c) = (yaw / 2.0).sin_cos();
        Self {
            x: 0.0,
            y: 0.0,
            z: s,
            w: c,
        }
    }

    /// The yaw (rad, counter-clockwise about z, in (−π, π]) of this orientation (ZYX
    /// order), `atan2(2(wz + xy), w² + x² − y² − z²)`: right for quaternions that are not
    /// exactly unit length too, since the ratio does not change with the scale. Components
    /// so large that their squares overflow (1e300) are divided by the largest first. NaN
    /// for a quaternion with a non-finite component or of (near) zero norm, which is no
    /// orientation at all (callers refuse non-finite yaws).
    pub fn yaw(&self) -> f64 {
        let q = [self.w, self.x, self.y, self.z];
        if !q.iter().all(|c| c.is_finite()) {
            return f64::NAN;
        }
        let norm2: f64 = q.iter().map(|c| c * c).sum();
        let scale = if norm2.is_finite() {
            1.0
        } else {
            q.iter().fold(0.0_f64, |m, c| m.max(c.abs()))
        };
        if norm2 <= 1e-12 {
            return f64::NAN;
        }
        let [w, x, y, z] = q.map(|c| c / scale);
        (2.0 * (w * z + x * y)).atan2(w * w + x * x - y * y - z * z)
    }
}

/// `geometry_msgs/msg/Pose`: position and orientation.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Position (m).
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

/// `geometry_msgs/msg/PoseStamped`: a pose with time and frame.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseStamped {
    /// Time and frame.
    pub header: Header,
    /// The pose.
    pub pose: Pose,
}

/// `geometry_msgs/msg/PoseWithCovariance`: a pose and its 6×6 covariance.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PoseWithCovariance {
    /// The pose.
    pub pose: Pose,
    /// Row-major 6×6 covariance of (x, y, z, rot x, rot y, rot z).
    #[serde(with = "BigArray")]
    pub covariance: [f64; 36],
}

impl Default for PoseWithCovariance {
    fn default() -> Self {
        Self {
            pose: Pose::default(),
            covariance: [0.0; 36],
        }
    }
}

/// `geometry_msgs/msg/PoseWithCovarianceStamped`: what a localizer publishes.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseWithCovarianceStamped {
    /// Time and frame.
    pub header: Header,
    /// Pose and covariance.
    pub pose: PoseWithCovariance,
}

/// `geometry_msgs/msg/Twist`: linear (m/s) and angular (rad/s) velocity.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Twist {
    /// Linear velocity (m/s).
    pub linear: Vector3,
    /// Angular velocity (rad/s).
    pub angular: Vector3,
}

/// `geometry_msgs/msg/TwistWithCovariance`: a twist and its 6×6 covariance.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TwistWithCovariance {
    /// The twist.
    pub twist: Twist,
    /// Row-major 6×6 covariance of (vx, vy, vz, wx, wy, wz).
    #[serde(with = "BigArray")]
    pub covariance: [f64; 36],
}

impl Default for TwistWithCovariance {
    fn default() -> Self {
        Self {
            twist: Twist::default(),
            covariance: [0.0; 36],
        }
    }
}

/// `geometry_msgs/msg/Transform`: a translation and rotation between two frames.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    /// Translation (m).
    pub translation: Vector3,
    /// Rotation.
    pub rotation: Quaternion,
}

/// `geometry_msgs/msg/TransformStamped`: the pose of `child_frame_id` in `header.frame_id`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TransformStamped {
    /// Time and parent frame.
    pub header: Header,
    /// The frame being located.
    #[serde(with = "string")]
    pub child_frame_id: String,
    /// The transform from the child to the parent frame.
    pub transform: Transform,
}

/// Definition of `geometry_msgs/msg/Point`.
pub const POINT: MsgDef = MsgDef {
    name: "geometry_msgs/msg/Point",
    text: "float64 x\nfloat64 y\nfloat64 z\n",
    deps: &[],
};

/// Definition of `geometry_msgs/msg/Vector3`.
pub const VECTOR3: MsgDef = MsgDef {
    name: "geometry_msgs/msg/Vector3",
    text: "float64 x\nfloat64 y\nfloat64 z\n",
    deps: &[],
};

/// Definition of `geometry_msgs/msg/Quaternion` (with the ROS 2 defaults).
pub const QUATERNION: MsgDef = MsgDef {
    name: "geometry_msgs/msg/Quaternion",
    text: "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    deps: &[],
};

/// Definition of `geometry_msgs/msg/Pose`.
pub const POSE: MsgDef = MsgDef {
    name: "geometry_msgs/msg/Pose",
    text: "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n",
    deps: &[&POINT, &QUATERNION],
};

/// Definition of `geometry_msgs/msg/PoseStamped`.
pub const POSE_STAMPED: MsgDef = MsgDef {
    name: "geometry_msgs/msg/PoseStamped",
    text: "std_msgs/Header header\ngeometry_msgs/Pose pose\n",
    deps: &[&HEADER, &POSE],
};

/// Definition of `geometry_msgs/msg/PoseWithCovariance`.
pub const POSE_WITH_COVARIANCE: MsgDef = MsgDef {
    name: "geometry_msgs/msg/PoseWithCovariance",
    text: "geometry_msgs/Pose pose\nfloat64[36] covariance\n",
    deps: &[&POSE],
};

/// Definition of `geometry_msgs/msg/PoseWithCovarianceStamped`.
pub const POSE_WITH_COVARIANCE_STAMPED: MsgDef = MsgDef {
    name: "geometry_msgs/msg/PoseWithCovarianceStamped",
    text: "std_msgs/Header header\ngeometry_msgs/PoseWithCovariance pose\n",
    deps: &[&HEADER, &POSE_WITH_COVARIANCE],
};

/// Definition of `geometry_msgs/msg/Twist`.
pub const TWIST: MsgDef = MsgDef {
    name: "geometry_msgs/msg/Twist",
    text: "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n",
    deps: &[&VECTOR3],
};

/// Definition of `geometry_msgs/msg/TwistWithCovariance`.
pub const TWIST_WITH_COVARIANCE: MsgDef = MsgDef {
    name: "geometry_msgs/msg/TwistWithCovariance",
    text: "geometry_msgs/Twist twist\nfloat64[36] covariance\n",
    deps: &[&TWIST],
};

/// Definition of `geometry_msgs/msg/Transform`.
pub const TRANSFORM: MsgDef = MsgDef {
    name: "geometry_msgs/msg/Transform",
    text: "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n",
    deps: &[&VECTOR3, &QUATERNION],
};

/// Definition of `geometry_msgs/msg/TransformStamped`.
pub const TRANSFORM_STAMPED: MsgDef = MsgDef {
    name: "geometry_msgs/msg/TransformStamped",
    text: "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n",
    deps: &[&HEADER, &TRANSFORM],
};

impl RosMessage for Point {
    const DEF: &'static MsgDef = &POINT;
}
impl RosMessage for Vector3 {
    const DEF: &'static MsgDef = &VECTOR3;
}
impl RosMessage for Quaternion {
    const DEF: &'static MsgDef = &QUATERNION;
}
impl RosMessage for Pose {
    const DEF: &'static MsgDef = &POSE;
}
impl RosMessage for PoseStamped {
    const DEF: &'static MsgDef = &POSE_STAMPED;
}
impl RosMessage for PoseWithCovariance {
    const DEF: &'static MsgDef = &POSE_WITH_COVARIANCE;
}
impl RosMessage for PoseWithCovarianceStamped {
    const DEF: &'static MsgDef = &POSE_WITH_COVARIANCE_STAMPED;
}
impl RosMessage for Twist {
    const DEF: &'static MsgDef = &TWIST;
}
impl RosMessage for TwistWithCovariance {
    const DEF: &'static MsgDef = &TWIST_WITH_COVARIANCE;
}
impl RosMessage for Transform {
    const DEF: &'static MsgDef = &TRANSFORM;
}
impl RosMessage for TransformStamped {
    const DEF: &'static MsgDef = &TRANSFORM_STAMPED;
}

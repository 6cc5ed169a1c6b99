//! `sensor_msgs`: wheel joints, laser scans, the compass (IMU or magnetometer), GPS fixes
//! and the compressed image a marker texture carries.

use super::cdr::string;
use super::geometry_msgs::{Quaternion, Vector3, QUATERNION, VECTOR3};
use super::schema::MsgDef;
use super::std_msgs::{Header, HEADER};
use super::RosMessage;
use serde::{Deserialize, Serialize};

/// `sensor_msgs/msg/JointState`: per-joint position (rad), velocity (rad/s) and effort;
/// the arrays are either empty or as long as `name`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct JointState {
    /// Time of the reading.
    pub header: Header,
    /// Joint names.
    #[serde(with = "string::seq")]
    pub name: Vec<String>,
    /// Joint positions (rad or m).
    pub position: Vec<f64>,
    /// Joint velocities (rad/s or m/s).
    pub velocity: Vec<f64>,
    /// Joint efforts (N·m or N).
    pub effort: Vec<f64>,
}

/// `sensor_msgs/msg/LaserScan`: one sweep of a planar laser, beams counter-clockwise from
/// `angle_min` in the sensor frame.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct LaserScan {
    /// Time of the first beam and the sensor frame.
    pub header: Header,
    /// Bearing of the first beam (rad).
    pub angle_min: f32,
    /// Bearing of the last beam (rad).
    pub angle_max: f32,
    /// Angle between beams (rad).
    pub angle_increment: f32,
    /// Time between beams (s).
    pub time_increment: f32,
    /// Time between scans (s).
    pub scan_time: f32,
    /// Smallest valid range (m).
    pub range_min: f32,
    /// Largest valid range (m).
    pub range_max: f32,
    /// Ranges (m); values outside `[range_min, range_max]` are invalid.
    pub ranges: Vec<f32>,
    /// Intensities (device units), empty or one per range.
    pub intensities: Vec<f32>,
}

impl LaserScan {
    /// This scan as the borrowed [`lrf_lines::LaserScan`] the line extractor takes.
    pub fn as_scan(&self) -> lrf_lines::LaserScan<'_> {
        lrf_lines::LaserScan {
            angle_min: f64::from(self.angle_min),
            angle_increment: f64::from(self.angle_increment),
            range_min: f64::from(self.range_min),
            range_max: f64::from(self.range_max),
            ranges: &self.ranges,
        }
    }

    /// This scan as the owned scan the time-ordered localizer holds
    /// ([`ekf_fusion::Input::Scan`]), the same beam geometry as [`as_scan`](Self::as_scan).
    pub fn into_scan(self) -> ekf_fusion::Scan {
        ekf_fusion::Scan {
            angle_min: f64::from(self.angle_min),
            angle_increment: f64::from(self.angle_increment),
            range_min: f64::from(self.range_min),
            range_max: f64::from(self.range_max),
            ranges: self.ranges,
        }
    }
}

/// `sensor_msgs/msg/Imu`: orientation, angular velocity and linear acceleration, each with a
/// row-major 3×3 covariance; a covariance starting with −1 means "not provided".
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Imu {
    /// Time and sensor frame.
    pub header: Header,
    /// Orientation (ENU for a compass).
    pub orientation: Quaternion,
    /// Covariance of the orientation about x, y, z (rad²).
    pub orientation_covariance: [f64; 9],
    /// Angular velocity (rad/s).
    pub angular_velocity: Vector3,
    /// Covariance of the angular velocity.
    pub angular_velocity_covariance: [f64; 9],
    /// Linear acceleration (m/s²).
    pub linear_acceleration: Vector3,
    /// Covariance of the linear acceleration.
    pub linear_acceleration_covariance: [f64; 9],
}

/// `sensor_msgs/msg/MagneticField`: the magnetic field vector (T) in the sensor frame.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MagneticField {
    /// Time and sensor frame.
    pub header: Header,
    /// Field (T).
    pub magnetic_field: Vector3,
    /// Row-major 3×3 covariance (T²); all zero means unknown.
    pub magnetic_field_covariance: [f64; 9],
}

/// `sensor_msgs/msg/NavSatStatus`: fix quality and which satellite systems were used.
/// Constants as in Humble and Jazzy; later distributions add `STATUS_UNKNOWN = -2`, which
/// changes no field.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct NavSatStatus {
    /// One of the `STATUS_*` constants.
    pub status: i8,
    /// Bit set of the `SERVICE_*` constants.
    pub service: u16,
}

impl NavSatStatus {
    /// No fix.
    pub const STATUS_NO_FIX: i8 = -1;
    /// Unaugmented fix.
    pub const STATUS_FIX: i8 = 0;
    /// Fix with satellite-based augmentation.
    pub const STATUS_SBAS_FIX: i8 = 1;
    /// Fix with ground-based augmentation.
    pub const STATUS_GBAS_FIX: i8 = 2;
    /// GPS.
    pub const SERVICE_GPS: u16 = 1;
    /// GLONASS.
    pub const SERVICE_GLONASS: u16 = 2;
    /// BeiDou (named COMPASS in ROS).
    pub const SERVICE_COMPASS: u16 = 4;
    /// Galileo.
    pub const SERVICE_GALILEO: u16 = 8;
}

/// `sensor_msgs/msg/NavSatFix`: a WGS 84 position with its ENU covariance (m²).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct NavSatFix {
    /// Time and antenna frame.
    pub header: Header,
    /// Fix quality.
    pub status: NavSatStatus,
    /// Latitude (degrees, north positive).
    pub latitude: f64,
    /// Longitude (degrees, east positive).
    pub longitude: f64,
    /// Altitude above the WGS 84 ellipsoid (m).
    pub altitude: f64,
    /// Row-major 3×3 covariance in east, north, up (m²).
    pub position_covariance: [f64; 9],
    /// One of the `COVARIANCE_TYPE_*` constants.
    pub position_covariance_type: u8,
}

impl NavSatFix {
    /// Covariance unknown.
    pub const COVARIANCE_TYPE_UNKNOWN: u8 = 0;
    /// Covariance approximated.
    pub const COVARIANCE_TYPE_APPROXIMATED: u8 = 1;
    /// Diagonal known.
    pub const COVARIANCE_TYPE_DIAGONAL_KNOWN: u8 = 2;
    /// Full covariance known.
    pub const COVARIANCE_TYPE_KNOWN: u8 = 3;
}

/// `sensor_msgs/msg/CompressedImage`: an encoded image (e.g. a marker texture).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CompressedImage {
    /// Time and camera frame.
    pub header: Header,
    /// Encoding, e.g. `png` or `jpeg`.
    #[serde(with = "string")]
    pub format: String,
    /// The encoded image.
    pub data: Vec<u8>,
}

/// Definition of `sensor_msgs/msg/JointState`.
pub const JOINT_STATE: MsgDef = MsgDef {
    name: "sensor_msgs/msg/JointState",
    text: "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n\
           float64[] effort\n",
    deps: &[&HEADER],
};

/// Definition of `sensor_msgs/msg/LaserScan`.
pub const LASER_SCAN: MsgDef = MsgDef {
    name: "sensor_msgs/msg/LaserScan",
    text: "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\n\
           float32 angle_increment\nfloat32 time_increment\nfloat32 scan_time\n\
           float32 range_min\nfloat32 range_max\nfloat32[] ranges\nfloat32[] intensities\n",
    deps: &[&HEADER],
};

/// Definition of `sensor_msgs/msg/Imu`.
pub const IMU: MsgDef = MsgDef {
    name: "sensor_msgs/msg/Imu",
    text: "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\n\
           float64[9] orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\n\
           float64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\n\
           float64[9] linear_acceleration_covariance\n",
    deps: &[&HEADER, &QUATERNION, &VECTOR3],
};

/// Definition of `sensor_msgs/msg/MagneticField`.
pub const MAGNETIC_FIELD: MsgDef = MsgDef {
    name: "sensor_msgs/msg/MagneticField",
    text: "std_msgs/Header header\ngeometry_msgs/Vector3 magnetic_field\n\
           float64[9] magnetic_field_covariance\n",
    deps: &[&HEADER, &VECTOR3],
};

/// Definition of `sensor_msgs/msg/NavSatStatus`.
pub const NAV_SAT_STATUS: MsgDef = MsgDef {
    name: "sensor_msgs/msg/NavSatStatus",
    text: "int8 STATUS_NO_FIX=-1\nint8 STATUS_FIX=0\nint8 STATUS_SBAS_FIX=1\n\
           int8 STATUS_GBAS_FIX=2\nint8 status\nuint16 SERVICE_GPS=1\nuint16 SERVICE_GLONASS=2\n\
           uint16 SERVICE_COMPASS=4\nuint16 SERVICE_GALILEO=8\nuint16 service\n",
    deps: &[],
};

/// Definition of `sensor_msgs/msg/NavSatFix`.
pub const NAV_SAT_FIX: MsgDef = MsgDef {
    name: "sensor_msgs/msg/NavSatFix",
    text: "std_msgs/Header header\nsensor_msgs/NavSatStatus status\nfloat64 latitude\n\
           float64 longitude\nfloat64 altitude\nfloat64[9] position_covariance\n\
           uint8 COVARIANCE_TYPE_UNKNOWN=0\nuint8 COVARIANCE_TYPE_APPROXIMATED=1\n\
           uint8 COVARIANCE_TYPE_DIAGONAL_KNOWN=2\nuint8 COVARIANCE_TYPE_KNOWN=3\n\
           uint8 position_covariance_type\n",
    deps: &[&HEADER, &NAV_SAT_STATUS],
};

/// Definition of `sensor_msgs/msg/CompressedImage`.
pub const COMPRESSED_IMAGE: MsgDef = MsgDef {
    name: "sensor_msgs/msg/CompressedImage",
    text: "std_msgs/Header header\nstring format\nuint8[] data\n",
    deps: &[&HEADER],
};

impl RosMessage for JointState {
    const DEF: &'static MsgDef = &JOINT_STATE;
}
impl RosMessage for LaserScan {
    const DEF: &'static MsgDef = &LASER_SCAN;
}
impl RosMessage for Imu {
    const DEF: &'static MsgDef = &IMU;
}
impl RosMessage for MagneticField {
    const DEF: &'static MsgDef = &MAGNETIC_FIELD;
}
impl RosMessage for NavSatStatus {
    const DEF: &'static MsgDef = &NAV_SAT_STATUS;
}
impl RosMessage for NavSatFix {
    const DEF: &'static MsgDef = &NAV_SAT_FIX;
}
impl RosMessage for CompressedImage {
    const DEF: &'static MsgDef = &COMPRESSED_IMAGE;
}

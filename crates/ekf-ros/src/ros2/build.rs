//! Builders of the messages a robot log holds, in the frames of docs/ARCHITECTURE.md §4, shared by
//! the importers and the simulator so both write the same layout.

use super::builtin_interfaces::Time;
use super::geometry_msgs::{
    Point, Pose, PoseWithCovariance, Quaternion, Transform, TransformStamped, Vector3,
};
use super::nav_msgs::Odometry;
use super::sensor_msgs::{Imu, LaserScan};
use super::std_msgs::Header;
use super::tf2_msgs::TFMessage;
use ekf_core::Pose2;

/// The fixed world frame of reference trajectories.
pub const MAP_FRAME: &str = "map";
/// The frame raw odometry is expressed in.
pub const ODOM_FRAME: &str = "odom";
/// The robot's body frame.
pub const BASE_FRAME: &str = "base_link";
/// The laser scanner's frame.
pub const LASER_FRAME: &str = "laser";

/// A header at `t_ns` in `frame` (stamps beyond the `Time` range become 0).
pub fn header(t_ns: u64, frame: &str) -> Header {
    Header {
        stamp: Time::from_nanos(t_ns).unwrap_or_default(),
        frame_id: frame.into(),
    }
}

/// A planar pose as a 3-D pose (z = 0, yaw only).
pub fn pose_msg(p: &Pose2<f64>) -> Pose {
    Pose {
        position: Point {
            x: p.x,
            y: p.y,
            z: 0.0,
        },
        orientation: Quaternion::from_yaw(p.theta),
    }
}

/// `nav_msgs/Odometry` of `base_link` at pose `p` in `frame`, without covariance.
pub fn odometry(t_ns: u64, p: &Pose2<f64>, frame: &str) -> Odometry {
    Odometry {
        header: header(t_ns, frame),
        child_frame_id: BASE_FRAME.into(),
        pose: PoseWithCovariance {
            pose: pose_msg(p),
            ..PoseWithCovariance::default()
        },
        ..Odometry::default()
    }
}

/// The laser's mounting pose as the static transform `base_link` → `laser`.
pub fn mount_transform(t_ns: u64, mount: &Pose2<f64>) -> TFMessage {
    TFMessage {
        transforms: vec![TransformStamped {
            header: header(t_ns, BASE_FRAME),
            child_frame_id: LASER_FRAME.into(),
            transform: Transform {
                translation: Vector3 {
                    x: mount.x,
                    y: mount.y,
                    z: 0.0,
                },
                rotation: Quaternion::from_yaw(mount.theta),
            },
        }],
    }
}

/// A compass heading (ENU yaw, rad) with its variance (rad²) as a `sensor_msgs/Imu` in
/// `base_link`: only the yaw is measured; roll and pitch variances are left at 0
/// ("unknown" would be −1 in element 0, which would also void the yaw), angular velocity
/// and acceleration are marked unknown.
pub fn compass_imu(t_ns: u64, heading: f64, variance: f64) -> Imu {
    Imu {
        header: header(t_ns, BASE_FRAME),
        orientation: Quaternion::from_yaw(heading),
        orientation_covariance: [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, variance],
        angular_velocity_covariance: [-1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        linear_acceleration_covariance: [-1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ..Imu::default()
    }
}

/// A counter-clockwise sweep of `ranges` from `angle_min` in steps of `angle_increment`
/// (rad) in the `laser` frame, valid between `range_min` and `range_max` (m).
pub fn laser_scan(
    t_ns: u64,
    angle_min: f64,
    angle_increment: f64,
    (range_min, range_max): (f64, f64),
    ranges: Vec<f32>,
) -> LaserScan {
    let n = ranges.len().max(1) as f64;
    LaserScan {
        header: header(t_ns, LASER_FRAME),
        angle_min: angle_min as f32,
        angle_max: (angle_min + (n - 1.0) * angle_increment) as f32,
        angle_increment: angle_increment as f32,
        range_min: range_min as f32,
        range_max: range_max as f32,
        ranges,
        ..LaserScan::default()
    }
}

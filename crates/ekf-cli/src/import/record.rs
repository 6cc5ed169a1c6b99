//! The records an importer yields, common to every source format; the integrator turns
//! them into ROS 2 messages (`/odom`, `/scan`, `/ground_truth`, `/compass`).

use ekf_core::Pose2;
use lrf_lines::LaserScan;

/// One item of an imported log. Times are nanoseconds from the log's own timestamps.
#[derive(Debug, Clone, PartialEq)]
pub enum ImportRecord {
    /// A raw wheel-odometry pose, for `/odom` (`nav_msgs/Odometry`).
    Odometry(Odometry),
    /// A laser scan, for `/scan` (`sensor_msgs/LaserScan`).
    Scan(Scan),
    /// A reference pose (SLAM-corrected, not a perfect truth), for `/ground_truth`.
    Reference(Reference),
    /// A compass heading, for `/compass` (`sensor_msgs/Imu`).
    Compass(Compass),
}

impl ImportRecord {
    /// The record's time (ns).
    pub fn t_ns(&self) -> u64 {
        match self {
            Self::Odometry(r) => r.t_ns,
            Self::Scan(r) => r.t_ns,
            Self::Reference(r) => r.t_ns,
            Self::Compass(r) => r.t_ns,
        }
    }

    /// Sets the record's time (ns): the importers' clock repair gives it.
    pub(crate) fn set_t_ns(&mut self, t_ns: u64) {
        match self {
            Self::Odometry(r) => r.t_ns = t_ns,
            Self::Scan(r) => r.t_ns = t_ns,
            Self::Reference(r) => r.t_ns = t_ns,
            Self::Compass(r) => r.t_ns = t_ns,
        }
    }
}

/// A raw odometry pose in the odometry frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Odometry {
    /// Time (ns).
    pub t_ns: u64,
    /// Pose `(x, y, θ)` (m, m, rad), θ wrapped to (−π, π].
    pub pose: Pose2<f64>,
}

/// A reference pose of the robot in the map frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reference {
    /// Time (ns).
    pub t_ns: u64,
    /// Pose `(x, y, θ)` (m, m, rad), θ wrapped to (−π, π].
    pub pose: Pose2<f64>,
}

/// A laser scan in the sensor frame, shaped like ROS `LaserScan`, plus the sensor's
/// mounting pose on the robot.
#[derive(Debug, Clone, PartialEq)]
pub struct Scan {
    /// Time (ns).
    pub t_ns: u64,
    /// Bearing of the first beam (rad), counter-clockwise in the sensor frame.
    pub angle_min: f64,
    /// Angle between consecutive beams (rad); negative for a clockwise scanner.
    pub angle_increment: f64,
    /// Smallest valid range (m).
    pub range_min: f64,
    /// Largest valid range (m); readings at or beyond it are invalid and kept as they are.
    pub range_max: f64,
    /// Ranges (m).
    pub ranges: Vec<f32>,
    /// Pose of the sensor in the robot frame `(x, y, yaw)`.
    pub mount: Pose2<f64>,
}

impl Scan {
    /// The scan as the line extractor's input type.
    pub fn as_laser_scan(&self) -> LaserScan<'_> {
        LaserScan {
            angle_min: self.angle_min,
            angle_increment: self.angle_increment,
            range_min: self.range_min,
            range_max: self.range_max,
            ranges: &self.ranges,
        }
    }
}

/// A compass heading, already in the map frame (θ counter-clockwise from x).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Compass {
    /// Time (ns).
    pub t_ns: u64,
    /// Heading (rad), wrapped to (−π, π].
    pub heading: f64,
    /// Variance of the heading (rad²).
    pub variance: f64,
    /// `true` when made up by the importer from a reference pose plus noise, not measured.
    pub synthetic: bool,
}

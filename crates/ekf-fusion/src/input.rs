//! The typed, time-stamped inputs of the localizer, and why one can be skipped.

use alloc::vec::Vec;
use core::fmt;
use ekf_core::Pose2;
use nalgebra::Matrix2;

/// One input, fused at the stamp it is pushed with ([`crate::TimedLocalizer::push`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Input {
    /// The wheels' encoder angles (rad, unwrapped, as `sensor_msgs/JointState.position`):
    /// the motion over the interval since the previous reading is their increment.
    WheelAngles {
        /// Left wheel angle (rad).
        left: f64,
        /// Right wheel angle (rad).
        right: f64,
        /// The wheels' speeds at the same time (rad/s, left and right), if the source
        /// reports them too: when the angles stop moving while these say the wheels turn
        /// (a stuck encoder count), the motion is taken from them
        /// ([`crate::wheels::WheelTracker::angles`]).
        velocities: Option<[f64; 2]>,
    },
    /// The wheels' angular speeds (rad/s), held since the previous wheel reading: for a
    /// source with no encoder angles.
    WheelVelocities {
        /// Left wheel speed (rad/s).
        left: f64,
        /// Right wheel speed (rad/s).
        right: f64,
    },
    /// A pose of the robot's own odometry (`nav_msgs/Odometry`): the motion since the
    /// previous one is their relative pose (paper eq. 3 from two poses).
    OdometryPose(Pose2<f64>),
    /// A heading in the map frame (rad) and its variance (rad²), `None` for the
    /// configured compass variance.
    Heading {
        /// Heading (rad).
        heading: f64,
        /// Variance (rad²), or `None` for `localizer.compass.variance`.
        variance: Option<f64>,
    },
    /// A position fix in the map frame (m) with its covariance (m²).
    Position {
        /// x (m).
        x: f64,
        /// y (m).
        y: f64,
        /// Covariance of `(x, y)` (m²).
        covariance: Matrix2<f64>,
    },
    /// A laser scan.
    Scan(Scan),
    /// A reference pose (ground truth): not fused, handed back in stamp order so that it
    /// meets the estimates of its time.
    Reference(Pose2<f64>),
}

impl Input {
    /// Whether this input moves the robot (wheels or odometry).
    pub fn is_motion(&self) -> bool {
        matches!(
            self,
            Input::WheelAngles { .. } | Input::WheelVelocities { .. } | Input::OdometryPose(_)
        )
    }
}

/// An owned laser scan, shaped like `sensor_msgs/LaserScan` (see [`lrf_lines::LaserScan`]
/// for the beam geometry).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Scan {
    /// Bearing of the first beam (rad).
    pub angle_min: f64,
    /// Angle between consecutive beams (rad).
    pub angle_increment: f64,
    /// Smallest valid range (m).
    pub range_min: f64,
    /// Largest valid range (m).
    pub range_max: f64,
    /// Ranges (m).
    pub ranges: Vec<f32>,
}

impl Scan {
    /// The borrowed form the line extractor takes.
    pub fn as_scan(&self) -> lrf_lines::LaserScan<'_> {
        lrf_lines::LaserScan {
            angle_min: self.angle_min,
            angle_increment: self.angle_increment,
            range_min: self.range_min,
            range_max: self.range_max,
            ranges: &self.ranges,
        }
    }
}

/// Why one input could not be used; it is reported and the run goes on.
#[derive(Debug, Clone, PartialEq)]
pub enum Skip {
    /// The stamp is not after the previous one of the same source.
    TimeNotIncreasing {
        /// Previous stamp (ns).
        previous_ns: u64,
        /// This stamp (ns).
        stamp_ns: u64,
    },
    /// A field is NaN or infinite.
    NonFinite {
        /// The field.
        field: &'static str,
    },
    /// The message says it has no such estimate (ROS: −1 in element 0 of its covariance).
    NotProvided {
        /// The field.
        field: &'static str,
    },
    /// The first reading of a differentiated or delta stream only sets the start.
    First,
    /// A field is finite but physically impossible or unusable.
    Implausible {
        /// The field.
        field: &'static str,
        /// What it should be.
        expected: &'static str,
        /// What it was.
        found: f64,
    },
}

impl Skip {
    /// The name of the check that skipped the input, as the summaries and diagnostics
    /// count it (`duplicate_stamp`, `time_not_increasing`, `non_finite`, `not_provided`,
    /// `first`, `implausible`).
    pub fn check(&self) -> &'static str {
        match self {
            Skip::TimeNotIncreasing {
                previous_ns,
                stamp_ns,
            } if previous_ns == stamp_ns => "duplicate_stamp",
            Skip::TimeNotIncreasing { .. } => "time_not_increasing",
            Skip::NonFinite { .. } => "non_finite",
            Skip::NotProvided { .. } => "not_provided",
            Skip::First => "first",
            Skip::Implausible { .. } => "implausible",
        }
    }
}

impl fmt::Display for Skip {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Skip::TimeNotIncreasing {
                previous_ns,
                stamp_ns,
            } if previous_ns == stamp_ns => {
                write!(f, "duplicate stamp {stamp_ns} ns")
            }
            Skip::TimeNotIncreasing {
                previous_ns,
                stamp_ns,
            } => {
                write!(
                    f,
                    "time going backwards: stamp {stamp_ns} ns after {previous_ns} ns"
                )
            }
            Skip::NonFinite { field } => write!(f, "{field} is not finite"),
            Skip::NotProvided { field } => {
                write!(f, "{field} not provided ({field}_covariance[0] = -1)")
            }
            Skip::First => write!(f, "first message sets the start"),
            Skip::Implausible {
                field,
                expected,
                found,
            } => write!(f, "{field}: expected {expected}, found {found}"),
        }
    }
}

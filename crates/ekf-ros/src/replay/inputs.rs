//! Turns ROS 2 messages into filter inputs ([`ekf_fusion::Input`]): wheel angles or
//! speeds from joint states, odometry poses, headings from `Imu` / `MagneticField`,
//! positions from `NavSatFix`, reference poses, and the laser's mounting pose from
//! `/tf_static`.

use crate::config::{CompassCalibrationConfig, GpsConfig};
use crate::geo::GeoOrigin;
use crate::ros2::geometry_msgs::{Pose, TransformStamped};
use crate::ros2::sensor_msgs::{Imu, JointState, MagneticField, NavSatFix, NavSatStatus};
use ekf_core::{heading_from_compass_bearing, wrap_angle, Pose2};
use ekf_fusion::{Input, Skip};
use nalgebra::{Matrix2, Vector2};

/// The wheel input a joint state is: the encoder angles (`position`) of the joints named
/// `left` and `right`, or their velocities when the message has no positions.
/// `Err(names)` when the message lacks one of the joints (the names it has);
/// `Ok(Err(skip))` when it has neither positions nor velocities for them. Readings the
/// wheels cannot make are judged by [`ekf_fusion::wheels::WheelTracker`].
pub fn wheel_input(
    msg: &JointState,
    left: &str,
    right: &str,
) -> Result<Result<Input, Skip>, Vec<String>> {
    let find = |name: &str| msg.name.iter().position(|n| n == name);
    let (Some(l), Some(r)) = (find(left), find(right)) else {
        return Err(msg.name.clone());
    };
    if let (Some(&left), Some(&right)) = (msg.position.get(l), msg.position.get(r)) {
        let velocities = match (msg.velocity.get(l), msg.velocity.get(r)) {
            (Some(&vl), Some(&vr)) => Some([vl, vr]),
            _ => None,
        };
        return Ok(Ok(Input::WheelAngles {
            left,
            right,
            velocities,
        }));
    }
    match (msg.velocity.get(l), msg.velocity.get(r)) {
        (Some(&left), Some(&right)) => Ok(Ok(Input::WheelVelocities { left, right })),
        _ => Ok(Err(Skip::NonFinite {
            field: "velocity (missing)",
        })),
    }
}

/// A `geometry_msgs/Pose` as a planar pose (yaw of the quaternion), finite or not.
pub fn planar(p: &Pose) -> Pose2<f64> {
    Pose2::new(p.position.x, p.position.y, p.orientation.yaw())
}

/// A `geometry_msgs/Pose` as a planar pose (yaw of the quaternion); `None` if not finite.
pub fn pose2(p: &Pose) -> Option<Pose2<f64>> {
    planar(p).validated("pose").ok()
}

/// A heading reading (rad, map frame) and its variance, if the message gives one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Heading {
    /// Heading in the map frame (rad).
    pub heading: f64,
    /// The message's own variance (rad²), when it states one.
    pub variance: Option<f64>,
}

/// Why a GPS fix is not fused.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FixRefused {
    /// `status.status` below `STATUS_FIX`.
    NoFix {
        /// The status.
        status: i8,
    },
    /// Latitude or longitude not finite or off the globe.
    OffTheGlobe {
        /// Latitude (degrees).
        latitude: f64,
        /// Longitude (degrees).
        longitude: f64,
    },
    /// The covariance is declared known but its east/north block is not finite, not
    /// positive definite, or zero.
    BadCovariance {
        /// `position_covariance[0]` (m²).
        east: f64,
        /// `position_covariance[4]` (m²).
        north: f64,
        /// `position_covariance[1]` (m²).
        coupling: f64,
    },
}

impl FixRefused {
    /// The name of the check, as the summary and diagnostics count it.
    pub fn check(&self) -> &'static str {
        match self {
            FixRefused::NoFix { .. } => "gps_no_fix",
            FixRefused::OffTheGlobe { .. } => "gps_off_the_globe",
            FixRefused::BadCovariance { .. } => "gps_bad_covariance",
        }
    }
}

impl std::fmt::Display for FixRefused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FixRefused::NoFix { status } => {
                write!(f, "GPS fix without a position (status {status})")
            }
            FixRefused::OffTheGlobe {
                latitude,
                longitude,
            } => write!(
                f,
                "GPS fix off the globe: latitude {latitude}° (expected within ±90), longitude \
                 {longitude}° (expected within ±180)"
            ),
            FixRefused::BadCovariance {
                east,
                north,
                coupling,
            } => write!(
                f,
                "GPS fix with a known position_covariance that is not positive definite: \
                 east {east} m², north {north} m², coupling {coupling} m²"
            ),
        }
    }
}

/// A GPS fix as a position `(x, y)` in the map and its 2×2 covariance (m²): projected
/// onto the east–north tangent plane about `gps`'s origin and rotated by `map_offset`
/// (the map's rotation from ENU, as for the compass). The covariance is the fix's east /
/// north block when its type says it is known, else `gps.sigma²` per axis. Refused
/// ([`FixRefused`]): a fix without a position, one off the globe, and one whose known
/// covariance is not finite and positive definite (a receiver reporting HDOP 0 gives a
/// zero one, which would make the fix exact).
pub fn gps_position(
    fix: &NavSatFix,
    gps: &GpsConfig,
    map_offset: f64,
) -> Result<(f64, f64, Matrix2<f64>), FixRefused> {
    if fix.status.status < NavSatStatus::STATUS_FIX {
        return Err(FixRefused::NoFix {
            status: fix.status.status,
        });
    }
    if !(fix.latitude.abs() <= 90.0 && fix.longitude.abs() <= 180.0) {
        return Err(FixRefused::OffTheGlobe {
            latitude: fix.latitude,
            longitude: fix.longitude,
        });
    }
    let origin = GeoOrigin {
        latitude: gps.origin_latitude,
        longitude: gps.origin_longitude,
        altitude: 0.0,
    };
    let (east, north) = origin.local(fix.latitude, fix.longitude);
    let c = &fix.position_covariance;
    let block = Matrix2::new(c[0], c[1], c[3], c[4]);
    let enu = if fix.position_covariance_type == NavSatFix::COVARIANCE_TYPE_UNKNOWN {
        Matrix2::identity() * gps.sigma * gps.sigma
    } else {
        let positive = block.iter().all(|v| v.is_finite())
            && c[0] > 0.0
            && c[4] > 0.0
            && c[0] * c[4] - c[1] * c[3] > 0.0;
        if !positive {
            return Err(FixRefused::BadCovariance {
                east: c[0],
                north: c[4],
                coupling: c[1],
            });
        }
        block
    };
    let (s, co) = map_offset.sin_cos();
    let r = Matrix2::new(co, -s, s, co);
    let p = r * Vector2::new(east, north);
    Ok((p.x, p.y, r * enu * r.transpose()))
}

/// An `Imu`'s yaw (already ENU) rotated into the map frame; its variance from
/// `orientation_covariance[8]` when that is positive (all zeros: unknown, `None`). An
/// `Imu` with −1 in `orientation_covariance[0]` has no orientation estimate (as
/// `sensor_msgs/Imu` defines it) and is skipped.
pub fn heading_from_imu(
    msg: &Imu,
    calibration: &CompassCalibrationConfig,
) -> Result<Heading, Skip> {
    let c = &msg.orientation_covariance;
    if c[0] == -1.0 {
        return Err(Skip::NotProvided {
            field: "orientation",
        });
    }
    let yaw = msg.orientation.yaw();
    if !yaw.is_finite() {
        return Err(Skip::NonFinite {
            field: "orientation",
        });
    }
    let q = &msg.orientation;
    let norm = (q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z).sqrt();
    if (norm - 1.0).abs() > UNIT_QUATERNION_TOLERANCE {
        return Err(Skip::Implausible {
            field: "orientation",
            expected: "a unit quaternion (norm within 0.01 of 1)",
            found: norm,
        });
    }
    if c[8].is_nan() || c[8] < 0.0 {
        return Err(Skip::Implausible {
            field: "orientation_covariance[8]",
            expected: "a yaw variance ≥ 0 (0: unknown)",
            found: c[8],
        });
    }
    let variance = (c[8] > 0.0).then_some(c[8]);
    Ok(Heading {
        heading: wrap_angle(yaw + calibration.map_offset),
        variance,
    })
}

/// Largest departure of an `Imu` orientation's norm from 1: a normalised quaternion
/// from a real driver is off by rounding (about 1e-7), so more means the message is
/// broken, and its yaw would be one of a scaled rotation.
const UNIT_QUATERNION_TOLERANCE: f64 = 0.01;

/// Smallest share of a magnetometer's field in the horizontal plane for its direction to
/// be a heading: the Earth's field dips at most about 80° outside the polar regions
/// (horizontal share 0.17), and at 87° (0.05) a percent of noise on the vertical
/// component turns the bearing by several degrees.
const MIN_HORIZONTAL_SHARE: f64 = 0.05;

/// A calibrated magnetometer reading: the field's horizontal direction in the robot frame
/// is magnetic north, so the bearing (clockwise from magnetic north) is
/// `atan2(m_y, m_x)`, and the map heading follows docs/ARCHITECTURE.md §2.
pub fn heading_from_magnetic_field(
    msg: &MagneticField,
    calibration: &CompassCalibrationConfig,
) -> Result<Heading, Skip> {
    let m = &msg.magnetic_field;
    if !(m.x.is_finite() && m.y.is_finite() && m.z.is_finite()) || (m.x == 0.0 && m.y == 0.0) {
        return Err(Skip::NonFinite {
            field: "magnetic_field",
        });
    }
    let horizontal = m.x.hypot(m.y);
    let share = horizontal / horizontal.hypot(m.z);
    if share < MIN_HORIZONTAL_SHARE {
        return Err(Skip::Implausible {
            field: "magnetic_field",
            expected: "a horizontal component of at least 5 % of the field (inclination \
                       under 87°)",
            found: share,
        });
    }
    let bearing = m.y.atan2(m.x);
    Ok(Heading {
        heading: heading_from_compass_bearing(
            bearing,
            calibration.declination,
            calibration.map_offset,
        ),
        variance: None,
    })
}

/// Largest tilt of a laser's scan plane from level that is still read as a planar scan
/// (rad): 5°, where a wall 10 m away appears 0.4 % farther (1/cos 5° − 1).
pub const MAX_MOUNT_TILT: f64 = 5.0 * core::f64::consts::PI / 180.0;

/// A transform in the laser's chain that is not a rotation about z.
#[derive(Debug, Clone, PartialEq)]
pub struct TiltedMount {
    /// The transform's parent frame.
    pub parent: String,
    /// Its child frame.
    pub child: String,
    /// The angle between its z axis and the parent's (rad); π is upside down.
    pub tilt: f64,
}

/// The pose of `frame` in `base` from static transforms (parent → child), following the
/// chain of parents; `None` if `frame` is not connected to `base`. A link whose z axis
/// is more than [`MAX_MOUNT_TILT`] from its parent's — a tilted or upside-down (mirrored)
/// scanner, whose scans are not the level, counter-clockwise scans the filter models — is
/// an error naming it.
pub fn mount_from_tf(
    transforms: &[TransformStamped],
    base: &str,
    frame: &str,
) -> Option<Result<Pose2<f64>, TiltedMount>> {
    let mut pose = Pose2::identity();
    let mut current = frame;
    for _ in 0..=transforms.len() {
        if current == base {
            return Some(Ok(pose));
        }
        let t = transforms.iter().find(|t| t.child_frame_id == current)?;
        let tr = &t.transform;
        let q = &tr.rotation;
        // z component of the rotated z axis, for the normalised quaternion.
        let norm2 = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
        let zz = 1.0 - 2.0 * (q.x * q.x + q.y * q.y) / norm2;
        let tilt = zz.clamp(-1.0, 1.0).acos();
        if tilt.is_nan() || tilt > MAX_MOUNT_TILT {
            return Some(Err(TiltedMount {
                parent: t.header.frame_id.clone(),
                child: t.child_frame_id.clone(),
                tilt,
            }));
        }
        let parent_to_child = Pose2::new(tr.translation.x, tr.translation.y, q.yaw());
        pose = parent_to_child.compose(&pose);
        current = &t.header.frame_id;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use ekf_core::WheelSpeeds;

    /// A joint state through [`wheel_input`] and the fusion's wheel tracker, as replay
    /// takes it.
    struct WheelTracker {
        left: &'static str,
        right: &'static str,
        tracker: ekf_fusion::wheels::WheelTracker,
    }

    impl WheelTracker {
        fn new(left: &'static str, right: &'static str, max_turns_per_s: f64) -> Self {
            Self {
                left,
                right,
                tracker: ekf_fusion::wheels::WheelTracker::new(max_turns_per_s),
            }
        }

        fn speeds(
            &mut self,
            stamp: u64,
            msg: &JointState,
        ) -> Result<Result<WheelSpeeds<f64>, Skip>, Vec<String>> {
            let input = wheel_input(msg, self.left, self.right)?;
            Ok(input.and_then(|input| match input {
                Input::WheelAngles {
                    left,
                    right,
                    velocities,
                } => self
                    .tracker
                    .angles(stamp, left, right, velocities)
                    .map(|(speeds, _)| speeds),
                Input::WheelVelocities { left, right } => {
                    self.tracker.velocities(stamp, left, right)
                }
                other => panic!("not a wheel input: {other:?}"),
            }))
        }
    }

    #[test]
    fn gps_fixes_become_map_positions() {
        let gps = GpsConfig {
            origin_latitude: 48.0,
            origin_longitude: 11.0,
            ..GpsConfig::default()
        };
        let origin = GeoOrigin {
            latitude: 48.0,
            longitude: 11.0,
            altitude: 0.0,
        };
        let at = origin.fix_at(10.0, 0.0);
        let mut fix = NavSatFix {
            latitude: at.latitude,
            longitude: at.longitude,
            ..NavSatFix::default()
        };
        // No covariance: σ = 3 m per axis. 10 m east is (10, 0) in an east-aligned map and
        // (0, 10) in a map whose x axis points north (map_offset = π/2).
        let (x, y, c) = gps_position(&fix, &gps, 0.0).unwrap();
        assert!((x - 10.0).abs() < 1e-6 && y.abs() < 1e-6);
        assert_eq!(c, Matrix2::identity() * 9.0);
        let (x, y, _) = gps_position(&fix, &gps, std::f64::consts::FRAC_PI_2).unwrap();
        assert!(x.abs() < 1e-6 && (y - 10.0).abs() < 1e-6, "{x} {y}");
        // The fix's own east/north covariance, rotated with it.
        fix.position_covariance[0] = 4.0;
        fix.position_covariance[4] = 1.0;
        fix.position_covariance_type = NavSatFix::COVARIANCE_TYPE_DIAGONAL_KNOWN;
        let (_, _, c) = gps_position(&fix, &gps, std::f64::consts::FRAC_PI_2).unwrap();
        assert!((c[(0, 0)] - 1.0).abs() < 1e-12 && (c[(1, 1)] - 4.0).abs() < 1e-12);
        fix.status.status = NavSatStatus::STATUS_NO_FIX;
        assert_eq!(
            gps_position(&fix, &gps, 0.0),
            Err(FixRefused::NoFix { status: -1 })
        );
    }

    #[test]
    fn implausible_fixes_are_refused_with_the_reason() {
        let gps = GpsConfig::default();
        let fix = |latitude: f64, longitude: f64| NavSatFix {
            latitude,
            longitude,
            ..NavSatFix::default()
        };
        for (lat, lon) in [
            (100.67, 10.0),
            (10.0, 181.5),
            (f64::NAN, 0.0),
            (0.0, f64::INFINITY),
        ] {
            let refused = gps_position(&fix(lat, lon), &gps, 0.0).unwrap_err();
            assert!(
                matches!(refused, FixRefused::OffTheGlobe { .. }),
                "{lat} {lon}"
            );
        }
        assert_eq!(
            gps_position(&fix(100.67, 181.5), &gps, 0.0)
                .unwrap_err()
                .to_string(),
            "GPS fix off the globe: latitude 100.67° (expected within ±90), longitude 181.5° \
             (expected within ±180)"
        );
        // A known covariance of zero (HDOP 0), NaN, negative or not positive definite.
        for (east, north, coupling) in [
            (0.0, 0.0, 0.0),
            (f64::NAN, 1.0, 0.0),
            (-1.0, 1.0, 0.0),
            (1.0, 1.0, 2.0),
        ] {
            let mut f = fix(10.0, 10.0);
            f.position_covariance[0] = east;
            f.position_covariance[4] = north;
            f.position_covariance[1] = coupling;
            f.position_covariance[3] = coupling;
            f.position_covariance_type = NavSatFix::COVARIANCE_TYPE_APPROXIMATED;
            let refused = gps_position(&f, &gps, 0.0).unwrap_err();
            assert!(
                matches!(refused, FixRefused::BadCovariance { .. }),
                "{east} {north} {coupling}"
            );
        }
    }
    use crate::ros2::geometry_msgs::{Quaternion, Transform, Vector3};
    use crate::ros2::std_msgs::Header;
    use core::f64::consts::FRAC_PI_2;

    fn joints(names: &[&str], position: Vec<f64>, velocity: Vec<f64>) -> JointState {
        JointState {
            name: names.iter().map(|s| s.to_string()).collect(),
            position,
            velocity,
            ..JointState::default()
        }
    }

    #[test]
    fn an_encoder_spike_costs_two_readings_and_a_jump_one() {
        let mut w = WheelTracker::new("l", "r", 10.0);
        let at = |w: &mut WheelTracker, k: u64, left: f64| {
            w.speeds(
                k * 100_000_000,
                &joints(&["l", "r"], vec![left, 0.0], vec![]),
            )
            .unwrap()
        };
        assert_eq!(at(&mut w, 0, 0.0), Err(Skip::First));
        assert!(at(&mut w, 1, 0.1).is_ok());
        // +100.1 rad in 0.1 s: 10 turns/s (62.8 rad/s) allow 9.4 rad in 0.15 s.
        let spike = at(&mut w, 2, 100.2);
        assert!(
            matches!(spike, Err(Skip::Implausible { field: "position", found, .. }) if (found - 100.1).abs() < 1e-9),
            "{spike:?}"
        );
        assert!(at(&mut w, 3, 0.3).is_err(), "back down from the spike");
        let s = at(&mut w, 4, 0.4).unwrap();
        assert!((s.left - 1.0).abs() < 1e-9, "{s:?}");
        // A jump that stays: one reading lost, then increments from the new count.
        assert!(at(&mut w, 5, 100.5).is_err());
        let s = at(&mut w, 6, 100.6).unwrap();
        assert!((s.left - 1.0).abs() < 1e-9, "{s:?}");
    }

    #[test]
    fn wheel_speeds_from_positions_and_velocities() {
        let mut w = WheelTracker::new("l", "r", 10.0);
        assert_eq!(
            w.speeds(0, &joints(&["r", "l"], vec![0.0, 0.0], vec![]))
                .unwrap(),
            Err(Skip::First)
        );
        // Differentiated: Δφ = (0.2, 0.4) over 0.1 s (joint order differs from config).
        let s = w
            .speeds(100_000_000, &joints(&["r", "l"], vec![0.4, 0.2], vec![]))
            .unwrap()
            .unwrap();
        assert!(
            (s.left - 2.0).abs() < 1e-12
                && (s.right - 4.0).abs() < 1e-12
                && (s.dt - 0.1).abs() < 1e-15
        );
        // Positions win over velocities: Δφ = (0.1, 0.1) over 0.1 s; (1.0, 1.5) is ignored.
        let s = w
            .speeds(
                200_000_000,
                &joints(&["l", "r"], vec![0.3, 0.5], vec![1.0, 1.5]),
            )
            .unwrap()
            .unwrap();
        assert!(
            (s.left - 1.0).abs() < 1e-12 && (s.right - 1.0).abs() < 1e-12,
            "{s:?}"
        );
        // Backwards and duplicate stamps are skipped and do not move the start.
        assert_eq!(
            w.speeds(150_000_000, &joints(&["l", "r"], vec![0.0, 0.0], vec![]))
                .unwrap(),
            Err(Skip::TimeNotIncreasing {
                previous_ns: 200_000_000,
                stamp_ns: 150_000_000
            })
        );
        assert_eq!(
            w.speeds(200_000_000, &joints(&["l", "r"], vec![0.0, 0.0], vec![]))
                .unwrap(),
            Err(Skip::TimeNotIncreasing {
                previous_ns: 200_000_000,
                stamp_ns: 200_000_000
            })
        );
        // A NaN position is skipped without moving the start: the next reading covers
        // the skipped interval (differentiated from 200 ms).
        assert_eq!(
            w.speeds(
                300_000_000,
                &joints(&["l", "r"], vec![f64::NAN, 0.0], vec![])
            )
            .unwrap(),
            Err(Skip::NonFinite { field: "position" })
        );
        // With positions present a NaN velocity does not matter.
        let s = w
            .speeds(
                400_000_000,
                &joints(&["l", "r"], vec![0.5, 0.7], vec![f64::NAN, 1.0]),
            )
            .unwrap()
            .unwrap();
        assert!(
            (s.left - 1.0).abs() < 1e-12 && (s.dt - 0.2).abs() < 1e-15,
            "{s:?}"
        );
        // Velocities only: the interval is the stamp difference; a NaN velocity is skipped.
        let mut v = WheelTracker::new("l", "r", 10.0);
        assert_eq!(
            v.speeds(0, &joints(&["l", "r"], vec![], vec![1.0, 2.0]))
                .unwrap(),
            Err(Skip::First)
        );
        let s = v
            .speeds(50_000_000, &joints(&["l", "r"], vec![], vec![1.0, 2.0]))
            .unwrap()
            .unwrap();
        assert_eq!((s.left, s.right), (1.0, 2.0));
        assert!((s.dt - 0.05).abs() < 1e-15);
        assert!(v
            .speeds(
                60_000_000,
                &joints(&["l", "r"], vec![], vec![f64::NAN, 2.0])
            )
            .unwrap()
            .is_err());
        assert_eq!(
            w.speeds(300_000_000, &joints(&["a", "b"], vec![0.0, 0.0], vec![])),
            Err(vec!["a".to_string(), "b".to_string()])
        );
    }

    #[test]
    fn compass_headings() {
        let cal = CompassCalibrationConfig {
            declination: 0.0,
            map_offset: 0.0,
        };
        // Field pointing along the robot's x axis: the robot faces magnetic north → θ = π/2.
        let north = MagneticField {
            magnetic_field: Vector3 {
                x: 2e-5,
                y: 0.0,
                z: -4e-5,
            },
            ..MagneticField::default()
        };
        assert!(
            (heading_from_magnetic_field(&north, &cal).unwrap().heading - FRAC_PI_2).abs() < 1e-12
        );
        // Field to the robot's left (+y): north is 90° counter-clockwise, the robot faces east.
        let east = MagneticField {
            magnetic_field: Vector3 {
                x: 0.0,
                y: 2e-5,
                z: 0.0,
            },
            ..MagneticField::default()
        };
        assert!(
            heading_from_magnetic_field(&east, &cal)
                .unwrap()
                .heading
                .abs()
                < 1e-12
        );
        let mut imu = Imu {
            orientation: Quaternion::from_yaw(0.3),
            ..Imu::default()
        };
        imu.orientation_covariance[8] = 4e-4;
        let h = heading_from_imu(
            &imu,
            &CompassCalibrationConfig {
                declination: 0.1,
                map_offset: -0.1,
            },
        )
        .unwrap();
        assert!((h.heading - 0.2).abs() < 1e-12 && h.variance == Some(4e-4));
        imu.orientation_covariance[8] = 0.0;
        assert_eq!(heading_from_imu(&imu, &cal).unwrap().variance, None);
        imu.orientation_covariance[8] = f64::NAN;
        assert_eq!(
            heading_from_imu(&imu, &cal).unwrap_err().to_string(),
            "orientation_covariance[8]: expected a yaw variance ≥ 0 (0: unknown), found NaN"
        );
        imu.orientation_covariance[8] = -4e-4;
        assert!(heading_from_imu(&imu, &cal).is_err());
        imu.orientation_covariance[8] = 0.0;
        let mut scaled = imu.clone();
        scaled.orientation.w *= 1.5;
        scaled.orientation.z *= 1.5;
        assert!(matches!(
            heading_from_imu(&scaled, &cal),
            Err(Skip::Implausible { field: "orientation", found, .. }) if (found - 1.5).abs() < 1e-12
        ));
        imu.orientation_covariance[0] = -1.0;
        let skip = heading_from_imu(&imu, &cal).unwrap_err();
        assert_eq!(
            skip.to_string(),
            "orientation not provided (orientation_covariance[0] = -1)"
        );
        // A field that points nearly straight down has no usable direction.
        let vertical = MagneticField {
            magnetic_field: Vector3 {
                x: 1e-7,
                y: 1e-7,
                z: -5e-5,
            },
            ..MagneticField::default()
        };
        assert!(matches!(
            heading_from_magnetic_field(&vertical, &cal),
            Err(Skip::Implausible {
                field: "magnetic_field",
                ..
            })
        ));
    }

    #[test]
    fn tf_chain() {
        let tf = |parent: &str, child: &str, x: f64, yaw: f64| TransformStamped {
            header: Header {
                frame_id: parent.into(),
                ..Header::default()
            },
            child_frame_id: child.into(),
            transform: Transform {
                translation: Vector3 { x, y: 0.0, z: 0.3 },
                rotation: Quaternion::from_yaw(yaw),
            },
        };
        let tfs = [
            tf("base_link", "mast", 0.2, FRAC_PI_2),
            tf("mast", "laser", 0.1, 0.0),
        ];
        let m = mount_from_tf(&tfs, "base_link", "laser").unwrap().unwrap();
        assert!(
            (m.x - 0.2).abs() < 1e-12
                && (m.y - 0.1).abs() < 1e-12
                && (m.theta - FRAC_PI_2).abs() < 1e-12
        );
        assert_eq!(mount_from_tf(&tfs, "base_link", "camera"), None);
        assert_eq!(
            mount_from_tf(&tfs, "base_link", "base_link"),
            Some(Ok(Pose2::identity()))
        );
        // An upside-down laser (roll π) is refused, naming the transform.
        let flipped = TransformStamped {
            transform: Transform {
                translation: Vector3 {
                    x: 0.2,
                    y: 0.0,
                    z: 0.3,
                },
                rotation: Quaternion {
                    x: 1.0,
                    y: 0.0,
                    z: 0.0,
                    w: 0.0,
                },
            },
            ..tf("base_link", "laser", 0.0, 0.0)
        };
        let err = mount_from_tf(&[flipped], "base_link", "laser")
            .unwrap()
            .unwrap_err();
        assert_eq!(
            (err.parent.as_str(), err.child.as_str()),
            ("base_link", "laser")
        );
        assert!((err.tilt - core::f64::consts::PI).abs() < 1e-9);
        // A laser pitched down by 3° is still read as level.
        let (sn, cs) = (1.5_f64.to_radians().sin(), 1.5_f64.to_radians().cos());
        let pitched = TransformStamped {
            transform: Transform {
                translation: Vector3 {
                    x: 0.2,
                    y: 0.0,
                    z: 0.3,
                },
                rotation: Quaternion {
                    x: 0.0,
                    y: sn,
                    z: 0.0,
                    w: cs,
                },
            },
            ..tf("base_link", "laser", 0.0, 0.0)
        };
        assert!(mount_from_tf(&[pitched], "base_link", "laser")
            .unwrap()
            .is_ok());
    }
}

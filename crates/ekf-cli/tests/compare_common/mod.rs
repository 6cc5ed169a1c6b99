//! A synthetic ROS 2 bag for the `ekf compare` tests: a differential-drive robot drives
//! laps in a rectangular room 8 m × 5 m for 60 s at 10 Hz.
//!
//! - `/joint_states`: wheel speeds (and integrated positions) of `left_wheel_joint` and
//!   `right_wheel_joint`, with a 3 % scale error on the right wheel, so dead reckoning
//!   turns too much and drifts;
//! - `/compass`: `sensor_msgs/Imu` with the true heading plus Gaussian noise, σ = 1°,
//!   stating that variance;
//! - `/scan`: a 360° `LaserScan` (1° steps) ray-cast against the room's walls, range
//!   noise σ = 1 cm;
//! - `/ground_truth`: `nav_msgs/Odometry` with the true pose at every scan.
//!
//! The robot starts at the origin heading along +x (the default `initial` pose), so the
//! first scan's map is in the right frame without `--init-from-truth`.

#![allow(dead_code)]

#[path = "../gauss_rng/mod.rs"]
mod gauss_rng;

use ekf_cli::mcap_io::BagWriter;
use ekf_cli::ros2::builtin_interfaces::Time;
use ekf_cli::ros2::geometry_msgs::{Point, Pose, PoseWithCovariance, Quaternion};
use ekf_cli::ros2::nav_msgs::Odometry;
use ekf_cli::ros2::sensor_msgs::{Imu, JointState, LaserScan};
use ekf_cli::ros2::std_msgs::Header;
use gauss_rng::Rng;
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;

/// The room: x from `X_MIN` to `X_MAX`, y from `Y_MIN` to `Y_MAX` (8 m × 5 m).
pub const X_MIN: f64 = -1.5;
/// See [`X_MIN`].
pub const X_MAX: f64 = 6.5;
/// See [`X_MIN`].
pub const Y_MIN: f64 = -1.5;
/// See [`X_MIN`].
pub const Y_MAX: f64 = 3.5;

/// Wheel radius and track of the default configuration (the paper's robot).
const WHEEL_RADIUS: f64 = 0.05;
const TRACK: f64 = 0.6;
/// Step (s) and number of steps: 60 s at 10 Hz.
const DT: f64 = 0.1;
const STEPS: usize = 600;
/// First stamp (ns): 1 s, so no stamp is zero.
const T0_NS: u64 = 1_000_000_000;
/// Scale error of the right wheel's reported speed.
const RIGHT_WHEEL_SCALE: f64 = 1.03;
/// Noise of the compass (rad) and of the laser ranges (m).
const COMPASS_SIGMA: f64 = PI / 180.0;
const RANGE_SIGMA: f64 = 0.01;

/// Which topics the bag gets (wheel speeds and scans always).
#[derive(Debug, Clone, Copy)]
pub struct BagContents {
    /// Write `/compass`.
    pub compass: bool,
    /// Write `/ground_truth`.
    pub reference: bool,
}

impl Default for BagContents {
    fn default() -> Self {
        Self {
            compass: true,
            reference: true,
        }
    }
}

/// The commanded `(v, ω)` at time `t` (s): laps of a rounded rectangle, 4 m and 2 m
/// straights at 0.4 m/s joined by quarter turns of 2.5 s at 0.3 m/s (40 s per lap).
fn command(t: f64) -> (f64, f64) {
    let turn = (0.3, FRAC_PI_2 / 2.5);
    let t = t.rem_euclid(40.0);
    let phases = [
        (10.0, (0.4, 0.0)),
        (2.5, turn),
        (5.0, (0.4, 0.0)),
        (2.5, turn),
    ];
    let mut start = 0.0;
    for _ in 0..2 {
        for (duration, vw) in phases {
            if t < start + duration {
                return vw;
            }
            start += duration;
        }
    }
    (0.4, 0.0)
}

/// The true pose after driving `(v, ω)` for `dt` from `(x, y, θ)` (exact arc).
fn drive((x, y, th): (f64, f64, f64), (v, w): (f64, f64), dt: f64) -> (f64, f64, f64) {
    if w.abs() < 1e-12 {
        (x + v * dt * th.cos(), y + v * dt * th.sin(), th)
    } else {
        let r = v / w;
        let th1 = th + w * dt;
        (
            x + r * (th1.sin() - th.sin()),
            y - r * (th1.cos() - th.cos()),
            th1,
        )
    }
}

/// Distance from `(x, y)` along the direction `phi` to the first wall of the room.
fn ray_cast(x: f64, y: f64, phi: f64) -> f64 {
    let (c, s) = (phi.cos(), phi.sin());
    let mut best = f64::INFINITY;
    for (wall, along) in [(X_MIN, c), (X_MAX, c)] {
        if along.abs() > 1e-12 {
            let t = (wall - x) / along;
            if t > 0.0 {
                best = best.min(t);
            }
        }
    }
    for (wall, along) in [(Y_MIN, s), (Y_MAX, s)] {
        if along.abs() > 1e-12 {
            let t = (wall - y) / along;
            if t > 0.0 {
                best = best.min(t);
            }
        }
    }
    best
}

fn header(t_ns: u64, frame: &str) -> Header {
    Header {
        stamp: Time::from_nanos(t_ns).expect("stamp fits"),
        frame_id: frame.into(),
    }
}

/// Writes the bag to `path`.
pub fn write_room_bag(path: &Path, contents: BagContents) {
    let mut rng = Rng::new(20_240_611);
    let mut bag = BagWriter::create(path).expect("create bag");
    let mut pose = (0.0, 0.0, 0.0);
    let mut wheel_positions = (0.0, 0.0);
    let beams = 360;
    let increment = 2.0 * PI / f64::from(beams);
    for k in 0..=STEPS {
        let t_ns = T0_NS + k as u64 * 100_000_000;
        // Wheel speeds of the step that ends now (none before the first message).
        let (v, w) = if k == 0 {
            (0.0, 0.0)
        } else {
            command((k - 1) as f64 * DT)
        };
        if k > 0 {
            pose = drive(pose, (v, w), DT);
        }
        let right = RIGHT_WHEEL_SCALE * (v + 0.5 * w * TRACK) / WHEEL_RADIUS;
        let left = (v - 0.5 * w * TRACK) / WHEEL_RADIUS;
        wheel_positions.0 += left * DT;
        wheel_positions.1 += right * DT;
        bag.write(
            "/joint_states",
            &JointState {
                header: header(t_ns, ""),
                name: vec!["left_wheel_joint".into(), "right_wheel_joint".into()],
                position: vec![wheel_positions.0, wheel_positions.1],
                velocity: vec![left, right],
                effort: vec![],
            },
        )
        .expect("joint state");

        // The scan and the reference 1 ms later (the robot moves 0.4 mm in between).
        let (x, y, th) = pose;
        let ranges = (0..beams)
            .map(|i| {
                let bearing = -PI + f64::from(i) * increment;
                (ray_cast(x, y, th + bearing) + rng.gauss(RANGE_SIGMA)) as f32
            })
            .collect();
        let scan_ns = t_ns + 1_000_000;
        bag.write(
            "/scan",
            &LaserScan {
                header: header(scan_ns, "laser"),
                angle_min: -PI as f32,
                angle_max: (-PI + f64::from(beams - 1) * increment) as f32,
                angle_increment: increment as f32,
                time_increment: 0.0,
                scan_time: DT as f32,
                range_min: 0.1,
                range_max: 12.0,
                ranges,
                intensities: vec![],
            },
        )
        .expect("scan");
        if contents.reference {
            let mut odometry = Odometry {
                header: header(scan_ns, "map"),
                child_frame_id: "base_link".into(),
                ..Odometry::default()
            };
            odometry.pose = PoseWithCovariance {
                pose: Pose {
                    position: Point { x, y, z: 0.0 },
                    orientation: Quaternion::from_yaw(th),
                },
                ..PoseWithCovariance::default()
            };
            bag.write("/ground_truth", &odometry).expect("reference");
        }
        if contents.compass {
            let variance = COMPASS_SIGMA * COMPASS_SIGMA;
            let mut covariance = [0.0; 9];
            covariance[0] = variance;
            covariance[4] = variance;
            covariance[8] = variance;
            bag.write(
                "/compass",
                &Imu {
                    header: header(t_ns + 2_000_000, "imu"),
                    orientation: Quaternion::from_yaw(th + rng.gauss(COMPASS_SIGMA)),
                    orientation_covariance: covariance,
                    ..Imu::default()
                },
            )
            .expect("compass");
        }
    }
    bag.finish().expect("finish bag");
}

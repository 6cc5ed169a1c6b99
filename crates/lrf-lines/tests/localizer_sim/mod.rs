//! A simulated run for the Localizer tests and benchmark: the paper's robot drives a
//! rectangle in a room, with biased, noisy wheel speeds, a noisy compass, and a SICK-style
//! 721-beam scan ray-cast from the true pose.
#![allow(dead_code)] // each test crate uses a different part

use crate::matching_support::{ray_cast, rect_room, Beams, Rng, Wall};
use ekf_core::{DiffDrive, Pose2, WheelSpeeds};
use lrf_lines::LaserScan;
use std::f64::consts::{FRAC_PI_2, PI};

/// The laser 20 cm ahead of the axle, its 0° pointing to the robot's right (the paper's
/// SICK mounting).
pub fn mount() -> Pose2<f64> {
    Pose2::new(0.2, 0.0, -FRAC_PI_2)
}

pub const BEAMS: usize = 721;
pub const INCREMENT: f64 = PI / 720.0;
pub const RANGE_MAX: f64 = 15.0;

/// The room `[−1, 7] × [−1, 5]` with a 1.5 m cabinet along the top wall.
pub fn walls() -> Vec<Wall> {
    let mut w = rect_room(-1.0, -1.0, 7.0, 5.0);
    w.push((
        nalgebra::Point2::new(2.0, 4.4),
        nalgebra::Point2::new(3.5, 4.4),
    ));
    w
}

/// The start pose.
pub fn start() -> Pose2<f64> {
    Pose2::new(0.5, 0.5, 0.0)
}

/// True wheel speeds for one lap of the rectangle (0.5, 0.5)–(5.5, 3.5) at Δt = 0.1 s:
/// straight legs at 0.04 m per step, 90° turns on the spot, each leg in whole steps.
pub fn commands() -> Vec<WheelSpeeds<f64>> {
    let robot = DiffDrive::<f64>::paper();
    let dt = 0.1;
    let mut out = Vec::new();
    for leg in [5.0, 3.0, 5.0, 3.0] {
        let n = (leg / 0.04_f64).round() as usize;
        let w = leg / n as f64 / (dt * robot.wheel_radius);
        out.extend((0..n).map(|_| WheelSpeeds::new(w, w, dt).unwrap()));
        let n = 20;
        let w = FRAC_PI_2 / n as f64 * robot.track / (2.0 * dt * robot.wheel_radius);
        out.extend((0..n).map(|_| WheelSpeeds::new(-w, w, dt).unwrap()));
    }
    out
}

/// What the encoders report: the right wheel reads 3 % fast, both with noise 0.1 rad/s.
pub fn measured(true_speeds: &WheelSpeeds<f64>, rng: &mut Rng) -> WheelSpeeds<f64> {
    WheelSpeeds::new(
        true_speeds.left + 0.1 * rng.normal_floored(),
        1.03 * true_speeds.right + 0.1 * rng.normal_floored(),
        true_speeds.dt,
    )
    .unwrap()
}

/// The ranges of a scan from the true robot pose, with 1 cm range noise.
pub fn ranges(truth: &Pose2<f64>, walls: &[Wall], rng: &mut Rng) -> Vec<f32> {
    let beams = Beams {
        angle_min: 0.0,
        increment: INCREMENT,
        count: BEAMS,
        range_max: RANGE_MAX,
    };
    ray_cast(walls, &truth.compose(&mount()), &beams, 0.01, Some(rng))
}

/// The scan header for `ranges`.
pub fn scan(ranges: &[f32]) -> LaserScan<'_> {
    LaserScan {
        angle_min: 0.0,
        angle_increment: INCREMENT,
        range_min: 0.05,
        range_max: RANGE_MAX,
        ranges,
    }
}

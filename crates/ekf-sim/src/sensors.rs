//! The simulated compass and laser scanner.

use super::rng::SimRng;
use super::room::Room;
use ekf_core::{wrap_angle, Pose2};
use nalgebra::Point2;
use serde::Serialize;

/// A compass reporting the heading (ENU yaw, as a ROS `Imu` carries it).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CompassModel {
    /// Standard deviation of the heading noise (rad).
    pub sigma: f64,
    /// Constant bias added to every reading (rad); not reported in the message's variance.
    pub bias: f64,
    /// Probability that a reading is an outlier: the true heading plus an error drawn
    /// uniformly from ±[30°, 180°] (a disturbed magnetic field).
    pub outlier_probability: f64,
}

impl Default for CompassModel {
    /// A CMPS03 indoors, as measured rather than as specified: σ = 2°, no bias, 2 %
    /// outliers.
    fn default() -> Self {
        Self {
            sigma: 2f64.to_radians(),
            bias: 0.0,
            outlier_probability: 0.02,
        }
    }
}

impl CompassModel {
    /// The compass as the paper specifies it (§IV: "accuracy of 0.1°"; docs/ERRATA.md 3),
    /// with the same 2 % outliers.
    pub fn paper() -> Self {
        Self {
            sigma: 0.1f64.to_radians(),
            ..Self::default()
        }
    }
}

/// One compass reading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompassReading {
    /// The heading (rad, wrapped).
    pub heading: f64,
    /// Whether it is an outlier (known only to the simulator).
    pub outlier: bool,
}

impl CompassModel {
    /// A reading for the true heading `theta`.
    pub fn read(&self, theta: f64, rng: &mut SimRng) -> CompassReading {
        let noise = rng.normal(self.sigma);
        if rng.chance(self.outlier_probability) {
            let size = rng.uniform(30f64.to_radians(), std::f64::consts::PI);
            let sign = if rng.chance(0.5) { 1.0 } else { -1.0 };
            return CompassReading {
                heading: wrap_angle(theta + sign * size),
                outlier: true,
            };
        }
        CompassReading {
            heading: wrap_angle(theta + self.bias + noise),
            outlier: false,
        }
    }
}

/// A SICK LMS 221 in its 8 m / millimetre mode: a sweep centred ahead, readings in whole mm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LaserModel {
    /// Angular resolution (rad): 0.25°, 0.5° or 1°.
    pub resolution: f64,
    /// Field of view (rad): 180°, or 100° (the only one the LMS 2xx offers at 0.25°).
    pub fov: f64,
    /// Range noise σ (m). The paper: 30 mm.
    pub range_sigma: f64,
    /// Bearing noise σ of each beam (rad). The paper: 0.25°.
    pub bearing_sigma: f64,
    /// Largest range reported (m); farther walls give no return.
    pub max_range: f64,
    /// Probability that a beam returns an error code (dazzle, weak echo), written NaN.
    pub invalid_probability: f64,
    /// The scanner's pose on the robot.
    pub mount: Pose2<f64>,
    /// A scan every this many filter steps: as many as the measured-values telegram
    /// takes at 38400 baud ([`LaserModel::steps_per_sweep`]; 2 steps of 0.1 s at 0.5°).
    pub period_steps: u32,
}

/// The serial line's speed (baud): the LMS 2xx over RS-232.
pub const LASER_BAUD: f64 = 38_400.0;

/// Smallest range the scanner reports (m).
pub const LASER_RANGE_MIN: f64 = 0.05;

impl Default for LaserModel {
    /// The paper's LRF at 0.5°: σ 30 mm and 0.25°, 8 m, 0.2 % error codes, mounted 0.2 m
    /// ahead of the wheel axle facing forward, a scan every 0.2 s.
    fn default() -> Self {
        Self {
            resolution: 0.5f64.to_radians(),
            fov: std::f64::consts::PI,
            range_sigma: 0.03,
            bearing_sigma: 0.25f64.to_radians(),
            max_range: 8.0,
            invalid_probability: 0.002,
            mount: Pose2::new(0.2, 0.0, 0.0),
            period_steps: 2,
        }
    }
}

impl LaserModel {
    /// The default scanner at `resolution_deg` (0.25, 0.5 or 1): 180° wide, or 100° at
    /// 0.25°, and a sweep as often as its telegram fits through the serial line.
    pub fn at_resolution(resolution_deg: f64, dt: f64) -> Option<Self> {
        if ![0.25, 0.5, 1.0].contains(&resolution_deg) {
            return None;
        }
        let fov_deg: f64 = if resolution_deg == 0.25 { 100.0 } else { 180.0 };
        let mut model = Self {
            resolution: resolution_deg.to_radians(),
            fov: fov_deg.to_radians(),
            ..Self::default()
        };
        model.period_steps = model.steps_per_sweep(dt);
        Some(model)
    }

    /// Filter steps of `dt` seconds one measured-values telegram takes at
    /// [`LASER_BAUD`]: 2 bytes per value plus 10 of framing, 10 bits per byte.
    pub fn steps_per_sweep(&self, dt: f64) -> u32 {
        let bytes = 2.0 * self.beams() as f64 + 10.0;
        ((bytes * 10.0 / LASER_BAUD) / dt).ceil().max(1.0) as u32
    }

    /// Number of beams in the sweep.
    pub fn beams(&self) -> usize {
        (self.fov / self.resolution).round() as usize + 1
    }

    /// Bearing of the first beam in the sensor frame (rad): the sweep is centred ahead.
    pub fn angle_min(&self) -> f64 {
        -self.fov / 2.0
    }

    /// One sweep from the robot at `robot` in `room`: each beam's true bearing is off by
    /// the bearing noise, its range gets the range noise and is rounded to whole mm; no
    /// wall within range gives +∞ (no return, as REP 117), an error code gives NaN.
    pub fn scan(&self, room: &Room, robot: &Pose2<f64>, rng: &mut SimRng) -> Vec<f32> {
        let sensor = robot.compose(&self.mount);
        let origin = Point2::new(sensor.x, sensor.y);
        (0..self.beams())
            .map(|i| {
                let bearing = self.angle_min() + i as f64 * self.resolution;
                let actual = sensor.theta + bearing + rng.normal(self.bearing_sigma);
                let noise = rng.normal(self.range_sigma);
                let invalid = rng.chance(self.invalid_probability);
                match room.ray_cast(&origin, actual, self.max_range) {
                    _ if invalid => f32::NAN,
                    Some(r) => {
                        let mm = ((r + noise) * 1000.0).round() / 1000.0;
                        mm.clamp(LASER_RANGE_MIN, self.max_range) as f32
                    }
                    None => f32::INFINITY,
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Stream;

    #[test]
    fn compass_noise_and_outliers_have_the_configured_statistics() {
        let model = CompassModel::default();
        let mut rng = SimRng::new(2, Stream::Compass);
        let (mut outliers, mut sum_sq, mut n) = (0, 0.0, 0);
        for _ in 0..20_000 {
            let r = model.read(3.1, &mut rng);
            let e = ekf_core::angle_diff(r.heading, 3.1);
            if r.outlier {
                outliers += 1;
                assert!(e.abs() >= 30f64.to_radians() - 1e-9);
            } else {
                sum_sq += e * e;
                n += 1;
            }
        }
        let sigma = (sum_sq / f64::from(n)).sqrt();
        assert!((sigma / model.sigma - 1.0).abs() < 0.03, "{sigma}");
        assert!(
            (f64::from(outliers) / 20_000.0 - 0.02).abs() < 0.004,
            "{outliers}"
        );
    }

    #[test]
    fn a_noiseless_scan_measures_the_room() {
        let model = LaserModel {
            range_sigma: 0.0,
            bearing_sigma: 0.0,
            invalid_probability: 0.0,
            ..LaserModel::default()
        };
        assert_eq!(model.beams(), 361);
        assert_eq!(model.steps_per_sweep(0.1), model.period_steps);
        let fine = LaserModel::at_resolution(0.25, 0.1).unwrap();
        assert_eq!((fine.beams(), fine.period_steps), (401, 3));
        assert!((fine.angle_min() + 50f64.to_radians()).abs() < 1e-12);
        let coarse = LaserModel::at_resolution(1.0, 0.1).unwrap();
        assert_eq!((coarse.beams(), coarse.period_steps), (181, 1));
        assert_eq!(LaserModel::at_resolution(0.3, 0.1), None);
        let mut rng = SimRng::new(1, Stream::Laser);
        // Robot at (2.8, 2) facing +x: the sensor at (3, 2), 3 m from the east wall.
        let ranges = model.scan(&Room::paper(), &Pose2::new(2.8, 2.0, 0.0), &mut rng);
        assert_eq!(ranges.len(), 361);
        assert_eq!(ranges[180], 3.0);
        assert_eq!(ranges[0], 2.0); // right: the south wall
        assert_eq!(ranges[360], 2.0); // left: the north wall
                                      // Out of range: a corridor seen lengthwise.
        let far = model.scan(&Room::corridor(), &Pose2::new(1.0, 1.1, 0.0), &mut rng);
        assert!(far[180].is_infinite());
    }

    #[test]
    fn scan_noise_and_invalid_returns_have_the_configured_rates() {
        let model = LaserModel {
            bearing_sigma: 0.0,
            invalid_probability: 0.05,
            ..LaserModel::default()
        };
        let mut rng = SimRng::new(9, Stream::Laser);
        let (mut nan, mut sum_sq, mut n) = (0, 0.0, 0);
        for _ in 0..50 {
            let r = model.scan(&Room::paper(), &Pose2::new(2.8, 2.0, 0.0), &mut rng);
            nan += r.iter().filter(|v| v.is_nan()).count();
            if r[180].is_finite() {
                sum_sq += (f64::from(r[180]) - 3.0).powi(2);
                n += 1;
            }
        }
        let rate = nan as f64 / (50.0 * 361.0);
        assert!((rate - 0.05).abs() < 0.01, "{rate}");
        let sigma = (sum_sq / f64::from(n)).sqrt();
        assert!(sigma > 0.02 && sigma < 0.04, "{sigma}");
    }
}

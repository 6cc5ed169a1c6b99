//! The Localizer's configuration: one serde struct, grouped as robot, noise, laser,
//! extraction, matching and compass, with every default documented here.

use super::LocalizerError;
use crate::{ExtractionParams, LineExtractor, MatchParams, Matcher};
use ekf_core::setting::{check, Expected};
use ekf_core::{ChiSquareGate, Compass, DiffDrive, OdometryNoise, Pose2, WheelNoise};
use serde::{Deserialize, Serialize};

/// Everything a [`Localizer`](super::Localizer) needs besides the initial state and the
/// map. Missing groups or fields in a config file take the defaults below
/// (`#[serde(default)]`, down to the fields of `robot`, `wheel_noise`,
/// `odometry_noise` and `laser_mount`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LocalizerConfig {
    /// Wheel geometry. Default: the paper's robot, wheel radius 0.05 m, track 0.60 m.
    pub robot: DiffDrive<f64>,
    /// Wheel-speed noise for [`Localizer::predict_wheels`](super::Localizer::predict_wheels).
    /// Default: δ = 0.01 (the paper) and a floor of (0.036 rad/s)².
    pub wheel_noise: WheelNoise<f64>,
    /// Odometry-delta noise for
    /// [`Localizer::predict_odometry`](super::Localizer::predict_odometry). Default:
    /// `σ_s = 0.05·L + 0.01 m`, `σ_e = 0.03·L + 0.01 m`, `σ_θ = 0.30·R + 0.07·L + 0.5°`.
    pub odometry_noise: OdometryNoise<f64>,
    /// The laser's pose on the robot `(x, y, θ)` (m, m, rad). Default: the identity, a
    /// ROS-style scanner at the robot's origin facing forward. The paper's SICK, whose 0°
    /// points to the robot's right, is `θ = −π/2`. A table with some of `x`, `y`,
    /// `theta` takes 0 for the others.
    #[serde(deserialize_with = "mount_with_defaults")]
    pub laser_mount: Pose2<f64>,
    /// Line extraction. Default: [`ExtractionParams::default`] (a SICK LMS 2xx).
    pub extraction: ExtractionParams,
    /// Data association. Default: gate probability 0.99 (2 dof, NIS ≤ 9.21), overlap
    /// `min(0.2 m, 0.5 · observed length)`.
    pub matching: MatchParams,
    /// Compass measurement noise and gate.
    pub compass: CompassConfig,
}

impl Default for LocalizerConfig {
    fn default() -> Self {
        Self {
            robot: DiffDrive::paper(),
            wheel_noise: WheelNoise::default(),
            odometry_noise: OdometryNoise::default(),
            laser_mount: Pose2::identity(),
            extraction: ExtractionParams::default(),
            matching: MatchParams::default(),
            compass: CompassConfig::default(),
        }
    }
}

/// Largest wheel radius taken as a robot's (m): a larger one is a unit slip.
const MAX_WHEEL_RADIUS_M: f64 = 2.0;
/// Largest track taken as a robot's (m).
const MAX_TRACK_M: f64 = 10.0;
/// Largest laser offset from the robot's centre (m).
const MAX_MOUNT_OFFSET_M: f64 = 10.0;

impl LocalizerConfig {
    /// Checks every group, in the order they are listed: sizes a wheeled robot can have
    /// (a radius over 2 m or a track over 10 m is millimetres, not a robot), a laser
    /// within 10 m of the robot's centre and turned by radians, not degrees, positive
    /// noise, gate probabilities in (0, 1), and each group's own rules (noise models,
    /// extraction, matching). Keys are named from this table (`robot.track`); the
    /// [`Localizer`](super::Localizer) refuses a configuration that fails this.
    pub fn validate(&self) -> Result<(), LocalizerError> {
        self.validated_parts().map(|_| ())
    }

    /// [`validate`](Self::validate), returning the compass gate, matcher and extractor
    /// it had to build to check their groups, so the [`Localizer`](super::Localizer)
    /// does not build them again.
    pub(super) fn validated_parts(&self) -> Result<ValidatedParts, LocalizerError> {
        let ranges = [
            (
                "robot.wheel_radius",
                self.robot.wheel_radius,
                Expected::Positive,
            ),
            ("robot.track", self.robot.track, Expected::Positive),
            (
                "robot.wheel_radius",
                self.robot.wheel_radius,
                Expected::LengthUpTo(MAX_WHEEL_RADIUS_M),
            ),
            (
                "robot.track",
                self.robot.track,
                Expected::LengthUpTo(MAX_TRACK_M),
            ),
            (
                "laser_mount.x",
                self.laser_mount.x,
                Expected::MetresWithin(MAX_MOUNT_OFFSET_M),
            ),
            (
                "laser_mount.y",
                self.laser_mount.y,
                Expected::MetresWithin(MAX_MOUNT_OFFSET_M),
            ),
            (
                "laser_mount.theta",
                self.laser_mount.theta,
                Expected::Radians,
            ),
            (
                "compass.variance",
                self.compass.variance,
                Expected::Positive,
            ),
            (
                "compass.gate_probability",
                self.compass.gate_probability,
                Expected::Probability,
            ),
            (
                "matching.gate_probability",
                self.matching.gate_probability,
                Expected::Probability,
            ),
        ];
        for (key, value, expected) in ranges {
            check(key, value, expected).map_err(LocalizerError::Setting)?;
        }
        let cfg = |group| move |error| LocalizerError::Config { group, error };
        DiffDrive::new(self.robot.wheel_radius, self.robot.track).map_err(cfg("robot"))?;
        WheelNoise::new(self.wheel_noise.delta, self.wheel_noise.floor)
            .map_err(cfg("wheel_noise"))?;
        self.odometry_noise
            .validated()
            .map_err(cfg("odometry_noise"))?;
        self.laser_mount
            .validated("laser mount")
            .map_err(cfg("laser_mount"))?;
        Compass::new(0.0, self.compass.variance).map_err(cfg("compass"))?;
        let compass_gate = ChiSquareGate::from_probability(self.compass.gate_probability, 1)
            .map_err(cfg("compass"))?;
        if self.compass.recover_after == 1 {
            return Err(LocalizerError::Config {
                group: "compass",
                error: ekf_core::Error::OutOfRange {
                    what: "recover_after",
                    expected: "0 (never) or ≥ 2; 1 would fuse every rejected heading",
                },
            });
        }
        Ok(ValidatedParts {
            compass_gate,
            matcher: Matcher::new(self.matching).map_err(cfg("matching"))?,
            extractor: LineExtractor::new(self.extraction)?,
        })
    }
}

/// The parts of a [`Localizer`](super::Localizer) that checking a configuration builds.
pub(super) struct ValidatedParts {
    /// The compass innovation gate (1 dof).
    pub compass_gate: ChiSquareGate<f64>,
    /// The line matcher.
    pub matcher: Matcher,
    /// The line extractor.
    pub extractor: LineExtractor,
}

/// A laser mount table in which every key is optional (0 when missing).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PartialPose {
    #[serde(default)]
    x: f64,
    #[serde(default)]
    y: f64,
    #[serde(default)]
    theta: f64,
}

/// Reads `laser_mount` with each missing key at the identity's value. A `theta` beyond
/// ±2π is refused rather than wrapped: it is degrees, not radians.
fn mount_with_defaults<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Pose2<f64>, D::Error> {
    let p = PartialPose::deserialize(d)?;
    if !p.theta.is_finite() || p.theta.abs() > core::f64::consts::TAU {
        return Err(serde::de::Error::custom(format_args!(
            "theta: expected radians within ±2π (6.283), found {} (degrees?)",
            p.theta
        )));
    }
    Ok(Pose2::new(p.x, p.y, p.theta))
}

/// Compass heading noise and gate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CompassConfig {
    /// Heading variance (rad²). Default `(2°)² = 1.218e-3 rad²`: a CMPS03 is good to a
    /// few degrees indoors. The paper's "0.1°" is [`CompassConfig::paper`].
    pub variance: f64,
    /// Probability of the chi-square gate (1 dof) on the heading innovation. Default
    /// 0.999 (NIS ≤ 10.83, 3.3σ of the innovation): a magnetic disturbance, tens of
    /// degrees off, is far outside it. A narrower gate refuses more good headings, and
    /// refuses them just when the filter's error is largest (a rejection is likely only
    /// then): the filter keeps that error and believes itself better than it is, and the
    /// next heading is as likely to fail. In the paper's simulated room 0.99 left the
    /// heading NEES 9 % high and its RMSE 37 % larger (docs/RESULTS.md).
    pub gate_probability: f64,
    /// Recovery from gate lock-out: after this many rejected readings in a row, each
    /// agreeing with the one before (once odometry's turn between them is taken out)
    /// better than with the filter, and no laser line fused meanwhile, the filter is
    /// taken to be off: the heading error it missed is added to its covariance (with the
    /// position error its correlations tie to it) and the last reading fused without the
    /// gate. 0: never. A number of readings, not a time:
    /// default 3, 0.3 s at 10 Hz; raise it for a faster source (an AHRS at 100 Hz) or
    /// one whose disturbances last. See
    /// [`Localizer::update_compass`](super::Localizer::update_compass).
    pub recover_after: u32,
}

impl Default for CompassConfig {
    fn default() -> Self {
        let sigma = 2.0_f64.to_radians();
        Self {
            variance: sigma * sigma,
            gate_probability: 0.999,
            recover_after: 3,
        }
    }
}

impl CompassConfig {
    /// The paper's compass: "0.1° accuracy", i.e. variance `(0.1°)² = 3.05e-6 rad²`
    /// (docs/ERRATA.md 3: the paper's "0.01" is in degrees²); gate and recovery as the
    /// default.
    pub fn paper() -> Self {
        let sigma = 0.1_f64.to_radians();
        Self {
            variance: sigma * sigma,
            ..Self::default()
        }
    }
}

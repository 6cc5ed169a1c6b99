//! The `ekf` configuration file (TOML): topics, motion source, initial pose, compass
//! calibration, laser mounting source, and the filter's own [`LocalizerConfig`]. Every
//! key has a default; `ekf config` prints [`DEFAULT_TOML`], the documented defaults.
//! Unknown keys are errors (a typo must not silently fall back to a default).

use ekf_core::setting::{check, Expected, InvalidSetting};
use ekf_fusion::FusionError;
use lrf_lines::{LocalizerConfig, LocalizerError};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The documented default configuration, as `ekf config` prints it. A test checks that
/// it parses to exactly [`Config::default`].
pub const DEFAULT_TOML: &str = include_str!("default_config.toml");

/// Built-in presets, `(name, TOML text)`: overrides of the defaults for a known robot.
/// `paper-robot` is the paper's robot with the sensors `ekf simulate` models.
pub const PRESETS: [(&str, &str); 1] =
    [("paper-robot", include_str!("../presets/paper-robot.toml"))];

/// Why a configuration could not be used.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// What the OS said.
        source: std::io::Error,
    },
    /// The file is not valid TOML or has a wrong key or value; the message names the
    /// line, column and key.
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// The parser's message (line, column, key, what was expected).
        message: String,
    },
    /// No preset has this name.
    #[error("unknown preset {name:?}; the presets are: {}", PRESETS.map(|p| p.0).join(", "))]
    UnknownPreset {
        /// The name asked for.
        name: String,
    },
    /// A value is out of range.
    #[error("{path}: {}{key}: {message}", line.map(|l| format!("line {l}: ")).unwrap_or_default())]
    Invalid {
        /// The file.
        path: String,
        /// 1-based line of the key (or of its table) when the file sets it.
        line: Option<usize>,
        /// The offending key, dotted (`localizer.robot.track`).
        key: String,
        /// What was expected.
        message: String,
    },
}

/// The whole configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
pub struct Config {
    /// Topic names of the input log.
    pub topics: Topics,
    /// Where the motion comes from.
    pub motion: MotionConfig,
    /// The initial pose and its uncertainty (unless `--init-from-truth`).
    pub initial: InitialPose,
    /// How a `sensor_msgs/MagneticField` becomes a map heading.
    pub compass_calibration: CompassCalibrationConfig,
    /// Where the laser's mounting pose comes from.
    pub laser: LaserConfig,
    /// The filter: robot, noise models, laser mount, extraction, matching, compass.
    pub localizer: LocalizerConfig,
    /// Serial devices for `ekf live`.
    pub devices: crate::devices_config::DevicesConfig,
    /// GPS fixes as position measurements.
    pub gps: GpsConfig,
    /// How late a measurement may be and still be fused at its stamp.
    pub timing: TimingConfig,
    /// `ekf map build --slam`: key scans, loop closures, the pose graph.
    pub slam: crate::slam_config::SlamParams,
}

/// Measurements fused at their own stamps ([`ekf_fusion::TimedLocalizer`]): replay holds
/// each input back until one stamped `max_lag` later has been read, and fuses them in
/// stamp order.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TimingConfig {
    /// Longest a measurement may be logged after inputs stamped later than it and still be
    /// fused at its stamp (s); later ones are dropped and counted. 0 fuses in log order.
    pub max_lag: f64,
}

impl Default for TimingConfig {
    /// 0.5 s: robot_localization's usual `history_length` order, well above the few
    /// hundred milliseconds a busy robot computer takes to log a scan.
    fn default() -> Self {
        Self { max_lag: 0.5 }
    }
}

/// GPS fixes (`sensor_msgs/NavSatFix`) as position measurements: each fix is projected
/// onto the east–north tangent plane about the origin ([`crate::geo::GeoOrigin`]),
/// rotated into the map by `compass_calibration.map_offset`, and fused as `(x, y)` with
/// the fix's own covariance (or `sigma` when the fix has none) through a 2-dof gate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GpsConfig {
    /// Fuse the fixes (they are always recorded by `ekf live`).
    pub fuse: bool,
    /// Latitude of the map origin (degrees, north positive).
    pub origin_latitude: f64,
    /// Longitude of the map origin (degrees, east positive).
    pub origin_longitude: f64,
    /// Standard deviation of a fix in east and north (m) when it carries no covariance.
    pub sigma: f64,
    /// Chi-square gate on the 2-D position innovation.
    pub gate_probability: f64,
}

impl Default for GpsConfig {
    /// Off; origin (0, 0); σ 3 m (an uncorrected consumer receiver); gate 0.99.
    fn default() -> Self {
        Self {
            fuse: false,
            origin_latitude: 0.0,
            origin_longitude: 0.0,
            sigma: 3.0,
            gate_probability: 0.99,
        }
    }
}

/// Topic names (docs/ARCHITECTURE.md §4 defaults).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Topics {
    /// `sensor_msgs/msg/JointState` with the wheel joints.
    pub joint_states: String,
    /// `nav_msgs/msg/Odometry`, the alternative motion source.
    pub odom: String,
    /// `sensor_msgs/msg/LaserScan`.
    pub scan: String,
    /// `sensor_msgs/msg/Imu` (orientation yaw) or `sensor_msgs/msg/MagneticField`.
    pub compass: String,
    /// `nav_msgs/msg/Odometry` or `geometry_msgs/msg/PoseStamped`: the reference.
    pub ground_truth: String,
    /// `tf2_msgs/msg/TFMessage` with the static transforms.
    pub tf_static: String,
    /// `sensor_msgs/msg/NavSatFix`: GPS fixes (fused only with `gps.fuse`).
    pub fix: String,
}

impl Default for Topics {
    fn default() -> Self {
        Self {
            joint_states: "/joint_states".into(),
            odom: "/odom".into(),
            scan: "/scan".into(),
            compass: "/compass".into(),
            ground_truth: "/ground_truth".into(),
            tf_static: "/tf_static".into(),
            fix: "/fix".into(),
        }
    }
}

/// Which motion source drives the prediction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MotionSource {
    /// Wheel speeds from the joint states when the log has that topic, else odometry.
    Auto,
    /// Wheel speeds from `sensor_msgs/JointState` (paper eqs. 1–9).
    JointStates,
    /// Pose deltas of `nav_msgs/Odometry` with the odometry noise model.
    Odom,
}

/// The motion source and the wheel joints.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MotionConfig {
    /// `auto`, `joint_states` or `odom`.
    pub source: MotionSource,
    /// Name of the left wheel joint in the joint states.
    pub left_joint: String,
    /// Name of the right wheel joint in the joint states.
    pub right_joint: String,
}

impl Default for MotionConfig {
    fn default() -> Self {
        Self {
            source: MotionSource::Auto,
            left_joint: "left_wheel_joint".into(),
            right_joint: "right_wheel_joint".into(),
        }
    }
}

/// The initial pose (map frame) and its standard deviations.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct InitialPose {
    /// x (m).
    pub x: f64,
    /// y (m).
    pub y: f64,
    /// Heading (rad).
    pub theta: f64,
    /// Standard deviation of x and y (m).
    pub sigma_xy: f64,
    /// Standard deviation of the heading (rad).
    pub sigma_theta: f64,
}

impl Default for InitialPose {
    fn default() -> Self {
        Self {
            x: 0.0,
            y: 0.0,
            theta: 0.0,
            sigma_xy: 0.05,
            sigma_theta: 0.02,
        }
    }
}

/// Raw magnetometer → map heading: `θ = wrap(π/2 − (bearing + declination)) + map_offset`
/// (`ekf_core::heading_from_compass_bearing`). An `Imu` orientation is already an ENU yaw
/// and only gets `map_offset`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
pub struct CompassCalibrationConfig {
    /// Magnetic declination, east-positive (rad).
    pub declination: f64,
    /// Rotation from ENU to the map frame (rad): 0 when the map's x axis points east.
    pub map_offset: f64,
}

/// Where the laser's mounting pose comes from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LaserConfig {
    /// Use the transform `base_frame` → the scan's `frame_id` from `/tf_static` when the
    /// log has it (as ROS 2 bags do); otherwise `localizer.laser_mount`.
    pub mount_from_tf_static: bool,
    /// The robot's base frame in the TF tree.
    pub base_frame: String,
}

impl Default for LaserConfig {
    fn default() -> Self {
        Self {
            mount_from_tf_static: true,
            base_frame: "base_link".into(),
        }
    }
}

impl Config {
    /// The time-ordered localizer's configuration for `mode`, loss detection off (the
    /// caller knows whether there is a map to search).
    pub fn fusion(&self, mode: ekf_fusion::Mode) -> ekf_fusion::FusionConfig {
        ekf_fusion::FusionConfig {
            localizer: self.localizer.clone(),
            mode,
            tracking: ekf_fusion::Tracking::Off,
            max_lag: self.timing.max_lag,
            max_wheel_turns_per_s: self.devices.max_wheel_turns_per_s,
            position_gate_probability: self.gps.gate_probability,
        }
    }

    /// Parses TOML text; `path` names the source in errors.
    pub fn from_toml(text: &str, path: &str) -> Result<Self, ConfigError> {
        let config: Config = toml::from_str(text).map_err(|e| ConfigError::Parse {
            path: path.into(),
            message: e.to_string().trim_end().to_string(),
        })?;
        config.validated(path).map_err(|e| match e {
            ConfigError::Invalid {
                path, key, message, ..
            } => ConfigError::Invalid {
                line: line_of(text, &key),
                path,
                key,
                message,
            },
            other => other,
        })
    }

    /// The TOML text of the preset `name` ([`PRESETS`]).
    pub fn preset_text(name: &str) -> Result<&'static str, ConfigError> {
        PRESETS
            .iter()
            .find(|p| p.0 == name)
            .map(|p| p.1)
            .ok_or_else(|| ConfigError::UnknownPreset { name: name.into() })
    }

    /// The configuration of the preset `name` ([`PRESETS`]).
    pub fn preset(name: &str) -> Result<Self, ConfigError> {
        Self::from_toml(Self::preset_text(name)?, &format!("preset {name}"))
    }

    /// Reads and parses a TOML file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Io {
            path: name.clone(),
            source,
        })?;
        Self::from_toml(&text, &name)
    }

    /// Checks the values that serde cannot. Each section checks its own keys (the
    /// localizer's groups in `lrf-lines`, the fusion loop's in `ekf-fusion`, the rest
    /// here); this names the key as the file spells it.
    pub fn validated(self, path: &str) -> Result<Self, ConfigError> {
        let setting = |e: InvalidSetting| ConfigError::Invalid {
            path: path.into(),
            line: None,
            key: e.full_key().to_string(),
            message: e.message().to_string(),
        };
        let sections = [
            self.initial.validate().map_err(|e| e.in_table("initial")),
            self.gps.validate().map_err(|e| e.in_table("gps")),
            self.compass_calibration
                .validate()
                .map_err(|e| e.in_table("compass_calibration")),
            self.devices.validate().map_err(|e| e.in_table("devices")),
            self.slam.validate().map_err(|e| e.in_table("slam")),
        ];
        for result in sections {
            result.map_err(setting)?;
        }
        self.fusion(ekf_fusion::Mode::default())
            .validate()
            .map_err(|e| {
                let (key, message) = match e {
                    FusionError::Setting(e) => return setting(fusion_key_in_file(e)),
                    FusionError::Localizer(LocalizerError::Config { group, error }) => {
                        (format!("localizer.{group}"), error.to_string())
                    }
                    FusionError::Localizer(LocalizerError::Extraction(e)) => {
                        ("localizer.extraction".into(), e.to_string())
                    }
                    other => ("localizer".into(), other.to_string()),
                };
                ConfigError::Invalid {
                    path: path.into(),
                    line: None,
                    key,
                    message,
                }
            })?;
        Ok(self)
    }
}

/// A [`FusionConfig`](ekf_fusion::FusionConfig) key as the file spells it: the fusion
/// loop's own keys come from `[timing]`, `[devices]` and `[gps]`.
fn fusion_key_in_file(e: InvalidSetting) -> InvalidSetting {
    match e.key {
        "max_lag" => e.in_table("timing"),
        "max_wheel_turns_per_s" => e.in_table("devices"),
        "position_gate_probability" => InvalidSetting {
            key: "gate_probability",
            ..e
        }
        .in_table("gps"),
        _ => e,
    }
}

/// Largest map coordinate of a start pose (m): a UTM northing is below 1e7.
const MAX_MAP_COORDINATE_M: f64 = 1e7;

impl InitialPose {
    /// A pose within ±1e7 m (a UTM northing is below that) and ±2π rad, and positive
    /// standard deviations.
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        check("x", self.x, Expected::MetresWithin(MAX_MAP_COORDINATE_M))?;
        check("y", self.y, Expected::MetresWithin(MAX_MAP_COORDINATE_M))?;
        check("theta", self.theta, Expected::Radians)?;
        check("sigma_xy", self.sigma_xy, Expected::Positive)?;
        check("sigma_theta", self.sigma_theta, Expected::Positive)
    }
}

impl GpsConfig {
    /// A positive `sigma` and an origin off the poles (the tangent plane degenerates
    /// there) within ±180° of longitude. The gate is the fusion loop's
    /// (`position_gate_probability`).
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        check("sigma", self.sigma, Expected::Positive)?;
        check(
            "origin_latitude",
            self.origin_latitude,
            Expected::DegreesWithin(89.0, " (the tangent plane degenerates at the poles)"),
        )?;
        check(
            "origin_longitude",
            self.origin_longitude,
            Expected::DegreesWithin(180.0, ""),
        )
    }
}

impl CompassCalibrationConfig {
    /// Angles in radians within ±2π: a larger one is in degrees.
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        check("declination", self.declination, Expected::Radians)?;
        check("map_offset", self.map_offset, Expected::Radians)
    }
}

/// The 1-based line where `text` sets the dotted `key`, or the deepest table of it that
/// the text has; `None` when the text sets none of it (the value is a default).
fn line_of(text: &str, key: &str) -> Option<usize> {
    use toml::de::{DeTable, DeValue};
    let root = DeTable::parse(text).ok()?;
    let mut table = root.get_ref();
    let mut start = None;
    for part in key.split('.') {
        let Some((k, v)) = table.iter().find(|(k, _)| k.get_ref().as_ref() == part) else {
            break;
        };
        start = Some(k.span().start);
        match v.get_ref() {
            DeValue::Table(t) => table = t,
            _ => break,
        }
    }
    start.map(|s| text[..s].matches('\n').count() + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn documented_defaults_are_the_defaults() {
        let parsed = Config::from_toml(DEFAULT_TOML, "default").unwrap();
        assert_eq!(parsed, Config::default());
    }

    #[test]
    fn the_paper_robot_preset_sets_the_simulated_sensors_and_keeps_the_rest() {
        let c = Config::preset("paper-robot").unwrap();
        let e = &c.localizer.extraction;
        assert_eq!((e.range_sigma, e.split_distance), (0.03, 0.1));
        assert!((e.bearing_sigma - 0.25f64.to_radians()).abs() < 1e-15);
        assert!((c.localizer.compass.variance - 2f64.to_radians().powi(2)).abs() < 1e-15);
        let d = Config::default();
        assert_eq!((c.topics, c.localizer.robot), (d.topics, d.localizer.robot));
        let err = Config::preset("mars-rover").unwrap_err().to_string();
        assert!(
            err.contains("\"mars-rover\"") && err.contains("paper-robot"),
            "{err}"
        );
    }

    #[test]
    fn a_partial_table_takes_the_defaults_for_the_keys_it_leaves_out() {
        let text = "[localizer.robot]\ntrack = 0.5\n\n[localizer.odometry_noise]\na1 = 0.2\n\n\
                    [localizer.wheel_noise]\ndelta = 0.02\n";
        let c = Config::from_toml(text, "robot.toml").unwrap();
        let mut want = Config::default();
        want.localizer.robot.track = 0.5;
        want.localizer.odometry_noise.a1 = 0.2;
        want.localizer.wheel_noise.delta = 0.02;
        assert_eq!(c, want);
        // An unknown key in a partial table is still an error.
        let err = Config::from_toml("[localizer.robot]\ntrak = 0.5\n", "robot.toml").unwrap_err();
        assert!(err.to_string().contains("unknown field `trak`"), "{err}");
    }

    #[test]
    fn errors_name_line_and_key() {
        let err = Config::from_toml("[initial]\nx = 1.0\nsigma_xx = 2.0\n", "robot.toml")
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("robot.toml: "), "{err}");
        assert!(err.contains("line 3") && err.contains("sigma_xx"), "{err}");
        let err = Config::from_toml(
            "[localizer.robot]\nwheel_radius = 0.05\ntrack = \"wide\"\n",
            "r.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("line 3") && err.contains("track"), "{err}");
        let err = Config::from_toml(
            "[localizer.robot]\nwheel_radius = -0.05\ntrack = 0.5\n",
            "r.toml",
        )
        .unwrap_err()
        .to_string();
        assert_eq!(
            err,
            "r.toml: line 2: localizer.robot.wheel_radius: expected a finite number > 0, found -0.05"
        );
        // Finite but not a robot's, not an angle: named before anything runs.
        for (toml, expected) in [
            (
                "[localizer.robot]\nwheel_radius = 1e300\n",
                "w.toml: line 2: localizer.robot.wheel_radius: expected metres in (0, 2], \
                 found 1e300 (millimetres?)",
            ),
            (
                "[compass_calibration]\nmap_offset = 1e300\n",
                "w.toml: line 2: compass_calibration.map_offset: expected radians within \
                 ±2π (6.283), found 1e300 (degrees?)",
            ),
            (
                "[initial]\ny = -2e7\n",
                "w.toml: line 2: initial.y: expected metres within ±1e7, found -2e7",
            ),
            // The fusion loop's keys, checked in ekf-fusion, named as the file has them.
            (
                "[timing]\nmax_lag = 90\n",
                "w.toml: line 2: timing.max_lag: expected seconds in [0, 60], found 90",
            ),
            (
                "[gps]\nsigma = 2.0\ngate_probability = 1.5\n",
                "w.toml: line 3: gps.gate_probability: expected a probability in (0, 1), \
                 found 1.5",
            ),
            (
                "[devices]\nmax_wheel_turns_per_s = 0\n",
                "w.toml: line 2: devices.max_wheel_turns_per_s: expected a finite number > 0, \
                 found 0",
            ),
            (
                "[gps]\norigin_latitude = 100.67\n",
                "w.toml: line 2: gps.origin_latitude: expected degrees within ±89 (the tangent \
                 plane degenerates at the poles), found 100.67",
            ),
        ] {
            let err = Config::from_toml(toml, "w.toml").unwrap_err().to_string();
            assert_eq!(err, expected);
        }
        // A partial laser mount takes 0 for the keys it lacks; degrees are refused.
        let c = Config::from_toml("[localizer.laser_mount]\ntheta = -1.5\n", "m.toml").unwrap();
        assert_eq!(
            c.localizer.laser_mount,
            ekf_core::Pose2::new(0.0, 0.0, -1.5)
        );
        let err = Config::from_toml("[localizer.laser_mount]\ntheta = 90\n", "m.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("line 1") && err.contains("theta: expected radians within ±2π"),
            "{err}"
        );
        let err = Config::from_toml("[initial]\nx = 1.0\n\nsigma_theta = 0.0\n", "i.toml")
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "i.toml: line 4: initial.sigma_theta: expected a finite number > 0, found 0"
        );
        let err = Config::from_toml("[localizer.extraction]\nsplit_distanse = 0.1\n", "t.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("line 2") && err.contains("split_distanse"),
            "{err}"
        );
        let err = Config::from_toml(
            "[localizer.wheel_noise]\ndelta = 0.01\nflor = 0.0\n",
            "t.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("line 3") && err.contains("flor"), "{err}");
        let err = Config::from_toml("[motion]\nsource = \"gps\"\n", "m.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("line 2") && err.contains("gps"), "{err}");
        let err = Config::from_toml("[localizer.extraction]\nmin_points = 1\n", "e.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("localizer.extraction") && err.contains("min_points"),
            "{err}"
        );
        let err = Config::from_toml(
            "# map noise\n[localizer.matching]\nmap_sigma_r = -1\n",
            "m.toml",
        )
        .unwrap_err()
        .to_string();
        assert_eq!(
            err,
            "m.toml: line 2: localizer.matching: matching map_sigma_r is out of range: expected >= 0"
        );
    }
}

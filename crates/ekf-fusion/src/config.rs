//! What the localizer is configured with, beyond the filter's own configuration.

use crate::FusionError;
use ekf_core::setting::{check, Expected};
use lrf_lines::{LocalizerConfig, LocalizerError};

/// Longest lag an input may be held back for (s): a minute of inputs is more than any
/// robot computer's logging delay, and bounds the memory held.
const MAX_LAG_S: f64 = 60.0;

/// The default fastest wheel speed (turns/s): 10 turns/s is 3 m/s on a 10 cm wheel,
/// beyond what an indoor robot drives, well below an encoder glitch.
pub const DEFAULT_MAX_WHEEL_TURNS_PER_S: f64 = 10.0;

/// The paper's four estimator configurations (Fig. 9/10); the default is all sensors,
/// laser + compass.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mode {
    /// Prediction only: dead reckoning.
    Odometry,
    /// Prediction + compass.
    Compass,
    /// Prediction + laser lines.
    Laser,
    /// Prediction + laser lines + compass.
    #[default]
    LaserCompass,
}

impl Mode {
    /// All four, in the paper's order.
    pub const ALL: [Mode; 4] = [
        Mode::Odometry,
        Mode::Compass,
        Mode::Laser,
        Mode::LaserCompass,
    ];

    /// The name used on the command line and in summaries.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Odometry => "odometry",
            Mode::Compass => "compass",
            Mode::Laser => "laser",
            Mode::LaserCompass => "laser+compass",
        }
    }

    /// Whether the mode fuses the compass.
    pub fn uses_compass(self) -> bool {
        matches!(self, Mode::Compass | Mode::LaserCompass)
    }

    /// Whether the mode fuses laser lines.
    pub fn uses_laser(self) -> bool {
        matches!(self, Mode::Laser | Mode::LaserCompass)
    }
}

/// Whether the loss monitor ([`crate::tracking`]) runs, and how it starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Tracking {
    /// Off: the map is the first scan's, whose placement error is in the filter, so a
    /// restart would break it.
    #[default]
    Off,
    /// On, starting from the initial pose (a given map).
    FromInitialPose,
    /// Global localization: no initial pose; the map is searched from the first scans and
    /// the filter starts where the search locks on.
    Global,
}

/// The localizer's configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct FusionConfig {
    /// The filter, the line pipeline and the sensors' noise.
    pub localizer: LocalizerConfig,
    /// Which measurements are fused.
    pub mode: Mode,
    /// Loss detection and relocalization.
    pub tracking: Tracking,
    /// How late an input may come, after the newest one, and still be fused at its own
    /// stamp (s). Inputs are held back this long.
    pub max_lag: f64,
    /// Fastest the wheels can turn (turns/s): larger encoder increments are broken
    /// readings.
    pub max_wheel_turns_per_s: f64,
    /// Probability of the 2-dof chi-square gate on position fixes.
    pub position_gate_probability: f64,
}

impl Default for FusionConfig {
    fn default() -> Self {
        Self {
            localizer: LocalizerConfig::default(),
            mode: Mode::default(),
            tracking: Tracking::default(),
            max_lag: 0.5,
            max_wheel_turns_per_s: DEFAULT_MAX_WHEEL_TURNS_PER_S,
            position_gate_probability: 0.99,
        }
    }
}

impl FusionConfig {
    /// Checks the localizer's groups ([`LocalizerConfig::validate`], keys in the table
    /// `localizer`) and this configuration's own keys: `max_lag` in [0, 60] s,
    /// `max_wheel_turns_per_s` > 0, `position_gate_probability` in (0, 1). The
    /// [`Fuser`](crate::Fuser) refuses a configuration that fails this.
    pub fn validate(&self) -> Result<(), FusionError> {
        self.localizer.validate().map_err(|e| match e {
            LocalizerError::Setting(s) => FusionError::Setting(s.in_table("localizer")),
            other => FusionError::Localizer(other),
        })?;
        let ranges = [
            ("max_lag", self.max_lag, Expected::SecondsIn(0.0, MAX_LAG_S)),
            (
                "max_wheel_turns_per_s",
                self.max_wheel_turns_per_s,
                Expected::Positive,
            ),
            (
                "position_gate_probability",
                self.position_gate_probability,
                Expected::Probability,
            ),
        ];
        for (key, value, expected) in ranges {
            check(key, value, expected).map_err(FusionError::Setting)?;
        }
        Ok(())
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_pass_and_each_key_is_named_from_the_fusion_table() {
        assert_eq!(FusionConfig::default().validate(), Ok(()));
        let c = FusionConfig {
            max_lag: 61.0,
            ..FusionConfig::default()
        };
        assert_eq!(
            c.validate().unwrap_err().to_string(),
            "invalid config: max_lag: expected seconds in [0, 60], found 61"
        );
        let mut c = FusionConfig::default();
        c.localizer.robot.track = 600.0;
        assert_eq!(
            c.validate().unwrap_err().to_string(),
            "invalid config: localizer.robot.track: expected metres in (0, 10], found 600 \
             (millimetres?)"
        );
        let c = FusionConfig {
            position_gate_probability: 1.0,
            ..FusionConfig::default()
        };
        assert!(c
            .validate()
            .unwrap_err()
            .to_string()
            .contains("position_gate_probability"));
    }
}

//! What the localizer is configured with, beyond the filter's own configuration.

use lrf_lines::LocalizerConfig;

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
            max_wheel_turns_per_s: 10.0,
            position_gate_probability: 0.99,
        }
    }
}

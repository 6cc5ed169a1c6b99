//! Why the Localizer refused its configuration or an input.

use crate::ExtractionError;
use core::fmt;

/// A Localizer error. Every fallible call leaves the Localizer's state as it was.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LocalizerError {
    /// A configuration value is out of range.
    Config {
        /// The config group: `robot`, `wheel_noise`, `odometry_noise`, `laser_mount`,
        /// `matching` or `compass`.
        group: &'static str,
        /// What was wrong, naming the field.
        error: ekf_core::Error,
    },
    /// A configuration value is outside its range, named by its dotted key.
    Setting(ekf_core::InvalidSetting),
    /// The line extractor refused its parameters (group `extraction`) or a scan header.
    Extraction(ExtractionError),
    /// The filter refused an input (a non-finite initial state, wheel speed, motion or
    /// heading) or a step produced a non-finite state.
    Filter(ekf_core::Error),
}

impl fmt::Display for LocalizerError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Config { group, error } => write!(f, "invalid config [{group}]: {error}"),
            Self::Setting(e) => write!(f, "invalid config: {e}"),
            Self::Extraction(e) => write!(f, "line extraction: {e}"),
            Self::Filter(e) => write!(f, "filter: {e}"),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for LocalizerError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Config { error, .. } => Some(error),
            Self::Setting(e) => Some(e),
            Self::Extraction(e) => Some(e),
            Self::Filter(e) => Some(e),
        }
    }
}

impl From<ExtractionError> for LocalizerError {
    fn from(e: ExtractionError) -> Self {
        Self::Extraction(e)
    }
}

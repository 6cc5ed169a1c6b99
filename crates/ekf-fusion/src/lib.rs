//! The time-ordered localizer: typed, time-stamped inputs — wheel encoder angles or
//! speeds, odometry poses, headings, laser scans, position fixes — fused in stamp order
//! with the paper's EKF ([`lrf_lines::Localizer`] over [`ekf_core`]).
//!
//! * [`TimedLocalizer`] takes inputs as they arrive, holds each back until one stamped
//!   `max_lag` later has come ([`reorder`]), and fuses them in stamp order, each at its
//!   own stamp; it answers the pose now by predicting through what it holds.
//! * [`Fuser`] fuses inputs already in stamp order: motion predicts the state over its
//!   interval ([`motion`]), a measurement is fused after the state is brought to its stamp
//!   at the last motion rate, broken wheel readings are skipped ([`wheels`]), and with a
//!   given map the loss monitor ([`tracking`], [`verification`]) finds a lost filter
//!   again; a consistency monitor ([`consistency`]) watches the laser innovations.
//!
//! `ekf replay` (`ekf-ros`), `ekf live` (`ekf-devices`), the simulator (`ekf-sim`) and
//! the Python module drive this loop; docs/ARCHITECTURE.md shows where it sits. `#![no_std]` with `alloc` unless the
//! default `std` feature is on; the `serde` feature makes the counts serializable.

#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

pub mod config;
pub mod consistency;
pub mod counts;
pub mod fuser;
pub mod input;
pub mod motion;
pub mod reorder;
pub mod timed;
pub mod tracking;
pub mod verification;
pub mod wheels;

pub use config::{FusionConfig, Mode, Tracking, DEFAULT_MAX_WHEEL_TURNS_PER_S};
pub use counts::{CompassCounts, FusionCounts, GatedCounts, LineCounts};
pub use fuser::{Forecast, Fused, Fuser, Predicted, ScanFused, TrackingChange};
pub use input::{Input, Scan, Skip};
pub use reorder::{Reorder, TooLate};
pub use timed::{Step, TimedLocalizer};

use core::fmt;
use lrf_lines::LocalizerError;

/// Why the localizer could not go on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FusionError {
    /// The filter refused its configuration or an input, or a step produced a non-finite
    /// state.
    Localizer(LocalizerError),
    /// A configuration value is outside its range ([`FusionConfig::validate`]).
    Setting(ekf_core::InvalidSetting),
    /// Loss detection and relocalization ([`Tracking::FromInitialPose`],
    /// [`Tracking::Global`]) need a given map: a first-scan map carries its own placement
    /// error in the filter, which a restart would break.
    TrackingNeedsMap,
}

impl fmt::Display for FusionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Localizer(e) => e.fmt(f),
            Self::Setting(e) => write!(f, "invalid config: {e}"),
            Self::TrackingNeedsMap => write!(
                f,
                "loss detection and global localization need a map (a first-scan map cannot \
                 be searched)"
            ),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for FusionError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Localizer(e) => Some(e),
            Self::Setting(e) => Some(e),
            Self::TrackingNeedsMap => None,
        }
    }
}

impl From<LocalizerError> for FusionError {
    fn from(e: LocalizerError) -> Self {
        Self::Localizer(e)
    }
}

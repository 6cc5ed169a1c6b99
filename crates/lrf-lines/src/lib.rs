//! Line features from 2-D laser scans, maps of lines, matching against a map, and the
//! `Localizer` facade that drives one localization step over `ekf-core`.
//!
//! `#![no_std]` with `alloc` (unless the default `std` feature is on). Scans are shaped
//! like ROS `sensor_msgs/LaserScan`; all lengths in metres, angles in radians,
//! counter-clockwise, in the sensor frame unless a name says otherwise. Computations are
//! in `f64` (on a Cortex-M4F that runs in software; the per-scan cost stays small).
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

mod checks;
pub mod extract;
pub mod localizer;
pub mod map;
pub mod matching;
pub mod observed;
pub mod point3d;
pub mod relocalize;
pub mod scan;

pub use extract::{ExtractionError, ExtractionParams, LineExtractor};
pub use localizer::{
    CompassConfig, CompassUpdate, LineFusion, Localizer, LocalizerConfig, LocalizerError,
    ScanReport, ScanStage, StageClock, REFIT_AFTER_LINES,
};
pub use map::{LineMap, MapBuilder, MapBuilderParams, MapFormatError, MapSegment};
pub use matching::{
    LineMatch, MatchParams, MatchResult, Matcher, RejectReason, Rejection, WallErrors,
};
pub use observed::ObservedLine;
pub use point3d::pitched_scan_point;
pub use relocalize::{
    direction_diff, fit_poses, relocalize, HeadingWindow, Hypothesis, PoseFits, Relocalization,
    RelocalizeParams, SearchWindow,
};
pub use scan::LaserScan;
pub use scan::ScanError;

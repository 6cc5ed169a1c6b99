//! What the localizer did with its inputs, counted.

use crate::consistency::ConsistencyCounts;
use crate::tracking::TrackingCounts;

/// Counts of the laser pipeline.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct LineCounts {
    /// Scans read.
    pub scans: u64,
    /// Scans used for an update (0 in the modes without laser).
    pub scans_used: u64,
    /// Lines extracted.
    pub extracted: u64,
    /// Lines matched to the map (passed gate and overlap).
    pub matched: u64,
    /// Lines not matched (outside the gate, no overlap, wall taken).
    pub rejected: u64,
    /// Matched lines fused.
    pub fused: u64,
    /// Matched lines refused by the re-evaluated gate.
    pub refused: u64,
    /// Walls no fused line lay on, fitted from the scan points on them and fused
    /// (`refit_missed_walls`).
    pub refitted: u64,
    /// Observed lines fitted together with another line on the same wall and fused with
    /// it as one.
    pub merged: u64,
}

/// Counts of a gated measurement's updates (position fixes).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct GatedCounts {
    /// Measurements fused.
    pub accepted: u64,
    /// Measurements rejected by the chi-square gate.
    pub rejected: u64,
}

/// Counts of the compass headings.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct CompassCounts {
    /// Headings fused.
    pub accepted: u64,
    /// Headings rejected by the chi-square gate.
    pub rejected: u64,
    /// Of those fused, the ones that failed the gate and were fused to end a gate
    /// lock-out (`CompassConfig::recover_after`).
    pub recovered: u64,
    /// Of those rejected, the ones whose lock-out recovery the laser refused: the last
    /// scan's lines fit the filter's heading better (a stuck or biased compass).
    pub refused_by_laser: u64,
    /// Of those rejected, the ones not even tried: the compass did not follow the
    /// robot's turns as odometry measured them (stuck, or not measuring the heading).
    pub not_following: u64,
}

/// Everything the localizer counts.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FusionCounts {
    /// Motion steps predicted.
    pub motion_steps: u64,
    /// Of those, wheel readings predicted from their velocities because their encoder
    /// angles stood still against them ([`crate::wheels::WheelTracker::angles`]).
    pub wheel_velocities_used: u64,
    /// Laser pipeline counts.
    pub lines: LineCounts,
    /// Compass counts.
    pub compass: CompassCounts,
    /// Position fix counts.
    pub positions: GatedCounts,
    /// Losses and relocalizations ([`crate::tracking`]).
    pub tracking: TrackingCounts,
    /// The laser innovations' consistency ([`crate::consistency`]).
    pub consistency: ConsistencyCounts,
    /// Inputs stamped before one already fused, more than the lag late: dropped.
    pub too_late: u64,
}

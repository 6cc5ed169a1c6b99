//! The summary of a replay (`ekf replay`'s table, `--json`'s object), and the per-stage
//! timing record.

use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt;

/// Median and 99th percentile of one stage's durations (µs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StageTiming {
    /// Number of timed calls.
    pub count: u64,
    /// Median (µs), to within 1 %.
    pub median_us: f64,
    /// 99th percentile (µs), to within 1 %.
    pub p99_us: f64,
}

/// Durations in a fixed log-spaced histogram (bins 1 % wide from 0.01 µs to about
/// 10 s), so that the percentiles of a replay of any length take constant memory.
#[derive(Debug, Clone)]
pub struct LatencyHistogram {
    counts: Vec<u64>,
    total: u64,
}

const LOWEST_US: f64 = 0.01;
const GROWTH: f64 = 1.01;
const BINS: usize = 2800;

impl Default for LatencyHistogram {
    fn default() -> Self {
        Self {
            counts: vec![0; BINS],
            total: 0,
        }
    }
}

impl LatencyHistogram {
    /// Records one duration (µs).
    pub fn record(&mut self, us: f64) {
        let bin = if us > LOWEST_US {
            ((us / LOWEST_US).ln() / GROWTH.ln()) as usize
        } else {
            0
        };
        self.counts[bin.min(BINS - 1)] += 1;
        self.total += 1;
    }

    /// The nearest-rank quantile `q`, as the geometric centre of its bin (µs).
    pub fn quantile(&self, q: f64) -> f64 {
        let rank = ((q * self.total as f64).ceil() as u64).max(1);
        let mut seen = 0;
        for (i, &c) in self.counts.iter().enumerate() {
            seen += c;
            if seen >= rank {
                return LOWEST_US * GROWTH.powf(i as f64 + 0.5);
            }
        }
        0.0
    }

    /// Count, median and 99th percentile.
    pub fn timing(&self) -> StageTiming {
        if self.total == 0 {
            return StageTiming::default();
        }
        StageTiming {
            count: self.total,
            median_us: self.quantile(0.5),
            p99_us: self.quantile(0.99),
        }
    }
}

/// Per-stage timings of the scan updates.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Timings {
    /// Line extraction.
    pub extraction: StageTiming,
    /// Matching against the map.
    pub matching: StageTiming,
    /// The sequential EKF update.
    pub update: StageTiming,
}

pub use ekf_fusion::{CompassCounts, GatedCounts, LineCounts};

/// Accuracy against the log's reference (`evo`'s APE without alignment).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Accuracy {
    /// Estimated poses matched to a reference pose by time stamp (within 10 ms).
    pub matched_poses: usize,
    /// Position RMSE (m).
    pub position_rmse_m: f64,
    /// Median position error (m).
    pub position_median_m: f64,
    /// 95th percentile of the position error (m).
    pub position_p95_m: f64,
    /// Largest position error (m).
    pub position_max_m: f64,
    /// Share of matched poses with a position error over 0.5 m (0–1).
    pub share_over_half_m: f64,
    /// Share of matched poses with a position error over 1 m (0–1).
    pub share_over_1m: f64,
    /// Heading RMSE (degrees).
    pub heading_rmse_deg: f64,
}

/// A message that was read but not used, and why.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Warning {
    /// Its topic.
    pub topic: String,
    /// Its log time (ns).
    pub log_time_ns: u64,
    /// The check that skipped or flagged it (the key of [`ReplaySummary::checks`]).
    pub check: String,
    /// Why it was skipped.
    pub reason: String,
}

/// Everything `ekf replay --json` prints.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ReplaySummary {
    /// The input log.
    pub log: String,
    /// The estimator configuration (`odometry`, `compass`, `laser`, `laser+compass`).
    pub mode: String,
    /// Where the motion came from (a topic name).
    pub motion_topic: String,
    /// Where the map came from (`first scan` or a file) and its size.
    pub map: String,
    /// Map segments.
    pub map_segments: usize,
    /// The laser mounting pose used, `[x, y, θ]`, and where it came from.
    pub laser_mount: [f64; 3],
    /// `config` or `tf_static`.
    pub laser_mount_source: String,
    /// Messages read per topic, those dropped as too late included.
    pub messages_read: BTreeMap<String, u64>,
    /// Motion steps predicted.
    pub motion_steps: u64,
    /// Poses written (TUM rows).
    pub poses_written: u64,
    /// Laser pipeline counts.
    pub lines: LineCounts,
    /// Compass counts.
    pub compass: CompassCounts,
    /// GPS fix counts (both 0 unless `gps.fuse`).
    pub gps: GatedCounts,
    /// Losses and relocalizations ([`ekf_fusion::tracking`]).
    pub tracking: ekf_fusion::tracking::TrackingCounts,
    /// The laser innovations' consistency ([`ekf_fusion::consistency`]).
    pub consistency: ekf_fusion::consistency::ConsistencyCounts,
    /// Per-stage timings of the scan updates.
    pub timings: Timings,
    /// Wall-clock time of the replay (s).
    pub wall_time_s: f64,
    /// Messages skipped, in total.
    pub warning_count: u64,
    /// Of those, inputs stamped before one already fused, more than `[timing] max_lag`
    /// late ([`ekf_fusion::TimedLocalizer`]).
    pub too_late: u64,
    /// The first skipped messages with their reasons (at most 20).
    pub warnings: Vec<Warning>,
    /// Messages skipped or flagged, by the check that did it (`duplicate_stamp`,
    /// `implausible`, `compass_stuck`, `gps_off_the_globe`, `damaged_log`, …); they sum
    /// to `warning_count`.
    pub checks: BTreeMap<String, u64>,
    /// Accuracy against the reference, when the log has one.
    pub accuracy: Option<Accuracy>,
    /// What about the log or the configuration a user may want to act on, e.g. a
    /// reference trajectory under another topic name.
    pub notes: Vec<String>,
    /// Damaged stretches of the log that were read past, in the order met: their
    /// messages are lost, the replay went on after each.
    pub damaged: Vec<DamagedStretch>,
    /// Input messages whose CDR could not be decoded, skipped (each also a warning).
    pub undecodable: u64,
}

/// A damaged stretch of a log that the replay read past.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DamagedStretch {
    /// The storage file.
    pub file: String,
    /// Where the damaged chunk starts (byte offset).
    pub byte_offset: u64,
    /// The log times whose messages were lost.
    pub lost: crate::mcap_io::LostRange,
    /// What the MCAP reader found.
    pub reason: String,
}

impl DamagedStretch {
    /// The stretch a read error reports, if it is damage that was read past.
    pub fn of(e: &crate::mcap_io::ReadError) -> Option<Self> {
        match e {
            crate::mcap_io::ReadError::SkippedChunk {
                path,
                offset,
                lost,
                source,
            } => Some(Self {
                file: path.display().to_string(),
                byte_offset: *offset,
                lost: *lost,
                reason: source.to_string(),
            }),
            _ => None,
        }
    }
}

/// Most warnings kept verbatim in the summary.
pub const MAX_WARNINGS: usize = 20;

impl ReplaySummary {
    /// Records a message skipped or flagged by `check`; returns how many `check` has
    /// counted.
    pub fn warn(&mut self, topic: &str, log_time_ns: u64, check: &str, reason: String) -> u64 {
        self.warning_count += 1;
        let count = self.checks.entry(check.to_owned()).or_default();
        *count += 1;
        let count = *count;
        if self.warnings.len() < MAX_WARNINGS {
            self.warnings.push(Warning {
                topic: topic.into(),
                log_time_ns,
                check: check.into(),
                reason,
            });
        }
        count
    }
}

/// The summary as `ekf replay` prints it: one line per stage, lines of what did not
/// happen (GPS, tracking losses, skipped messages) left out.
impl fmt::Display for ReplaySummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{} ({}, map: {}, {} segments)",
            self.log, self.mode, self.map, self.map_segments
        )?;
        let l = &self.lines;
        writeln!(
            f,
            "  motion steps {}, poses written {}, scans {} (used {})",
            self.motion_steps, self.poses_written, l.scans, l.scans_used
        )?;
        writeln!(
            f,
            "  lines: extracted {}, matched {}, rejected {} ({} of them fused with another line of their wall), fused {}, refused {}; walls refitted from points {}",
            l.extracted, l.matched, l.rejected, l.merged, l.fused, l.refused, l.refitted
        )?;
        let c = &self.compass;
        writeln!(
            f,
            "  compass: fused {} ({} to end a gate lock-out), rejected {}",
            c.accepted, c.recovered, c.rejected
        )?;
        if self.gps.accepted + self.gps.rejected > 0 {
            writeln!(
                f,
                "  gps: fused {}, rejected {}",
                self.gps.accepted, self.gps.rejected
            )?;
        }
        if let Some(a) = &self.accuracy {
            writeln!(
                f,
                "  accuracy vs reference ({} poses): position RMSE {:.3} m (median {:.3}, p95 \
                 {:.3}, max {:.3} m; over 1 m on {:.1} %), heading RMSE {:.2}°",
                a.matched_poses,
                a.position_rmse_m,
                a.position_median_m,
                a.position_p95_m,
                a.position_max_m,
                100.0 * a.share_over_1m,
                a.heading_rmse_deg
            )?;
        }
        let t = &self.timings;
        writeln!(
            f,
            "  per scan (median/p99 µs): extraction {:.1}/{:.1}, matching {:.1}/{:.1}, update \
             {:.1}/{:.1}",
            t.extraction.median_us,
            t.extraction.p99_us,
            t.matching.median_us,
            t.matching.p99_us,
            t.update.median_us,
            t.update.p99_us
        )?;
        if let Some(w) = self.warnings.first() {
            writeln!(
                f,
                "  {} messages skipped, e.g. {} at {} ns: {}",
                self.warning_count, w.topic, w.log_time_ns, w.reason
            )?;
        }
        let k = &self.tracking;
        if k.losses + k.searches > 0 || k.locked_on_scan.is_some() {
            write!(
                f,
                "  tracking: lost {} times ({} motion gaps), {} scans lost, {} relocalizations \
                 ({} searches, {} refused)",
                k.losses, k.motion_gaps, k.scans_lost, k.relocalizations, k.searches, k.refused
            )?;
            if let Some(n) = k.locked_on_scan {
                write!(f, "; locked on at scan {n}")?;
            }
            if k.lost_at_end > 0 {
                write!(f, "; lost at the end")?;
            }
            writeln!(f)?;
        }
        let c = &self.consistency;
        if let Some(nis) = c.nis_per_dof {
            writeln!(
                f,
                "  line innovations: NIS per dof {nis:.2}; over-confident on {} of {} scans ({} \
                 stretches)",
                c.over_confident_scans, c.scans, c.over_confident_stretches
            )?;
        }
        for d in &self.damaged {
            writeln!(
                f,
                "  damaged: {} at byte {} read past ({}): {}",
                d.file, d.byte_offset, d.lost, d.reason
            )?;
        }
        for note in &self.notes {
            writeln!(f, "  note: {note}")?;
        }
        writeln!(f, "  wall time {:.2} s", self.wall_time_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_within_one_percent() {
        let mut h = LatencyHistogram::default();
        for v in (1..=200).rev() {
            h.record(f64::from(v));
        }
        let t = h.timing();
        assert_eq!(t.count, 200);
        assert!((t.median_us / 100.0 - 1.0).abs() < 0.01, "{t:?}");
        assert!((t.p99_us / 198.0 - 1.0).abs() < 0.01, "{t:?}");
        assert_eq!(LatencyHistogram::default().timing(), StageTiming::default());
        // Out-of-range values land in the end bins instead of panicking.
        h.record(0.0);
        h.record(1e12);
        assert_eq!(h.timing().count, 202);
    }

    #[test]
    fn table_shows_only_what_happened() {
        let mut s = ReplaySummary {
            log: "run.mcap".into(),
            mode: "laser".into(),
            map: "first scan".into(),
            map_segments: 5,
            motion_steps: 600,
            poses_written: 601,
            wall_time_s: 0.123,
            ..ReplaySummary::default()
        };
        s.lines.scans = 301;
        s.lines.scans_used = 300;
        let quiet = "run.mcap (laser, map: first scan, 5 segments)\n  \
            motion steps 600, poses written 601, scans 301 (used 300)\n  \
            lines: extracted 0, matched 0, rejected 0 (0 of them fused with another line of their wall), fused 0, refused 0; walls refitted from points 0\n  \
            compass: fused 0 (0 to end a gate lock-out), rejected 0\n  \
            per scan (median/p99 µs): extraction 0.0/0.0, matching 0.0/0.0, update 0.0/0.0\n  \
            wall time 0.12 s\n";
        assert_eq!(s.to_string(), quiet);
        s.gps.accepted = 3;
        s.warn("/scan", 42, "test", "bad".into());
        s.tracking.searches = 2;
        s.tracking.locked_on_scan = Some(7);
        s.tracking.lost_at_end = 1;
        s.notes.push("look".into());
        let text = s.to_string();
        for line in [
            "  gps: fused 3, rejected 0\n",
            "  1 messages skipped, e.g. /scan at 42 ns: bad\n",
            "  tracking: lost 0 times (0 motion gaps), 0 scans lost, 0 relocalizations (2 \
             searches, 0 refused); locked on at scan 7; lost at the end\n",
            "  note: look\n",
        ] {
            assert!(text.contains(line), "{line:?} missing from {text}");
        }
        assert_eq!(text.lines().count(), quiet.lines().count() + 4);
    }
}

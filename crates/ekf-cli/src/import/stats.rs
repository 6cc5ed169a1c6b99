//! What an import saw: record counts, time span, time going backwards, skipped lines.

use super::record::ImportRecord;
use serde::Serialize;

/// Counts kept while importing; complete once the iterator has returned `None`.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ImportStats {
    /// Odometry records yielded.
    pub odometry: u64,
    /// Scan records yielded.
    pub scans: u64,
    /// Reference records yielded.
    pub references: u64,
    /// Compass records yielded.
    pub compass: u64,
    /// CARMEN "corrected" reset records recognised and left out of the odometry chain.
    pub odometry_resets: u64,
    /// Earliest record time (ns).
    pub t_min_ns: Option<u64>,
    /// Latest record time (ns).
    pub t_max_ns: Option<u64>,
    /// Records whose time is earlier than the record yielded before them. They are kept
    /// in file order, not sorted.
    pub backwards_time: u64,
    /// Timestamps repaired (CARMEN): what kind, how many, the first lines.
    pub time_repairs: TimeRepairs,
    /// Records left out because they repeat the record before them exactly (CARMEN).
    pub duplicates: RepairCount,
    /// Scans with negative range readings, which no scanner measures: those readings are
    /// written as NaN (no return, as `sensor_msgs/LaserScan` has it). Non-finite ones are
    /// errors naming the field.
    pub invalid_ranges: RepairCount,
    /// The range at and beyond which `FLASER` readings are no return (m), and where it came
    /// from; `None` before the first scan.
    pub laser_range_max: Option<RangeMax>,
    /// `#` comment lines.
    pub comment_lines: u64,
    /// `PARAM` lines.
    pub param_lines: u64,
    /// `NEFF` lines (a leftover of the SLAM run that made a corrected log).
    pub neff_lines: u64,
    /// Lines of record types the importer does not read (e.g. `RLASER`, `TRUEPOS`).
    pub unknown_lines: u64,
}

/// Where a log's laser range limit came from.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RangeMaxSource {
    /// The readings saturate: many sit within 1 % of the largest one.
    Saturation,
    /// The log's `PARAM robot_front_laser_max` (no saturation seen).
    Param,
    /// The importer's option (no saturation seen, no `PARAM`).
    Default,
}

/// Where the limit came from, as the import summary says it.
impl std::fmt::Display for RangeMaxSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            RangeMaxSource::Saturation => "where the readings saturate",
            RangeMaxSource::Param => "the log's PARAM robot_front_laser_max",
            RangeMaxSource::Default => "--laser-max-range",
        })
    }
}

/// A log's laser range limit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RangeMax {
    /// Readings at or beyond it are no return (m).
    pub value: f64,
    /// Where it came from.
    pub source: RangeMaxSource,
}

impl ImportStats {
    /// Latest minus earliest record time (ns); 0 before any record.
    pub fn span_ns(&self) -> u64 {
        match (self.t_min_ns, self.t_max_ns) {
            (Some(a), Some(b)) => b - a,
            _ => 0,
        }
    }

    /// Accounts for one yielded record, `prev_ns` being the time of the record before it.
    pub(crate) fn count(&mut self, record: &ImportRecord, prev_ns: Option<u64>) {
        match record {
            ImportRecord::Odometry(_) => self.odometry += 1,
            ImportRecord::Scan(_) => self.scans += 1,
            ImportRecord::Reference(_) => self.references += 1,
            ImportRecord::Compass(_) => self.compass += 1,
        }
        let t = record.t_ns();
        if prev_ns.is_some_and(|p| t < p) {
            self.backwards_time += 1;
        }
        self.t_min_ns = Some(self.t_min_ns.map_or(t, |m| m.min(t)));
        self.t_max_ns = Some(self.t_max_ns.map_or(t, |m| m.max(t)));
    }
}

/// How many line numbers a [`RepairCount`] keeps.
const FIRST_LINES: usize = 5;

/// How often one kind of repair was made, and where.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct RepairCount {
    /// Records repaired.
    pub count: u64,
    /// The first few of their 1-based line numbers.
    pub first_lines: Vec<u64>,
}

impl RepairCount {
    /// Counts one repair at `line`.
    pub(crate) fn add(&mut self, line: u64) {
        self.count += 1;
        if self.first_lines.len() < FIRST_LINES {
            self.first_lines.push(line);
        }
    }
}

/// The clock repairs of an import (see the module docs for the rules).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct TimeRepairs {
    /// The clock was judged broken throughout: every record has a synthetic time in file
    /// order, [`SYNTHETIC_STEP_NS`](super::clock::SYNTHETIC_STEP_NS) apart (a sensor record directly after an odometry
    /// record shares its time). The other counts stay 0 then.
    pub clock_broken: bool,
    /// Negative stamps repaired.
    pub negative: RepairCount,
    /// Zero stamps repaired.
    pub zero: RepairCount,
    /// Non-zero stamps below one nanosecond repaired.
    pub denormal: RepairCount,
    /// Stamps earlier than the last good one repaired.
    pub backwards: RepairCount,
}

impl TimeRepairs {
    /// Records whose time is not their own stamp (all of them when the clock is broken).
    pub fn repaired(&self) -> u64 {
        self.negative.count + self.zero.count + self.denormal.count + self.backwards.count
    }
}

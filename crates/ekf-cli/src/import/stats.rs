//! What an import saw: record counts, time span, time going backwards, skipped lines.

use super::record::ImportRecord;

/// Counts kept while importing; complete once the iterator has returned `None`.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
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
    /// `#` comment lines.
    pub comment_lines: u64,
    /// `PARAM` lines.
    pub param_lines: u64,
    /// `NEFF` lines (a leftover of the SLAM run that made a corrected log).
    pub neff_lines: u64,
    /// Lines of record types the importer does not read (e.g. `RLASER`, `TRUEPOS`).
    pub unknown_lines: u64,
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

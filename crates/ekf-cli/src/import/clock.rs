//! Repairs a text log's clock: timestamps that are negative, zero, below a nanosecond or
//! out of order get a time from the file order and their neighbours; a log whose clock is
//! broken throughout gets synthetic times in file order.
//!
//! # Rules
//!
//! Records arrive in file order, each with its own stamp or sharing the stamp of the
//! record before it (a reference yielded for a scan). The first [`PROBE_RECORDS`] records
//! with a stamp of their own decide whether the clock can be trusted at all:
//!
//! * **Broken throughout** when fewer than half of the stamps in that window are positive
//!   times, or fewer than half of the consecutive positive ones increase (CARMEN logs
//!   whose stamps are all 0, run backwards, or are printed with six significant digits so
//!   that thousands of records share one value). The records then get synthetic times in
//!   file order, `SYNTHETIC_STEP_NS` apart, and the summary says so; but a sensor record
//!   directly after an odometry record shares that record's time. Without a clock nothing
//!   says that time passed between the two, and where CARMEN's clock works every scan
//!   carries the stamp of the odometry record before it (4,225 of 4,225 in the nine
//!   shared logs). Replay then fuses the scan where the odometry left the robot instead of
//!   carrying the robot on for another step at its last rate.
//! * **Otherwise** a stamp is *good* when it is a positive time not before the last good
//!   stamp. A record with a bad stamp (negative, 0, a non-zero value below 1 ns such as
//!   `8.97e-67`, or earlier than the last good stamp) waits for the next good stamp; the
//!   records waiting between two good stamps `a` and `b` are spread evenly over `(a, b)`
//!   by their place in the file. Bad stamps before the first good one take its time; bad
//!   stamps after the last one follow it at `SYNTHETIC_STEP_NS` each. At most
//!   [`PROBE_RECORDS`] records wait: a longer run of bad stamps is placed after the last
//!   good stamp at `SYNTHETIC_STEP_NS` each, and the last of them becomes the new anchor.
//!
//! Each kind of repair is counted in [`TimeRepairs`](super::TimeRepairs) with the first few line numbers. In
//! strict mode the first bad stamp is an error naming its line instead.

use super::error::ImportError;
use super::fields::RawStamp;
use super::record::ImportRecord;
use super::stream::Output;
use std::collections::VecDeque;

/// Records with their own stamp that decide whether the clock is broken throughout, and
/// the most records that wait for a good stamp.
pub const PROBE_RECORDS: usize = 1000;

/// Time between records given synthetic times (ns): 0.1 s, a typical odometry period.
pub const SYNTHETIC_STEP_NS: u64 = 100_000_000;

/// Where a record's time comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Stamp {
    /// Its own stamp, from field `field` (named `name`) of its line.
    Own {
        raw: RawStamp,
        field: usize,
        name: &'static str,
    },
    /// The time of the record before it (a reference or compass reading made for a scan).
    Shared,
}

/// A record waiting for its time.
#[derive(Debug)]
pub(crate) struct Entry {
    pub(crate) record: ImportRecord,
    pub(crate) line: u64,
    pub(crate) tag: &'static str,
    pub(crate) stamp: Stamp,
}

/// Whether the clock is trusted, once the probe window is judged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    Trusted,
    Broken,
}

/// Assigns each record its time; see the module docs.
#[derive(Debug)]
pub(crate) struct ClockRepair {
    strict: bool,
    mode: Option<Mode>,
    /// Records waiting for the next good stamp (trusted mode).
    waiting: VecDeque<Entry>,
    /// The last good (or synthetic) time given.
    anchor_ns: Option<u64>,
    /// The time given to the last record.
    last_ns: u64,
    /// Synthetic steps taken so far (broken mode).
    placed: u64,
    /// The last record placed with a stamp of its own was odometry (broken mode).
    after_odometry: bool,
    /// The first good stamp (trusted mode).
    first_ns: Option<u64>,
    /// A run of increasing stamps earlier than the anchor that began at the log's first
    /// stamp: (its first line, its first stamp, its last stamp, its length).
    restart: Option<(u64, u64, u64, usize)>,
}

/// Increasing stamps in a row, earlier than the last good one and beginning within a
/// second of the log's first stamp, that show the log starting over (one stray stamp
/// back at the start does not).
pub const RESTART_RECORDS: usize = 20;

/// How close to the log's first stamp a run must begin to be the log starting over.
const RESTART_TOLERANCE_NS: u64 = 1_000_000_000;

impl ClockRepair {
    /// A repair that has not judged the clock yet; `strict` makes a bad stamp an error.
    pub(crate) fn new(strict: bool) -> Self {
        Self {
            strict,
            mode: None,
            waiting: VecDeque::new(),
            anchor_ns: None,
            last_ns: 0,
            placed: 0,
            after_odometry: false,
            first_ns: None,
            restart: None,
        }
    }

    /// Judges the clock from the probe window `entries` (file order) and notes the verdict
    /// in `out`'s stats; see the module docs.
    pub(crate) fn judge(&mut self, entries: &[Entry], out: &mut Output) -> Result<(), ImportError> {
        let stamps: Vec<Option<u64>> = entries
            .iter()
            .filter_map(|e| match e.stamp {
                Stamp::Own { raw, .. } => Some(match raw {
                    RawStamp::Valid(ns) => Some(ns),
                    _ => None,
                }),
                Stamp::Shared => None,
            })
            .collect();
        let valid: Vec<u64> = stamps.iter().flatten().copied().collect();
        let pairs = valid.len().saturating_sub(1);
        let increasing = valid.windows(2).filter(|w| w[1] > w[0]).count();
        let broken = 2 * valid.len() < stamps.len() || (pairs > 0 && 2 * increasing < pairs);
        if broken && self.strict {
            let first = entries.first().map_or(1, |e| e.line);
            return Err(ImportError::BrokenClock {
                line: first,
                stamps: stamps.len(),
                valid: valid.len(),
                increasing,
                pairs,
            });
        }
        self.mode = Some(if broken { Mode::Broken } else { Mode::Trusted });
        out.stats.time_repairs.clock_broken = broken;
        Ok(())
    }

    /// Gives `entry` its time, appending records whose time is known to `out`'s queue in
    /// file order and counting repairs in its stats. Before [`judge`](Self::judge) the
    /// clock is trusted.
    pub(crate) fn place(&mut self, entry: Entry, out: &mut Output) -> Result<(), ImportError> {
        match self.mode {
            Some(Mode::Broken) => {
                if matches!(entry.stamp, Stamp::Own { .. }) {
                    let odometry = matches!(entry.record, ImportRecord::Odometry(_));
                    if odometry || !self.after_odometry {
                        self.placed += 1;
                        self.last_ns = self.placed * SYNTHETIC_STEP_NS;
                    }
                    self.after_odometry = odometry;
                }
                self.emit(entry.record, self.last_ns, out);
            }
            Some(Mode::Trusted) | None => self.place_trusted(entry, out)?,
        }
        Ok(())
    }

    /// Places the records still waiting after the last good stamp; call at end of input.
    pub(crate) fn finish(&mut self, out: &mut Output) {
        self.release_after_anchor(out);
    }

    fn place_trusted(&mut self, entry: Entry, out: &mut Output) -> Result<(), ImportError> {
        let Stamp::Own { raw, field, name } = entry.stamp else {
            if self.waiting.is_empty() {
                self.emit(entry.record, self.last_ns, out);
            } else {
                self.waiting.push_back(entry);
            }
            return Ok(());
        };
        let flaw = match raw {
            RawStamp::Valid(ns) if self.anchor_ns.is_none_or(|a| ns >= a) => {
                self.release_until(ns, out);
                self.anchor_ns = Some(ns);
                self.first_ns.get_or_insert(ns);
                self.restart = None;
                self.emit(entry.record, ns, out);
                return Ok(());
            }
            RawStamp::Valid(ns) => {
                self.follow_restart(entry.line, ns)?;
                "earlier than the stamp before it"
            }
            RawStamp::Zero => "zero",
            RawStamp::Denormal => "below one nanosecond",
            RawStamp::Negative => "negative",
        };
        if self.strict {
            return Err(ImportError::BadStamp {
                line: entry.line,
                record: entry.tag,
                field,
                name,
                flaw,
            });
        }
        let repairs = &mut out.stats.time_repairs;
        let count = match raw {
            RawStamp::Valid(_) => &mut repairs.backwards,
            RawStamp::Zero => &mut repairs.zero,
            RawStamp::Denormal => &mut repairs.denormal,
            RawStamp::Negative => &mut repairs.negative,
        };
        count.add(entry.line);
        self.waiting.push_back(entry);
        if self.waiting.len() > PROBE_RECORDS {
            self.release_after_anchor(out);
        }
        Ok(())
    }

    /// Follows a stamp `ns` (line `line`) earlier than the anchor: [`RESTART_RECORDS`]
    /// of them in a row, increasing from within [`RESTART_TOLERANCE_NS`] of the first
    /// stamp, are the log starting over, an error naming where.
    fn follow_restart(&mut self, line: u64, ns: u64) -> Result<(), ImportError> {
        let (Some(first), Some(anchor)) = (self.first_ns, self.anchor_ns) else {
            return Ok(());
        };
        self.restart = match self.restart {
            Some((start_line, start_ns, last, n)) if ns >= last => {
                Some((start_line, start_ns, ns, n + 1))
            }
            _ if ns <= first.saturating_add(RESTART_TOLERANCE_NS) => Some((line, ns, ns, 1)),
            _ => None,
        };
        match self.restart {
            Some((start_line, start_ns, _, n)) if n >= RESTART_RECORDS => {
                let s = |t: u64| t as f64 * 1e-9;
                Err(ImportError::StartsOver {
                    line: start_line,
                    stamp_s: s(start_ns),
                    first_s: s(first),
                    span_s: s(anchor - first),
                })
            }
            _ => Ok(()),
        }
    }

    /// Spreads the waiting records evenly between the anchor and the good stamp `b_ns`.
    fn release_until(&mut self, b_ns: u64, out: &mut Output) {
        let a_ns = self.anchor_ns.unwrap_or(b_ns);
        let own = self.own_waiting();
        let mut k = 0u64;
        let mut t = a_ns;
        while let Some(e) = self.waiting.pop_front() {
            if matches!(e.stamp, Stamp::Own { .. }) {
                k += 1;
                let span = u128::from(b_ns - a_ns);
                t = a_ns + (span * u128::from(k) / u128::from(own + 1)) as u64;
            }
            self.emit(e.record, t, out);
        }
    }

    /// Places the waiting records after the anchor at [`SYNTHETIC_STEP_NS`] each.
    fn release_after_anchor(&mut self, out: &mut Output) {
        let mut t = self.anchor_ns.unwrap_or(0);
        while let Some(e) = self.waiting.pop_front() {
            if matches!(e.stamp, Stamp::Own { .. }) {
                t += SYNTHETIC_STEP_NS;
                self.anchor_ns = Some(t);
            }
            self.emit(e.record, t, out);
        }
    }

    fn own_waiting(&self) -> u64 {
        self.waiting
            .iter()
            .filter(|e| matches!(e.stamp, Stamp::Own { .. }))
            .count() as u64
    }

    fn emit(&mut self, mut record: ImportRecord, t_ns: u64, out: &mut Output) {
        record.set_t_ns(t_ns);
        self.last_ns = t_ns;
        out.queue.push_back(record);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::import::record::Odometry;
    use crate::import::stats::TimeRepairs;
    use ekf_core::Pose2;

    fn entry(line: u64, raw: RawStamp) -> Entry {
        Entry {
            record: ImportRecord::Odometry(Odometry {
                t_ns: 0,
                pose: Pose2::new(0.0, 0.0, 0.0),
            }),
            line,
            tag: "ODOM",
            stamp: Stamp::Own {
                raw,
                field: 8,
                name: "timestamp",
            },
        }
    }

    /// Times and repairs of `entries` placed in order, the clock judged on the first
    /// `judged` of them.
    fn place_all(
        entries: Vec<Entry>,
        judged: usize,
        strict: bool,
    ) -> Result<(Vec<u64>, TimeRepairs), ImportError> {
        let mut clock = ClockRepair::new(strict);
        let mut out = Output::default();
        clock.judge(&entries[..judged], &mut out)?;
        for e in entries {
            clock.place(e, &mut out)?;
        }
        clock.finish(&mut out);
        Ok((
            out.queue.iter().map(ImportRecord::t_ns).collect(),
            out.stats.time_repairs,
        ))
    }

    /// Times and repairs of odometry records with `stamps` (lines 1, 2, …), the clock
    /// judged on the first `judged` of them.
    fn run_judged(
        stamps: &[RawStamp],
        judged: usize,
        strict: bool,
    ) -> Result<(Vec<u64>, TimeRepairs), ImportError> {
        let entries: Vec<Entry> = stamps
            .iter()
            .enumerate()
            .map(|(i, &s)| entry(i as u64 + 1, s))
            .collect();
        place_all(entries, judged, strict)
    }

    fn run(stamps: &[RawStamp], strict: bool) -> Result<(Vec<u64>, TimeRepairs), ImportError> {
        run_judged(stamps, stamps.len(), strict)
    }

    const S: u64 = 1_000_000_000;

    #[test]
    fn raw_stamps_are_classified() {
        assert_eq!(
            RawStamp::parse("21.5"),
            Some(RawStamp::Valid(21_500_000_000))
        );
        assert_eq!(RawStamp::parse("0"), Some(RawStamp::Zero));
        assert_eq!(RawStamp::parse("-0.0"), Some(RawStamp::Zero));
        assert_eq!(RawStamp::parse("8.97e-67"), Some(RawStamp::Denormal));
        assert_eq!(RawStamp::parse("-1.63023"), Some(RawStamp::Negative));
        for bad in ["", "abc", "nan", "inf", "1e30"] {
            assert_eq!(RawStamp::parse(bad), None, "{bad}");
        }
    }

    #[test]
    fn bad_stamps_are_spread_between_their_good_neighbours() {
        use RawStamp::*;
        let (t, r) = run(
            &[
                Valid(S),
                Negative,
                Denormal,
                Valid(4 * S),
                Valid(2 * S),
                Valid(5 * S),
            ],
            false,
        )
        .unwrap();
        assert_eq!(t, [S, 2 * S, 3 * S, 4 * S, 4 * S + S / 2, 5 * S]);
        assert!(!r.clock_broken);
        assert_eq!(
            (r.negative.count, r.negative.first_lines.clone()),
            (1, vec![2])
        );
        assert_eq!(
            (r.denormal.count, r.denormal.first_lines.clone()),
            (1, vec![3])
        );
        assert_eq!(
            (r.backwards.count, r.backwards.first_lines.clone()),
            (1, vec![5])
        );
        assert_eq!(r.repaired(), 3);
    }

    #[test]
    fn bad_stamps_at_the_ends_take_the_nearest_good_time() {
        use RawStamp::*;
        let stamps = [Zero, Valid(3 * S), Valid(4 * S), Valid(5 * S), Zero, Zero];
        let (t, r) = run(&stamps, false).unwrap();
        let step = SYNTHETIC_STEP_NS;
        assert_eq!(
            t,
            [3 * S, 3 * S, 4 * S, 5 * S, 5 * S + step, 5 * S + 2 * step]
        );
        assert_eq!(r.zero.first_lines, [1, 5, 6]);
    }

    #[test]
    fn a_clock_that_never_advances_is_broken_throughout() {
        use RawStamp::*;
        let (t, r) = run(&[Valid(7 * S), Valid(7 * S), Valid(7 * S), Zero], false).unwrap();
        assert!(r.clock_broken);
        assert_eq!(r.repaired(), 0);
        assert_eq!(
            t,
            [1, 2, 3, 4].map(|k| k * SYNTHETIC_STEP_NS),
            "synthetic times in file order"
        );
    }

    #[test]
    fn a_broken_clock_keeps_a_scan_at_the_instant_of_the_odometry_before_it() {
        use RawStamp::*;
        let t = Valid(7 * S);
        let scan = |line, raw| Entry {
            record: ImportRecord::Scan(crate::import::record::Scan {
                t_ns: 0,
                angle_min: 0.0,
                angle_increment: 0.01,
                range_min: 0.0,
                range_max: 10.0,
                ranges: vec![1.0],
                mount: Pose2::new(0.0, 0.0, 0.0),
            }),
            line,
            tag: "FLASER",
            stamp: Stamp::Own {
                raw,
                field: 0,
                name: "timestamp",
            },
        };
        // odometry, scan, odometry, scan, scan (no odometry between), odometry, scan
        // (whatever its stamp says).
        let entries = vec![
            entry(1, t),
            scan(2, t),
            entry(3, t),
            scan(4, t),
            scan(5, t),
            entry(6, t),
            scan(7, Valid(8 * S)),
        ];
        let judged = entries.len();
        let (times, repairs) = place_all(entries, judged, false).unwrap();
        assert!(repairs.clock_broken);
        assert_eq!(times, [1, 1, 2, 2, 3, 4, 4].map(|k| k * SYNTHETIC_STEP_NS));
    }

    #[test]
    fn strict_mode_names_the_first_bad_stamp() {
        use RawStamp::*;
        let e = run(&[Valid(S), Valid(2 * S), Negative, Valid(3 * S)], true).unwrap_err();
        assert_eq!(
            e.to_string(),
            "line 3: ODOM field 8 (timestamp): the time is negative (--strict refuses \
             repairing it)"
        );
        let e = run(&[Zero, Zero, Zero], true).unwrap_err();
        assert!(e.to_string().contains("broken throughout"), "{e}");
    }

    #[test]
    fn a_long_run_of_bad_stamps_is_placed_without_waiting_for_the_end() {
        use RawStamp::*;
        let mut stamps = vec![Valid(S)];
        stamps.extend(std::iter::repeat_n(Zero, PROBE_RECORDS + 1));
        stamps.extend([Valid(S + 10 * SYNTHETIC_STEP_NS)]);
        // The probe window itself is good: judge on the first stamp only.
        let (t, _) = run_judged(&stamps, 1, false).unwrap();
        assert_eq!(t.len(), PROBE_RECORDS + 3);
        assert!(t.windows(2).all(|w| w[1] >= w[0]), "times never go back");
        assert_eq!(t[1], S + SYNTHETIC_STEP_NS);
    }
}

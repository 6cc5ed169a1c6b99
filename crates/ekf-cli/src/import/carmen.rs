//! The CARMEN text log importer (`ODOM`, `FLASER`, `ROBOTLASER1`), plain or "corrected".
//!
//! # Records read
//!
//! * `ODOM x y theta tv rv accel timestamp host logger_timestamp` → [`Odometry`].
//! * `FLASER n r1 .. rn x y theta odom_x odom_y odom_theta timestamp host logger_timestamp`
//!   → [`Scan`]: the beams go counter-clockwise from the robot's right, beam `i` at
//!   `−π/2 + i·π/m` with `m = n` rounded down to even (180 or 181 beams → 1°, 360 or 361 →
//!   0.5°, as GMapping reads CARMEN logs). Checked on the real ACES log: the walls of the
//!   building line up only with this convention (see `tests/import_carmen_real.rs`). The
//!   sensor sits at `(robot_frontlaser_offset, 0, 0)` on the robot (a `PARAM`, default 0);
//!   `range_max` is the `PARAM robot_front_laser_max` if the log has one, else
//!   [`CarmenOptions::laser_max_range`] (50 m, the ACES laser's).
//! * `ROBOTLASER1 laser_type start_angle field_of_view angular_resolution maximum_range
//!   accuracy remission_mode n r1 .. rn m remission1 .. remissionm laser_x laser_y
//!   laser_theta robot_x robot_y robot_theta laser_tv laser_rv forward_safety_dist
//!   side_safety_dist turn_axis timestamp host logger_timestamp` → [`Scan`] with
//!   `angle_min = start_angle`, `angle_increment = angular_resolution`, `range_max =
//!   maximum_range` and mount `robot⁻¹ ⊕ laser` (both poses are given in the world).
//! * `#` comments, `PARAM`, `NEFF` and other record types are counted in
//!   [`ImportStats`](super::ImportStats) and skipped.
//!
//! Ranges are kept as they are: readings at `range_max` are invalid and the line
//! extractor drops them. `range_min` is 0. A `FLASER` scan's `range_max` comes from the
//! data when the readings saturate (see `range_limit.rs`), else as said above.
//!
//! # Timestamps
//!
//! Stamps that are negative, zero, below a nanosecond or out of order are repaired, and a
//! clock broken throughout is replaced by file order (`clock.rs`); every repair is counted
//! in [`ImportStats::time_repairs`](super::ImportStats::time_repairs), and
//! [`CarmenOptions::strict`] refuses such a log instead. Exact repeats of the `ODOM` line
//! before are left out and counted in [`ImportStats::duplicates`](super::ImportStats).
//! A log whose stamps return to its first one and run on from there
//! ([`RESTART_RECORDS`](super::RESTART_RECORDS) of them) is a second copy appended
//! to the first (`cat log.gz log.gz`, two gzip members): the first copy is imported and
//! [`ImportError::StartsOver`](super::ImportError::StartsOver) names the line.
//!
//! # Ranges
//!
//! A negative reading, which no scanner measures, is written as NaN (no return) and its
//! scan counted in [`ImportStats::invalid_ranges`](super::ImportStats).
//!
//! # The "corrected" flavour
//!
//! A corrected log is the output of a grid-SLAM run: each scan's robot pose is the
//! SLAM-corrected pose, and the `ODOM` right after a scan is *reset* to it. A reset is
//! recognised by what it is: the first `ODOM` after a scan whose pose equals the scan's
//! robot pose (unless it also repeats the `ODOM` before the scan with a good stamp: a
//! plain log's robot standing still). Its timestamp says nothing: 0 in ACES, negative,
//! `8.97e-67` or far off in other logs of the family, and it is ignored. The importer then
//!
//! * yields each scan's robot pose as a [`Reference`] at the scan's time;
//! * re-chains the raw odometry: an accumulated pose starts at the first `ODOM`; for each
//!   consecutive pair of `ODOM` poses `(prev, cur)` the relative motion `prev⁻¹ ⊕ cur` (in
//!   the robot frame) is composed onto it. The jump from the last `ODOM` before a scan to
//!   the reset is left out: a reset only becomes the new `prev`, and yields no record.
//!
//! With [`CarmenFlavour::Auto`] (the default) a log counts as corrected from its first
//! reset on: a scan's [`Reference`] is yielded when its reset is seen, so a plain log
//! yields no references. Before the first reset the chain is the `ODOM` poses exactly,
//! so a plain log's odometry comes out as it is written.

use super::clock::{ClockRepair, Entry, Stamp, PROBE_RECORDS};
use super::compass::{CompassNoise, SyntheticCompass};
use super::error::ImportError;
use super::fields::Fields;
use super::fields::RawStamp;
use super::range_limit::range_limit;
use super::record::{ImportRecord, Odometry, Reference, Scan};
use super::stats::{ImportStats, RangeMax};
use super::stream::{LineParser, Output, RecordStream};
use ekf_core::Pose2;
use std::f64::consts::{FRAC_PI_2, PI};
use std::io::BufRead;

/// Which CARMEN flavour the log is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CarmenFlavour {
    /// Corrected if resets are found (see the module docs), else plain.
    #[default]
    Auto,
    /// Corrected: every scan pose is a reference, resets are taken out of the odometry.
    Corrected,
    /// Plain: `ODOM` poses are used as they are, no references.
    Plain,
}

/// Options of the CARMEN importer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CarmenOptions {
    /// Which flavour the log is.
    pub flavour: CarmenFlavour,
    /// `range_max` of `FLASER` scans (m) unless a `PARAM robot_front_laser_max` says
    /// otherwise. Default 50 m (the ACES log's laser).
    pub laser_max_range: f64,
    /// Make a synthetic compass reading from every reference pose.
    pub synthetic_compass: Option<SyntheticCompass>,
    /// Refuse a log whose timestamps need repair (see [`TimeRepairs`](super::TimeRepairs))
    /// instead of repairing them.
    pub strict: bool,
}

impl Default for CarmenOptions {
    fn default() -> Self {
        Self {
            flavour: CarmenFlavour::Auto,
            laser_max_range: 50.0,
            synthetic_compass: None,
            strict: false,
        }
    }
}

/// Streams the records of a CARMEN log from `reader`; see the module docs for the rules.
pub fn read_carmen<R: BufRead>(reader: R, options: CarmenOptions) -> CarmenReader<R> {
    CarmenReader {
        inner: RecordStream::new(reader, CarmenParser::new(options)),
    }
}

/// Iterator over the records of a CARMEN log, made by [`read_carmen`].
pub struct CarmenReader<R> {
    inner: RecordStream<R, CarmenParser>,
}

impl<R: BufRead> CarmenReader<R> {
    /// What was imported so far; complete once the iterator has returned `None`.
    pub fn stats(&self) -> &ImportStats {
        self.inner.stats()
    }
}

impl<R: BufRead> Iterator for CarmenReader<R> {
    type Item = Result<ImportRecord, ImportError>;

    fn next(&mut self) -> Option<Self::Item> {
        self.inner.next()
    }
}

/// The raw odometry chain: the last `ODOM` pose as written and the accumulated raw pose.
#[derive(Debug, Clone, Copy)]
struct Chain {
    prev: Pose2<f64>,
    raw: Pose2<f64>,
}

/// The state of a CARMEN import between lines.
struct CarmenParser {
    flavour: CarmenFlavour,
    laser_max_range: f64,
    param_range_max: Option<f64>,
    front_laser_offset: f64,
    compass: Option<CompassNoise>,
    /// Line tag and robot pose of the latest scan not yet followed by an `ODOM`.
    open_scan: Option<(&'static str, Pose2<f64>)>,
    chain: Option<Chain>,
    reset_seen: bool,
    /// Pose and stamp of the last `ODOM` line (duplicates, resets).
    last_odom: Option<(Pose2<f64>, RawStamp)>,
    /// A scan came after that `ODOM`: the next one repeating it is no duplicate.
    scan_since_odom: bool,
    /// The look-ahead window until the clock and the range limit are judged.
    probe: Option<Vec<Entry>>,
    probe_stamps: usize,
    range_max: Option<RangeMax>,
    clock: ClockRepair,
}

impl CarmenParser {
    fn new(options: CarmenOptions) -> Self {
        Self {
            flavour: options.flavour,
            laser_max_range: options.laser_max_range,
            param_range_max: None,
            front_laser_offset: 0.0,
            compass: options.synthetic_compass.map(CompassNoise::new),
            open_scan: None,
            chain: None,
            reset_seen: false,
            last_odom: None,
            scan_since_odom: false,
            probe: Some(Vec::new()),
            probe_stamps: 0,
            range_max: None,
            clock: ClockRepair::new(options.strict),
        }
    }

    fn param(&mut self, f: &Fields) -> Result<(), ImportError> {
        match f.text(2) {
            Some("robot_front_laser_max") => self.param_range_max = Some(f.f64(3, "value")?),
            Some("robot_frontlaser_offset") => self.front_laser_offset = f.f64(3, "value")?,
            _ => {}
        }
        Ok(())
    }

    fn odom(&mut self, f: &Fields, out: &mut Output) -> Result<(), ImportError> {
        f.expect_len(10)?;
        let pose = f.pose(2, ["x", "y", "theta"])?;
        for (field, name) in [(5, "tv"), (6, "rv"), (7, "accel")] {
            f.f64(field, name)?;
        }
        let raw_stamp = f.stamp(8, "timestamp")?;
        let last = self.last_odom.replace((pose, raw_stamp));
        let after_scan = std::mem::replace(&mut self.scan_since_odom, false);
        if let Some((scan_tag, scan_pose)) = self.open_scan.take() {
            // A reset is the first ODOM after a scan, at the scan's pose. A plain log's robot
            // standing still repeats its pose with a good stamp: that is no reset.
            let standing =
                last.is_some_and(|(p, _)| p == pose) && matches!(raw_stamp, RawStamp::Valid(_));
            if scan_pose == pose && !standing {
                out.stats.odometry_resets += 1;
                let raw = self.chain.map_or(pose, |c| c.raw);
                self.chain = Some(Chain { prev: pose, raw });
                self.reset_seen = true;
                if self.flavour == CarmenFlavour::Auto {
                    self.reference(f.line(), scan_tag, scan_pose, out)?;
                }
                return Ok(());
            }
        } else if !after_scan && last == Some((pose, raw_stamp)) {
            out.stats.duplicates.add(f.line());
            return Ok(());
        }
        let raw = match self.chain {
            Some(c) if self.reset_seen => c.raw.compose(&c.prev.inverse().compose(&pose)),
            _ => pose,
        };
        self.chain = Some(Chain { prev: pose, raw });
        let record = ImportRecord::Odometry(Odometry { t_ns: 0, pose: raw });
        self.hold(
            f.line(),
            "ODOM",
            record,
            own(raw_stamp, 8, "timestamp"),
            out,
        )
    }

    fn flaser(&mut self, f: &Fields, out: &mut Output) -> Result<(), ImportError> {
        let n = f.count(2, "num_readings")?;
        let context = format!("declares {n} readings");
        f.expect_declared_len(n.saturating_add(11), &context)?;
        let mut ranges = f.ranges(3, n)?;
        no_return_for_negative(&mut ranges, f.line(), out);
        let robot = f.pose(n + 3, ["x", "y", "theta"])?;
        f.pose(n + 6, ["odom_x", "odom_y", "odom_theta"])?;
        let raw_stamp = f.stamp(n + 9, "timestamp")?;
        f.stamp(n + 11, "logger_timestamp")?;
        let span = (n - n % 2).max(1) as f64;
        let scan = Scan {
            t_ns: 0,
            angle_min: -FRAC_PI_2,
            angle_increment: PI / span,
            range_min: 0.0,
            range_max: self.laser_max_range,
            ranges,
            mount: Pose2::new(self.front_laser_offset, 0.0, 0.0),
        };
        self.scan(
            f,
            "FLASER",
            scan,
            own(raw_stamp, n + 9, "timestamp"),
            robot,
            out,
        )
    }

    fn robotlaser(&mut self, f: &Fields, out: &mut Output) -> Result<(), ImportError> {
        let n = f.count(9, "num_readings")?;
        let m_field = n.saturating_add(10);
        if f.len() < m_field {
            return Err(f.count_error(
                n.saturating_add(24),
                Some(&format!("declares {n} readings")),
            ));
        }
        let m = f.count(m_field, "num_remissions")?;
        let context = format!("declares {n} readings and {m} remissions");
        f.expect_declared_len(n.saturating_add(m).saturating_add(24), &context)?;
        let mut ranges = f.ranges(10, n)?;
        no_return_for_negative(&mut ranges, f.line(), out);
        for field in m_field + 1..=m_field + m {
            f.f64(field, "remission")?;
        }
        let k = m_field + m + 1;
        let laser = f.pose(k, ["laser_pose_x", "laser_pose_y", "laser_pose_theta"])?;
        let robot = f.pose(k + 3, ["robot_pose_x", "robot_pose_y", "robot_pose_theta"])?;
        let names = [
            "laser_tv",
            "laser_rv",
            "forward_safety_dist",
            "side_safety_dist",
            "turn_axis",
        ];
        for (i, name) in names.into_iter().enumerate() {
            f.f64(k + 6 + i, name)?;
        }
        let raw_stamp = f.stamp(k + 11, "timestamp")?;
        f.stamp(k + 13, "logger_timestamp")?;
        let scan = Scan {
            t_ns: 0,
            angle_min: f.f64(3, "start_angle")?,
            angle_increment: f.f64(5, "angular_resolution")?,
            range_min: 0.0,
            range_max: f.f64(6, "maximum_range")?,
            ranges,
            mount: robot.inverse().compose(&laser),
        };
        self.scan(
            f,
            "ROBOTLASER1",
            scan,
            own(raw_stamp, k + 11, "timestamp"),
            robot,
            out,
        )
    }

    /// A scan from a `tag` line (`FLASER` or `ROBOTLASER1`), with its reference when the
    /// flavour is forced to corrected.
    fn scan(
        &mut self,
        f: &Fields,
        tag: &'static str,
        scan: Scan,
        stamp: Stamp,
        robot: Pose2<f64>,
        out: &mut Output,
    ) -> Result<(), ImportError> {
        self.scan_since_odom = true;
        self.hold(f.line(), tag, ImportRecord::Scan(scan), stamp, out)?;
        if self.flavour == CarmenFlavour::Corrected {
            self.reference(f.line(), tag, robot, out)?;
        }
        if self.flavour != CarmenFlavour::Plain {
            self.open_scan = Some((tag, robot));
        }
        Ok(())
    }

    /// A reference at `pose` for the scan just emitted (from a `tag` line), and its
    /// synthetic compass reading; both share the scan's time.
    fn reference(
        &mut self,
        line: u64,
        tag: &'static str,
        pose: Pose2<f64>,
        out: &mut Output,
    ) -> Result<(), ImportError> {
        let record = ImportRecord::Reference(Reference { t_ns: 0, pose });
        self.hold(line, tag, record, Stamp::Shared, out)?;
        if let Some(noise) = &mut self.compass {
            // The heading is drawn now, in file order; its time is the scan's.
            let record = ImportRecord::Compass(noise.reading(0, &pose));
            self.hold(line, tag, record, Stamp::Shared, out)?;
        }
        Ok(())
    }

    /// Passes a record on: into the look-ahead window while it is open, else to the clock.
    fn hold(
        &mut self,
        line: u64,
        tag: &'static str,
        record: ImportRecord,
        stamp: Stamp,
        out: &mut Output,
    ) -> Result<(), ImportError> {
        let entry = Entry {
            record,
            line,
            tag,
            stamp,
        };
        let Some(probe) = &mut self.probe else {
            return self.release(entry, out);
        };
        if matches!(stamp, Stamp::Own { .. }) {
            self.probe_stamps += 1;
        }
        probe.push(entry);
        if self.probe_stamps >= PROBE_RECORDS {
            self.close_probe(out)?;
        }
        Ok(())
    }

    /// Judges the clock and the range limit on the window, then releases it.
    fn close_probe(&mut self, out: &mut Output) -> Result<(), ImportError> {
        let Some(probe) = self.probe.take() else {
            return Ok(());
        };
        let flaser_ranges = probe
            .iter()
            .filter_map(flaser_scan)
            .map(|s| s.ranges.as_slice());
        self.range_max = Some(range_limit(
            flaser_ranges,
            self.param_range_max,
            self.laser_max_range,
        ));
        self.clock.judge(&probe, out)?;
        for entry in probe {
            self.release(entry, out)?;
        }
        Ok(())
    }

    /// Gives a `FLASER` scan the log's range limit, then the record its time.
    fn release(&mut self, mut entry: Entry, out: &mut Output) -> Result<(), ImportError> {
        if let (Some(limit), true) = (self.range_max, flaser_scan(&entry).is_some()) {
            if let ImportRecord::Scan(scan) = &mut entry.record {
                scan.range_max = limit.value;
                out.stats.laser_range_max = Some(limit);
            }
        }
        self.clock.place(entry, out)
    }
}

/// The scan of a `FLASER` line (whose range limit comes from the data), if `entry` is one.
fn flaser_scan(entry: &Entry) -> Option<&Scan> {
    match &entry.record {
        ImportRecord::Scan(s) if entry.tag == "FLASER" => Some(s),
        _ => None,
    }
}

/// A record's own stamp, read from field `field` (`name`).
fn own(raw: RawStamp, field: usize, name: &'static str) -> Stamp {
    Stamp::Own { raw, field, name }
}

impl LineParser for CarmenParser {
    fn parse_line(&mut self, line: u64, text: &str, out: &mut Output) -> Result<(), ImportError> {
        let f = Fields::new(line, text);
        match f.tag() {
            None => {}
            Some(tag) if tag.starts_with('#') => out.stats.comment_lines += 1,
            Some("PARAM") => {
                out.stats.param_lines += 1;
                self.param(&f)?;
            }
            Some("NEFF") => out.stats.neff_lines += 1,
            Some("ODOM") => self.odom(&f, out)?,
            Some("FLASER") => self.flaser(&f, out)?,
            Some("ROBOTLASER1") => self.robotlaser(&f, out)?,
            Some(_) => out.stats.unknown_lines += 1,
        }
        Ok(())
    }

    fn finish(&mut self, out: &mut Output) -> Result<(), ImportError> {
        self.close_probe(out)?;
        self.clock.finish(out);
        Ok(())
    }
}

/// Negative readings (no scanner measures them: a logging bug or a corrupted field)
/// become NaN, no return, and the scan's line is counted.
fn no_return_for_negative(ranges: &mut [f32], line: u64, out: &mut Output) {
    let mut found = false;
    for r in ranges.iter_mut().filter(|r| **r < 0.0) {
        *r = f32::NAN;
        found = true;
    }
    if found {
        out.stats.invalid_ranges.add(line);
    }
}

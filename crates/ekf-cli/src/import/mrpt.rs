//! The importer for MRPT rawlogs exported to CARMEN-like text (`ODOM`, `RAWSCAN`).
//!
//! * `ODOM x y theta 0 0 0 timestamp` → [`Odometry`]: the accumulated odometry, as is.
//! * `RAWSCAN timestamp n aperture max_range sx sy stheta r1 .. rn [key=value ..]` →
//!   [`Scan`]: `n` beams spread evenly over `aperture`, ends included (361 beams over π →
//!   0.5°), from `−aperture/2` counter-clockwise; or from `+aperture/2` clockwise when a
//!   trailing `rightToLeft=0` says so (the export writes `label=` and `rightToLeft=1`).
//!   Mount `(sx, sy, stheta)`, `range_max = max_range`; invalid beams are written as
//!   `max_range` and kept as they are. `range_min` is 0.
//! * `#` comments and other record types are counted and skipped. There is no reference.
//!
//! Timestamps are seconds since the Unix epoch with microseconds, converted exactly.

use super::error::ImportError;
use super::fields::Fields;
use super::record::{ImportRecord, Odometry, Scan};
use super::stats::ImportStats;
use super::stream::{LineParser, Output, RecordStream};
use std::io::BufRead;

/// Streams the records of an MRPT text export from `reader`; see the module docs.
pub fn read_mrpt<R: BufRead>(reader: R) -> MrptReader<R> {
    MrptReader {
        inner: RecordStream::new(reader, MrptParser),
    }
}

/// Iterator over the records of an MRPT text export, made by [`read_mrpt`].
pub struct MrptReader<R> {
    inner: RecordStream<R, MrptParser>,
}

impl<R: BufRead> MrptReader<R> {
    /// What was imported so far; complete once the iterator has returned `None`.
    pub fn stats(&self) -> &ImportStats {
        self.inner.stats()
    }
}

impl<R: BufRead> Iterator for MrptReader<R> {
    type Item = Result<ImportRecord, ImportError>;

    fn next(&mut self) -> Option<Self::Item> {
        self.inner.next()
    }
}

/// The MRPT export has no state between lines.
struct MrptParser;

fn odom(f: &Fields) -> Result<ImportRecord, ImportError> {
    f.expect_len(8)?;
    let pose = f.pose(2, ["x", "y", "theta"])?;
    for (field, name) in [(5, "v"), (6, "w"), (7, "unused")] {
        f.f64(field, name)?;
    }
    let t_ns = f.time_ns(8, "timestamp")?;
    Ok(ImportRecord::Odometry(Odometry { t_ns, pose }))
}

fn rawscan(f: &Fields) -> Result<ImportRecord, ImportError> {
    let t_ns = f.time_ns(2, "timestamp")?;
    let n = f.count(3, "num_readings")?;
    let aperture = f.f64(4, "aperture")?;
    let range_max = f.f64(5, "max_range")?;
    let mount = f.pose(6, ["sx", "sy", "stheta"])?;
    let needed = n.saturating_add(8);
    if f.len() < needed {
        return Err(f.count_error(needed, Some(&format!("declares {n} readings"))));
    }
    let ranges = f.ranges(9, n)?;
    let mut right_to_left = true;
    for field in needed + 1..=f.len() {
        match f.text(field).and_then(|t| t.split_once('=')) {
            Some(("rightToLeft", "1")) => right_to_left = true,
            Some(("rightToLeft", "0")) => right_to_left = false,
            Some(("rightToLeft", _)) => {
                return Err(f.bad(field, "rightToLeft", "rightToLeft=0 or rightToLeft=1"))
            }
            Some(_) => {}
            None => return Err(f.bad(field, "trailing", "key=value after the readings")),
        }
    }
    let step = if n > 1 {
        aperture / (n - 1) as f64
    } else {
        0.0
    };
    let (angle_min, angle_increment) = if right_to_left {
        (-aperture / 2.0, step)
    } else {
        (aperture / 2.0, -step)
    };
    Ok(ImportRecord::Scan(Scan {
        t_ns,
        angle_min,
        angle_increment,
        range_min: 0.0,
        range_max,
        ranges,
        mount,
    }))
}

impl LineParser for MrptParser {
    fn parse_line(&mut self, line: u64, text: &str, out: &mut Output) -> Result<(), ImportError> {
        let f = Fields::new(line, text);
        match f.tag() {
            None => {}
            Some(tag) if tag.starts_with('#') => out.stats.comment_lines += 1,
            Some("ODOM") => out.queue.push_back(odom(&f)?),
            Some("RAWSCAN") => out.queue.push_back(rawscan(&f)?),
            Some(_) => out.stats.unknown_lines += 1,
        }
        Ok(())
    }
}

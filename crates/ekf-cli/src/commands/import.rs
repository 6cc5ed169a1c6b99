//! `ekf import carmen|mrpt LOG --out LOG.mcap`: a CARMEN or MRPT text log as a ROS 2 bag.
//!
//! Records become messages on the default topics of docs/ARCHITECTURE.md §4: raw odometry →
//! `/odom` (`nav_msgs/Odometry`, frame `odom` → `base_link`), scans → `/scan`
//! (`sensor_msgs/LaserScan`, frame `laser`) with the laser's mounting pose on
//! `/tf_static` (`base_link` → `laser`, written again only if it changes), reference poses
//! → `/ground_truth` (`nav_msgs/Odometry`, frame `map`), synthetic compass readings →
//! `/compass` (`sensor_msgs/Imu`, yaw only) and an MCAP metadata record
//! `synthetic_compass` that labels them. Log times are the source log's timestamps.

use crate::import::{
    open_log, read_carmen, read_mrpt, CarmenOptions, ImportError, ImportRecord, ImportStats,
    RepairCount, SYNTHETIC_STEP_NS,
};
use crate::mcap_io::{BagWriter, WriteError};
use crate::ros2::build::{
    compass_imu, laser_scan, mount_transform, odometry, MAP_FRAME, ODOM_FRAME,
};
use ekf_core::Pose2;
use serde::Serialize;
use std::fmt;
use std::path::Path;

/// The source log's format.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LogFormat {
    /// CARMEN text log (ODOM, FLASER, ROBOTLASER1), plain or "corrected".
    Carmen(CarmenOptions),
    /// MRPT's text export (ODOM, RAWSCAN).
    Mrpt,
}

/// Why an import failed. Whatever was converted before the failure is in the output
/// file, which is finished and readable.
#[derive(Debug, thiserror::Error)]
pub enum ImportCommandError {
    /// The input could not be opened.
    #[error("{path}: {source}")]
    Open {
        /// The input file.
        path: String,
        /// What the OS said.
        source: std::io::Error,
    },
    /// The input is malformed; the message names the line and field.
    #[error("{path}: {source}")]
    Parse {
        /// The input file.
        path: String,
        /// Where and what.
        source: ImportError,
    },
    /// The input has no record the importer reads (the output bag is empty).
    #[error(
        "{path}: nothing to import: no {expected} line (other record types: {unknown}, \
         comments: {comments}, PARAM: {params}, NEFF: {neff})"
    )]
    NoRecords {
        /// The input file.
        path: String,
        /// The record lines the format has.
        expected: &'static str,
        /// Lines of record types the importer does not read.
        unknown: u64,
        /// Comment lines.
        comments: u64,
        /// `PARAM` lines.
        params: u64,
        /// `NEFF` lines.
        neff: u64,
    },
    /// The output could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
}

/// What an import wrote.
#[derive(Debug, Clone, Serialize)]
pub struct ImportSummary {
    /// Counts and time span of the records read.
    pub stats: ImportStats,
    /// Messages written to the bag.
    pub messages_written: u64,
}

/// What the import wrote, as `ekf import` prints it after the bag's name: the message
/// counts and time span, and the laser's range limit with its source.
impl fmt::Display for ImportSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = &self.stats;
        writeln!(
            f,
            "{} messages ({} odometry, {} scans, {} reference, {} compass) over {:.1} s",
            self.messages_written,
            s.odometry,
            s.scans,
            s.references,
            s.compass,
            s.span_ns() as f64 * 1e-9
        )?;
        if let Some(r) = s.laser_range_max {
            writeln!(
                f,
                "  laser readings from {:.2} m up are no return ({})",
                r.value, r.source
            )?;
        }
        Ok(())
    }
}

/// Converts `input` into the ROS 2 bag `output`. On a malformed line, everything before
/// it is written, the bag is finished, and the error names the line. An input without
/// any record to convert is an error (the bag written is empty).
pub fn import_log(
    input: &Path,
    output: &Path,
    format: LogFormat,
) -> Result<ImportSummary, ImportCommandError> {
    let name = input.display().to_string();
    let reader = open_log(input).map_err(|source| ImportCommandError::Open {
        path: name.clone(),
        source,
    })?;
    let mut writer = BagWriter::create(output)?;
    let mut converter = Converter {
        writer: &mut writer,
        mount: None,
        written: 0,
    };
    let (stats, result) = match format {
        LogFormat::Carmen(options) => {
            if let Some(c) = options.synthetic_compass {
                converter.writer.write_metadata(
                    "synthetic_compass",
                    &[
                        ("topic", "/compass".to_string()),
                        (
                            "description",
                            "SYNTHETIC: reference heading plus Gaussian noise, not a real sensor"
                                .to_string(),
                        ),
                        ("sigma_deg", c.sigma_deg.to_string()),
                        ("seed", c.seed.to_string()),
                    ],
                )?;
            }
            let mut records = read_carmen(reader, options);
            let result = converter.convert_all(&mut records);
            (records.stats().clone(), result)
        }
        LogFormat::Mrpt => {
            let mut records = read_mrpt(reader);
            let result = converter.convert_all(&mut records);
            (records.stats().clone(), result)
        }
    };
    let written = converter.written;
    let finished = writer.finish();
    match result {
        Err(ConvertError::Parse(source)) => {
            return Err(ImportCommandError::Parse { path: name, source })
        }
        Err(ConvertError::Write(e)) => return Err(e.into()),
        Ok(()) => {}
    }
    finished?;
    if written == 0 {
        return Err(ImportCommandError::NoRecords {
            path: name,
            expected: match format {
                LogFormat::Carmen(_) => "ODOM, FLASER or ROBOTLASER1",
                LogFormat::Mrpt => "ODOM or RAWSCAN",
            },
            unknown: stats.unknown_lines,
            comments: stats.comment_lines,
            params: stats.param_lines,
            neff: stats.neff_lines,
        });
    }
    Ok(ImportSummary {
        stats,
        messages_written: written,
    })
}

enum ConvertError {
    Parse(ImportError),
    Write(WriteError),
}

/// Writes records as messages, remembering the last published laser mount.
struct Converter<'a> {
    writer: &'a mut BagWriter,
    mount: Option<Pose2<f64>>,
    written: u64,
}

impl Converter<'_> {
    fn convert_all(
        &mut self,
        records: &mut dyn Iterator<Item = Result<ImportRecord, ImportError>>,
    ) -> Result<(), ConvertError> {
        for record in records {
            self.convert(&record.map_err(ConvertError::Parse)?)
                .map_err(ConvertError::Write)?;
        }
        Ok(())
    }

    fn convert(&mut self, record: &ImportRecord) -> Result<(), WriteError> {
        match record {
            ImportRecord::Odometry(o) => self
                .writer
                .write("/odom", &odometry(o.t_ns, &o.pose, ODOM_FRAME))?,
            ImportRecord::Reference(r) => self
                .writer
                .write("/ground_truth", &odometry(r.t_ns, &r.pose, MAP_FRAME))?,
            ImportRecord::Scan(s) => {
                if self.mount != Some(s.mount) {
                    self.writer.write_at(
                        "/tf_static",
                        s.t_ns,
                        &mount_transform(s.t_ns, &s.mount),
                    )?;
                    self.written += 1;
                    self.mount = Some(s.mount);
                }
                let scan = laser_scan(
                    s.t_ns,
                    s.angle_min,
                    s.angle_increment,
                    (s.range_min, s.range_max),
                    s.ranges.clone(),
                );
                self.writer.write("/scan", &scan)?
            }
            ImportRecord::Compass(c) => {
                let imu = compass_imu(c.t_ns, c.heading, c.variance);
                self.writer.write("/compass", &imu)?
            }
        }
        self.written += 1;
        Ok(())
    }
}

/// What the import repaired or left out, one sentence each, for the text summary: the
/// clock's repairs and duplicates, with their first lines. Empty for a log that needed
/// nothing.
pub fn repair_lines(stats: &ImportStats) -> Vec<String> {
    let r = &stats.time_repairs;
    let mut lines = Vec::new();
    if r.clock_broken {
        lines.push(format!(
            "the log's clock is broken throughout (its stamps do not advance); every record \
             has a synthetic time in file order, {} s apart (a scan directly after an \
             odometry record at that record's time)",
            SYNTHETIC_STEP_NS as f64 * 1e-9
        ));
    }
    let kinds = [
        ("negative", &r.negative),
        ("zero", &r.zero),
        ("below one nanosecond", &r.denormal),
        ("earlier than the stamp before", &r.backwards),
    ];
    for (what, count) in kinds {
        if count.count > 0 {
            lines.push(format!(
                "{} timestamps {what} repaired from their neighbours ({})",
                count.count,
                where_found(count)
            ));
        }
    }
    if stats.duplicates.count > 0 {
        lines.push(format!(
            "{} duplicate records left out ({})",
            stats.duplicates.count,
            where_found(&stats.duplicates)
        ));
    }
    if stats.invalid_ranges.count > 0 {
        lines.push(format!(
            "{} scans with negative ranges, read as no return ({})",
            stats.invalid_ranges.count,
            where_found(&stats.invalid_ranges)
        ));
    }
    lines
}

/// "lines 3, 9, …": the first lines of a repair, with an ellipsis when there are more.
fn where_found(count: &RepairCount) -> String {
    let mut lines: Vec<String> = count.first_lines.iter().map(u64::to_string).collect();
    if count.count > lines.len() as u64 {
        lines.push("…".to_string());
    }
    format!("lines {}", lines.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_and_repairs_as_printed() {
        let mut summary = ImportSummary {
            stats: ImportStats {
                odometry: 3,
                scans: 2,
                references: 2,
                t_min_ns: Some(1_000_000_000),
                t_max_ns: Some(3_500_000_000),
                laser_range_max: Some(crate::import::RangeMax {
                    value: 81.09,
                    source: crate::import::RangeMaxSource::Saturation,
                }),
                ..ImportStats::default()
            },
            messages_written: 8,
        };
        assert_eq!(
            summary.to_string(),
            "8 messages (3 odometry, 2 scans, 2 reference, 0 compass) over 2.5 s\n  \
             laser readings from 81.09 m up are no return (where the readings saturate)\n"
        );
        assert!(repair_lines(&summary.stats).is_empty());
        summary.stats.time_repairs.negative = RepairCount {
            count: 4,
            first_lines: vec![3, 9],
        };
        summary.stats.duplicates = RepairCount {
            count: 1,
            first_lines: vec![12],
        };
        assert_eq!(
            repair_lines(&summary.stats),
            [
                "4 timestamps negative repaired from their neighbours (lines 3, 9, …)",
                "1 duplicate records left out (lines 12)"
            ]
        );
    }
}

//! `ekf map build LOG.mcap --out MAP.json [--from-truth]`: a line map from the log's
//! first scan (the paper's global map, at the configured initial pose or the first
//! reference pose), or from every scan placed along the log's reference trajectory with
//! repeated sightings of a wall fused into one segment.

use crate::config::Config;
use crate::mcap_io::BagReader;
use crate::replay::{laser_mount, read_preamble, reference_pose, ReplayError};
use crate::ros2::AnyMessage;
use crate::trajectory::Trajectory;
use ekf_core::Pose2;
use lrf_lines::{LineExtractor, LineMap, MapBuilder, MapBuilderParams, ObservedLine};
use serde::Serialize;
use std::path::Path;

/// A scan is placed at the reference pose nearest in time, if within this (ns).
pub const MAX_REFERENCE_GAP_NS: u64 = 50_000_000;

/// How the map is made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MapSource {
    /// The first scan, at the configured initial pose (or, with `init_from_truth`, the
    /// first reference pose).
    FirstScan {
        /// Place the first scan at the first reference pose.
        init_from_truth: bool,
    },
    /// Every scan within [`MAX_REFERENCE_GAP_NS`] of a reference pose, fused.
    Reference(MapBuilderParams),
}

/// What was built.
#[derive(Debug, Clone, Serialize)]
pub struct MapBuildSummary {
    /// Scans used.
    pub scans_used: u64,
    /// Scans skipped (no reference pose near in time, or extraction refused them).
    pub scans_skipped: u64,
    /// Lines extracted from the used scans.
    pub lines: u64,
    /// Segments in the map.
    pub segments: usize,
    /// `[x, y, θ]` of the laser mount used, and its source.
    pub laser_mount: [f64; 3],
    /// `tf_static` or `config`.
    pub laser_mount_source: &'static str,
}

/// The summary as `ekf map build` prints it after the map's file name: one line.
impl std::fmt::Display for MapBuildSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{} segments from {} scans ({} lines; {} scans skipped)",
            self.segments, self.scans_used, self.lines, self.scans_skipped
        )
    }
}

/// Builds the map of `log` (see [`MapSource`]).
pub fn build_map(
    log: &Path,
    config: &Config,
    source: MapSource,
) -> Result<(LineMap, MapBuildSummary), ReplayError> {
    let log_name = log.display().to_string();
    let bag = BagReader::open(log)?;
    let topics = &config.topics;
    let no_reference = || ReplayError::NoReference {
        log: log_name.clone(),
        topic: topics.ground_truth.clone(),
    };
    if !bag.topics().iter().any(|t| t.topic == topics.scan) {
        return Err(ReplayError::MissingTopic {
            log: log_name.clone(),
            topic: topics.scan.clone(),
            role: "laser scans",
            available: bag.describe_topics(),
            hint: crate::replay::TOPIC_HINT,
        });
    }
    let needs_reference = matches!(
        source,
        MapSource::Reference(_)
            | MapSource::FirstScan {
                init_from_truth: true
            }
    );
    let preamble = read_preamble(&bag, config, needs_reference)?;
    let (mount, mount_source) = laser_mount(&preamble, config)?;
    let mut extractor =
        LineExtractor::new(config.localizer.extraction).map_err(lrf_lines::LocalizerError::from)?;
    let mut summary = MapBuildSummary {
        scans_used: 0,
        scans_skipped: 0,
        lines: 0,
        segments: 0,
        laser_mount: [mount.x, mount.y, mount.theta],
        laser_mount_source: mount_source,
    };
    let mut lines: Vec<ObservedLine> = Vec::new();

    let map = match source {
        MapSource::FirstScan { init_from_truth } => {
            let robot = if init_from_truth {
                preamble.first_reference.ok_or_else(no_reference)?.1
            } else {
                let i = &config.initial;
                Pose2::new(i.x, i.y, i.theta)
            };
            let mut map = None;
            for message in bag.messages()? {
                let message = message?;
                if message.topic() != topics.scan {
                    continue;
                }
                if let AnyMessage::LaserScan(scan) = message.decode()? {
                    extractor
                        .extract(&scan.as_scan(), &mut lines)
                        .map_err(lrf_lines::LocalizerError::from)?;
                    map = Some(
                        LineMap::from_scan(&lines, &robot.compose(&mount))
                            .map_err(lrf_lines::LocalizerError::Filter)?,
                    );
                    summary.scans_used = 1;
                    summary.lines = lines.len() as u64;
                    break;
                }
            }
            map.unwrap_or_default()
        }
        MapSource::Reference(params) => {
            let reference = read_reference(&bag, &topics.ground_truth)?;
            if reference.is_empty() {
                return Err(no_reference());
            }
            let mut builder = MapBuilder::new(params).map_err(lrf_lines::LocalizerError::Filter)?;
            for message in bag.messages()? {
                let message = message?;
                if message.topic() != topics.scan {
                    continue;
                }
                let AnyMessage::LaserScan(scan) = message.decode()? else {
                    continue;
                };
                let Some(robot) = nearest(&reference, message.log_time) else {
                    summary.scans_skipped += 1;
                    continue;
                };
                if extractor.extract(&scan.as_scan(), &mut lines).is_err()
                    || builder.add_scan(&lines, &robot.compose(&mount)).is_err()
                {
                    summary.scans_skipped += 1;
                    continue;
                }
                summary.scans_used += 1;
                summary.lines += lines.len() as u64;
            }
            builder.finish()
        }
    };
    summary.segments = map.len();
    if map.is_empty() {
        return Err(ReplayError::Map {
            path: log_name,
            message: format!(
                "no lines were extracted from {} scans; nothing to map",
                summary.scans_used
            ),
        });
    }
    Ok((map, summary))
}

/// The reference trajectory of the log (first pass).
fn read_reference(bag: &BagReader, topic: &str) -> Result<Trajectory, ReplayError> {
    let mut reference = Trajectory::default();
    for message in bag.messages()? {
        let message = message?;
        if message.topic() == topic {
            if let Some(pose) = message.decode().ok().and_then(|m| reference_pose(&m)) {
                reference.push(message.log_time, pose);
            }
        }
    }
    reference.samples.sort_by_key(|s| s.t_ns);
    Ok(reference)
}

/// The reference pose nearest to `t_ns`, if within [`MAX_REFERENCE_GAP_NS`].
fn nearest(reference: &Trajectory, t_ns: u64) -> Option<Pose2<f64>> {
    let s = &reference.samples;
    let i = s.partition_point(|p| p.t_ns < t_ns);
    [i.checked_sub(1), Some(i)]
        .into_iter()
        .flatten()
        .filter_map(|k| s.get(k))
        .min_by_key(|p| p.t_ns.abs_diff(t_ns))
        .filter(|p| p.t_ns.abs_diff(t_ns) <= MAX_REFERENCE_GAP_NS)
        .map(|p| p.pose)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_reference_within_the_gap() {
        let mut r = Trajectory::default();
        for (t, x) in [(1_000_000_000u64, 1.0), (2_000_000_000, 2.0)] {
            r.push(t, Pose2::new(x, 0.0, 0.0));
        }
        assert_eq!(nearest(&r, 1_040_000_000).map(|p| p.x), Some(1.0));
        assert_eq!(nearest(&r, 1_960_000_000).map(|p| p.x), Some(2.0));
        assert_eq!(nearest(&r, 1_500_000_000), None);
        assert_eq!(nearest(&r, 3_000_000_000), None);
    }

    #[test]
    fn summary_as_printed() {
        let s = MapBuildSummary {
            scans_used: 440,
            scans_skipped: 2,
            lines: 1867,
            segments: 268,
            laser_mount: [0.0; 3],
            laser_mount_source: "config",
        };
        assert_eq!(
            s.to_string(),
            "268 segments from 440 scans (1867 lines; 2 scans skipped)\n"
        );
    }
}

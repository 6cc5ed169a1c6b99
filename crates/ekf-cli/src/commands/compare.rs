//! `ekf compare LOG`: the paper's Fig. 9/10 experiment. The same log is replayed in the
//! four estimator configurations ([`Mode::ALL`]: odometry, compass, laser,
//! laser+compass), each estimate is compared with the log's reference trajectory, and
//! [`write_svg`] draws the trajectories (Fig. 9) and the x and y errors over time
//! (Fig. 10) in one SVG.
//!
//! A configuration that cannot run on the log (say compass mode on a log without a
//! compass topic) is reported as not available, with the reason; the others still run.
//! A log without a reference topic is an error: there is nothing to compare against.

use crate::commands::figures::walls_of;
use crate::config::Config;
use crate::eval::{ape, ApeOptions, PoseError};
use crate::mcap_io::{BagReader, ReadError};
use crate::plot::{plot_figure, Panel, PlotError, PlotOptions, TimeSeries, TrajectorySeries, Wall};
use crate::replay::{replay, Mode, ReplayOptions};
use crate::trajectory::Trajectory;
use serde::Serialize;
use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};

/// How the four replays are run (the options `ekf replay` shares with `ekf compare`).
#[derive(Debug, Clone, Default)]
pub struct CompareOptions {
    /// A line map (JSON); `None`: each replay builds its map from the first scan.
    pub map: Option<PathBuf>,
    /// Start every replay at the first reference pose instead of `config.initial`.
    pub init_from_truth: bool,
}

/// Why a comparison could not be made at all (one mode failing is not an error).
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// The log could not be opened.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// The log has no reference trajectory on the configured topic.
    #[error("{log}: compare needs a reference trajectory, but the log has no topic {topic} (nav_msgs/msg/Odometry or geometry_msgs/msg/PoseStamped; set topics.ground_truth); the log has: {available}")]
    NoReference {
        /// The log.
        log: String,
        /// The reference topic looked for (`topics.ground_truth`).
        topic: String,
        /// The topics the log has, with their types.
        available: String,
    },
    /// The SVG could not be drawn or written.
    #[error("{path}: {source}")]
    Svg {
        /// The SVG file.
        path: String,
        /// What went wrong.
        source: PlotError,
    },
}

/// Accuracy of one estimate against the reference (APE without alignment, as `evo`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ModeAccuracy {
    /// Estimated poses matched to a reference pose by time stamp (within 10 ms).
    pub matched_poses: usize,
    /// Position RMSE (m).
    pub position_rmse_m: f64,
    /// Largest position error (m).
    pub position_max_m: f64,
    /// RMSE of the x error alone (m): the paper's Fig. 10, top.
    pub x_rmse_m: f64,
    /// RMSE of the y error alone (m): the paper's Fig. 10, bottom.
    pub y_rmse_m: f64,
    /// Heading RMSE (degrees).
    pub heading_rmse_deg: f64,
}

/// A mode that ran: its accuracy, what it fused, and (not serialized) its trajectory and
/// per-pose errors for the plots.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModeRun {
    /// Accuracy against the reference.
    pub accuracy: ModeAccuracy,
    /// Laser lines fused (0 without laser).
    pub lines_fused: u64,
    /// Compass headings fused (0 without compass).
    pub compass_fused: u64,
    /// Poses estimated.
    pub poses: usize,
    /// Set when the log broke off during the replay: the numbers cover the part before.
    pub stopped_early: Option<String>,
    /// The estimate.
    #[serde(skip)]
    pub trajectory: Trajectory,
    /// The error of every matched pose, estimate minus reference.
    #[serde(skip)]
    pub errors: Vec<PoseError>,
}

/// What became of one mode.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum ModeOutcome {
    /// The replay ran and its estimate was compared with the reference.
    Ran(ModeRun),
    /// The mode could not run on this log, or its estimate could not be compared.
    Unavailable {
        /// Why (the replay's or the evaluation's error message).
        reason: String,
    },
}

/// One of the four configurations and its outcome.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModeResult {
    /// `odometry`, `compass`, `laser` or `laser+compass` ([`Mode::name`]).
    pub mode: String,
    /// Its accuracy, or why it is not available.
    #[serde(flatten)]
    pub outcome: ModeOutcome,
}

impl ModeResult {
    /// The run, if the mode ran.
    pub fn run(&self) -> Option<&ModeRun> {
        match &self.outcome {
            ModeOutcome::Ran(run) => Some(run),
            ModeOutcome::Unavailable { .. } => None,
        }
    }
}

/// What `ekf compare` reports; `--json` prints it as JSON.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Comparison {
    /// The log.
    pub log: String,
    /// The reference topic.
    pub reference_topic: String,
    /// Reference poses read (0 if no mode ran).
    pub reference_poses: usize,
    /// Where the map came from: `first scan` or the map file.
    pub map: String,
    /// The four modes in the paper's order ([`Mode::ALL`]).
    pub modes: Vec<ModeResult>,
    /// The reference trajectory, for the plots.
    #[serde(skip)]
    pub reference: Trajectory,
    /// The walls of the map the laser modes used (the given map, or the first laser
    /// mode's first-scan map), for the plots.
    #[serde(skip)]
    pub walls: Vec<Wall>,
}

impl Comparison {
    /// The result of `mode`, by its name (`"laser+compass"`).
    pub fn mode(&self, name: &str) -> Option<&ModeResult> {
        self.modes.iter().find(|m| m.mode == name)
    }

    /// The modes that ran.
    pub fn runs(&self) -> impl Iterator<Item = (&str, &ModeRun)> {
        self.modes
            .iter()
            .filter_map(|m| m.run().map(|r| (m.mode.as_str(), r)))
    }

    /// A human-readable table: one row per mode, or its reason for being unavailable.
    pub fn to_table(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{}: reference {} ({} poses), map: {}",
            self.log, self.reference_topic, self.reference_poses, self.map
        );
        let _ = writeln!(
            s,
            "{:<14} {:>8} {:>8} {:>8} {:>8} {:>10} {:>8} {:>8} {:>7}",
            "mode", "RMSE m", "max m", "x RMSE", "y RMSE", "head. deg", "lines", "compass", "poses"
        );
        for m in &self.modes {
            match &m.outcome {
                ModeOutcome::Ran(r) => {
                    let a = &r.accuracy;
                    let _ = writeln!(
                        s,
                        "{:<14} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>10.2} {:>8} {:>8} {:>7}",
                        m.mode,
                        a.position_rmse_m,
                        a.position_max_m,
                        a.x_rmse_m,
                        a.y_rmse_m,
                        a.heading_rmse_deg,
                        r.lines_fused,
                        r.compass_fused,
                        a.matched_poses
                    );
                    if let Some(why) = &r.stopped_early {
                        let _ = writeln!(s, "{:<14} (log broke off: {why})", "");
                    }
                }
                ModeOutcome::Unavailable { reason } => {
                    let _ = writeln!(s, "{:<14} not available: {reason}", m.mode);
                }
            }
        }
        let _ = writeln!(
            s,
            "(RMSE/max: position error; x/y RMSE: per axis; lines/compass: measurements fused; poses: matched to the reference)"
        );
        s
    }
}

/// Replays `log` in each of the four modes (no outputs written) and compares every
/// estimate with the log's reference trajectory (`config.topics.ground_truth`).
///
/// Fails only if the log cannot be opened or has no reference topic; a mode that cannot
/// run is [`ModeOutcome::Unavailable`] with the reason.
pub fn compare(
    log: &Path,
    config: &Config,
    options: &CompareOptions,
) -> Result<Comparison, CompareError> {
    let log_name = log.display().to_string();
    let reference_topic = config.topics.ground_truth.clone();
    {
        let bag = BagReader::open(log)?;
        if !bag.topics().iter().any(|t| t.topic == reference_topic) {
            let available = bag.describe_topics();
            return Err(CompareError::NoReference {
                log: log_name,
                topic: reference_topic,
                available,
            });
        }
    }
    let mut comparison = Comparison {
        log: log_name,
        reference_topic,
        reference_poses: 0,
        map: options
            .map
            .as_ref()
            .map_or_else(|| "first scan".into(), |p| p.display().to_string()),
        modes: Vec::with_capacity(Mode::ALL.len()),
        reference: Trajectory::default(),
        walls: Vec::new(),
    };
    for mode in Mode::ALL {
        let replay_options = ReplayOptions {
            mode,
            map: options.map.clone(),
            init_from_truth: options.init_from_truth,
            out_mcap: None,
            tum: None,
            keep_trajectories: true,
            global: false,
            grow_map: false,
        };
        let outcome = match replay(log, config, &replay_options, &mut |_, _| {}) {
            Err(e) => ModeOutcome::Unavailable {
                reason: e.to_string(),
            },
            Ok(out) => {
                if comparison.reference.len() < out.reference.len() {
                    comparison.reference = out.reference.clone();
                }
                if comparison.walls.is_empty() {
                    comparison.walls = walls_of(&out.map.segments);
                }
                evaluate_run(out, &comparison.reference_topic)
            }
        };
        comparison.modes.push(ModeResult {
            mode: mode.name().into(),
            outcome,
        });
    }
    comparison.reference_poses = comparison.reference.len();
    Ok(comparison)
}

/// The accuracy of one replay against its reference.
fn evaluate_run(out: crate::replay::ReplayOutcome, reference_topic: &str) -> ModeOutcome {
    if out.reference.is_empty() {
        return ModeOutcome::Unavailable {
            reason: format!("no usable reference pose on {reference_topic}"),
        };
    }
    let result = match ape(&out.reference, &out.trajectory, &ApeOptions::default()) {
        Ok(r) => r,
        Err(e) => {
            return ModeOutcome::Unavailable {
                reason: format!("cannot compare with the reference: {e}"),
            }
        }
    };
    let rms = |f: fn(&PoseError) -> f64| {
        let n = result.errors.len().max(1) as f64;
        (result.errors.iter().map(|e| f(e).powi(2)).sum::<f64>() / n).sqrt()
    };
    let s = &result.summary;
    ModeOutcome::Ran(ModeRun {
        accuracy: ModeAccuracy {
            matched_poses: s.matched_poses,
            position_rmse_m: s.translation_m.rmse,
            position_max_m: s.translation_m.max,
            x_rmse_m: rms(|e| e.dx),
            y_rmse_m: rms(|e| e.dy),
            heading_rmse_deg: s.heading_error_deg.rmse,
        },
        lines_fused: out.summary.lines.fused,
        compass_fused: out.summary.compass.accepted,
        poses: out.trajectory.len(),
        stopped_early: out.failure.map(|e| e.to_string()),
        trajectory: out.trajectory,
        errors: result.errors,
    })
}

/// Size of the figure [`write_svg`] draws (px): two charts across, two down.
pub const FIGURE_SIZE: (u32, u32) = (1500, 1150);

/// Draws the comparison as one SVG figure of four charts and writes it to `writer`: the
/// estimated trajectories with the reference over the map's walls (the paper's Fig. 9), the
/// position error over time, and the x and y errors over time (the paper's Fig. 10), one
/// line per mode that ran, named by the mode (the reference is named `reference`).
///
/// Fails with [`PlotError::NoData`] if no mode ran.
pub fn render_svg<W: Write>(comparison: &Comparison, writer: W) -> Result<(), PlotError> {
    let runs: Vec<(&str, &ModeRun)> = comparison.runs().collect();
    if runs.is_empty() {
        return Err(PlotError::NoData);
    }
    let estimates: Vec<TrajectorySeries<'_>> = runs
        .iter()
        .map(|&(name, r)| TrajectorySeries {
            name,
            trajectory: &r.trajectory,
        })
        .collect();
    let points = |f: fn(&PoseError) -> f64| -> Vec<Vec<(u64, f64)>> {
        runs.iter()
            .map(|(_, r)| r.errors.iter().map(|e| (e.t_ns, f(e))).collect())
            .collect()
    };
    let (position, dx, dy) = (
        points(|e| e.translation),
        points(|e| e.dx),
        points(|e| e.dy),
    );
    let (position, dx, dy) = (
        time_series(&runs, &position),
        time_series(&runs, &dx),
        time_series(&runs, &dy),
    );
    let panels = [
        Panel::Trajectories {
            title: "Trajectories (Fig. 9)",
            reference: Some(TrajectorySeries {
                name: "reference",
                trajectory: &comparison.reference,
            }),
            estimates: &estimates,
            walls: &comparison.walls,
            markers: &[],
        },
        Panel::ErrorsOverTime {
            title: "Position error",
            series: &position,
            y_desc: "position error [m]",
            markers: &[],
        },
        Panel::ErrorsOverTime {
            title: "Deviation in X (Fig. 10)",
            series: &dx,
            y_desc: "x estimated - x real [m]",
            markers: &[],
        },
        Panel::ErrorsOverTime {
            title: "Deviation in Y (Fig. 10)",
            series: &dy,
            y_desc: "y estimated - y real [m]",
            markers: &[],
        },
    ];
    let log = Path::new(&comparison.log);
    let name = log.file_name().unwrap_or(log.as_os_str()).to_string_lossy();
    let options = PlotOptions {
        title: format!("{name}: four estimators against the reference"),
        width: FIGURE_SIZE.0,
        height: FIGURE_SIZE.1,
    };
    plot_figure(writer, &panels, 2, &options)
}

/// One named series per run.
fn time_series<'a>(
    runs: &[(&'a str, &ModeRun)],
    values: &'a [Vec<(u64, f64)>],
) -> Vec<TimeSeries<'a>> {
    runs.iter()
        .zip(values)
        .map(|(&(name, _), points)| TimeSeries { name, points })
        .collect()
}

/// Writes the figure of [`render_svg`] to the file `path` (all four charts in this one
/// file).
pub fn write_svg(comparison: &Comparison, path: &Path) -> Result<(), CompareError> {
    let svg_error = |source| CompareError::Svg {
        path: path.display().to_string(),
        source,
    };
    let file = std::fs::File::create(path).map_err(|e| svg_error(PlotError::Io(e)))?;
    render_svg(comparison, std::io::BufWriter::new(file)).map_err(svg_error)
}

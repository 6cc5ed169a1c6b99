//! `ekf map build LOG --slam`: a line map from a log without a reference trajectory
//! (docs/ARCHITECTURE.md §3 "Maps without a reference").
//!
//! The log is replayed with the filter localizing in a map that it builds as it goes
//! ([`FrontEnd`]): key scans every `key_distance` or `key_angle`, each a node of a 2D
//! pose graph ([`pose_graph`]) tied to the one before by the filter's relative pose. When
//! the robot comes back to a place it mapped, the relocalization search finds the scan in
//! a submap of the old key scans there, an EKF update on those walls refines the pose,
//! and the next key scans must fit the same correction before the closure enters the
//! graph (`slam/loop_closure.rs`); unless the graph already agrees with it (its edges'
//! cost within a chi-square bound), the graph is then optimised (Gauss–Newton, sparse
//! Cholesky) and the filter restarted at the corrected pose; the rest wait for the
//! optimisation at the end. At the end every key scan's lines are
//! fused at its optimised pose into the map ([`lrf_lines::MapBuilder`], as
//! `--from-truth` does with the reference), and every scan's pose is corrected with its
//! key scan's. The reference topic is not read.

mod front_end;
mod key_scans;
mod loop_closure;
pub mod pose_graph;
mod rematch;
mod scan_match;

pub use crate::slam_config::{MatchParams, SlamParams};
pub use front_end::FrontEnd;
pub use loop_closure::LoopCounts;

use crate::config::Config;
use crate::mcap_io::BagReader;
use crate::replay::{laser_mount, read_preamble, replay_with, ReplayError, ReplayOptions};
use crate::trajectory::Trajectory;
use ekf_fusion::Mode;
use lrf_lines::LineMap;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// What a SLAM build did.
#[derive(Debug, Clone, Serialize)]
pub struct SlamSummary {
    /// The log.
    pub log: String,
    /// `laser` or `laser+compass`.
    pub mode: String,
    /// Scans with a corrected pose (those from the first key scan on).
    pub scans: usize,
    /// Key scans (graph nodes).
    pub key_scans: usize,
    /// Path length driven (m).
    pub path_m: f64,
    /// Edges in the graph (key-scan chain and loop closures).
    pub edges: usize,
    /// What the loop-closure search did.
    pub loops: LoopCounts,
    /// Optimisations of the graph (a closure it already agreed with waits for the last).
    pub optimizations: usize,
    /// Gauss–Newton iterations over all optimisations.
    pub graph_iterations: usize,
    /// Scans the front end re-matched in its local map (odometry that erred more than
    /// the filter allowed).
    pub rematched: u64,
    /// Scans whose pose the scan matcher corrected (their points aligned to the local
    /// map's).
    pub aligned: u64,
    /// Segments in the map.
    pub segments: usize,
    /// Wall time of the build (s).
    pub wall_time_s: f64,
}

/// The summary as `ekf map build --slam` prints it after the map's file name.
impl std::fmt::Display for SlamSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{} segments from {} key scans of {} ({:.0} m driven); {} loop closures \
             ({} hypotheses, {} refuted); {} scans re-matched, {} aligned; {:.2} s",
            self.segments,
            self.key_scans,
            self.scans,
            self.path_m,
            self.loops.closures,
            self.loops.hypotheses,
            self.loops.refuted,
            self.rematched,
            self.aligned,
            self.wall_time_s
        )
    }
}

/// The results of a SLAM build.
#[derive(Debug)]
pub struct SlamOutcome {
    /// The map.
    pub map: LineMap,
    /// Every scan's corrected pose (log times).
    pub trajectory: Trajectory,
    /// Counts and timing.
    pub summary: SlamSummary,
    /// Set when the log broke off: the map and trajectory are of what came before.
    pub failure: Option<ReplayError>,
}

/// Builds the map of `log` without its reference ([module documentation](self)), with
/// `config.slam`.
/// `progress(done, total)` is called as messages are read.
pub fn build_slam_map(
    log: &Path,
    config: &Config,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<SlamOutcome, ReplayError> {
    let params = config.slam;
    params
        .validate()
        .map_err(|e| ReplayError::Slam(e.in_table("slam").to_string()))?;
    let started = Instant::now();
    let mut config = config.clone();
    // Mapping must not see the reference: the topic is renamed away.
    config.topics.ground_truth = String::new();
    let bag = BagReader::open(log)?;
    let has_compass = bag
        .topics()
        .iter()
        .any(|t| t.topic == config.topics.compass);
    let mode = if has_compass {
        Mode::LaserCompass
    } else {
        Mode::Laser
    };
    let preamble = read_preamble(&bag, &config, false)?;
    let (mount, _) = laser_mount(&preamble, &config)?;
    drop(bag);
    let mut localizer = config.localizer.clone();
    localizer.laser_mount = mount;
    let mut front = FrontEnd::new(params, localizer, mode == Mode::Laser);
    let options = ReplayOptions {
        mode,
        ..ReplayOptions::default()
    };
    let outcome = replay_with(log, &config, &options, Some(&mut front), progress)?;
    // A graph that cannot be solved at the end leaves the map of the last optimisation;
    // the failure is reported with it.
    let unsolved = front.finish().err();
    let map = front.map();
    let mut trajectory = Trajectory::default();
    for (t, pose) in front.corrected_scans() {
        trajectory.push(t, pose);
    }
    let summary = SlamSummary {
        log: log.display().to_string(),
        mode: mode.name().into(),
        scans: trajectory.samples.len(),
        key_scans: front.keys().len(),
        path_m: front.path(),
        edges: front.graph().edges().len(),
        loops: front.loops(),
        optimizations: front.optimizations,
        graph_iterations: front.iterations,
        rematched: front.rematched,
        aligned: front.aligned,
        segments: map.len(),
        wall_time_s: started.elapsed().as_secs_f64(),
    };
    if map.is_empty() && outcome.failure.is_none() {
        return Err(ReplayError::Map {
            path: summary.log,
            message: format!(
                "no lines were extracted from {} scans; nothing to map",
                summary.scans
            ),
        });
    }
    Ok(SlamOutcome {
        map,
        trajectory,
        summary,
        failure: outcome.failure.or(unsolved),
    })
}

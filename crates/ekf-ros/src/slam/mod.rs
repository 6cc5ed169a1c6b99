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
mod growth;
mod key_scans;
mod loop_closure;
pub mod pose_graph;
mod rematch;
mod scan_match;

pub use scan_match::MatchParams;

pub use front_end::FrontEnd;
pub use growth::MapGrowth;
pub use loop_closure::LoopCounts;

use crate::config::Config;
use crate::mcap_io::BagReader;
use crate::replay::{laser_mount, read_preamble, replay_with, ReplayError, ReplayOptions};
use crate::trajectory::Trajectory;
use ekf_core::setting::{check, Expected, InvalidSetting};
use ekf_fusion::Mode;
use lrf_lines::{LineMap, MapBuilderParams};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// The settings of the SLAM map builder (`[slam]` in the configuration). The defaults
/// suit an indoor robot with a 2D laser of 8–80 m range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SlamParams {
    /// A scan this far (m) from the last key scan is a key scan.
    pub key_distance: f64,
    /// ... or turned this much (rad).
    pub key_angle: f64,
    /// The filter localizes in the map of the key scans up to this path length (m)
    /// behind the newest.
    pub local_map_path: f64,
    /// A loop closure ties a key scan to old ones at least this path length (m) behind.
    pub loop_min_path: f64,
    /// Searched radius (m) around the filter's pose for a loop closure: `loop_radius +
    /// loop_drift · s`, `s` the path since the old key scan or the last closure,
    /// at most `loop_max_radius`.
    pub loop_radius: f64,
    /// See `loop_radius` (m per m driven).
    pub loop_drift: f64,
    /// See `loop_radius` (m).
    pub loop_max_radius: f64,
    /// Largest heading correction (rad) a loop closure may make.
    pub loop_max_turn: f64,
    /// Path (m) after a closure before the next is searched for.
    pub loop_cooldown_path: f64,
    /// A loop closure is searched for with the walls of the key scans up to this path
    /// (m) before the newest, placed by the front end and fused: a few scans' walls,
    /// where one scan's two to six lines are often ambiguous; their lines refine the
    /// pose found.
    pub chain_path: f64,
    /// Old key scans within this distance (m) of the closure's anchor make its submap ...
    pub submap_radius: f64,
    /// ... the nearest this many of them.
    pub submap_max_keys: usize,
    /// Key scans after a hypothesis that must fit its correction before it is a closure.
    pub verify_key_scans: usize,
    /// How close (m) a confirming key scan's pose must come to the correction's.
    pub verify_distance: f64,
    /// ... and its heading (rad).
    pub verify_angle: f64,
    /// Prior standard deviation (m) of the refinement's EKF update.
    pub refine_sigma_xy: f64,
    /// ... of its heading (rad).
    pub refine_sigma_theta: f64,
    /// A scan the filter's pose does not explain is fused again with the covariance
    /// widened by this standard deviation of position (m) ...
    pub rematch_sigma_xy: f64,
    /// ... and of heading (rad): about three times the heading error of the odometry of
    /// one scan interval on the shared logs (RMS 2.6° on ACES).
    pub rematch_sigma_theta: f64,
    /// Fewest lines that must fuse in a refinement.
    pub min_loop_lines: usize,

    /// Odometry edge: position standard deviation per key step (m) ...
    pub odometry_sigma_xy: f64,
    /// ... plus this per metre of the step.
    pub odometry_sigma_xy_per_m: f64,
    /// Odometry edge: heading standard deviation per key step (rad) ...
    pub odometry_sigma_theta: f64,
    /// ... plus this per radian turned.
    pub odometry_sigma_theta_per_rad: f64,
    /// Gauss–Newton iterations per optimisation, at most.
    pub max_iterations: usize,
    /// How the key scans' lines are fused into walls.
    pub map_builder: MapBuilderParams,
    /// The scan matcher that corrects each scan's pose, and each loop closure's, with the
    /// scan's points.
    pub scan_match: MatchParams,
}

impl Default for SlamParams {
    fn default() -> Self {
        Self {
            key_distance: 0.5,
            key_angle: 15f64.to_radians(),
            local_map_path: 10.0,
            loop_min_path: 15.0,
            loop_radius: 1.0,
            loop_drift: 0.1,
            loop_max_radius: 10.0,
            loop_max_turn: 20f64.to_radians(),
            loop_cooldown_path: 2.0,
            chain_path: 3.0,
            submap_radius: 8.0,
            submap_max_keys: 40,
            verify_key_scans: 2,
            verify_distance: 0.3,
            verify_angle: 3f64.to_radians(),
            refine_sigma_xy: 0.15,
            refine_sigma_theta: 3f64.to_radians(),
            rematch_sigma_xy: 0.3,
            rematch_sigma_theta: 0.15,
            min_loop_lines: 3,
            odometry_sigma_xy: 0.02,
            odometry_sigma_xy_per_m: 0.03,
            odometry_sigma_theta: 0.3f64.to_radians(),
            odometry_sigma_theta_per_rad: 0.03,
            max_iterations: 20,
            map_builder: MapBuilderParams::default(),
            scan_match: MatchParams::default(),
        }
    }
}

impl SlamParams {
    /// Distances and standard deviations positive, angles in radians, rates, tolerances
    /// and the map builder's gap not negative, its gate probability in (0, 1), the scan
    /// matcher's settings valid ([`MatchParams::validate`]).
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        for (key, value) in [
            ("key_distance", self.key_distance),
            ("local_map_path", self.local_map_path),
            ("loop_min_path", self.loop_min_path),
            ("loop_radius", self.loop_radius),
            ("loop_max_radius", self.loop_max_radius),
            ("submap_radius", self.submap_radius),
            ("verify_distance", self.verify_distance),
            ("refine_sigma_xy", self.refine_sigma_xy),
            ("rematch_sigma_xy", self.rematch_sigma_xy),
            ("odometry_sigma_xy", self.odometry_sigma_xy),
            ("odometry_sigma_theta", self.odometry_sigma_theta),
        ] {
            check(key, value, Expected::Positive)?;
        }
        for (key, value) in [
            ("key_angle", self.key_angle),
            ("loop_max_turn", self.loop_max_turn),
            ("verify_angle", self.verify_angle),
            ("refine_sigma_theta", self.refine_sigma_theta),
            ("rematch_sigma_theta", self.rematch_sigma_theta),
        ] {
            check(key, value, Expected::Radians)?;
            check(key, value, Expected::Positive)?;
        }
        for (key, value) in [
            ("loop_drift", self.loop_drift),
            ("loop_cooldown_path", self.loop_cooldown_path),
            ("chain_path", self.chain_path),
            ("odometry_sigma_xy_per_m", self.odometry_sigma_xy_per_m),
            (
                "odometry_sigma_theta_per_rad",
                self.odometry_sigma_theta_per_rad,
            ),
            ("map_builder.tolerance_rho", self.map_builder.tolerance_rho),
            (
                "map_builder.tolerance_beta",
                self.map_builder.tolerance_beta,
            ),
            ("map_builder.max_gap", self.map_builder.max_gap),
        ] {
            check(key, value, Expected::MetresWithin(1e6))?;
            if value < 0.0 {
                check(key, value, Expected::Positive)?;
            }
        }
        check(
            "map_builder.gate_probability",
            self.map_builder.gate_probability,
            Expected::Probability,
        )?;
        self.scan_match.validate()
    }
}

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

//! `ekf simulate SCENARIO --out LOG.mcap`: a simulated run written as a ROS 2 bag with
//! exact ground truth (see [`crate`]).

use crate::{
    simulate, Estimator, Feedback, LaserModel, LogRecorder, Scenario, ScenarioError, SimError,
    SimOptions, SimResult, SimStats,
};
use ekf_fusion::Mode;
use ekf_ros::config::{Config, ConfigError};
use ekf_ros::mcap_io::WriteError;
use ekf_ros::replay::{load_map, ReplayError};
use serde::Serialize;
use std::path::Path;

/// What steers the simulated robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Steering {
    /// The true pose: the robot follows the path as well as the drive allows.
    Truth,
    /// The laser + compass EKF running in the loop (map from the first scan).
    Ekf,
    /// Dead reckoning from the encoders.
    Odometry,
}

/// Settings of `ekf simulate` beyond the scenario's own.
#[derive(Debug, Clone)]
pub struct SimulateOptions {
    /// Noise seed.
    pub seed: u64,
    /// Run length (s); `None`: the scenario's.
    pub duration_s: Option<f64>,
    /// What steers the robot.
    pub steering: Steering,
    /// Laser angular resolution (degrees): 0.25, 0.5 or 1; `None`: the scenario's.
    pub resolution_deg: Option<f64>,
    /// Wheel slip events per minute; `None`: the scenario's (none).
    pub slips_per_minute: Option<f64>,
    /// Compass bias (degrees); `None`: the scenario's (none).
    pub compass_bias_deg: Option<f64>,
    /// Compass outlier probability; `None`: the scenario's (2 %).
    pub compass_outliers: Option<f64>,
}

impl Default for SimulateOptions {
    fn default() -> Self {
        Self {
            seed: 1,
            duration_s: None,
            steering: Steering::Truth,
            resolution_deg: None,
            slips_per_minute: None,
            compass_bias_deg: None,
            compass_outliers: None,
        }
    }
}

/// Why a simulation could not be made.
#[derive(Debug, thiserror::Error)]
pub enum SimulateError {
    /// The scenario name or map is not usable.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The map file could not be read.
    #[error(transparent)]
    Map(#[from] ReplayError),
    /// An option is out of range.
    #[error("{option}: {message}")]
    Option {
        /// The option (as on the command line).
        option: &'static str,
        /// What was expected.
        message: String,
    },
    /// The preset configuration failed to load (a build defect).
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The run failed.
    #[error(transparent)]
    Run(#[from] SimError),
    /// The log could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
}

/// What `ekf simulate` reports.
#[derive(Debug, Clone, Serialize)]
pub struct SimulateSummary {
    /// The scenario.
    pub scenario: String,
    /// The seed.
    pub seed: u64,
    /// The log written (empty when none was).
    pub out: String,
    /// Simulated time (s).
    pub duration_s: f64,
    /// Messages written.
    pub messages: u64,
    /// What happened in the run.
    pub stats: SimStats,
}

/// The summary as `ekf simulate` prints it: one line.
impl std::fmt::Display for SimulateSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = &self.stats;
        writeln!(
            f,
            "{}: {} ({} s, seed {}): {} messages, {} scans, {:.1} m driven, {} compass \
             outliers, {} slips, closest to a wall {:.2} m",
            self.out,
            self.scenario,
            self.duration_s,
            self.seed,
            self.messages,
            s.scans,
            s.distance_m,
            s.compass_outliers,
            s.slips,
            s.min_clearance_m
        )
    }
}

/// A built-in scenario by name, or a user's room from a line map (a path ending in
/// `.json`), with `options` applied.
pub fn load_scenario(name: &str, options: &SimulateOptions) -> Result<Scenario, SimulateError> {
    let mut s = if name.ends_with(".json") {
        let map = load_map(Path::new(name))?;
        Scenario::from_map(name, &map)?
    } else {
        Scenario::builtin(name)?
    };
    let bad = |option, message: &str| SimulateError::Option {
        option,
        message: message.into(),
    };
    if let Some(d) = options.duration_s {
        if !(d.is_finite() && d > 0.0 && d <= 86_400.0) {
            return Err(bad("--duration", "expected seconds in (0, 86400]"));
        }
        s.duration_s = d;
    }
    if let Some(r) = options.resolution_deg {
        let laser = LaserModel::at_resolution(r, s.dt).ok_or_else(|| {
            bad(
                "--resolution",
                "the LMS 221 scans at 0.25 (over 100°), 0.5 or 1 degree",
            )
        })?;
        s.laser.resolution = laser.resolution;
        s.laser.fov = laser.fov;
        s.laser.period_steps = laser.period_steps;
    }
    if let Some(m) = options.slips_per_minute {
        if !(m.is_finite() && m >= 0.0) {
            return Err(bad("--slips-per-minute", "expected a rate >= 0"));
        }
        s.robot.slips_per_minute = m;
    }
    if let Some(b) = options.compass_bias_deg {
        if !(b.is_finite() && b.abs() <= 180.0) {
            return Err(bad("--compass-bias", "expected degrees in [-180, 180]"));
        }
        s.compass.bias = b.to_radians();
    }
    if let Some(p) = options.compass_outliers {
        if !(0.0..=1.0).contains(&p) {
            return Err(bad(
                "--compass-outliers",
                "expected a probability in [0, 1]",
            ));
        }
        s.compass.outlier_probability = p;
    }
    Ok(s)
}

/// The in-loop estimator `ekf simulate` and the experiments use: the paper-robot preset
/// in `mode`, starting at the true pose with the configured initial uncertainty, map
/// from the first scan.
pub fn paper_estimator(mode: Mode) -> Result<Estimator, ConfigError> {
    let config = Config::preset("paper-robot")?;
    Ok(Estimator {
        mode,
        config: config.localizer,
        initial_sigma: (config.initial.sigma_xy, config.initial.sigma_theta),
        map: None,
    })
}

/// Runs `scenario`, writing its log to `out` when given, and returns the run (true
/// trajectory, the in-loop estimate when the robot steered by one) with its summary. If
/// the run fails part way, what was simulated is in the log, which is finished and
/// readable, and the error is returned.
pub fn run_simulation(
    scenario: &Scenario,
    options: &SimulateOptions,
    out: Option<&Path>,
) -> Result<(SimResult, SimulateSummary), SimulateError> {
    let (feedback, estimator) = match options.steering {
        Steering::Truth => (Feedback::Truth, None),
        Steering::Ekf => (
            Feedback::Estimate,
            Some(paper_estimator(Mode::LaserCompass)?),
        ),
        Steering::Odometry => (Feedback::Estimate, Some(paper_estimator(Mode::Odometry)?)),
    };
    let sim_options = SimOptions {
        seed: options.seed,
        feedback,
        estimator,
    };
    let (run, messages) = match out {
        Some(path) => {
            let mut recorder = LogRecorder::create(path, scenario, options.seed)?;
            let run = simulate(scenario, &sim_options, Some(&mut recorder));
            let messages = recorder.messages();
            let finished = recorder.finish();
            let run = run?;
            finished?;
            (run, messages)
        }
        None => (simulate(scenario, &sim_options, None)?, 0),
    };
    let summary = SimulateSummary {
        scenario: scenario.name.clone(),
        seed: options.seed,
        out: out.map(|p| p.display().to_string()).unwrap_or_default(),
        duration_s: run.stats.steps as f64 * scenario.dt,
        messages,
        stats: run.stats,
    };
    Ok((run, summary))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_as_printed() {
        let s = SimulateSummary {
            scenario: "paper".into(),
            seed: 1,
            out: "sim.mcap".into(),
            duration_s: 20.0,
            messages: 705,
            stats: SimStats {
                scans: 101,
                distance_m: 6.04,
                compass_outliers: 2,
                slips: 0,
                min_clearance_m: 0.951,
                ..SimStats::default()
            },
        };
        assert_eq!(
            s.to_string(),
            "sim.mcap: paper (20 s, seed 1): 705 messages, 101 scans, 6.0 m driven, 2 compass \
             outliers, 0 slips, closest to a wall 0.95 m\n"
        );
    }
}

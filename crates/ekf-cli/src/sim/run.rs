//! The closed loop: the follower steers by the true pose or by an estimator's, the robot
//! drives, the sensors measure, an optional in-loop estimator (the same [`Localizer`] that
//! `ekf replay` runs) fuses what they measure, and a [`LogRecorder`] may write it all.

use super::log::LogRecorder;
use super::path::PurePursuit;
use super::rng::{SimRng, Stream};
use super::robot::Robot;
use super::scenario::Scenario;
use super::sensors::{CompassReading, LASER_RANGE_MIN};
use crate::mcap_io::WriteError;
use crate::replay::Mode;
use crate::trajectory::Trajectory;
use ekf_core::{angle_diff, Pose2, WheelSpeeds};
use lrf_lines::{LaserScan, LineMap, Localizer, LocalizerConfig, LocalizerError};
use nalgebra::{Matrix3, Point2, Vector3};
use serde::Serialize;

/// What the path follower steers by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feedback {
    /// The true pose (a perfect localization: the reference run).
    Truth,
    /// The in-loop estimator's pose ([`SimOptions::estimator`] must be set).
    Estimate,
}

/// An estimator running inside the loop.
#[derive(Debug, Clone)]
pub struct Estimator {
    /// Which sensors it fuses (odometry alone is dead reckoning).
    pub mode: Mode,
    /// Its configuration.
    pub config: LocalizerConfig,
    /// Initial standard deviations of position (m) and heading (rad); it starts at the
    /// true pose.
    pub initial_sigma: (f64, f64),
    /// Its map; `None`: the lines of the first scan, as in the paper.
    pub map: Option<LineMap>,
}

/// How a run is made.
#[derive(Debug, Clone)]
pub struct SimOptions {
    /// Seed of every noise source.
    pub seed: u64,
    /// What the follower steers by.
    pub feedback: Feedback,
    /// The in-loop estimator, if any.
    pub estimator: Option<Estimator>,
}

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// Steering by the estimate without an estimator.
    #[error("feedback from the estimate needs an in-loop estimator")]
    NoEstimator,
    /// The estimator refused its configuration or failed.
    #[error("in-loop estimator: {0}")]
    Estimator(#[from] LocalizerError),
    /// The log could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
}

/// One step's measurements, as the sensors report them.
#[derive(Debug, Clone, Copy)]
pub struct Sample<'a> {
    /// Time (ns since the start).
    pub t_ns: u64,
    /// The true pose.
    pub truth: Pose2<f64>,
    /// Encoder counts since the start (left, right).
    pub ticks: [i64; 2],
    /// The compass reading.
    pub compass: CompassReading,
    /// A laser sweep, on the steps that have one.
    pub scan: Option<&'a [f32]>,
}

/// Counts of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct SimStats {
    /// Control steps.
    pub steps: u64,
    /// Laser sweeps.
    pub scans: u64,
    /// Compass readings.
    pub compass_readings: u64,
    /// Compass outliers injected.
    pub compass_outliers: u64,
    /// Compass readings the in-loop estimator fused.
    pub compass_fused: u64,
    /// Outliers among them (a consistent gate keeps this at 0).
    pub compass_outliers_fused: u64,
    /// Laser lines the in-loop estimator fused.
    pub lines_fused: u64,
    /// Wheel slip events.
    pub slips: u32,
    /// Distance the robot travelled (m).
    pub distance_m: f64,
    /// Closest the robot came to a wall (m).
    pub min_clearance_m: f64,
}

/// What a run produced.
#[derive(Debug, Clone)]
pub struct SimResult {
    /// The true pose at every step.
    pub truth: Trajectory,
    /// The in-loop estimate at every step (empty without an estimator).
    pub estimate: Trajectory,
    /// The estimate's NEES `eᵀ P⁻¹ e` at every step, `e = (x̂ − x, ŷ − y, wrap(θ̂ − θ))`.
    pub nees: Vec<f64>,
    /// Distance of the true position from the commanded path at every step (m).
    pub path_deviation: Vec<f64>,
    /// Distance travelled up to every step (m).
    pub travelled: Vec<f64>,
    /// Counts.
    pub stats: SimStats,
    /// The estimator's map at the end (`None` without an estimator).
    pub map: Option<LineMap>,
}

/// `eᵀ P⁻¹ e` for the error of `est` against `truth`; `None` if `P` is not SPD.
pub fn nees(est: &Pose2<f64>, truth: &Pose2<f64>, p: &Matrix3<f64>) -> Option<f64> {
    let e = Vector3::new(
        est.x - truth.x,
        est.y - truth.y,
        angle_diff(est.theta, truth.theta),
    );
    let chol = p.cholesky()?;
    Some(e.dot(&chol.solve(&e)))
}

/// Runs `scenario` with `options`, writing every measurement to `recorder` if given.
pub fn simulate(
    scenario: &Scenario,
    options: &SimOptions,
    mut recorder: Option<&mut LogRecorder>,
) -> Result<SimResult, SimError> {
    if options.feedback == Feedback::Estimate && options.estimator.is_none() {
        return Err(SimError::NoEstimator);
    }
    let (mut wheel_rng, mut compass_rng, mut laser_rng) = (
        SimRng::new(options.seed, Stream::Wheels),
        SimRng::new(options.seed, Stream::Compass),
        SimRng::new(options.seed, Stream::Laser),
    );
    let start = scenario.start;
    let mut robot = Robot::new(scenario.robot, start);
    let d = scenario.drive;
    let mut follower = PurePursuit::new(d.lookahead, d.speed, d.max_turn_rate);
    follower.join(&scenario.path, &start);
    let mut filter = match &options.estimator {
        Some(e) => Some(InLoop::new(e, start, scenario)?),
        None => None,
    };
    let laser = scenario.laser;
    let compass_variance = scenario.compass.sigma.powi(2);
    let mut result = SimResult {
        truth: Trajectory::new(),
        estimate: Trajectory::new(),
        nees: Vec::new(),
        path_deviation: Vec::new(),
        travelled: Vec::new(),
        stats: SimStats {
            min_clearance_m: f64::INFINITY,
            ..SimStats::default()
        },
        map: None,
    };
    let dt_ns = (scenario.dt * 1e9).round() as u64;
    let mut last_ticks = [0i64; 2];
    for k in 0..=scenario.steps() {
        let t_ns = k * dt_ns;
        if k > 0 {
            let steer_by = match (&filter, options.feedback) {
                (Some(f), Feedback::Estimate) => f.localizer.pose(),
                _ => robot.pose(),
            };
            let (v, omega) = follower.command(&scenario.path, &steer_by);
            let before = robot.pose();
            robot.step(
                scenario.robot.wheel_speeds(v, omega),
                scenario.dt,
                &mut wheel_rng,
            );
            let after = robot.pose();
            result.stats.distance_m += (after.x - before.x).hypot(after.y - before.y);
        }
        let truth = robot.pose();
        let ticks = robot.ticks();
        let compass = scenario.compass.read(truth.theta, &mut compass_rng);
        let ranges = (k % u64::from(laser.period_steps.max(1)) == 0)
            .then(|| laser.scan(&scenario.room, &truth, &mut laser_rng));
        let sample = Sample {
            t_ns,
            truth,
            ticks,
            compass,
            scan: ranges.as_deref(),
        };
        if let Some(r) = recorder.as_deref_mut() {
            r.record(&sample)?;
        }
        let s = &mut result.stats;
        s.steps = k;
        s.compass_readings += 1;
        s.compass_outliers += u64::from(compass.outlier);
        s.scans += u64::from(ranges.is_some());
        let position = Point2::new(truth.x, truth.y);
        s.min_clearance_m = s.min_clearance_m.min(scenario.room.clearance(&position));
        if let Some(f) = filter.as_mut() {
            let wheel = (k > 0).then(|| {
                let tick = scenario.robot.tick();
                WheelSpeeds {
                    left: (ticks[0] - last_ticks[0]) as f64 * tick / scenario.dt,
                    right: (ticks[1] - last_ticks[1]) as f64 * tick / scenario.dt,
                    dt: scenario.dt,
                }
            });
            f.step(wheel, &sample, compass_variance, scenario, s)?;
            let est = f.localizer.pose();
            result.estimate.push(t_ns, est);
            result
                .nees
                .push(nees(&est, &truth, f.localizer.covariance()).unwrap_or(f64::NAN));
        }
        last_ticks = ticks;
        result.truth.push(t_ns, truth);
        result
            .path_deviation
            .push(scenario.path.distance(&position));
        result.travelled.push(s.distance_m);
    }
    result.stats.slips = robot.slips();
    result.map = filter.map(|f| f.localizer.map().clone());
    Ok(result)
}

/// The in-loop estimator.
struct InLoop {
    localizer: Localizer,
    mode: Mode,
}

impl InLoop {
    fn new(e: &Estimator, start: Pose2<f64>, scenario: &Scenario) -> Result<Self, SimError> {
        let mut config = e.config.clone();
        config.laser_mount = scenario.laser.mount;
        let (sxy, sth) = e.initial_sigma;
        let p0 = Matrix3::from_diagonal(&Vector3::new(sxy * sxy, sxy * sxy, sth * sth));
        let localizer = match &e.map {
            Some(map) => Localizer::new(config, start, p0, map.clone())?,
            None => Localizer::with_first_scan_map(config, start, p0)?,
        };
        Ok(Self {
            localizer,
            mode: e.mode,
        })
    }

    /// Prediction over the step, then the compass, then the scan (the order `ekf
    /// replay` fuses a recording of the run in).
    fn step(
        &mut self,
        wheels: Option<WheelSpeeds<f64>>,
        sample: &Sample<'_>,
        compass_variance: f64,
        scenario: &Scenario,
        stats: &mut SimStats,
    ) -> Result<(), SimError> {
        if let Some(w) = wheels {
            self.localizer.predict_wheels(&w)?;
        }
        if self.mode.uses_compass() {
            let outcome = self
                .localizer
                .update_compass_with_variance(sample.compass.heading, compass_variance)?;
            if outcome.accepted {
                stats.compass_fused += 1;
                stats.compass_outliers_fused += u64::from(sample.compass.outlier);
            }
        }
        if let (Some(ranges), true) = (sample.scan, self.mode.uses_laser()) {
            // The angles as the log stores them (float32), so a replay sees the same scan.
            let laser = &scenario.laser;
            let scan = LaserScan {
                angle_min: f64::from(laser.angle_min() as f32),
                angle_increment: f64::from(laser.resolution as f32),
                range_min: f64::from(LASER_RANGE_MIN as f32),
                range_max: f64::from(laser.max_range as f32),
                ranges,
            };
            let report = self.localizer.update_scan(&scan)?;
            stats.lines_fused += report.fused as u64;
        }
        Ok(())
    }
}

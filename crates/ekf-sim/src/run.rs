//! The closed loop: the follower steers by the true pose or by an estimator's, the robot
//! drives, the sensors measure, an optional in-loop estimator (the time-ordered
//! localizer's [`Fuser`], which `ekf replay` drives too) fuses what they measure, and a
//! [`LogRecorder`] may write it all.

use super::log::LogRecorder;
use super::rng::{SimRng, Stream};
use super::scenario::Scenario;
use super::sensors::LASER_RANGE_MIN;
use super::stepper::{Sample, Simulator};
use ekf_core::{angle_diff, Pose2};
use ekf_fusion::{Fused, Fuser, FusionConfig, FusionError, Input, Mode, Scan, Tracking};
use ekf_ros::mcap_io::WriteError;
use ekf_ros::trajectory::Trajectory;
use lrf_lines::{LineMap, LocalizerConfig, LocalizerError};
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
    /// Initial standard deviations of position (m) and heading (rad). It starts at the
    /// true pose plus an error drawn from them (see [`Estimator::initial_estimate`]).
    pub initial_sigma: (f64, f64),
    /// Its map; `None`: the lines of the first scan, as in the paper.
    pub map: Option<LineMap>,
}

impl Estimator {
    /// Where the estimator starts when the robot is at `truth`: `truth + e` with
    /// `e ~ N(0, diag(σ_xy², σ_xy², σ_θ²))` drawn from the seed's own stream, as the
    /// consistency test (Bar-Shalom et al. 2001, §5.4.2) needs: an initial error that the
    /// initial covariance describes. A robot set down at a surveyed pose is off it by as
    /// much; a first-scan map placed at the estimate inherits the error.
    pub fn initial_estimate(&self, truth: &Pose2<f64>, seed: u64) -> Pose2<f64> {
        let mut rng = SimRng::new(seed, Stream::InitialPose);
        let (sxy, sth) = self.initial_sigma;
        let (dx, dy, dth) = (rng.normal(sxy), rng.normal(sxy), rng.normal(sth));
        Pose2::new(truth.x + dx, truth.y + dy, truth.theta + dth)
    }
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
    /// The time-ordered localizer refused its configuration.
    #[error("in-loop estimator: {0}")]
    Fusion(#[from] FusionError),
    /// The log could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
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
    /// The estimate's NEES at every step (see [`Nees`]).
    pub nees: Vec<Nees>,
    /// Distance of the true position from the commanded path at every step (m).
    pub path_deviation: Vec<f64>,
    /// Distance travelled up to every step (m).
    pub travelled: Vec<f64>,
    /// Counts.
    pub stats: SimStats,
    /// The estimator's map at the end (`None` without an estimator).
    pub map: Option<LineMap>,
    /// Where the estimator started (`None` without an estimator); see
    /// [`Estimator::initial_estimate`].
    pub initial_estimate: Option<Pose2<f64>>,
}

/// The normalised estimation error squared of one estimate, whole and by part, with
/// `e = (x̂ − x, ŷ − y, wrap(θ̂ − θ))`. For a consistent filter each is chi-square
/// distributed with as many degrees of freedom as it has components, so the parts show
/// which of position and heading a filter is over- or under-confident in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nees {
    /// `eᵀ P⁻¹ e` (3 dof).
    pub pose: f64,
    /// `e_xyᵀ P_xy⁻¹ e_xy` with the 2×2 position block of `P` (2 dof).
    pub position: f64,
    /// `e_θ² / P_θθ` (1 dof).
    pub heading: f64,
}

impl Nees {
    /// The NEES of `est` against `truth` with covariance `p`; `None` if `p` is not
    /// symmetric positive definite.
    pub fn of(est: &Pose2<f64>, truth: &Pose2<f64>, p: &Matrix3<f64>) -> Option<Self> {
        let e = Vector3::new(
            est.x - truth.x,
            est.y - truth.y,
            angle_diff(est.theta, truth.theta),
        );
        let pose = e.dot(&p.cholesky()?.solve(&e));
        let e_xy = e.fixed_rows::<2>(0).into_owned();
        let p_xy = p.fixed_view::<2, 2>(0, 0).into_owned();
        let position = e_xy.dot(&p_xy.cholesky()?.solve(&e_xy));
        Some(Self {
            pose,
            position,
            heading: e.z * e.z / p[(2, 2)],
        })
    }

    /// All three NaN: a step whose covariance was not positive definite.
    pub const UNDEFINED: Self = Self {
        pose: f64::NAN,
        position: f64::NAN,
        heading: f64::NAN,
    };
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
    let start = scenario.start;
    let mut sim = Simulator::new(scenario, options.seed);
    let mut filter = match &options.estimator {
        Some(e) => Some(InLoop::new(
            e,
            e.initial_estimate(&start, options.seed),
            scenario,
        )?),
        None => None,
    };
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
        initial_estimate: filter.as_ref().map(|f| f.pose()),
    };
    for k in 0..=scenario.steps() {
        if k > 0 {
            let steer_by = match (&filter, options.feedback) {
                (Some(f), Feedback::Estimate) => f.pose(),
                _ => sim.pose(),
            };
            result.stats.distance_m += sim.advance(&steer_by);
        }
        let sample = sim.measure();
        let (t_ns, truth, compass) = (sample.t_ns, sample.truth, sample.compass);
        if let Some(r) = recorder.as_deref_mut() {
            r.record(&sample)?;
        }
        let s = &mut result.stats;
        s.steps = k;
        s.compass_readings += 1;
        s.compass_outliers += u64::from(compass.outlier);
        s.scans += u64::from(sample.scan.is_some());
        let position = Point2::new(truth.x, truth.y);
        s.min_clearance_m = s.min_clearance_m.min(scenario.room.clearance(&position));
        if let Some(f) = filter.as_mut() {
            f.step(&sample, compass_variance, scenario, s)?;
            let est = f.pose();
            result.estimate.push(t_ns, est);
            let covariance = f.fuser.localizer().covariance();
            result
                .nees
                .push(Nees::of(&est, &truth, covariance).unwrap_or(Nees::UNDEFINED));
        }
        result.truth.push(t_ns, truth);
        result
            .path_deviation
            .push(scenario.path.distance(&position));
        result.travelled.push(s.distance_m);
    }
    result.stats.slips = sim.slips();
    result.map = filter.map(|f| f.fuser.localizer().map().clone());
    Ok(result)
}

/// The in-loop estimator: the fuser `ekf replay` drives, given each step's readings as a
/// recording of the run gives them to replay (encoder angles, heading, scan, all at the
/// step's stamp, in that order).
struct InLoop {
    fuser: Fuser,
}

impl InLoop {
    fn new(e: &Estimator, initial: Pose2<f64>, scenario: &Scenario) -> Result<Self, SimError> {
        let mut localizer = e.config.clone();
        localizer.laser_mount = scenario.laser.mount;
        let config = FusionConfig {
            localizer,
            mode: e.mode,
            tracking: Tracking::Off,
            // The loop hands over each step's readings in order.
            max_lag: 0.0,
            ..FusionConfig::default()
        };
        let (sxy, sth) = e.initial_sigma;
        let p0 = Matrix3::from_diagonal(&Vector3::new(sxy * sxy, sxy * sxy, sth * sth));
        let fuser = Fuser::new(&config, initial, p0, 0, e.map.clone())?;
        Ok(Self { fuser })
    }

    /// The estimate.
    fn pose(&self) -> Pose2<f64> {
        self.fuser.localizer().pose()
    }

    /// The wheels' encoder angles (a prediction over the step from the previous ones),
    /// then the compass, then the scan.
    fn step(
        &mut self,
        sample: &Sample,
        compass_variance: f64,
        scenario: &Scenario,
        stats: &mut SimStats,
    ) -> Result<(), SimError> {
        let t = sample.t_ns;
        let tick = scenario.robot.tick();
        let wheels = Input::WheelAngles {
            left: sample.ticks[0] as f64 * tick,
            right: sample.ticks[1] as f64 * tick,
            velocities: None,
        };
        self.fuser.fuse(t, &wheels, &mut ())?;
        let heading = Input::Heading {
            heading: sample.compass.heading,
            variance: Some(compass_variance),
        };
        if let Fused::Heading { update, .. } = self.fuser.fuse(t, &heading, &mut ())? {
            if update.outcome.accepted {
                stats.compass_fused += 1;
                stats.compass_outliers_fused += u64::from(sample.compass.outlier);
            }
        }
        if let (Some(ranges), true) = (sample.scan.as_deref(), self.fuser.mode().uses_laser()) {
            // The angles as the log stores them (float32), so a replay sees the same scan.
            let laser = &scenario.laser;
            let scan = Input::Scan(Scan {
                angle_min: f64::from(laser.angle_min() as f32),
                angle_increment: f64::from(laser.resolution as f32),
                range_min: f64::from(LASER_RANGE_MIN as f32),
                range_max: f64::from(laser.max_range as f32),
                ranges: ranges.to_vec(),
            });
            match self.fuser.fuse(t, &scan, &mut ())? {
                Fused::Scan(s) => stats.lines_fused += s.report.fused as u64,
                Fused::ScanRefused(e) => return Err(LocalizerError::Extraction(e).into()),
                _ => {}
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nees_parts_add_up_without_correlation_and_the_position_is_marginal() {
        let truth = Pose2::new(1.0, 2.0, 3.1);
        // A heading error across ±π: −3.1 − 3.1 wraps to 2π − 6.2 = 0.0832 rad.
        let est = Pose2::new(1.03, 1.96, -3.1);
        let diagonal = Matrix3::from_diagonal(&Vector3::new(1e-3, 4e-3, 1e-2));
        let n = Nees::of(&est, &truth, &diagonal).unwrap();
        let e_theta = angle_diff(est.theta, truth.theta);
        assert!((e_theta - (std::f64::consts::TAU - 6.2)).abs() < 1e-12);
        assert!((n.position - (0.03f64.powi(2) / 1e-3 + 0.04f64.powi(2) / 4e-3)).abs() < 1e-9);
        assert!((n.heading - e_theta * e_theta / 1e-2).abs() < 1e-9);
        assert!((n.pose - (n.position + n.heading)).abs() < 1e-9);
        // With x and heading correlated, the position part still uses only P's position
        // block, and the whole differs from the sum of the parts.
        let mut p = diagonal;
        p[(0, 2)] = 2e-3;
        p[(2, 0)] = 2e-3;
        let c = Nees::of(&est, &truth, &p).unwrap();
        assert_eq!((c.position, c.heading), (n.position, n.heading));
        assert!((c.pose - n.pose).abs() > 1e-3);
        let not_spd = Matrix3::from_diagonal(&Vector3::new(1e-3, -1.0, 1e-2));
        assert_eq!(Nees::of(&est, &truth, &not_spd), None);
    }
}

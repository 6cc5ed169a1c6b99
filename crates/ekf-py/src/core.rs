//! The filter behind the Python `Filter` class, in plain Rust: one [`Ekf`] with the robot,
//! noise, laser mount and gates of a `LocalizerConfig`, and counts of what it fused. Both
//! the per-call methods and the batch API drive it, so they cannot disagree.

use ekf_core::{
    ChiSquareGate, Compass, DiffDrive, Ekf, Error, LaserLine, Line, Motion, OdometryNoise, Pose2,
    UpdateOutcome, WheelNoise, WheelSpeeds,
};
use lrf_lines::LocalizerConfig;
use nalgebra::{Matrix2, Matrix3};

/// How many predictions and updates a filter ran, and how many updates its gates refused.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counts {
    /// Predictions (wheel speeds or odometry).
    pub predictions: u64,
    /// Compass headings fused.
    pub compass_accepted: u64,
    /// Compass headings refused by the gate.
    pub compass_rejected: u64,
    /// Laser lines fused.
    pub lines_accepted: u64,
    /// Laser lines refused by the gate.
    pub lines_rejected: u64,
}

/// The filter state and the fixed models it uses.
#[derive(Debug, Clone)]
pub struct Core {
    /// The EKF.
    pub ekf: Ekf<f64>,
    robot: DiffDrive<f64>,
    wheel_noise: WheelNoise<f64>,
    odometry_noise: OdometryNoise<f64>,
    /// The laser's pose on the robot.
    pub mount: Pose2<f64>,
    /// Default compass variance (rad²).
    pub compass_variance: f64,
    compass_gate: Option<ChiSquareGate<f64>>,
    line_gate: Option<ChiSquareGate<f64>>,
    /// What was fused and refused so far.
    pub counts: Counts,
}

impl Core {
    /// A filter at `pose` with covariance `p`; the gates are the config's chi-square gates
    /// (1 dof for the compass, 2 for a line) when `gating`, none otherwise. The config must
    /// already be validated.
    pub fn new(
        config: &LocalizerConfig,
        pose: Pose2<f64>,
        p: Matrix3<f64>,
        gating: bool,
    ) -> Result<Self, Error> {
        let gate = |probability, dof| {
            gating
                .then(|| ChiSquareGate::from_probability(probability, dof))
                .transpose()
        };
        Ok(Self {
            ekf: Ekf::new(pose, p)?,
            robot: config.robot,
            wheel_noise: config.wheel_noise,
            odometry_noise: config.odometry_noise,
            mount: config.laser_mount,
            compass_variance: config.compass.variance,
            compass_gate: gate(config.compass.gate_probability, 1)?,
            line_gate: gate(config.matching.gate_probability, 2)?,
            counts: Counts::default(),
        })
    }

    /// Prediction from wheel speeds `(ω_L, ω_R)` (rad/s) held for `dt` (s).
    pub fn predict_wheels(&mut self, left: f64, right: f64, dt: f64) -> Result<(), Error> {
        let speeds = WheelSpeeds::new(left, right, dt)?;
        self.ekf
            .predict_wheels(&self.robot, &speeds, &self.wheel_noise)?;
        self.counts.predictions += 1;
        Ok(())
    }

    /// Prediction from an odometry delta `(Δs, Δθ)` (m, rad).
    pub fn predict_odometry(&mut self, ds: f64, dtheta: f64) -> Result<(), Error> {
        let motion = Motion::new(ds, dtheta)?;
        self.ekf.predict_odometry(&motion, &self.odometry_noise)?;
        self.counts.predictions += 1;
        Ok(())
    }

    /// A compass heading (rad, map frame) with its variance (rad²).
    pub fn update_compass(
        &mut self,
        heading: f64,
        variance: f64,
    ) -> Result<UpdateOutcome<f64>, Error> {
        let compass = Compass::new(heading, variance)?;
        let outcome = self.ekf.update(&compass, self.compass_gate.as_ref())?;
        count(
            outcome.accepted,
            &mut self.counts.compass_accepted,
            &mut self.counts.compass_rejected,
        );
        Ok(outcome)
    }

    /// One laser line `(r, ψ)` (sensor frame) with covariance `r_psi_cov`, matched to the
    /// map line `(ρ, β)` (world frame).
    pub fn update_line(
        &mut self,
        observed: (f64, f64),
        r_psi_cov: Matrix2<f64>,
        map_line: (f64, f64),
    ) -> Result<UpdateOutcome<f64>, Error> {
        let line = LaserLine::new(
            Line::new(observed.0, observed.1)?,
            r_psi_cov,
            Line::new(map_line.0, map_line.1)?,
            self.mount,
        )?;
        let outcome = self.ekf.update(&line, self.line_gate.as_ref())?;
        count(
            outcome.accepted,
            &mut self.counts.lines_accepted,
            &mut self.counts.lines_rejected,
        );
        Ok(outcome)
    }
}

fn count(accepted: bool, yes: &mut u64, no: &mut u64) {
    if accepted {
        *yes += 1;
    } else {
        *no += 1;
    }
}

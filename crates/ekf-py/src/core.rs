//! The filter behind the Python `Filter` class, in plain Rust: one [`Ekf`] with the robot,
//! noise, laser mount and gates of a `LocalizerConfig`, and counts of what it fused. Both
//! the per-call methods and the batch API drive it, so they cannot disagree.

use ekf_core::{
    ChiSquareGate, Compass, ConsideredUpdate, DiffDrive, Ekf, Error, LaserLine, Line, Measurement,
    Motion, OdometryNoise, Pose2, UpdateOutcome, WheelNoise, WheelSpeeds,
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
#[derive(Debug, Clone, PartialEq)]
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

    /// A compass heading (rad, map frame) with its variance (rad²), fused by `R` (see
    /// [`Report`]: the outcome alone, or with `y`, `S` and `K`).
    pub fn update_compass<R: Report<1>>(
        &mut self,
        heading: f64,
        variance: f64,
    ) -> Result<R, Error> {
        let compass = Compass::new(heading, variance)?;
        let report = R::update(&mut self.ekf, &compass, self.compass_gate.as_ref())?;
        count(
            report.accepted(),
            &mut self.counts.compass_accepted,
            &mut self.counts.compass_rejected,
        );
        Ok(report)
    }

    /// One laser line `(r, ψ)` (sensor frame) with covariance `r_psi_cov`, matched to the
    /// map line `(ρ, β)` (world frame), fused by `R` as [`Core::update_compass`] does.
    pub fn update_line<R: Report<2>>(
        &mut self,
        observed: (f64, f64),
        r_psi_cov: Matrix2<f64>,
        map_line: (f64, f64),
    ) -> Result<R, Error> {
        let line = LaserLine::new(
            Line::new(observed.0, observed.1)?,
            r_psi_cov,
            Line::new(map_line.0, map_line.1)?,
            self.mount,
        )?;
        let report = R::update(&mut self.ekf, &line, self.line_gate.as_ref())?;
        count(
            report.accepted(),
            &mut self.counts.lines_accepted,
            &mut self.counts.lines_rejected,
        );
        Ok(report)
    }

    /// Everything this filter holds, as plain numbers (what `pickle` stores).
    pub fn snapshot(&self) -> Snapshot {
        let p = self.ekf.covariance();
        let x = self.ekf.state();
        Snapshot {
            state: [x[0], x[1], x[2]],
            covariance: [0, 1, 2].map(|i| [p[(i, 0)], p[(i, 1)], p[(i, 2)]]),
            robot: self.robot,
            wheel_noise: self.wheel_noise,
            odometry_noise: self.odometry_noise,
            mount: self.mount,
            compass_variance: self.compass_variance,
            compass_gate: self.compass_gate.map(|g| g.threshold),
            line_gate: self.line_gate.map(|g| g.threshold),
            counts: self.counts,
        }
    }

    /// The filter a [`Snapshot`] describes, bit for bit: `Core::from_snapshot(&c.snapshot())`
    /// equals `c`. Every value is validated as the constructors validate it (the state
    /// finite, the covariance symmetric positive definite, the models' parameters in
    /// range, gate thresholds finite and > 0), since a snapshot may come from anywhere.
    pub fn from_snapshot(s: &Snapshot) -> Result<Self, Error> {
        let [x, y, theta] = s.state;
        let pose = Pose2::new(x, y, theta).validated("state")?;
        let p = Matrix3::from_fn(|i, j| s.covariance[i][j]);
        // Ekf::new names its arguments "initial ..."; here they are the saved ones.
        let ekf = Ekf::new(pose, p).map_err(|e| match e {
            Error::NonFinite { .. } => Error::NonFinite { what: "covariance" },
            Error::NotSymmetric { .. } => Error::NotSymmetric { what: "covariance" },
            Error::NotPositiveDefinite { .. } => Error::NotPositiveDefinite { what: "covariance" },
            e => e,
        })?;
        let robot = DiffDrive::new(s.robot.wheel_radius, s.robot.track)?;
        let wheel_noise = WheelNoise::new(s.wheel_noise.delta, s.wheel_noise.floor)?;
        let odometry_noise = s.odometry_noise.validated()?;
        let mount = s.mount.validated("laser mount")?;
        let mount = Pose2::new(mount.x, mount.y, mount.theta);
        // A compass with this variance must be constructible (finite, ≥ 0).
        Compass::new(0.0, s.compass_variance)?;
        let gate = |threshold: Option<f64>, dof| {
            threshold
                .map(|threshold| {
                    if threshold.is_finite() && threshold > 0.0 {
                        Ok(ChiSquareGate { threshold, dof })
                    } else {
                        Err(Error::OutOfRange {
                            what: "gate threshold",
                            expected: "a finite number > 0",
                        })
                    }
                })
                .transpose()
        };
        Ok(Self {
            ekf,
            robot,
            wheel_noise,
            odometry_noise,
            mount,
            compass_variance: s.compass_variance,
            compass_gate: gate(s.compass_gate, 1)?,
            line_gate: gate(s.line_gate, 2)?,
            counts: s.counts,
        })
    }
}

/// What an update of a [`Core`] hands back, and so which update of ekf-core it runs: the
/// [`UpdateOutcome`] alone ([`Ekf::update`]; the batch API, which reports nothing more),
/// or a [`ConsideredUpdate`] that also carries the innovation `y = z − h(x)`, its
/// covariance `S = H P Hᵀ + R` and the gain `K = P Hᵀ S⁻¹` applied, zero if refused
/// ([`Ekf::update_reporting`]; the per-call API). Both leave the filter in the same state
/// bit for bit; the first copies less.
pub trait Report<const M: usize>: Sized {
    /// Fuses `m` into `ekf` through `gate`.
    fn update<Z: Measurement<f64, M>>(
        ekf: &mut Ekf<f64>,
        m: &Z,
        gate: Option<&ChiSquareGate<f64>>,
    ) -> Result<Self, Error>;

    /// Whether the measurement passed the gate and was fused.
    fn accepted(&self) -> bool;
}

impl<const M: usize> Report<M> for UpdateOutcome<f64> {
    fn update<Z: Measurement<f64, M>>(
        ekf: &mut Ekf<f64>,
        m: &Z,
        gate: Option<&ChiSquareGate<f64>>,
    ) -> Result<Self, Error> {
        ekf.update(m, gate)
    }

    fn accepted(&self) -> bool {
        self.accepted
    }
}

impl<const M: usize> Report<M> for ConsideredUpdate<f64, M> {
    fn update<Z: Measurement<f64, M>>(
        ekf: &mut Ekf<f64>,
        m: &Z,
        gate: Option<&ChiSquareGate<f64>>,
    ) -> Result<Self, Error> {
        ekf.update_reporting(m, gate)
    }

    fn accepted(&self) -> bool {
        self.outcome.accepted
    }
}

/// A [`Core`] as plain numbers: the state, the covariance (row by row), the models, the
/// gates' NIS thresholds (`None`: no gate) and the counts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Snapshot {
    /// `[x, y, θ]`.
    pub state: [f64; 3],
    /// `P`, row by row.
    pub covariance: [[f64; 3]; 3],
    /// The wheel geometry.
    pub robot: DiffDrive<f64>,
    /// The wheel-speed noise model.
    pub wheel_noise: WheelNoise<f64>,
    /// The odometry-delta noise model.
    pub odometry_noise: OdometryNoise<f64>,
    /// The laser's pose on the robot.
    pub mount: Pose2<f64>,
    /// Default compass variance (rad²).
    pub compass_variance: f64,
    /// The compass gate's threshold (1 dof).
    pub compass_gate: Option<f64>,
    /// The line gate's threshold (2 dof).
    pub line_gate: Option<f64>,
    /// What was fused and refused so far.
    pub counts: Counts,
}

fn count(accepted: bool, yes: &mut u64, no: &mut u64) {
    if accepted {
        *yes += 1;
    } else {
        *no += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn driven() -> Core {
        let mut config = LocalizerConfig {
            robot: DiffDrive::new(0.07, 0.5).unwrap(),
            laser_mount: Pose2::new(0.2, 0.05, -1.5),
            ..Default::default()
        };
        config.compass.variance = 1e-3;
        let p = Matrix3::new(2e-3, 1e-4, 0.0, 1e-4, 3e-3, -2e-4, 0.0, -2e-4, 1e-3);
        let mut core = Core::new(&config, Pose2::new(1.0, 2.0, 0.3), p, true).unwrap();
        for k in 0..20 {
            core.predict_wheels(2.0, 2.2 + 0.01 * k as f64, 0.1)
                .unwrap();
            core.update_compass::<UpdateOutcome<f64>>(0.3 + 0.004 * k as f64, 1e-3)
                .unwrap();
            // The wall x cos 0.4 + y sin 0.4 = 6 as the laser sees it, 1 cm off.
            let s = core.ekf.pose().compose(&core.mount);
            let r = 6.0 - s.x * 0.4_f64.cos() - s.y * 0.4_f64.sin() + 0.01;
            core.update_line::<ConsideredUpdate<f64, 2>>(
                (r, 0.4 - s.theta),
                Matrix2::identity() * 1e-4,
                (6.0, 0.4),
            )
            .unwrap();
        }
        core.update_compass::<UpdateOutcome<f64>>(2.0, 1e-3)
            .unwrap(); // refused: counted
        core
    }

    #[test]
    fn both_reports_leave_the_filter_in_the_same_state() {
        let mut a = driven();
        let mut b = a.clone();
        for k in 0..10 {
            let heading = 0.4 + 0.3 * f64::from(k % 4); // some refused
            let plain: UpdateOutcome<f64> = a.update_compass(heading, 1e-3).unwrap();
            let full: ConsideredUpdate<f64, 1> = b.update_compass(heading, 1e-3).unwrap();
            assert_eq!(plain, full.outcome);
            let line = ((2.0, 0.4), Matrix2::identity() * 1e-4, (6.0, 0.4));
            let plain: UpdateOutcome<f64> = a.update_line(line.0, line.1, line.2).unwrap();
            let full: ConsideredUpdate<f64, 2> = b.update_line(line.0, line.1, line.2).unwrap();
            assert_eq!(plain, full.outcome);
            assert_eq!(a, b);
        }
        assert!(a.counts.compass_rejected > driven().counts.compass_rejected);
    }

    #[test]
    fn a_snapshot_rebuilds_the_core_bit_for_bit() {
        let core = driven();
        assert!(core.counts.compass_rejected > 0 && core.counts.lines_accepted > 0);
        let back = Core::from_snapshot(&core.snapshot()).unwrap();
        assert_eq!(back, core);
        let mut ungated = core.clone();
        ungated.compass_gate = None;
        ungated.line_gate = None;
        assert_eq!(Core::from_snapshot(&ungated.snapshot()).unwrap(), ungated);
    }

    #[test]
    fn an_invalid_snapshot_is_refused_naming_the_value() {
        let good = driven().snapshot();
        type Spoil = fn(&mut Snapshot);
        let cases: [(Spoil, &str); 5] = [
            (
                |s| s.covariance[0][0] = -1.0,
                "covariance is not positive definite",
            ),
            (
                |s| s.state[1] = f64::NAN,
                "state is not finite (NaN or infinite)",
            ),
            (
                |s| s.robot.track = 0.0,
                "track is out of range: expected > 0",
            ),
            (
                |s| s.line_gate = Some(f64::INFINITY),
                "gate threshold is out of range: expected a finite number > 0",
            ),
            (
                |s| s.compass_variance = 0.0,
                "compass variance is not positive definite",
            ),
        ];
        for (spoil, message) in cases {
            let mut s = good;
            spoil(&mut s);
            assert_eq!(Core::from_snapshot(&s).unwrap_err().to_string(), message);
        }
    }
}

//! The simulated robot: a differential drive whose wheel speeds a PID holds to within a
//! tolerance of the command, optical quadrature encoders that count wheel rotation in
//! ticks, and wheel–ground noise of the paper's δ model (plus optional slip events).

use super::rng::SimRng;
use ekf_core::{wrap_angle, Pose2};
use serde::Serialize;

/// Physical parameters of the robot and its drive.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RobotModel {
    /// Wheel radius `R` (m). The paper: 0.05.
    pub wheel_radius: f64,
    /// Distance between the wheels `L` (m). The paper: 0.60.
    pub track: f64,
    /// Encoder counts per wheel revolution (a 500-line encoder read in quadrature: 2000).
    pub ticks_per_rev: u32,
    /// The PID holds each wheel's speed within this fraction of the command (the paper
    /// measured ±5 %).
    pub speed_tolerance: f64,
    /// The paper's δ: the ground speed of a wheel differs from its rotation by noise of
    /// variance `δ·ω²` ((rad/s)²), white from step to step.
    pub delta: f64,
    /// Slip events: expected number per minute (0: none). During one, a wheel's ground
    /// speed is only [`SLIP_GRIP`] of its rotation, which the encoders do not see.
    pub slips_per_minute: f64,
}

/// Fraction of its rotation a slipping wheel turns into ground motion.
pub const SLIP_GRIP: f64 = 0.6;
/// Duration of a slip event (s).
pub const SLIP_DURATION_S: f64 = 0.5;

impl Default for RobotModel {
    /// The paper's robot (§IV).
    fn default() -> Self {
        Self {
            wheel_radius: 0.05,
            track: 0.6,
            ticks_per_rev: 2000,
            speed_tolerance: 0.05,
            delta: 0.01,
            slips_per_minute: 0.0,
        }
    }
}

impl RobotModel {
    /// One encoder tick (rad of wheel rotation).
    pub fn tick(&self) -> f64 {
        std::f64::consts::TAU / f64::from(self.ticks_per_rev)
    }

    /// Wheel speeds `(ω_L, ω_R)` (rad/s) for forward speed `v` (m/s) and turn rate `ω`.
    pub fn wheel_speeds(&self, v: f64, omega: f64) -> [f64; 2] {
        let half = omega * self.track / 2.0;
        [
            (v - half) / self.wheel_radius,
            (v + half) / self.wheel_radius,
        ]
    }
}

/// The true state of the simulated robot.
#[derive(Debug, Clone)]
pub struct Robot {
    model: RobotModel,
    pose: Pose2<f64>,
    /// True rotation of each wheel since the start (rad), left then right.
    rotation: [f64; 2],
    /// The PID's relative speed error of each wheel (AR(1), within the tolerance).
    tracking: [f64; 2],
    /// A slip in progress: the wheel and the time left (s).
    slip: Option<(usize, f64)>,
    slips: u32,
}

impl Robot {
    /// A robot at `pose`, wheels at rest.
    pub fn new(model: RobotModel, pose: Pose2<f64>) -> Self {
        Self {
            model,
            pose,
            rotation: [0.0; 2],
            tracking: [0.0; 2],
            slip: None,
            slips: 0,
        }
    }

    /// The true pose.
    pub fn pose(&self) -> Pose2<f64> {
        self.pose
    }

    /// Carries the robot: its true pose moves by `by` (in its own frame) while the
    /// wheels do not turn, so the encoders see nothing (a kidnapping).
    pub fn carry(&mut self, by: &Pose2<f64>) {
        self.pose = self.pose.compose(by);
    }

    /// Slip events so far.
    pub fn slips(&self) -> u32 {
        self.slips
    }

    /// The encoder counts `(left, right)`: whole ticks of wheel rotation since the start.
    pub fn ticks(&self) -> [i64; 2] {
        let tick = self.model.tick();
        self.rotation.map(|r| (r / tick).floor() as i64)
    }

    /// Drives for `dt` seconds with commanded wheel speeds `command` (rad/s, left then
    /// right): the PID's tracking error, then the wheel–ground noise and slip, then the
    /// exact arc the wheels' ground motion describes.
    pub fn step(&mut self, command: [f64; 2], dt: f64, rng: &mut SimRng) {
        let m = self.model;
        if self.slip.is_none() && rng.chance(m.slips_per_minute * dt / 60.0) {
            let wheel = usize::from(rng.chance(0.5));
            self.slip = Some((wheel, SLIP_DURATION_S));
            self.slips += 1;
        }
        let mut ground = [0.0; 2];
        for w in 0..2 {
            let e = 0.7 * self.tracking[w] + rng.normal(0.4 * m.speed_tolerance);
            self.tracking[w] = e.clamp(-m.speed_tolerance, m.speed_tolerance);
            let omega = command[w] * (1.0 + self.tracking[w]);
            self.rotation[w] += omega * dt;
            let mut g = omega + rng.normal(m.delta.sqrt() * omega.abs());
            if matches!(self.slip, Some((s, _)) if s == w) {
                g *= SLIP_GRIP;
            }
            ground[w] = g * dt * m.wheel_radius;
        }
        if let Some((w, left)) = self.slip {
            self.slip = (left - dt > 1e-9).then_some((w, left - dt));
        }
        let ds = (ground[0] + ground[1]) / 2.0;
        let dth = (ground[1] - ground[0]) / m.track;
        let p = self.pose;
        let (dx, dy) = if dth.abs() > 1e-9 {
            let r = ds / dth;
            (
                r * ((p.theta + dth).sin() - p.theta.sin()),
                -r * ((p.theta + dth).cos() - p.theta.cos()),
            )
        } else {
            (ds * p.theta.cos(), ds * p.theta.sin())
        };
        self.pose = Pose2::new(p.x + dx, p.y + dy, wrap_angle(p.theta + dth));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Stream;

    #[test]
    fn a_quiet_robot_drives_the_exact_circle() {
        let model = RobotModel {
            speed_tolerance: 0.0,
            delta: 0.0,
            ..RobotModel::default()
        };
        let mut robot = Robot::new(model, Pose2::new(0.0, 0.0, 0.0));
        let mut rng = SimRng::new(1, Stream::Wheels);
        // v = 0.2 m/s, ω = 0.2 rad/s: a circle of radius 1 m around (0, 1).
        let cmd = model.wheel_speeds(0.2, 0.2);
        for _ in 0..50 {
            robot.step(cmd, 0.1, &mut rng);
        }
        let p = robot.pose();
        assert!((p.x - 1.0f64.sin()).abs() < 1e-12 && (p.y - (1.0 - 1.0f64.cos())).abs() < 1e-12);
        assert!((p.theta - 1.0).abs() < 1e-12);
        // Encoders: 5 s of the left wheel at (0.2 − 0.06)/0.05 = 2.8 rad/s is 14 rad.
        let t = robot.ticks();
        assert_eq!(t[0], (14.0 / model.tick()).floor() as i64);
        assert_eq!(t[1], (26.0 / model.tick()).floor() as i64);
    }

    #[test]
    fn the_pid_keeps_speeds_within_tolerance_and_noise_has_the_delta_variance() {
        let model = RobotModel {
            delta: 0.0,
            ..RobotModel::default()
        };
        let mut robot = Robot::new(model, Pose2::new(0.0, 0.0, 0.0));
        let mut rng = SimRng::new(3, Stream::Wheels);
        let mut last = 0.0;
        for _ in 0..2000 {
            robot.step([4.0, 4.0], 0.1, &mut rng);
            let speed = (robot.rotation[0] - last) / 0.1;
            last = robot.rotation[0];
            assert!((speed / 4.0 - 1.0).abs() <= 0.05 + 1e-12, "{speed}");
        }
        // With δ = 0.01 the heading change of a straight drive has variance
        // 2·δ·(ωR dt / L)² per step.
        let model = RobotModel {
            speed_tolerance: 0.0,
            ..RobotModel::default()
        };
        let (n, omega, dt) = (20_000, 4.0, 0.1);
        let mut rng = SimRng::new(4, Stream::Wheels);
        let mut sum_sq = 0.0;
        for _ in 0..n {
            let mut r = Robot::new(model, Pose2::new(0.0, 0.0, 0.0));
            r.step([omega, omega], dt, &mut rng);
            sum_sq += r.pose().theta.powi(2);
        }
        let want = 2.0 * 0.01 * (omega * 0.05 * dt / 0.6f64).powi(2);
        let got = sum_sq / n as f64;
        assert!((got / want - 1.0).abs() < 0.05, "{got} vs {want}");
    }

    #[test]
    fn slips_shorten_the_drive_without_the_encoders_noticing() {
        let quiet = RobotModel {
            speed_tolerance: 0.0,
            delta: 0.0,
            ..RobotModel::default()
        };
        let slippery = RobotModel {
            slips_per_minute: 600.0,
            ..quiet
        };
        let mut rng = SimRng::new(5, Stream::Wheels);
        let (mut a, mut b) = (
            Robot::new(quiet, Pose2::identity()),
            Robot::new(slippery, Pose2::identity()),
        );
        for _ in 0..100 {
            a.step([4.0, 4.0], 0.1, &mut rng);
            b.step([4.0, 4.0], 0.1, &mut rng);
        }
        assert_eq!(a.ticks(), b.ticks());
        assert!(b.slips() > 0);
        assert!(
            b.pose().x < a.pose().x - 0.05,
            "{} {}",
            b.pose().x,
            a.pose().x
        );
    }
}

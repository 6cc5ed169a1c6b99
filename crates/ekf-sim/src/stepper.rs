//! The simulated world one control period at a time: the robot driving its scenario's
//! path and its sensors measuring. [`simulate`](crate::simulate()) runs it as fast as it
//! can; `ekf emulate` serves it in real time through the device emulators.

use super::path::PurePursuit;
use super::rng::{SimRng, Stream};
use super::robot::Robot;
use super::scenario::Scenario;
use super::sensors::CompassReading;
use ekf_core::Pose2;

/// One step's measurements, as the sensors report them.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// Time (ns since the start).
    pub t_ns: u64,
    /// The true pose.
    pub truth: Pose2<f64>,
    /// Encoder counts since the start (left, right).
    pub ticks: [i64; 2],
    /// The compass reading.
    pub compass: CompassReading,
    /// A laser sweep, on the steps that have one.
    pub scan: Option<Vec<f32>>,
}

/// A scenario being driven: the robot, its path follower and the seeded noise of its
/// sensors. Step 0 is the start; each [`advance`](Self::advance) drives one period.
#[derive(Debug, Clone)]
pub struct Simulator<'s> {
    scenario: &'s Scenario,
    robot: Robot,
    follower: PurePursuit,
    wheel_rng: SimRng,
    compass_rng: SimRng,
    laser_rng: SimRng,
    step: u64,
    dt_ns: u64,
}

impl<'s> Simulator<'s> {
    /// The robot at the scenario's start, its noise seeded with `seed`.
    pub fn new(scenario: &'s Scenario, seed: u64) -> Self {
        let d = scenario.drive;
        let mut follower = PurePursuit::new(d.lookahead, d.speed, d.max_turn_rate);
        follower.join(&scenario.path, &scenario.start);
        Self {
            scenario,
            robot: Robot::new(scenario.robot, scenario.start),
            follower,
            wheel_rng: SimRng::new(seed, Stream::Wheels),
            compass_rng: SimRng::new(seed, Stream::Compass),
            laser_rng: SimRng::new(seed, Stream::Laser),
            step: 0,
            dt_ns: (scenario.dt * 1e9).round() as u64,
        }
    }

    /// The scenario.
    pub fn scenario(&self) -> &'s Scenario {
        self.scenario
    }

    /// The current step (0 at the start).
    pub fn step(&self) -> u64 {
        self.step
    }

    /// The true pose.
    pub fn pose(&self) -> Pose2<f64> {
        self.robot.pose()
    }

    /// Carries the robot by `by` (in its own frame) without a wheel turning (a
    /// kidnapping, for testing a localizer's recovery); the follower then rejoins the
    /// path from where the robot was put down.
    pub fn carry(&mut self, by: &Pose2<f64>) {
        self.robot.carry(by);
        self.follower.join(&self.scenario.path, &self.robot.pose());
    }

    /// Slip events so far.
    pub fn slips(&self) -> u32 {
        self.robot.slips()
    }

    /// Drives one period, the follower steering by `steer_by` (the true pose, or an
    /// estimate of it); returns the distance the robot travelled (m).
    pub fn advance(&mut self, steer_by: &Pose2<f64>) -> f64 {
        let s = self.scenario;
        let (v, omega) = self.follower.command(&s.path, steer_by);
        let before = self.robot.pose();
        self.robot
            .step(s.robot.wheel_speeds(v, omega), s.dt, &mut self.wheel_rng);
        let after = self.robot.pose();
        self.step += 1;
        (after.x - before.x).hypot(after.y - before.y)
    }

    /// What the sensors measure at the current step: the encoders, a compass reading,
    /// and a laser sweep every [`period_steps`](super::LaserModel::period_steps) steps.
    /// Call it once per step: each call draws the sensors' noise.
    pub fn measure(&mut self) -> Sample {
        let s = self.scenario;
        let truth = self.robot.pose();
        let compass = s.compass.read(truth.theta, &mut self.compass_rng);
        let laser = &s.laser;
        let scan = self
            .step
            .is_multiple_of(u64::from(laser.period_steps.max(1)))
            .then(|| laser.scan(&s.room, &truth, &mut self.laser_rng));
        Sample {
            t_ns: self.step * self.dt_ns,
            truth,
            ticks: self.robot.ticks(),
            compass,
            scan,
        }
    }
}

//! Motion steps over time intervals, and the clock that says which part of a step the
//! state has not yet been predicted through.

use ekf_core::{Ekf, Motion, OdometryTravel, WheelSpeeds};
use lrf_lines::LocalizerConfig;

/// Longest time after the end of the last motion step up to which the state is brought
/// forward at that step's rate (ns).
pub const MAX_EXTRAPOLATION_NS: u64 = 200_000_000;

/// One motion reading's step over its whole interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MotionStep {
    /// Wheel speeds held over `dt`.
    Wheels(WheelSpeeds<f64>),
    /// An odometry pose delta.
    Odometry(Motion<f64>),
}

impl MotionStep {
    /// Wheel speeds over the interval `(t0, t1]` that ends at `stamp` and lasts the
    /// speeds' `dt`: `(step, t0, t1)`.
    pub fn wheels_until(speeds: WheelSpeeds<f64>, stamp: u64) -> (Self, u64, u64) {
        let t0 = stamp - libm::round(speeds.dt * 1e9) as u64;
        (MotionStep::Wheels(speeds), t0, stamp)
    }

    /// The part of the step after a fraction `1 − f` of its interval has passed.
    pub fn part(self, f: f64) -> Self {
        match self {
            MotionStep::Wheels(s) => MotionStep::Wheels(WheelSpeeds { dt: s.dt * f, ..s }),
            MotionStep::Odometry(m) => MotionStep::Odometry(Motion {
                ds: m.ds * f,
                dtheta: m.dtheta * f,
            }),
        }
    }

    /// Predicts `ekf` through the step with the robot and noise of `config`, an odometry
    /// step's noise taken after `travel` in its interval (see [`OdometryTravel`]), as
    /// [`lrf_lines::Localizer`] predicts.
    pub fn predict(
        self,
        ekf: &mut Ekf<f64>,
        config: &LocalizerConfig,
        travel: &mut OdometryTravel<f64>,
    ) -> Result<(), ekf_core::Error> {
        match self {
            MotionStep::Wheels(s) => ekf
                .predict_wheels(&config.robot, &s, &config.wheel_noise)
                .map(drop),
            MotionStep::Odometry(m) => ekf
                .predict_odometry_in(&m, &config.odometry_noise, travel)
                .map(drop),
        }
    }

    /// The step per second, for a step over `dt` seconds.
    fn rate(self, dt: f64) -> MotionRate {
        match self {
            MotionStep::Wheels(s) => MotionRate(MotionStep::Wheels(WheelSpeeds { dt: 1.0, ..s })),
            MotionStep::Odometry(m) => MotionRate(MotionStep::Odometry(Motion {
                ds: m.ds / dt,
                dtheta: m.dtheta / dt,
            })),
        }
    }
}

/// A motion step per second of time.
#[derive(Debug, Clone, Copy, PartialEq)]
struct MotionRate(MotionStep);

impl MotionRate {
    /// The step over `dt` seconds at this rate.
    fn over(self, dt: f64) -> MotionStep {
        self.0.part(dt)
    }
}

/// The time the filter state refers to, and the rate and end of the last motion step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MotionClock {
    state_ns: Option<u64>,
    rate: Option<MotionRate>,
    /// The end of the last motion step taken (ns): extrapolation at its rate reaches at
    /// most [`MAX_EXTRAPOLATION_NS`] beyond it.
    motion_ns: Option<u64>,
    /// The time of the initial state: motion before it is already in the initial pose (a
    /// reference pose taken as the start), so only the part of a step after it counts.
    start_ns: u64,
}

impl MotionClock {
    /// A clock whose initial state refers to `start_ns`.
    pub fn starting_at(start_ns: u64) -> Self {
        Self {
            start_ns,
            ..Self::default()
        }
    }

    /// The time the state refers to (ns); `None` before the first motion step.
    pub fn state_ns(&self) -> Option<u64> {
        self.state_ns
    }

    /// Takes a motion step over `(t0, t1]` and returns the part of it after the time the
    /// state already refers to (a scan or heading in between was fused at its own time,
    /// after a prediction at the previous rate, or the initial state's time); `None` if
    /// nothing of it is left.
    pub fn advance(&mut self, step: MotionStep, t0: u64, t1: u64) -> Option<MotionStep> {
        if t1 <= self.start_ns {
            return None;
        }
        let start = self.state_ns.map_or(t0, |s| s.max(t0)).max(self.start_ns);
        self.state_ns = Some(self.state_ns.map_or(t1, |s| s.max(t1)));
        self.motion_ns = Some(self.motion_ns.map_or(t1, |s| s.max(t1)));
        self.rate = Some(step.rate((t1 - t0) as f64 * 1e-9));
        (start < t1).then(|| step.part((t1 - start) as f64 / (t1 - t0) as f64))
    }

    /// The step that brings the state from its time to `t_ns` at the last motion rate,
    /// if `t_ns` is later than the state and at most [`MAX_EXTRAPOLATION_NS`] after the
    /// end of the last motion step; the state then refers to `t_ns`. Later times are left
    /// to the next motion reading (the robot may have stopped). The limit counts from the
    /// last motion reading, not from the last extrapolation: a source that falls silent
    /// is not carried on at its last rate scan after scan.
    pub fn extrapolate(&mut self, t_ns: u64) -> Option<MotionStep> {
        let (state, rate, motion) = (self.state_ns?, self.rate?, self.motion_ns?);
        if t_ns <= state || t_ns - motion > MAX_EXTRAPOLATION_NS {
            return None;
        }
        self.state_ns = Some(t_ns);
        Some(rate.over((t_ns - state) as f64 * 1e-9))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extrapolation_reaches_only_shortly_past_the_last_motion_step() {
        const MS: u64 = 1_000_000;
        let mut clock = MotionClock::default();
        let step = MotionStep::Odometry(Motion {
            ds: 0.1,
            dtheta: 0.02,
        });
        // A step of 0.1 m over 100 ms, then scans 50, 150 and 250 ms after it ends.
        assert!(clock.advance(step, 1000 * MS, 1100 * MS).is_some());
        let ds = |s: Option<MotionStep>| match s {
            Some(MotionStep::Odometry(m)) => Some((m.ds * 1e6).round() / 1e6),
            _ => None,
        };
        assert_eq!(ds(clock.extrapolate(1150 * MS)), Some(0.05));
        assert_eq!(ds(clock.extrapolate(1150 * MS)), None, "already there");
        assert_eq!(ds(clock.extrapolate(1250 * MS)), Some(0.1));
        assert_eq!(
            ds(clock.extrapolate(1350 * MS)),
            None,
            "250 ms after the last motion message: not carried on"
        );
        // The next message's step counts only after the time the state refers to.
        assert_eq!(ds(clock.advance(step, 1200 * MS, 1300 * MS)), Some(0.05));
    }

    #[test]
    fn motion_before_the_initial_state_is_not_applied() {
        const MS: u64 = 1_000_000;
        let mut clock = MotionClock::starting_at(1000 * MS);
        let step = MotionStep::Odometry(Motion {
            ds: 0.2,
            dtheta: 0.0,
        });
        assert_eq!(
            clock.advance(step, 800 * MS, 1000 * MS),
            None,
            "ends at the start"
        );
        let part = clock.advance(step, 900 * MS, 1100 * MS);
        assert_eq!(
            part,
            Some(MotionStep::Odometry(Motion {
                ds: 0.1,
                dtheta: 0.0
            })),
            "only its half after the start"
        );
    }
}

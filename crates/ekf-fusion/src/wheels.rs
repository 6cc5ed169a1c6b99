//! Motion from successive readings: wheel speeds from encoder angles or wheel velocities,
//! and motion steps from odometry poses.

use crate::Skip;
use ekf_core::{Motion, Pose2, WheelSpeeds};

/// Stamp jitter allowed when an encoder increment is judged against the fastest the
/// wheels can turn (s): a reading stamped when it was received can be late by a
/// scheduling delay, and the next one then comes soon after it with a normal increment.
const STAMP_JITTER_S: f64 = 0.05;

/// Wheel speeds from successive wheel readings: the difference of the encoder angles over
/// the stamp difference (the encoder increment), or the velocities for a source with no
/// angles. A wheel that would have turned faster than the robot's wheels can is a broken
/// reading (an encoder spike or jump, a counter reset): it is skipped, and the next
/// increment is taken from it, so a spike costs two readings and a jump one.
#[derive(Debug, Clone)]
pub struct WheelTracker {
    /// Fastest plausible wheel speed (rad/s).
    max_speed: f64,
    previous: Option<(u64, f64, f64)>,
    /// Readings in a row whose velocities moved the wheels clearly more than their
    /// angles did.
    contradicted: u32,
}

/// Readings in a row whose angles stand still against their velocities before the
/// velocities are used instead ([`WheelTracker::angles`]).
pub const CONTRADICTED_READINGS: u32 = 3;

/// A reading whose encoder angles contradicted its velocities: the increments each gave
/// over the interval (rad, left and right).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contradiction {
    /// From the encoder angles.
    pub angles: [f64; 2],
    /// From the velocities held over the interval.
    pub velocities: [f64; 2],
}

impl WheelTracker {
    /// Tracks wheels that turn at most `max_turns_per_s` (the configuration's
    /// `devices.max_wheel_turns_per_s`).
    pub fn new(max_turns_per_s: f64) -> Self {
        Self {
            max_speed: max_turns_per_s * core::f64::consts::TAU,
            previous: None,
            contradicted: 0,
        }
    }

    /// Wheel speeds over the interval from the previous reading to encoder angles
    /// `(left, right)` (rad) at `stamp_ns`: the increments over the stamp difference.
    ///
    /// With the reading's `velocities` (rad/s), the two are checked against each other: a
    /// wheel whose velocity, held over the interval, moves it more than its angle did, by
    /// more than half the larger of the two and a hundredth of a radian, contradicts it.
    /// After [`CONTRADICTED_READINGS`] such readings in a row the angles are taken to be
    /// stuck (an encoder count that stopped updating) and the velocities are used, the one
    /// that moves; the [`Contradiction`] is returned with the speeds then. Angles that
    /// move while the velocities stay at zero are used as they are (many drivers leave the
    /// velocities unset).
    pub fn angles(
        &mut self,
        stamp_ns: u64,
        left: f64,
        right: f64,
        velocities: Option<[f64; 2]>,
    ) -> Result<(WheelSpeeds<f64>, Option<Contradiction>), Skip> {
        let (t0, l0, r0) = self.advance(stamp_ns, left, right, "position")?;
        // The encoder increment over the interval is exact; a velocity in the same reading
        // is one sample at its end, so it is not used (paper eqs. 1–2 integrate ω over Δt).
        let dt = (stamp_ns - t0) as f64 * 1e-9;
        let largest = (left - l0).abs().max((right - r0).abs());
        if largest > self.max_speed * (dt + STAMP_JITTER_S) {
            return Err(Skip::Implausible {
                field: "position",
                expected: "an encoder increment the wheels can make in the interval \
                           (devices.max_wheel_turns_per_s, 50 ms of stamp jitter allowed; rad)",
                found: largest,
            });
        }
        let increments = [left - l0, right - r0];
        let from_velocities = velocities
            .filter(|v| v.iter().all(|w| w.is_finite()))
            .map(|[vl, vr]| [vl * dt, vr * dt]);
        let contradiction = from_velocities.filter(|e| {
            increments.iter().zip(e).any(|(d, e)| {
                e.abs() > d.abs() && (d - e).abs() > 0.5 * d.abs().max(e.abs()) + 0.01
            })
        });
        self.contradicted = match contradiction {
            Some(_) => self.contradicted.saturating_add(1),
            None => 0,
        };
        if let (Some(e), true) = (contradiction, self.contradicted >= CONTRADICTED_READINGS) {
            let speeds = WheelSpeeds::new(e[0] / dt, e[1] / dt, dt)
                .map_err(|_| Skip::NonFinite { field: "velocity" })?;
            let seen = Contradiction {
                angles: increments,
                velocities: e,
            };
            return Ok((speeds, Some(seen)));
        }
        let speeds = WheelSpeeds::from_increments(increments[0], increments[1], dt)
            .map_err(|_| Skip::NonFinite { field: "position" })?;
        Ok((speeds, None))
    }

    /// Wheel speeds `(left, right)` (rad/s) held over the interval from the previous
    /// reading to `stamp_ns`.
    pub fn velocities(
        &mut self,
        stamp_ns: u64,
        left: f64,
        right: f64,
    ) -> Result<WheelSpeeds<f64>, Skip> {
        let (t0, _, _) = self.advance(stamp_ns, left, right, "velocity")?;
        WheelSpeeds::new(left, right, (stamp_ns - t0) as f64 * 1e-9)
            .map_err(|_| Skip::NonFinite { field: "velocity" })
    }
    /// Makes `(left, right)` at `stamp_ns` the previous reading and returns the one
    /// before, `(stamp, left, right)`. A non-finite `field`, the first reading, or a stamp
    /// not after the previous one is refused; the last two leave the previous reading as
    /// it was.
    fn advance(
        &mut self,
        stamp_ns: u64,
        left: f64,
        right: f64,
        field: &'static str,
    ) -> Result<(u64, f64, f64), Skip> {
        if !(left.is_finite() && right.is_finite()) {
            return Err(Skip::NonFinite { field });
        }
        let previous = self.previous.replace((stamp_ns, left, right));
        let Some((t0, l0, r0)) = previous else {
            return Err(Skip::First);
        };
        if stamp_ns <= t0 {
            self.previous = previous;
            return Err(Skip::TimeNotIncreasing {
                previous_ns: t0,
                stamp_ns,
            });
        }
        Ok((t0, l0, r0))
    }
}

/// An odometry step is a jump when it is longer than this many times the RMS of the
/// steps before it ...
pub const JUMP_FACTOR: f64 = 10.0;

/// ... and longer than this (m): more than a robot moves between two odometry messages
/// at the rates robots publish them (1 m/s at 2 Hz).
pub const JUMP_MIN_M: f64 = 0.5;

/// Moving steps the RMS runs over (and the fewest before the jump test applies).
pub const JUMP_HISTORY: u32 = 10;

/// The field a jump is refused under ([`Skip::Implausible`]).
pub const JUMP_FIELD: &str = "odometry step";

/// Motion steps from consecutive odometry poses.
#[derive(Debug, Clone, Default)]
pub struct OdometryTracker {
    previous: Option<(u64, Pose2<f64>)>,
    /// Running mean of the squared lengths of the moving steps (m²).
    step_square: f64,
    /// Moving steps seen.
    moving: u32,
}

impl OdometryTracker {
    /// The motion from the previous odometry pose to `pose` at `stamp_ns`, and the stamp
    /// of the previous one (the start of the interval). A jump (see [`JUMP_FACTOR`]: a
    /// glitch, a reset, a robot carried while its odometry counted) is refused as
    /// implausible, the chain going on from `pose`. Speeds are not judged: the stamps of
    /// real logs are too often broken for that.
    pub fn motion(&mut self, stamp_ns: u64, pose: &Pose2<f64>) -> Result<(Motion<f64>, u64), Skip> {
        let pose = pose
            .validated("pose")
            .map_err(|_| Skip::NonFinite { field: "pose" })?;
        let Some((t0, p0)) = self.previous else {
            self.previous = Some((stamp_ns, pose));
            return Err(Skip::First);
        };
        if stamp_ns <= t0 {
            return Err(Skip::TimeNotIncreasing {
                previous_ns: t0,
                stamp_ns,
            });
        }
        self.previous = Some((stamp_ns, pose));
        let motion = Motion::from_odometry_poses(&p0, &pose)
            .map_err(|_| Skip::NonFinite { field: "pose" })?;
        let length = libm::fabs(motion.ds);
        if length == 0.0 {
            return Ok((motion, t0));
        }
        let rms = libm::sqrt(self.step_square);
        let jump = self.moving >= JUMP_HISTORY && length > JUMP_MIN_M.max(JUMP_FACTOR * rms);
        // Every moving step counts, a jump too: a robot that really drives faster from
        // now on is judged by its new steps after a few of them.
        let weight = 1.0 / f64::from((self.moving + 1).min(JUMP_HISTORY));
        self.step_square += weight * (length * length - self.step_square);
        self.moving = self.moving.saturating_add(1);
        if jump {
            return Err(Skip::Implausible {
                field: JUMP_FIELD,
                expected: "at most 10 times the RMS of the steps before it or 0.5 m, whichever is more (m)",
                found: length,
            });
        }
        Ok((motion, t0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    /// Feeds odometry poses along x with the given step lengths, 100 ms apart; returns
    /// which steps were refused as jumps.
    fn jumps(steps: &[f64]) -> Vec<bool> {
        let mut odometry = OdometryTracker::default();
        let mut x = 0.0;
        assert_eq!(
            odometry.motion(0, &Pose2::new(x, 0.0, 0.0)),
            Err(Skip::First)
        );
        (1..)
            .zip(steps)
            .map(|(k, step)| {
                x += step;
                match odometry.motion(k * 100 * MS, &Pose2::new(x, 0.0, 0.0)) {
                    Ok((m, _)) => {
                        assert!((m.ds - step).abs() < 1e-9);
                        false
                    }
                    Err(Skip::Implausible { found, .. }) => {
                        assert!((found - step).abs() < 1e-9);
                        true
                    }
                    Err(other) => panic!("{other:?}"),
                }
            })
            .collect()
    }

    #[test]
    fn an_odometry_jump_is_refused_and_the_chain_goes_on_from_it() {
        let mut steps = vec![0.05; 20];
        steps.extend([2.0, 0.05, 0.05]);
        let refused = jumps(&steps);
        assert_eq!(refused.iter().filter(|&&j| j).count(), 1, "{refused:?}");
        assert!(refused[20], "the 2 m step");
    }

    #[test]
    fn steps_that_grow_stops_and_a_short_history_are_motion() {
        // Speeding up from 0.02 to 0.5 m per step over 30 steps, standing still, then
        // driving on; and a big step before ten moving steps are known.
        let mut steps: Vec<f64> = (0..30).map(|k| 0.02 + 0.016 * f64::from(k)).collect();
        steps.extend([0.0; 50]);
        steps.extend([0.45, 0.5]);
        assert!(jumps(&steps).iter().all(|j| !j));
        assert!(jumps(&[0.05, 0.05, 3.0]).iter().all(|j| !j));
        // Ten times the RMS but under half a metre: a slow robot that starts to drive.
        let mut slow = vec![0.01; 20];
        slow.push(0.3);
        assert!(jumps(&slow).iter().all(|j| !j));
    }

    #[test]
    fn angles_that_stand_still_against_their_velocities_give_way_after_three_readings() {
        let mut w = WheelTracker::new(10.0);
        let v = Some([2.0, 2.2]);
        assert_eq!(w.angles(0, 1.0, 1.0, v), Err(Skip::First));
        // The counts stopped at 1.0 while the wheels turn at 2 and 2.2 rad/s.
        let mut used = Vec::new();
        for k in 1..=5 {
            let (speeds, seen) = w.angles(k * 20 * MS, 1.0, 1.0, v).unwrap();
            used.push(seen.is_some());
            if let Some(seen) = seen {
                assert_eq!(seen.angles, [0.0, 0.0]);
                assert!((seen.velocities[0] - 0.04).abs() < 1e-12, "{seen:?}");
                assert!((speeds.left - 2.0).abs() < 1e-9 && (speeds.right - 2.2).abs() < 1e-9);
            } else {
                assert_eq!((speeds.left, speeds.right), (0.0, 0.0));
            }
        }
        assert_eq!(used, [false, false, true, true, true]);
        // The counts move again, with the velocities: the angles are used.
        let (speeds, seen) = w.angles(120 * MS, 1.04, 1.044, v).unwrap();
        assert!(seen.is_none());
        assert!((speeds.left - 2.0).abs() < 1e-9, "{speeds:?}");
    }

    #[test]
    fn angles_that_move_while_the_velocities_are_zero_are_used() {
        let mut w = WheelTracker::new(10.0);
        let zero = Some([0.0, 0.0]);
        assert_eq!(w.angles(0, 0.0, 0.0, zero), Err(Skip::First));
        for k in 1..=5u32 {
            let a = 0.04 * f64::from(k);
            let (speeds, seen) = w.angles(u64::from(k) * 20 * MS, a, a, zero).unwrap();
            assert!(seen.is_none());
            assert!((speeds.left - 2.0).abs() < 1e-9, "{speeds:?}");
        }
    }
}

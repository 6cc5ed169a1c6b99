//! Does the compass follow the robot's turns? A stuck or dead compass does not.
//!
//! Two readings `φ₀` and `φ` of the true heading differ by the turn between them, which
//! odometry measured with the heading variance `Q_θθ` its predictions added:
//!
//! `d = wrap(φ − φ₀ − Δθ_odo)`,  `d² ≤ χ²₁(p)·(σ₀² + σ² + Q_θθ)`
//!
//! with `p` = [`FOLLOW_PROBABILITY`]. A compass is **stuck** when its reading fails that
//! test but agrees with `φ₀` unchanged (`wrap(φ − φ₀)² ≤ χ²₁(p)·(σ₀² + σ²)`): it stood
//! still while the robot turned. The test does not involve the filter's state, so a
//! filter that has drifted cannot make a good compass fail it; and a reading that changed
//! otherwise than odometry says is not called stuck, since wheels that slip turn the
//! robot without odometry seeing it (the gate and the lock-out judge those). Each reading
//! is tested against a reference reading up to [`REFERENCE_SPAN`] readings older, which
//! is then moved on, so a compass stuck at one value fails as soon as the robot has
//! turned more than the window allows (about 7° with a 2° compass), and keeps failing
//! while it stays stuck. A stuck reading is not fused at all: within the gate a stuck
//! compass would pull the filter to its one value.

use ekf_core::{angle_diff, wrap_angle};

/// Probability of the follow test: a good compass fails it once in a thousand readings.
pub const FOLLOW_PROBABILITY: f64 = 0.999;

/// Readings a reference is kept for before the current reading replaces it.
pub const REFERENCE_SPAN: u32 = 10;

/// The reference reading and the odometry turn since it.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct CompassFollow {
    /// The reference reading `(φ₀, σ₀²)`.
    reference: Option<(f64, f64)>,
    /// Heading change `Δθ_odo` the predictions made since the reference (rad).
    turned: f64,
    /// Heading variance `Q_θθ` the predictions added since the reference (rad²).
    turned_variance: f64,
    /// Readings since the reference.
    readings: u32,
}

impl CompassFollow {
    /// A prediction turned the heading by `turned` (rad) and added `variance` (rad²).
    pub(super) fn predicted(&mut self, turned: f64, variance: f64) {
        self.turned += turned;
        self.turned_variance += variance;
    }

    /// Tests reading `heading` (variance `variance`) against the reference with the
    /// test's threshold `χ²₁(p)`; returns `false` if the compass stood still while the
    /// robot turned: the reading agrees with the reference unchanged and not with the
    /// reference turned as odometry turned. A reading that changed otherwise than
    /// odometry says (a wheel slip, which turns the robot unseen by odometry, or an
    /// outlier) is not the compass's fault here: it passes, and becomes the reference.
    pub(super) fn follows(&mut self, heading: f64, variance: f64, threshold: f64) -> bool {
        let Some((h0, v0)) = self.reference else {
            self.restart_at(heading, variance);
            return true;
        };
        let still = angle_diff(heading, h0);
        let followed = angle_diff(heading, wrap_angle(h0 + self.turned));
        let stood_still = still * still <= threshold * (v0 + variance);
        let turned_with = followed * followed <= threshold * (v0 + variance + self.turned_variance);
        self.readings += 1;
        if stood_still && !turned_with {
            return false;
        }
        if !turned_with || self.readings >= REFERENCE_SPAN {
            self.restart_at(heading, variance);
        }
        true
    }

    /// Makes `(heading, variance)` the reference, with no turn since.
    fn restart_at(&mut self, heading: f64, variance: f64) {
        *self = Self {
            reference: Some((heading, variance)),
            ..Self::default()
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const THRESHOLD: f64 = 10.83; // χ²₁(0.999)
    const SIGMA2: f64 = 1.2e-3; // (2°)²

    #[test]
    fn a_compass_that_turns_with_the_robot_follows_and_a_stuck_one_does_not() {
        let (mut good, mut stuck) = (CompassFollow::default(), CompassFollow::default());
        let mut heading: f64 = 0.3;
        let mut failed = (0, 0);
        for _ in 0..100 {
            // 0.03 rad of turn between readings, measured by odometry to 1e-6 rad².
            for f in [&mut good, &mut stuck] {
                f.predicted(0.03, 1e-6);
            }
            heading += 0.03;
            failed.0 += usize::from(!good.follows(wrap_angle(heading), SIGMA2, THRESHOLD));
            failed.1 += usize::from(!stuck.follows(0.3, SIGMA2, THRESHOLD));
        }
        assert_eq!(failed.0, 0);
        // The first reading is the reference; the window is 3.29·√(2.4e-3 + Q) ≈ 0.16
        // rad, so the stuck one passes 5 turns of 0.03 after it and fails the other 94.
        assert_eq!(failed.1, 94);
    }

    #[test]
    fn a_compass_that_comes_back_follows_again_from_its_next_reading() {
        let mut f = CompassFollow::default();
        assert!(f.follows(1.0, SIGMA2, THRESHOLD));
        f.predicted(0.5, 1e-6);
        assert!(
            !f.follows(1.0, SIGMA2, THRESHOLD),
            "did not turn with the robot"
        );
        f.predicted(0.1, 1e-6);
        assert!(
            f.follows(1.6, SIGMA2, THRESHOLD),
            "turned by 0.6 as the robot did"
        );
        f.predicted(0.0, 1e-6);
        assert!(f.follows(1.6, SIGMA2, THRESHOLD));
    }
}

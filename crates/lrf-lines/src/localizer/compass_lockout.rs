//! Recovery of the compass from gate lock-out.
//!
//! The compass gate rejects a heading far from the prediction, as a disturbed magnetic
//! field gives. But a gate also rejects good headings once the filter itself is off: a
//! consistent filter's reading fails by chance (0.1 % at the default 0.999 gate), and in
//! a turn odometry can add heading error as fast as the covariance grows. Then every later
//! reading fails too, and so do the laser lines, whose angles are as far off; the filter
//! runs on odometry alone until something happens to pull it back.
//!
//! Outliers and a drifted filter are told apart by how the rejected readings agree with
//! each other. Consecutive readings `φ_{k−1}, φ_k` of the true heading differ by the turn
//! between them, which odometry measured with the heading variance `Q_θθ` the predictions
//! added; so
//!
//! `d = wrap(φ_k − φ_{k−1} − Δθ_odo)`,  `d² / (σ²_{k−1} + σ²_k + Q_θθ) ≤ χ²₁(p)`
//!
//! at the compass gate's probability `p`. Outliers (an error of tens of degrees, a new
//! one each time) pass this with small probability; readings of a drifted filter pass it
//! with probability `p`. After `recover_after` consecutive rejected readings that each
//! agree with the one before, the last is fused without the gate — an ordinary Kalman
//! update, which keeps every correlation. This is PX4 EKF2's reset of a sensor that has
//! failed its innovation test for too long, with evidence that the readings are not
//! outliers asked for first. A disturbance that stays the same (a steel cabinet beside a
//! parked robot) agrees with itself and is fused after the lock-out; no gate can tell it
//! from the truth.

use ekf_core::{angle_diff, wrap_angle, ChiSquareGate};

/// The rejected compass readings in a row and the odometry turn since the last reading.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct CompassLockout {
    /// Heading change `Δθ_odo` the predictions made since the last reading (rad).
    turned: f64,
    /// Heading variance `Q_θθ` the predictions added since the last reading (rad²).
    turned_variance: f64,
    /// The last reading, `(φ, σ²)`, if it was rejected.
    last_rejected: Option<(f64, f64)>,
    /// Consecutive rejected readings, each agreeing with the one before.
    in_a_row: u32,
}

impl CompassLockout {
    /// A prediction turned the heading by `turned` (rad) and added `variance` (rad²) to
    /// `P_θθ`. (Every motion model here has `θ' = θ + Δθ`, so the row of `A` for `θ` is
    /// `(0, 0, 1)` and the growth of `P_θθ` is exactly the added process noise.)
    pub(super) fn predicted(&mut self, turned: f64, variance: f64) {
        self.turned += turned;
        self.turned_variance += variance;
    }

    /// A reading `φ` of variance `σ²` failed `gate`. Returns how many consecutive
    /// rejected readings, this one included, agree each with the one before.
    pub(super) fn rejected(
        &mut self,
        heading: f64,
        variance: f64,
        gate: &ChiSquareGate<f64>,
    ) -> u32 {
        let agrees = self.last_rejected.is_some_and(|(last, last_variance)| {
            let d = angle_diff(heading, wrap_angle(last + self.turned));
            gate.accepts(d * d / (last_variance + variance + self.turned_variance))
        });
        self.in_a_row = if agrees { self.in_a_row + 1 } else { 1 };
        self.last_rejected = Some((heading, variance));
        self.reading_done();
        self.in_a_row
    }

    /// A reading was fused: the lock-out, if there was one, is over.
    pub(super) fn fused(&mut self) {
        self.last_rejected = None;
        self.in_a_row = 0;
        self.reading_done();
    }

    fn reading_done(&mut self) {
        self.turned = 0.0;
        self.turned_variance = 0.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gate() -> ChiSquareGate<f64> {
        ChiSquareGate::from_probability(0.99, 1).unwrap()
    }

    const SIGMA2: f64 = 1e-6; // (0.057°)²

    #[test]
    fn readings_that_follow_the_odometry_turn_count_up() {
        let mut lockout = CompassLockout::default();
        assert_eq!(lockout.rejected(3.1, SIGMA2, &gate()), 1);
        // Turned 0.1 rad, across ±π; the reading follows to within 1.5σ of the difference.
        lockout.predicted(0.1, 4e-6);
        let next = wrap_angle(3.2 + 1.5 * (2.0 * SIGMA2 + 4e-6_f64).sqrt());
        assert_eq!(lockout.rejected(next, SIGMA2, &gate()), 2);
        lockout.predicted(0.0, 0.0);
        assert_eq!(lockout.rejected(next, SIGMA2, &gate()), 3);
    }

    #[test]
    fn a_reading_that_disagrees_starts_a_new_run_and_a_fused_one_ends_it() {
        let mut lockout = CompassLockout::default();
        lockout.rejected(1.0, SIGMA2, &gate());
        lockout.predicted(0.02, 1e-6);
        assert_eq!(lockout.rejected(1.02, SIGMA2, &gate()), 2);
        // 2.7σ off the turn: an outlier as far as the pair can tell (χ²₁(0.99) = 2.576²).
        lockout.predicted(0.0, 1e-6);
        assert_eq!(
            lockout.rejected(1.02 + 2.7 * 3e-6_f64.sqrt(), SIGMA2, &gate()),
            1
        );
        lockout.fused();
        lockout.predicted(0.0, 0.0);
        assert_eq!(lockout.rejected(1.02, SIGMA2, &gate()), 1);
    }

    #[test]
    fn the_turn_is_counted_from_the_last_reading_only() {
        let mut lockout = CompassLockout::default();
        lockout.predicted(0.5, 0.0);
        lockout.rejected(0.0, SIGMA2, &gate());
        lockout.predicted(0.01, 0.0);
        assert_eq!(lockout.rejected(0.01, SIGMA2, &gate()), 2);
    }
}

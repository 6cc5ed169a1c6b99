//! Recovery of the compass from gate lock-out.
//!
//! The compass gate rejects a heading far from the prediction, as a disturbed magnetic
//! field gives. But a gate also rejects good headings once the filter itself is off: a
//! consistent filter's reading fails by chance (0.1 % at the default 0.999 gate), and in
//! a turn odometry can add heading error as fast as the covariance grows; a wheel slip
//! turns the robot without odometry seeing it at all. Then every later reading fails
//! too, and so do the laser lines, whose angles are as far off; the filter runs on
//! odometry alone until something happens to pull it back.
//!
//! A drifted filter is told from a disturbed compass by two things:
//! - **The readings agree with each other better than with the filter.** Consecutive
//!   readings `φ_{k−1}, φ_k` of the true heading differ by the turn between them, which
//!   odometry measured with the heading variance `Q_θθ` the predictions added:
//!
//!   `d = wrap(φ_k − φ_{k−1} − Δθ_odo)`,  `d² ≤ χ²₁(p)·(σ²_{k−1} + σ²_k + Q_θθ)`,
//!   `χ²₁(p)·Q_θθ < ν_k²`
//!
//!   with `ν_k` the reading's innovation and `p` the compass gate's probability. The
//!   second inequality asks that odometry know the turn between the two better than the
//!   reading is from the filter; without it a long gap between two readings (large
//!   `Q_θθ`) would let anything agree. A spike tens of degrees off agrees with a good
//!   reading, or with another spike, only by chance.
//! - **No laser line was fused meanwhile.** A fused line means the laser agrees with the
//!   filter's heading, so the compass is the one that is off; the run starts again.
//!
//! After `recover_after` such readings in a row the lock-out is taken as evidence that
//! the filter is further off than its covariance allows (see
//! [`Localizer::update_compass`](super::Localizer::update_compass)).
//! What this cannot tell from a drifted filter is a disturbance that lasts and holds still
//! while no line is fused (a steel cabinet beside a robot parked where it sees no wall),
//! or one that moves with the robot; readings much faster than the field changes (an AHRS
//! at 100 Hz) agree at once, so `recover_after` is a number of readings, to be raised for
//! such sources.

use ekf_core::{angle_diff, wrap_angle, ChiSquareGate};

/// The rejected compass readings in a row and the odometry turn since the last reading.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct CompassLockout {
    /// Heading change `Δθ_odo` the predictions made since the last reading (rad).
    turned: f64,
    /// Heading variance `Q_θθ` the predictions added since the last reading (rad²).
    turned_variance: f64,
    /// The last reading, `(φ, σ²)`, if it was rejected.
    last_rejected: Option<(f64, f64)>,
    /// Rejected readings in a row, each after the first agreeing with the one before.
    in_a_row: u32,
}

/// A compass reading the gate rejected.
#[derive(Debug, Clone, Copy)]
pub(super) struct Rejected {
    /// The heading `φ` (rad).
    pub(super) heading: f64,
    /// Its variance `σ²` (rad²).
    pub(super) variance: f64,
    /// Its squared innovation `ν² = wrap(φ − θ⁻)²` (rad²).
    pub(super) innovation_squared: f64,
}

impl CompassLockout {
    /// A prediction turned the heading by `turned` (rad) and added `variance` (rad²) to
    /// `P_θθ`. (Every motion model here has `θ' = θ + Δθ`, so the row of `A` for `θ` is
    /// `(0, 0, 1)` and the growth of `P_θθ` is exactly the added process noise.)
    pub(super) fn predicted(&mut self, turned: f64, variance: f64) {
        self.turned += turned;
        self.turned_variance += variance;
    }

    /// A reading failed `gate`. Returns how many rejected readings in a row, this one
    /// included, each after the first agree with the one before (see the module
    /// documentation).
    pub(super) fn rejected(&mut self, reading: &Rejected, gate: &ChiSquareGate<f64>) -> u32 {
        let agrees = self.last_rejected.is_some_and(|(last, last_variance)| {
            let d = angle_diff(reading.heading, wrap_angle(last + self.turned));
            let window = gate.threshold * (last_variance + reading.variance + self.turned_variance);
            let turn_window = gate.threshold * self.turned_variance;
            d * d <= window && turn_window < reading.innovation_squared
        });
        self.in_a_row = if agrees {
            self.in_a_row.saturating_add(1)
        } else {
            1
        };
        self.last_rejected = Some((reading.heading, reading.variance));
        self.turned = 0.0;
        self.turned_variance = 0.0;
        self.in_a_row
    }

    /// The filter agreed with a measurement (a compass reading passed the gate, or a laser
    /// line was fused), or a recovery ended the lock-out: no run of rejections stands.
    pub(super) fn confirmed(&mut self) {
        self.last_rejected = None;
        self.in_a_row = 0;
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
    /// Far enough from the filter that no pair's window reaches it.
    const FAR: f64 = 0.2;

    fn reading(heading: f64) -> Rejected {
        Rejected {
            heading,
            variance: SIGMA2,
            innovation_squared: FAR * FAR,
        }
    }

    #[test]
    fn readings_that_follow_the_odometry_turn_count_up() {
        let mut lockout = CompassLockout::default();
        assert_eq!(lockout.rejected(&reading(3.1), &gate()), 1);
        // Turned 0.1 rad, across ±π; the reading follows to within 1.5σ of the difference.
        lockout.predicted(0.1, 4e-6);
        let next = wrap_angle(3.2 + 1.5 * (2.0 * SIGMA2 + 4e-6_f64).sqrt());
        assert_eq!(lockout.rejected(&reading(next), &gate()), 2);
        lockout.predicted(0.0, 0.0);
        assert_eq!(lockout.rejected(&reading(next), &gate()), 3);
    }

    #[test]
    fn a_reading_that_disagrees_starts_a_new_run_and_a_confirmation_ends_it() {
        let mut lockout = CompassLockout::default();
        lockout.rejected(&reading(1.0), &gate());
        lockout.predicted(0.02, 1e-6);
        assert_eq!(lockout.rejected(&reading(1.02), &gate()), 2);
        // 2.7σ off the turn: an outlier as far as the pair can tell (χ²₁(0.99) = 2.576²).
        lockout.predicted(0.0, 1e-6);
        let off = 1.02 + 2.7 * 3e-6_f64.sqrt();
        assert_eq!(lockout.rejected(&reading(off), &gate()), 1);
        lockout.confirmed();
        lockout.predicted(0.0, 0.0);
        assert_eq!(lockout.rejected(&reading(1.02), &gate()), 1);
    }

    #[test]
    fn a_pair_whose_window_reaches_the_filter_is_no_evidence() {
        // A long gap: odometry added (10°)² since the last reading, so the turn's window
        // (±25.8° at 0.99) is wider than this reading's 20° from the filter.
        let mut lockout = CompassLockout::default();
        lockout.rejected(&reading(1.0), &gate());
        lockout.predicted(0.0, 10f64.to_radians().powi(2));
        let far_from_filter = Rejected {
            innovation_squared: 20f64.to_radians().powi(2),
            ..reading(1.0)
        };
        assert_eq!(lockout.rejected(&far_from_filter, &gate()), 1);
    }

    #[test]
    fn the_turn_is_counted_from_the_last_reading_only() {
        let mut lockout = CompassLockout::default();
        lockout.predicted(0.5, 0.0);
        lockout.rejected(&reading(0.0), &gate());
        lockout.predicted(0.01, 0.0);
        assert_eq!(lockout.rejected(&reading(0.01), &gate()), 2);
    }
}

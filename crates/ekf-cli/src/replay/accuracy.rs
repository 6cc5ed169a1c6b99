//! Accuracy against the reference, computed while the replay streams, in bounded memory:
//! each reference pose is paired with the estimated pose nearest in time within 10 ms
//! (`evo`'s association when the reference is the sparser trajectory, as it is for a
//! filter that publishes at every motion step), then `evo`'s APE statistics without
//! alignment. Only the estimates of the last few tens of milliseconds are kept.

use crate::trajectory::StampedPose;
use ekf_core::angle_diff;
use std::collections::VecDeque;

/// Largest time difference of a pair (ns), as `evo`'s default `max_diff` of 0.01 s.
pub const MAX_DIFF_NS: u64 = 10_000_000;

/// Running sums of the pose errors.
#[derive(Debug, Clone, Default)]
pub struct OnlineAccuracy {
    estimates: VecDeque<StampedPose>,
    pending: VecDeque<StampedPose>,
    matched: usize,
    sum_sq_position: f64,
    max_position: f64,
    sum_sq_heading: f64,
}

/// The result: matched pairs, position RMSE and maximum (m), heading RMSE (rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccuracyTotals {
    /// Reference poses paired with an estimate.
    pub matched: usize,
    /// Position RMSE (m).
    pub position_rmse: f64,
    /// Largest position error (m).
    pub position_max: f64,
    /// Heading RMSE (rad).
    pub heading_rmse: f64,
}

impl OnlineAccuracy {
    /// An estimated pose (in non-decreasing time).
    pub fn estimate(&mut self, sample: StampedPose) {
        self.estimates.push_back(sample);
        // A pending reference more than MAX_DIFF before this estimate has seen every
        // candidate it can be paired with.
        while self
            .pending
            .front()
            .is_some_and(|r| r.t_ns + MAX_DIFF_NS < sample.t_ns)
        {
            if let Some(r) = self.pending.pop_front() {
                self.pair(&r);
            }
        }
        let horizon = self
            .pending
            .front()
            .map_or(sample.t_ns, |r| r.t_ns.min(sample.t_ns))
            .saturating_sub(MAX_DIFF_NS);
        while self.estimates.len() > 1 && self.estimates.front().is_some_and(|e| e.t_ns < horizon) {
            self.estimates.pop_front();
        }
    }

    /// A reference pose (in non-decreasing time).
    pub fn reference(&mut self, sample: StampedPose) {
        self.pending.push_back(sample);
    }

    /// Pairs what is still pending and returns the totals; `None` if nothing was paired.
    pub fn finish(mut self) -> Option<AccuracyTotals> {
        while let Some(r) = self.pending.pop_front() {
            self.pair(&r);
        }
        (self.matched > 0).then(|| {
            let n = self.matched as f64;
            AccuracyTotals {
                matched: self.matched,
                position_rmse: (self.sum_sq_position / n).sqrt(),
                position_max: self.max_position,
                heading_rmse: (self.sum_sq_heading / n).sqrt(),
            }
        })
    }

    fn pair(&mut self, r: &StampedPose) {
        let Some(e) = self
            .estimates
            .iter()
            .filter(|e| e.t_ns.abs_diff(r.t_ns) <= MAX_DIFF_NS)
            .min_by_key(|e| e.t_ns.abs_diff(r.t_ns))
        else {
            return;
        };
        let d = ((e.pose.x - r.pose.x).powi(2) + (e.pose.y - r.pose.y).powi(2)).sqrt();
        self.matched += 1;
        self.sum_sq_position += d * d;
        self.max_position = self.max_position.max(d);
        self.sum_sq_heading += angle_diff(e.pose.theta, r.pose.theta).powi(2);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::{ape, ApeOptions};
    use crate::trajectory::Trajectory;
    use ekf_core::Pose2;

    #[test]
    fn equals_evo_ape_on_a_dense_estimate() {
        let (mut est, mut reference) = (Trajectory::default(), Trajectory::default());
        let mut online = OnlineAccuracy::default();
        // Estimates every 100 ms; references every 1 s, 3 ms after an estimate, with an
        // error that grows; the references arrive before or after their estimate.
        for k in 0..300u64 {
            let t = k * 100_000_000;
            let e = StampedPose::new(t, Pose2::new(k as f64 * 0.1, 0.0, 0.01 * k as f64));
            est.samples.push(e);
            online.estimate(e);
            if k % 10 == 5 {
                let r = StampedPose::new(
                    t + 3_000_000,
                    Pose2::new(k as f64 * 0.1 + 0.001 * k as f64, 0.02, 0.0),
                );
                reference.samples.push(r);
                online.reference(r);
            }
        }
        let got = online.finish().unwrap();
        let want = ape(&reference, &est, &ApeOptions::default())
            .unwrap()
            .summary;
        assert_eq!(got.matched, want.matched_poses);
        assert!((got.position_rmse - want.translation_m.rmse).abs() < 1e-12);
        assert!((got.position_max - want.translation_m.max).abs() < 1e-12);
        assert!((got.heading_rmse.to_degrees() - want.heading_error_deg.rmse).abs() < 1e-9);
        assert!(OnlineAccuracy::default().finish().is_none());
    }
}

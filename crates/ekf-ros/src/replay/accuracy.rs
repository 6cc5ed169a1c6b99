//! Accuracy against the reference, computed while the replay streams, in bounded memory,
//! as `evo_ape` computes it without alignment: each pose of the trajectory with fewer
//! poses is paired with the nearest pose of the other within 10 ms. Both pairings run
//! side by side (only the last tens of milliseconds of poses are held) and the one `evo`
//! would pick is reported at the end.

use crate::trajectory::StampedPose;
use ekf_core::angle_diff;
use std::collections::VecDeque;

/// Largest time difference of a pair (ns), as `evo`'s default `max_diff` of 0.01 s.
pub const MAX_DIFF_NS: u64 = 10_000_000;

/// One direction of the pairing: each *query* pose is paired with the nearest
/// *candidate* within [`MAX_DIFF_NS`] (ties: the earlier candidate).
#[derive(Debug, Clone, Default)]
struct Pairing {
    candidates: VecDeque<StampedPose>,
    pending: VecDeque<StampedPose>,
    queries: usize,
    sums: Sums,
}

/// Running sums of the pose errors of the pairs, and each pair's position error (4 bytes
/// a pair, for the median and the shares over a bound).
#[derive(Debug, Clone, Default)]
struct Sums {
    matched: usize,
    sum_sq_position: f64,
    max_position: f64,
    sum_sq_heading: f64,
    position_errors: Vec<f32>,
}

impl Pairing {
    fn query(&mut self, sample: StampedPose) {
        self.queries += 1;
        self.pending.push_back(sample);
    }

    fn candidate(&mut self, sample: StampedPose) {
        self.candidates.push_back(sample);
    }

    /// Replaces the newest candidate (it had the same stamp).
    fn replace_candidate(&mut self, sample: StampedPose) {
        if let Some(last) = self.candidates.back_mut() {
            *last = sample;
        }
    }

    /// Replaces the newest query if it is still pending (it had the same stamp).
    fn replace_query(&mut self, sample: StampedPose) {
        match self.pending.back_mut() {
            Some(last) if last.t_ns == sample.t_ns => *last = sample,
            _ => self.query(sample),
        }
    }

    /// Everything later than `now` is in the future: a pending query older than
    /// `now − MAX_DIFF` has seen all its candidates; older candidates can go.
    fn advance(&mut self, now: u64) {
        while self
            .pending
            .front()
            .is_some_and(|q| q.t_ns + MAX_DIFF_NS < now)
        {
            if let Some(q) = self.pending.pop_front() {
                self.pair(&q);
            }
        }
        let horizon = self
            .pending
            .front()
            .map_or(now, |q| q.t_ns.min(now))
            .saturating_sub(MAX_DIFF_NS);
        while self.candidates.front().is_some_and(|c| c.t_ns < horizon) {
            self.candidates.pop_front();
        }
    }

    fn finish(mut self) -> (usize, Sums) {
        while let Some(q) = self.pending.pop_front() {
            self.pair(&q);
        }
        (self.queries, self.sums)
    }

    fn pair(&mut self, q: &StampedPose) {
        let Some(c) = self
            .candidates
            .iter()
            .filter(|c| c.t_ns.abs_diff(q.t_ns) <= MAX_DIFF_NS)
            .min_by_key(|c| c.t_ns.abs_diff(q.t_ns))
        else {
            return;
        };
        let d = ((c.pose.x - q.pose.x).powi(2) + (c.pose.y - q.pose.y).powi(2)).sqrt();
        let s = &mut self.sums;
        s.matched += 1;
        s.sum_sq_position += d * d;
        s.max_position = s.max_position.max(d);
        s.position_errors.push(d as f32);
        s.sum_sq_heading += angle_diff(c.pose.theta, q.pose.theta).powi(2);
    }
}

/// The pairing in both directions, so that at the end the one `evo` would use is known:
/// from the trajectory with fewer poses (the estimate when the counts are equal).
#[derive(Debug, Clone, Default)]
pub struct OnlineAccuracy {
    by_reference: Pairing,
    by_estimate: Pairing,
    now: u64,
    last_estimate_ns: Option<u64>,
}

/// The result: matched pairs, position RMSE, median, 95th percentile and maximum (m), the
/// shares of pairs over 0.5 m and 1 m, heading RMSE (rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccuracyTotals {
    /// Pairs of poses.
    pub matched: usize,
    /// Position RMSE (m).
    pub position_rmse: f64,
    /// Median position error (m), as `numpy.median`.
    pub position_median: f64,
    /// 95th percentile of the position error (m), linear between ranks as
    /// `numpy.percentile`.
    pub position_p95: f64,
    /// Largest position error (m).
    pub position_max: f64,
    /// Share of pairs with a position error over 0.5 m.
    pub share_over_half_m: f64,
    /// Share of pairs with a position error over 1 m.
    pub share_over_1m: f64,
    /// Heading RMSE (rad).
    pub heading_rmse: f64,
}

/// The `q`-quantile (0 ≤ q ≤ 1) of the sorted, non-empty `values`, linear between ranks.
fn quantile(sorted: &[f32], q: f64) -> f64 {
    let at = q * (sorted.len() - 1) as f64;
    let (lo, hi) = (at.floor() as usize, at.ceil() as usize);
    let (a, b) = (f64::from(sorted[lo]), f64::from(sorted[hi]));
    a + (b - a) * (at - lo as f64)
}

impl OnlineAccuracy {
    /// An estimated pose (estimates and references together in non-decreasing time). A
    /// later estimate with the same stamp replaces the earlier one (a motion step and a
    /// scan update at one time count as one pose, the last).
    pub fn estimate(&mut self, sample: StampedPose) {
        if self.last_estimate_ns == Some(sample.t_ns) {
            self.by_reference.replace_candidate(sample);
            self.by_estimate.replace_query(sample);
        } else {
            self.by_reference.candidate(sample);
            self.by_estimate.query(sample);
        }
        self.last_estimate_ns = Some(sample.t_ns);
        self.advance(sample.t_ns);
    }

    /// A reference pose.
    pub fn reference(&mut self, sample: StampedPose) {
        self.by_reference.query(sample);
        self.by_estimate.candidate(sample);
        self.advance(sample.t_ns);
    }

    fn advance(&mut self, t_ns: u64) {
        self.now = self.now.max(t_ns);
        self.by_reference.advance(self.now);
        self.by_estimate.advance(self.now);
    }

    /// Pairs what is still pending and returns the totals; `None` if nothing was paired.
    pub fn finish(self) -> Option<AccuracyTotals> {
        let (references, by_reference) = self.by_reference.finish();
        let (estimates, by_estimate) = self.by_estimate.finish();
        let s = if estimates > references {
            by_reference
        } else {
            by_estimate
        };
        (s.matched > 0).then(|| {
            let n = s.matched as f64;
            let mut errors = s.position_errors;
            errors.sort_by(f32::total_cmp);
            let share_over =
                |bound: f64| errors.iter().filter(|&&e| f64::from(e) > bound).count() as f64 / n;
            AccuracyTotals {
                matched: s.matched,
                position_rmse: (s.sum_sq_position / n).sqrt(),
                position_median: quantile(&errors, 0.5),
                position_p95: quantile(&errors, 0.95),
                position_max: s.max_position,
                share_over_half_m: share_over(0.5),
                share_over_1m: share_over(1.0),
                heading_rmse: (s.sum_sq_heading / n).sqrt(),
            }
        })
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

        // Same-stamp estimates replace each other, and references arriving between them
        // (denser than the estimates) still find their partner.
        let mut online = OnlineAccuracy::default();
        let mut reference = Trajectory::default();
        let mut est = Trajectory::default();
        for k in 0..400u64 {
            let t = k * 10_000_000;
            if k % 10 == 0 {
                online.estimate(StampedPose::new(t, Pose2::new(5.0, 5.0, 0.0)));
                let e = StampedPose::new(t, Pose2::new(k as f64 * 0.01 + 0.1, 0.0, 0.0));
                online.estimate(e);
                est.samples.push(e);
            }
            let r = StampedPose::new(t + 1_000_000, Pose2::new(k as f64 * 0.01, 0.0, 0.0));
            online.reference(r);
            reference.samples.push(r);
        }
        let got = online.finish().unwrap();
        let want = ape(&reference, &est, &ApeOptions::default())
            .unwrap()
            .summary;
        assert_eq!((got.matched, want.matched_poses), (40, 40));
        assert!((got.position_rmse - want.translation_m.rmse).abs() < 1e-12);
        assert!(OnlineAccuracy::default().finish().is_none());

        // A reference denser than the estimate: evo pairs from the estimate.
        let (mut est, mut reference) = (Trajectory::default(), Trajectory::default());
        let mut online = OnlineAccuracy::default();
        for k in 0..1000u64 {
            let t = k * 10_000_000;
            let r = StampedPose::new(t, Pose2::new(k as f64 * 0.01, 0.0, 0.0));
            reference.samples.push(r);
            online.reference(r);
            if k % 5 == 2 {
                let e = StampedPose::new(
                    t + 4_000_000,
                    Pose2::new(k as f64 * 0.01, 0.001 * (k % 7) as f64, 0.01),
                );
                est.samples.push(e);
                online.estimate(e);
            }
        }
        let got = online.finish().unwrap();
        let want = ape(&reference, &est, &ApeOptions::default())
            .unwrap()
            .summary;
        assert_eq!(got.matched, want.matched_poses);
        assert_eq!(got.matched, 200);
        assert!((got.position_rmse - want.translation_m.rmse).abs() < 1e-12);
        assert!((got.heading_rmse.to_degrees() - want.heading_error_deg.rmse).abs() < 1e-9);
    }
}

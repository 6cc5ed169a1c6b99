//! Verifying a relocalization over the scans after the search, before the filter is
//! restarted.
//!
//! One scan rarely tells a long corridor or a row of equal offices apart: the search's
//! best pose can be a wall-for-wall copy of the right one (on ACES, 11 m along the
//! corridor, and it explains every line there). So a search made while the filter is
//! lost only nominates: its best poses that are elsewhere than each other
//! ([`lrf_lines::Relocalization::candidates`]) are carried by the odometry to each of
//! the next scans and scored there as the search scores its hypotheses
//! ([`lrf_lines::fit_poses`]). After [`VERIFY_SCANS`] scans, the candidate with the
//! highest summed score is taken if it explains those scans as a single search's best
//! pose must explain its scan ([`RelocalizeParams::explains`]: half the summed observed
//! length; a third let a lone candidate 190 m off on freiburg-campus through) and beats
//! every candidate elsewhere by
//! [`RelocalizeParams::min_margin`]; otherwise the filter stays lost and searches again.
//! A motion gap in between ends the verification: the odometry no longer says where the
//! candidates went.

use alloc::vec::Vec;
use ekf_core::Pose2;
use lrf_lines::{PoseFits, Relocalization, RelocalizeParams};

/// Scans a relocalization is judged over, the search's own included.
pub const VERIFY_SCANS: u32 = 3;

/// One candidate pose being verified.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Candidate {
    /// The pose at the latest scan.
    pose: Pose2<f64>,
    /// Summed score over the scans so far (m).
    score: f64,
    /// Summed inliers.
    inliers: usize,
}

/// Candidates of a search, carried over the scans after it.
#[derive(Debug, Clone, PartialEq)]
pub struct Verification {
    candidates: Vec<Candidate>,
    /// Summed length of the observed lines used (m).
    observed_length: f64,
    /// Scans scored, the search's included.
    scans: u32,
}

/// The verdict: the pose to restart at, with its summed inliers and score and the best
/// summed score elsewhere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Verified {
    /// The candidate's pose at the latest scan.
    pub pose: Pose2<f64>,
    /// Its summed inliers.
    pub inliers: usize,
    /// Its summed score (m).
    pub score: f64,
    /// The best summed score of a candidate elsewhere (m; 0 if none).
    pub runner_up: f64,
}

impl Verification {
    /// Starts with the candidates of `found`, scored at the search's scan.
    pub fn start(found: &Relocalization) -> Self {
        Self {
            candidates: found
                .candidates
                .iter()
                .map(|h| Candidate {
                    pose: h.pose,
                    score: h.score,
                    inliers: h.inliers,
                })
                .collect(),
            observed_length: found.observed_length,
            scans: 1,
        }
    }

    /// The robot moved by `delta` (its own frame): every candidate moves with it.
    pub fn moved(&mut self, delta: &Pose2<f64>) {
        for c in &mut self.candidates {
            c.pose = c.pose.compose(delta);
        }
    }

    /// The candidates' poses, for scoring the next scan.
    pub fn poses(&self) -> Vec<Pose2<f64>> {
        self.candidates.iter().map(|c| c.pose).collect()
    }

    /// Adds a scan's fits, one per candidate in the order of [`poses`](Self::poses).
    pub fn add_scan(&mut self, fits: &PoseFits) {
        for (c, f) in self.candidates.iter_mut().zip(&fits.fits) {
            c.score += f.score;
            c.inliers += f.inliers;
        }
        self.observed_length += fits.observed_length;
        self.scans += 1;
    }

    /// Whether [`VERIFY_SCANS`] scans have been scored.
    pub fn done(&self) -> bool {
        self.scans >= VERIFY_SCANS
    }

    /// The candidate with the highest summed score if it explains the scans
    /// ([`RelocalizeParams::explains`], over the sums) and beats
    /// every candidate elsewhere by `params.min_margin`; `None` otherwise.
    pub fn verdict(&self, params: &RelocalizeParams) -> Option<Verified> {
        let best = self
            .candidates
            .iter()
            .max_by(|a, b| a.score.total_cmp(&b.score))?;
        let runner_up = self
            .candidates
            .iter()
            .filter(|c| params.elsewhere(&c.pose, &best.pose))
            .map(|c| c.score)
            .fold(0.0, f64::max);
        let clear = params.explains(best.inliers, best.score, self.observed_length)
            && best.score >= params.min_margin * runner_up;
        clear.then_some(Verified {
            pose: best.pose,
            inliers: best.inliers,
            score: best.score,
            runner_up,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lrf_lines::Hypothesis;

    fn hypothesis(x: f64, score: f64) -> Hypothesis {
        Hypothesis {
            pose: Pose2::new(x, 0.0, 0.0),
            inliers: 3,
            score,
        }
    }

    fn search(candidates: Vec<Hypothesis>, observed_length: f64) -> Relocalization {
        Relocalization {
            best: candidates[0],
            runner_up: candidates.get(1).map_or(0.0, |h| h.score),
            candidates,
            observed_length,
            hypotheses: 10,
        }
    }

    fn fits(scores: &[f64], observed_length: f64) -> PoseFits {
        PoseFits {
            fits: scores.iter().map(|&s| hypothesis(0.0, s)).collect(),
            observed_length,
        }
    }

    #[test]
    fn the_search_s_best_loses_to_a_candidate_that_explains_the_later_scans() {
        // A copy 11 m along the corridor wins the search's scan narrowly, then the scans
        // after it see what only the right place has.
        let mut v = Verification::start(&search(
            vec![hypothesis(11.0, 5.0), hypothesis(0.0, 4.8)],
            6.0,
        ));
        assert_eq!(
            v.verdict(&RelocalizeParams::default()).map(|w| w.pose.x),
            None
        );
        v.moved(&Pose2::new(1.0, 0.0, 0.0));
        v.add_scan(&fits(&[2.0, 5.5], 6.0));
        assert!(!v.done());
        v.moved(&Pose2::new(1.0, 0.0, 0.0));
        v.add_scan(&fits(&[2.5, 5.8], 6.0));
        assert!(v.done());
        let won = v.verdict(&RelocalizeParams::default()).unwrap();
        // Carried 2 m by the odometry; 16.1 against 9.5.
        assert_eq!(won.pose, Pose2::new(2.0, 0.0, 0.0));
        assert!((won.score - 16.1).abs() < 1e-9 && (won.runner_up - 9.5).abs() < 1e-9);
        assert_eq!(won.inliers, 9);
    }

    #[test]
    fn candidates_that_stay_alike_or_explain_too_little_are_refused() {
        let params = RelocalizeParams::default();
        let mut alike = Verification::start(&search(
            vec![hypothesis(0.0, 5.0), hypothesis(11.0, 4.9)],
            6.0,
        ));
        alike.add_scan(&fits(&[5.0, 4.8], 6.0));
        alike.add_scan(&fits(&[5.1, 4.9], 6.0));
        assert_eq!(alike.verdict(&params), None, "15.1 is not 1.2 × 14.6");
        let mut weak = Verification::start(&search(vec![hypothesis(0.0, 2.9)], 6.0));
        weak.add_scan(&fits(&[2.9], 6.0));
        weak.add_scan(&fits(&[2.9], 6.0));
        assert_eq!(weak.verdict(&params), None, "8.7 of 18 m explained");
    }

    #[test]
    fn a_candidate_turned_a_quarter_moves_along_its_own_heading() {
        let mut v = Verification::start(&search(
            vec![Hypothesis {
                pose: Pose2::new(1.0, 2.0, core::f64::consts::FRAC_PI_2),
                inliers: 3,
                score: 5.0,
            }],
            6.0,
        ));
        v.moved(&Pose2::new(1.0, 0.0, 0.0));
        let p = v.poses()[0];
        assert!((p.x - 1.0).abs() < 1e-12 && (p.y - 3.0).abs() < 1e-12);
    }
}

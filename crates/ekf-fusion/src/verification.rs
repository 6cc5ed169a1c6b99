//! Verifying a relocalization over the scans after the search, before the filter is
//! restarted.
//!
//! One scan rarely tells a long corridor or a row of equal offices apart: the search's
//! best pose can be a wall-for-wall copy of the right one (on ACES, 11 m along the
//! corridor, and it explains every line there). So a search made while the filter is
//! lost only nominates: its best poses that are elsewhere than each other
//! ([`lrf_lines::Relocalization::candidates`]) are tracked over the next scans, and
//! after [`VERIFY_SCANS`] scans the candidate with the highest summed score is taken if
//! it explains those scans as a single search's best pose must explain its scan
//! ([`RelocalizeParams::explains`]: half the summed observed length; a third let a lone
//! candidate 190 m off on freiburg-campus through) and beats every candidate elsewhere
//! by [`RelocalizeParams::min_margin`]; otherwise the filter stays lost and searches
//! again. A motion gap in between ends the verification: the odometry no longer says
//! where the candidates went.
//!
//! Each candidate is tracked as a hypothesis of its own: a pose with a covariance,
//! started at [`restart_covariance`] and predicted through every motion step with the
//! filter's motion model and noise, so it grows as the filter's would. At each later
//! scan the candidate is looked for within 99 % bounds of its position and of its
//! heading (position within `√χ²₂(0.99)` times its covariance's largest axis, heading
//! within `√χ²₁(0.99) σ_θ`) by
//! the same search ([`lrf_lines::relocalize()`] with a [`SearchWindow`] that bounds the
//! heading too), and scored where the scan fits best, or where the odometry carried it
//! if the search finds nothing better. Scoring only the carried pose refused the right
//! candidate whenever the odometry turned worse than the search's 3° tolerance over the
//! scans of the verification (csail: up to 20° between two scans, within its noise
//! model's 3σ).

use alloc::vec::Vec;
use ekf_core::{Ekf, OdometryTravel, Pose2};
use lrf_lines::{
    HeadingWindow, Localizer, LocalizerConfig, PoseFits, Relocalization, RelocalizeParams,
    SearchWindow,
};
use nalgebra::{Matrix3, Point2, Vector3};

use crate::motion::MotionStep;

/// Scans a relocalization is judged over, the search's own included.
pub const VERIFY_SCANS: u32 = 3;

/// χ² quantile at 0.99 with 2 degrees of freedom: a candidate's position window.
const CHI2_2_99: f64 = 9.210_340_371_976_184;

/// χ² quantile at 0.99 with 1 degree of freedom: a candidate's heading window.
const CHI2_1_99: f64 = 6.634_896_601_021_214;

/// Covariance of a pose the search found, before any line is fused there: the search's
/// inlier distance (0.15 m) and angle tolerance (3°) as 1σ. The filter restarts with it
/// at a relocalized pose, and a candidate being verified starts with it.
pub fn restart_covariance(params: &RelocalizeParams) -> Matrix3<f64> {
    let sxy = params.inlier_distance;
    let sth = params.angle_tolerance;
    Matrix3::from_diagonal(&Vector3::new(sxy * sxy, sxy * sxy, sth * sth))
}

/// One candidate pose being verified.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Candidate {
    /// The candidate's pose at the latest step and its covariance.
    ekf: Ekf<f64>,
    /// Odometry travelled since the last scan (the interval of the odometry noise).
    travel: OdometryTravel<f64>,
    /// Summed score over the scans so far (m).
    score: f64,
    /// Summed inliers.
    inliers: usize,
}

impl Candidate {
    /// Where the next scan may place the candidate: its position within the circle that
    /// holds the 99 % ellipse of its position covariance (`√χ²₂(0.99)` times the
    /// largest axis, `λ_max = (a + c)/2 + √(((a − c)/2)² + b²)` for `[[a, b], [b, c]]`),
    /// its heading within `√χ²₁(0.99) σ_θ`.
    fn window(&self) -> SearchWindow {
        let p = self.ekf.covariance();
        let pose = self.ekf.pose();
        let (a, b, c) = (p[(0, 0)], p[(0, 1)], p[(1, 1)]);
        let largest = ((a + c) / 2.0 + libm::hypot((a - c) / 2.0, b)).max(0.0);
        SearchWindow {
            center: Point2::new(pose.x, pose.y),
            radius: libm::sqrt(CHI2_2_99 * largest),
            heading: Some(HeadingWindow {
                theta: pose.theta,
                tolerance: libm::sqrt(CHI2_1_99 * p[(2, 2)].max(0.0)),
            }),
        }
    }
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
    /// The pose's covariance: the candidate's own after it was tracked over the scans,
    /// or [`restart_covariance`] for a pose one search found.
    pub covariance: Matrix3<f64>,
    /// Its summed inliers.
    pub inliers: usize,
    /// Its summed score (m).
    pub score: f64,
    /// The best summed score of a candidate elsewhere (m; 0 if none).
    pub runner_up: f64,
}

impl Verification {
    /// Starts with the candidates of `found`, scored at the search's scan, each with
    /// [`restart_covariance`].
    pub fn start(
        found: &Relocalization,
        params: &RelocalizeParams,
    ) -> Result<Self, ekf_core::Error> {
        let covariance = restart_covariance(params);
        let candidates = found
            .candidates
            .iter()
            .map(|h| {
                Ok(Candidate {
                    ekf: Ekf::new(h.pose, covariance)?,
                    travel: OdometryTravel::default(),
                    score: h.score,
                    inliers: h.inliers,
                })
            })
            .collect::<Result<_, ekf_core::Error>>()?;
        Ok(Self {
            candidates,
            observed_length: found.observed_length,
            scans: 1,
        })
    }

    /// The robot moved by `step`: every candidate is predicted through it with the
    /// robot and motion noise of `config`.
    pub fn predict(
        &mut self,
        step: MotionStep,
        config: &LocalizerConfig,
    ) -> Result<(), ekf_core::Error> {
        self.candidates
            .iter_mut()
            .try_for_each(|c| step.predict(&mut c.ekf, config, &mut c.travel))
    }

    /// Scores the last scan of `localizer` for every candidate ([`fits`](Self::fits))
    /// and adds the scores ([`add_fits`](Self::add_fits)).
    pub fn add_scan(
        &mut self,
        localizer: &Localizer,
        params: &RelocalizeParams,
    ) -> Result<(), ekf_core::Error> {
        let fits = self.fits(localizer, params);
        self.add_fits(&fits, params)
    }

    /// How the last scan of `localizer` fits each candidate, in candidate order: the
    /// search's best pose within the candidate's window if it scores more than the pose
    /// the candidate was carried to, else that pose.
    pub fn fits(&self, localizer: &Localizer, params: &RelocalizeParams) -> PoseFits {
        let carried: Vec<Pose2<f64>> = self.candidates.iter().map(|c| c.ekf.pose()).collect();
        let mut fits = localizer.fit_poses(&carried, params);
        for (c, fit) in self.candidates.iter().zip(fits.fits.iter_mut()) {
            if let Some(found) = localizer
                .relocalize(&c.window(), params)
                .map(|r| r.best)
                .filter(|h| h.score > fit.score)
            {
                *fit = found;
            }
        }
        fits
    }

    /// Adds a scan's `fits`, one per candidate in candidate order (as
    /// [`fits`](Self::fits) returns them): each candidate's score and inliers grow by its
    /// fit's, and a candidate whose fit's pose differs from the pose it was carried to
    /// (the search found the scan's best fit elsewhere in its window) moves there, with
    /// [`restart_covariance`].
    pub fn add_fits(
        &mut self,
        fits: &PoseFits,
        params: &RelocalizeParams,
    ) -> Result<(), ekf_core::Error> {
        debug_assert_eq!(
            fits.fits.len(),
            self.candidates.len(),
            "one fit per candidate"
        );
        for (c, fit) in self.candidates.iter_mut().zip(&fits.fits) {
            if fit.pose != c.ekf.pose() {
                c.ekf = Ekf::new(fit.pose, restart_covariance(params))?;
            }
            c.travel.reset();
            c.score += fit.score;
            c.inliers += fit.inliers;
        }
        self.observed_length += fits.observed_length;
        self.scans += 1;
        Ok(())
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
        let pose = best.ekf.pose();
        let runner_up = self
            .candidates
            .iter()
            .filter(|c| params.elsewhere(&c.ekf.pose(), &pose))
            .map(|c| c.score)
            .fold(0.0, f64::max);
        let clear = params.explains(best.inliers, best.score, self.observed_length)
            && best.score >= params.min_margin * runner_up;
        clear.then_some(Verified {
            pose,
            covariance: *best.ekf.covariance(),
            inliers: best.inliers,
            score: best.score,
            runner_up,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ekf_core::Motion;
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

    /// Fits where the candidates are (`v`'s poses), with these scores.
    fn fits_in_place(v: &Verification, scores: &[f64], observed_length: f64) -> PoseFits {
        PoseFits {
            fits: v
                .candidates
                .iter()
                .zip(scores)
                .map(|(c, &score)| Hypothesis {
                    pose: c.ekf.pose(),
                    inliers: 3,
                    score,
                })
                .collect(),
            observed_length,
        }
    }

    fn forward(v: &mut Verification, ds: f64, dtheta: f64) {
        v.predict(
            MotionStep::Odometry(Motion { ds, dtheta }),
            &LocalizerConfig::default(),
        )
        .unwrap();
    }

    #[test]
    fn the_search_s_best_loses_to_a_candidate_that_explains_the_later_scans() {
        // A copy 11 m along the corridor wins the search's scan narrowly, then the scans
        // after it see what only the right place has.
        let params = RelocalizeParams::default();
        let mut v = Verification::start(
            &search(vec![hypothesis(11.0, 5.0), hypothesis(0.0, 4.8)], 6.0),
            &params,
        )
        .unwrap();
        assert_eq!(v.verdict(&params).map(|w| w.pose.x), None);
        forward(&mut v, 1.0, 0.0);
        v.add_fits(&fits_in_place(&v, &[2.0, 5.5], 6.0), &params)
            .unwrap();
        assert!(!v.done());
        forward(&mut v, 1.0, 0.0);
        v.add_fits(&fits_in_place(&v, &[2.5, 5.8], 6.0), &params)
            .unwrap();
        assert!(v.done());
        let won = v.verdict(&params).unwrap();
        // Carried 2 m by the odometry; 16.1 against 9.5.
        assert!((won.pose.x - 2.0).abs() < 1e-12 && won.pose.y.abs() < 1e-12);
        assert!((won.score - 16.1).abs() < 1e-9 && (won.runner_up - 9.5).abs() < 1e-9);
        assert_eq!(won.inliers, 9);
        // Its covariance is its own, grown by 2 m of odometry noise.
        let start = restart_covariance(&params);
        assert!(won.covariance[(0, 0)] > start[(0, 0)] && won.covariance[(2, 2)] > start[(2, 2)]);
    }

    #[test]
    fn candidates_that_stay_alike_or_explain_too_little_are_refused() {
        let params = RelocalizeParams::default();
        let mut alike = Verification::start(
            &search(vec![hypothesis(0.0, 5.0), hypothesis(11.0, 4.9)], 6.0),
            &params,
        )
        .unwrap();
        alike
            .add_fits(&fits_in_place(&alike, &[5.0, 4.8], 6.0), &params)
            .unwrap();
        alike
            .add_fits(&fits_in_place(&alike, &[5.1, 4.9], 6.0), &params)
            .unwrap();
        assert_eq!(alike.verdict(&params), None, "15.1 is not 1.2 × 14.6");
        let mut weak =
            Verification::start(&search(vec![hypothesis(0.0, 2.9)], 6.0), &params).unwrap();
        weak.add_fits(&fits_in_place(&weak, &[2.9], 6.0), &params)
            .unwrap();
        weak.add_fits(&fits_in_place(&weak, &[2.9], 6.0), &params)
            .unwrap();
        assert_eq!(weak.verdict(&params), None, "8.7 of 18 m explained");
    }

    #[test]
    fn a_candidate_turned_a_quarter_moves_along_its_own_heading() {
        let params = RelocalizeParams::default();
        let mut v = Verification::start(
            &search(
                vec![Hypothesis {
                    pose: Pose2::new(1.0, 2.0, core::f64::consts::FRAC_PI_2),
                    inliers: 3,
                    score: 5.0,
                }],
                6.0,
            ),
            &params,
        )
        .unwrap();
        forward(&mut v, 1.0, 0.0);
        let p = v.candidates[0].ekf.pose();
        assert!((p.x - 1.0).abs() < 1e-12 && (p.y - 3.0).abs() < 1e-12);
    }

    #[test]
    fn a_candidate_s_window_is_its_99_percent_region_and_grows_with_the_motion() {
        let params = RelocalizeParams::default();
        let mut v = Verification::start(&search(vec![hypothesis(0.0, 5.0)], 6.0), &params).unwrap();
        let w0 = v.candidates[0].window();
        // σ = 0.15 m and 3° at the start.
        assert!((w0.radius - (9.210_340_371_976_184_f64).sqrt() * 0.15).abs() < 1e-9);
        let h0 = w0.heading.unwrap();
        assert!(
            (h0.tolerance - (6.634_896_601_021_214_f64).sqrt() * 3f64.to_radians()).abs() < 1e-9
        );
        forward(&mut v, 1.0, 1.0);
        let w1 = v.candidates[0].window();
        let h1 = w1.heading.unwrap();
        assert!(w1.radius > w0.radius && h1.tolerance > h0.tolerance);
        assert!((h1.theta - 1.0).abs() < 1e-12);
        // The default odometry noise: σ_θ² grows by (0.3·1 + 0.07·1 + 0.5°)² over the turn.
        let grown = 3f64.to_radians().powi(2) + (0.3 + 0.07 + 0.5f64.to_radians()).powi(2);
        assert!((h1.tolerance - (6.634_896_601_021_214 * grown).sqrt()).abs() < 1e-9);
    }

    #[test]
    fn the_window_constants_are_the_chi_square_quantiles() {
        for (constant, dof) in [(CHI2_2_99, 2), (CHI2_1_99, 1)] {
            let q = ekf_core::chi_square_quantile(0.99, dof).unwrap();
            assert!((constant - q).abs() < 1e-9 * q, "{constant} against {q}");
        }
    }

    #[test]
    fn a_fit_elsewhere_moves_the_candidate_and_restarts_its_covariance() {
        let params = RelocalizeParams::default();
        let mut v = Verification::start(&search(vec![hypothesis(0.0, 5.0)], 6.0), &params).unwrap();
        forward(&mut v, 1.0, 0.5);
        let moved_to = Pose2::new(1.1, 0.2, 0.3);
        let fits = PoseFits {
            fits: vec![Hypothesis {
                pose: moved_to,
                inliers: 4,
                score: 5.5,
            }],
            observed_length: 6.0,
        };
        v.add_fits(&fits, &params).unwrap();
        assert_eq!(v.candidates[0].ekf.pose(), moved_to);
        assert_eq!(
            *v.candidates[0].ekf.covariance(),
            restart_covariance(&params)
        );
        assert!((v.candidates[0].score - 10.5).abs() < 1e-12);
        assert_eq!(v.candidates[0].inliers, 7);
    }
}

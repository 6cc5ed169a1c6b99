//! The `Localizer` facade for embedders: one object that runs the whole localization
//! step — wheel or odometry prediction, compass update, and scan → extract → match →
//! update — over `ekf-core`, with per-step diagnostics and no printing.

mod compass_follow;
mod compass_lockout;
mod config;
mod error;
mod map_errors;
mod missed_walls;

pub use config::{CompassConfig, LocalizerConfig};
pub use error::LocalizerError;

use compass_follow::{CompassFollow, FOLLOW_PROBABILITY};
use compass_lockout::{CompassLockout, Rejected};
use config::ValidatedParts;
use map_errors::MapErrors;
use missed_walls::{MissedWalls, Tracing};

use crate::relocalize::{
    fit_poses, relocalize, Hypothesis, PoseFits, Relocalization, RelocalizeParams, SearchWindow,
};
use crate::{
    LaserScan, LineExtractor, LineMap, MatchResult, Matcher, ObservedLine, RejectReason, WallErrors,
};
use alloc::vec::Vec;
use core::ops::Range;
use ekf_core::{
    angle_diff, ChiSquareGate, Compass, Considered, Ekf, LaserLine, Measurement, Motion,
    OdometryTravel, Pose2, Position, UpdateOutcome, WheelSpeeds,
};
use nalgebra::{Matrix2, Matrix3, Vector3};

/// Fused lines a scan needs before the walls they missed are fitted from its points.
pub const REFIT_AFTER_LINES: usize = 2;

/// What happened to one matched line during the sequential update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineFusion {
    /// Index of the observed line in [`Localizer::last_lines`].
    pub observed: usize,
    /// Index of the wall in [`Localizer::map`].
    pub map: usize,
    /// NIS of the line at the state it was fused into (after the lines before it).
    pub nis: f64,
    /// `true` if it passed the gate again and was fused.
    pub accepted: bool,
    /// Other observed lines fused with it as one line (pieces of the same wall rejected
    /// for it, [`RejectReason::MapLineTaken`], fitted together with it); `nis` is then
    /// that of the joint line.
    pub merged: usize,
}

/// What [`Localizer::update_compass`] did with a heading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompassUpdate {
    /// The update: `accepted` if the heading was fused (through the gate or as the
    /// recovery from lock-out), its NIS at the predicted state (for a recovery, before
    /// the missed error was added).
    pub outcome: UpdateOutcome<f64>,
    /// Consecutive readings up to this one that failed the gate, each agreeing with the
    /// one before (once odometry's turn is taken out) better than with the filter, with
    /// no laser line fused meanwhile; 0 if this one passed the gate.
    pub rejected_in_a_row: u32,
    /// `true` if the heading failed the gate but was fused because `rejected_in_a_row`
    /// reached [`CompassConfig::recover_after`]: the filter, not the compass, was off.
    pub recovered: bool,
    /// `true` if `rejected_in_a_row` reached `recover_after` but the recovery was
    /// refused: the laser sides with the filter (see
    /// [`Localizer::update_compass`]), so the compass, not the filter, is off (stuck,
    /// biased, or disturbed). The run of rejections starts again, and until a reading
    /// passes the gate no recovery trusts the compass.
    pub refused_by_laser: bool,
    /// `true` if the reading was not fused because the compass does not follow the
    /// robot's turns as odometry measured them (`compass_follow.rs`): stuck, or not
    /// measuring the heading.
    pub not_following: bool,
}

/// Counts for one [`Localizer::update_scan`]; the lines, matches and fusions themselves
/// are [`Localizer::last_lines`], [`Localizer::last_matches`] and
/// [`Localizer::last_fusions`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ScanReport {
    /// Lines extracted from the scan.
    pub extracted: usize,
    /// Lines associated with a wall at the predicted state.
    pub matched: usize,
    /// Lines not associated (outside the gate, no overlap, wall taken, invalid).
    pub rejected: usize,
    /// Matched lines fused into the state.
    pub fused: usize,
    /// Matched lines that failed the gate when re-evaluated at the updated state.
    pub refused: usize,
    /// Walls no fused line lay on, fitted from the scan points on them and fused (see
    /// `missed_walls.rs`).
    pub refitted: usize,
    /// Observed lines that were pieces of a wall another line was matched to, fitted
    /// together with it and fused as one line.
    pub merged: usize,
    /// `true` if this scan's lines became the map (see [`Localizer::with_first_scan_map`]);
    /// nothing is fused then.
    pub map_built: bool,
}

/// A stage of [`Localizer::update_scan_timed`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScanStage {
    /// Line extraction from the scan.
    Extraction,
    /// Data association with the map.
    Matching,
    /// The sequential EKF update with the matched lines.
    Update,
}

/// Told when a scan update starts and when each of its stages ends; `()` ignores it.
pub trait StageClock {
    /// A scan update is starting (its first stage starts now).
    fn scan_started(&mut self) {}

    /// `stage` has just finished.
    fn stage_done(&mut self, stage: ScanStage);
}

impl StageClock for () {
    fn stage_done(&mut self, _stage: ScanStage) {}
}

/// The localization step for one robot: an [`Ekf`] plus a line map, a [`LineExtractor`],
/// a [`Matcher`] and the buffers they reuse, so that after the first scans no step
/// allocates.
///
/// A scan update ([`update_scan`](Self::update_scan)) does exactly this:
/// 1. extract the scan's lines (sensor frame);
/// 2. match them to the map at the predicted state `(x⁻, P⁻)` (see [`Matcher`]: 2-dof
///    chi-square gate on the line innovation, segment overlap, each wall at most once,
///    conflicts resolved by increasing NIS);
/// 3. fuse the matches one at a time in increasing order of their NIS at `x⁻`: each is
///    re-linearised at the current state (after the lines fused before it), gated again
///    with the same threshold, and fused with a Joseph-form update if it passes;
///    otherwise it is counted as refused and the state is left as it was. A line whose
///    wall is also the best wall of lines rejected for it (`MapLineTaken`: pieces of one
///    wall that extraction kept apart, at a door or behind clutter) is first fitted
///    together with those that are one line with it by extraction's merge test, as
///    extraction fits a line, and that line is fused instead if its points are straight
///    and it passes the gate ([`ScanReport::merged`]): one
///    measurement, so the wall's map noise is counted once;
/// 4. if at least [`REFIT_AFTER_LINES`] lines were fused (and
///    [`MatchParams::refit_missed_walls`](crate::MatchParams::refit_missed_walls) is on):
///    trace the beams not on a fused line to the first wall they meet at the updated
///    state, keep those whose point lies on it (1-dof chi-square gate), and fit each wall
///    no fused line lies on from its pieces of at least three consecutive beams, as
///    extraction fits a line; fuse each such line as in step 3
///    ([`ScanReport::refitted`]). Split-and-merge drops a wall seen only in short pieces
///    (behind clutter, at gaps, very oblique); its points still locate the robot.
///
/// For independent line noise, sequential fusion equals the paper's stacked update
/// (eq. 16) up to re-linearisation, and a line that no longer fits after the others have
/// corrected the pose is not forced in.
///
/// # Example
///
/// ```
/// use ekf_core::{Pose2, WheelSpeeds};
/// use lrf_lines::{LaserScan, LineMap, Localizer, LocalizerConfig};
/// use nalgebra::Matrix3;
///
/// let map = LineMap::from_json(
///     r#"{"format": "ekf-loc line map", "version": 1,
///         "segments": [{"start": [3, -2], "end": [3, 2]}, {"start": [-1, 1.5], "end": [3, 1.5]}]}"#,
/// )?;
/// let config = LocalizerConfig::default(); // the paper's robot, laser at the origin
/// let mut localizer = Localizer::new(config, Pose2::identity(), Matrix3::identity() * 1e-4, map)?;
///
/// localizer.predict_wheels(&WheelSpeeds::new(2.0, 2.0, 0.1)?)?;
/// let compass = localizer.update_compass(0.01)?;
/// assert!(compass.outcome.accepted && !compass.recovered);
///
/// // A 181-beam scan (1° steps, −90°…90°) of the wall 3 m ahead, 2.99 m from the laser.
/// let ranges: Vec<f32> = (0..181)
///     .map(|i| {
///         let bearing = (i as f64 - 90.0).to_radians();
///         let r = 2.99 / bearing.cos();
///         if r.abs() * bearing.sin().abs() < 1.4 { r as f32 } else { f32::INFINITY }
///     })
///     .collect();
/// let scan = LaserScan {
///     angle_min: -core::f64::consts::FRAC_PI_2,
///     angle_increment: 1.0_f64.to_radians(),
///     range_min: 0.05,
///     range_max: 8.0,
///     ranges: &ranges,
/// };
/// let report = localizer.update_scan(&scan)?;
/// assert_eq!((report.extracted, report.matched, report.fused), (1, 1, 1));
/// assert_eq!(localizer.last_fusions()[0].map, 0);
/// assert!((localizer.pose().x - 0.01).abs() < 0.005);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct Localizer {
    config: LocalizerConfig,
    ekf: Ekf<f64>,
    map: LineMap,
    /// The first-scan map's wall errors (empty for a given map).
    map_errors: MapErrors,
    build_map_from_next_scan: bool,
    /// The map is the first scan's lines, placed at the filter's pose then: it carries the
    /// filter's initial error, so it cannot judge the filter's heading against the compass.
    map_from_first_scan: bool,
    extractor: LineExtractor,
    /// Odometry travelled since the last measurement (scan, compass heading or position
    /// fix): the interval of the odometry noise ([`OdometryTravel`]).
    travel: OdometryTravel<f64>,
    matcher: Matcher,
    compass_gate: ChiSquareGate<f64>,
    compass_lockout: CompassLockout,
    compass_follow: CompassFollow,
    /// `χ²₁(FOLLOW_PROBABILITY)`, the follow test's threshold.
    follow_threshold: f64,
    /// The laser refused a compass recovery, and no reading has passed the gate since:
    /// the compass is suspect, and no recovery trusts it.
    compass_refuted: bool,
    lines: Vec<ObservedLine>,
    matches: MatchResult,
    fusions: Vec<LineFusion>,
    /// `χ²₁` at the matching's gate probability: whether a scan point lies on a wall.
    point_gate: f64,
    missed_walls: MissedWalls,
    /// Scratch: the beams of the pieces of a wall merged in step 3.
    merge_beams: Vec<Range<usize>>,
    /// The observed lines this scan's merges in step 3 joined to a matched line (their
    /// beams are not traced again in step 4).
    merged_lines: Vec<usize>,
    fused_lines: Vec<ObservedLine>,
}

impl Localizer {
    /// A localizer at `initial_pose` with covariance `initial_covariance` (3×3, `(x, y, θ)`)
    /// and a `map` in the same world frame. Fails, naming the config group and field, if a
    /// config value is out of range, or if the initial state is not finite or the
    /// covariance not symmetric positive definite.
    pub fn new(
        config: LocalizerConfig,
        initial_pose: Pose2<f64>,
        initial_covariance: Matrix3<f64>,
        map: LineMap,
    ) -> Result<Self, LocalizerError> {
        let ValidatedParts {
            compass_gate,
            matcher,
            extractor,
        } = config.validated_parts()?;
        let ekf = Ekf::new(initial_pose, initial_covariance).map_err(LocalizerError::Filter)?;
        let point_gate = ekf_core::chi_square_quantile(config.matching.gate_probability, 1)
            .map_err(|error| LocalizerError::Config {
                group: "matching",
                error,
            })?;
        Ok(Self {
            config,
            ekf,
            map,
            map_errors: MapErrors::default(),
            build_map_from_next_scan: false,
            map_from_first_scan: false,
            extractor,
            matcher,
            compass_gate,
            compass_lockout: CompassLockout::default(),
            compass_follow: CompassFollow::default(),
            follow_threshold: ekf_core::chi_square_quantile(FOLLOW_PROBABILITY, 1).map_err(
                |error| LocalizerError::Config {
                    group: "compass",
                    error,
                },
            )?,
            compass_refuted: false,
            travel: OdometryTravel::default(),
            lines: Vec::new(),
            matches: MatchResult::new(),
            fusions: Vec::new(),
            point_gate,
            missed_walls: MissedWalls::default(),
            merge_beams: Vec::new(),
            merged_lines: Vec::new(),
            fused_lines: Vec::new(),
        })
    }

    /// The paper's set-up (§III): no map yet; the first scan given to
    /// [`update_scan`](Self::update_scan) becomes the map, its lines placed in the world
    /// at the then current pose ⊕ laser mount ([`LineMap::from_scan`]). Later scans are
    /// matched against it.
    ///
    /// Each wall of that map is only as good as the pose it was placed from and the line
    /// it was fitted to, and that error stays the same however often the wall is seen
    /// again. The filter carries both parts:
    /// - the placement's error (the initial covariance at the first scan), shared by
    ///   every wall, is estimated with the pose; what is learnt of it moves the map
    ///   rigidly, so a compass turns the map into its frame and a position fix shifts it;
    /// - each wall's fit error (from the line's fit covariance) is a considered, not
    ///   estimated, parameter (Schmidt–Kalman; see [`ekf_core::Considered`]), carried
    ///   through its correlation with the state and the placement.
    ///
    /// A given map ([`Localizer::new`]) has no such model; its error is the matching's
    /// map noise, added to each line's `R` (which a first-scan map's lines get too).
    pub fn with_first_scan_map(
        config: LocalizerConfig,
        initial_pose: Pose2<f64>,
        initial_covariance: Matrix3<f64>,
    ) -> Result<Self, LocalizerError> {
        let mut localizer =
            Self::new(config, initial_pose, initial_covariance, LineMap::default())?;
        localizer.build_map_from_next_scan = true;
        localizer.map_from_first_scan = true;
        Ok(localizer)
    }

    /// Prediction from wheel speeds (paper eqs. 1–9) with the configured robot and wheel
    /// noise: `x⁻ = f(x, u)`, `P⁻ = A P Aᵀ + W Q Wᵀ`.
    pub fn predict_wheels(&mut self, speeds: &WheelSpeeds<f64>) -> Result<(), LocalizerError> {
        let (robot, noise) = (self.config.robot, self.config.wheel_noise);
        self.predict(|ekf| ekf.predict_wheels(&robot, speeds, &noise))
    }

    /// Prediction from an odometry delta `(Δs, Δθ)` with the configured odometry noise,
    /// applied over the interval since the last measurement, a scan, compass heading or
    /// position fix ([`OdometryTravel`]: the noise of an interval does not depend on how
    /// many odometry messages it took). With no measurement at all (dead reckoning) the
    /// interval is the whole run, and the proportional terms grow with the distance
    /// itself, as a systematic error does.
    pub fn predict_odometry(&mut self, motion: &Motion<f64>) -> Result<(), LocalizerError> {
        let noise = self.config.odometry_noise;
        let mut travel = self.travel;
        self.predict(|ekf| ekf.predict_odometry_in(motion, &noise, &mut travel))?;
        self.travel = travel;
        Ok(())
    }

    /// Runs a prediction that returns its transition Jacobian `A`, and tells the map's
    /// error model and the compass lock-out what it did.
    fn predict(
        &mut self,
        prediction: impl FnOnce(&mut Ekf<f64>) -> Result<Matrix3<f64>, ekf_core::Error>,
    ) -> Result<(), LocalizerError> {
        let (heading, p_theta) = (self.ekf.pose().theta, self.ekf.covariance()[(2, 2)]);
        let a = prediction(&mut self.ekf).map_err(LocalizerError::Filter)?;
        self.map_errors.predicted(&a);
        let (turned, variance) = (
            angle_diff(self.ekf.pose().theta, heading),
            self.ekf.covariance()[(2, 2)] - p_theta,
        );
        self.compass_lockout.predicted(turned, variance);
        self.compass_follow.predicted(turned, variance);
        Ok(())
    }

    /// Fuses a compass heading `φ` (rad, map frame; see
    /// [`ekf_core::heading_from_compass_bearing`] for raw bearings) with the configured
    /// variance, if its `NIS = ν² / S`, `ν = wrap(φ − θ)`, `S = P_θθ + σ²`, passes the 1-dof
    /// gate. A rejected heading leaves the state unchanged (`accepted == false`), unless
    /// it ends a gate lock-out: the [`recover_after`](CompassConfig::recover_after)-th
    /// rejected heading in a row, each agreeing with the one before once odometry's turn
    /// between them is taken out, with no laser line fused meanwhile (the test is in
    /// `compass_lockout.rs`). Such a run says the heading is further off than the filter
    /// allows; the recovery first adds that much heading error, and the position (and
    /// first-scan map placement) error that goes with it by the filter's correlations,
    /// so that the heading's NIS is at most 1, then fuses the heading without the gate
    /// (`recovered == true`).
    pub fn update_compass(&mut self, heading: f64) -> Result<CompassUpdate, LocalizerError> {
        self.update_compass_with_variance(heading, self.config.compass.variance)
    }

    /// As [`update_compass`](Self::update_compass), with this reading's own variance
    /// (rad²), e.g. a ROS `Imu`'s `orientation_covariance[8]`.
    pub fn update_compass_with_variance(
        &mut self,
        heading: f64,
        variance: f64,
    ) -> Result<CompassUpdate, LocalizerError> {
        let compass = Compass::new(heading, variance).map_err(LocalizerError::Filter)?;
        self.travel.reset();
        if !self
            .compass_follow
            .follows(heading, variance, self.follow_threshold)
        {
            // Stuck, or not measuring the heading: not fused, not part of a lock-out.
            let s = self.ekf.covariance()[(2, 2)] + variance;
            let innovation = angle_diff(heading, self.ekf.pose().theta);
            return Ok(CompassUpdate {
                outcome: UpdateOutcome {
                    accepted: false,
                    nis: innovation * innovation / s,
                    transition: Matrix3::identity(),
                },
                rejected_in_a_row: 0,
                recovered: false,
                refused_by_laser: false,
                not_following: true,
            });
        }
        let gate = self.compass_gate;
        let s = self.ekf.covariance()[(2, 2)] + variance;
        let outcome = self.update_state(&compass, Some(&gate))?;
        let mut lockout = self.compass_lockout;
        let mut update = CompassUpdate {
            outcome,
            rejected_in_a_row: 0,
            recovered: false,
            refused_by_laser: false,
            not_following: false,
        };
        if outcome.accepted {
            lockout.confirmed();
            self.compass_refuted = false;
        } else {
            // Rejected, so the state is as it was: `ν² = NIS · S`.
            let reading = Rejected {
                heading,
                variance,
                innovation_squared: outcome.nis * s,
            };
            update.rejected_in_a_row = lockout.rejected(&reading, &gate);
            let recover_after = self.config.compass.recover_after;
            if recover_after > 0 && update.rejected_in_a_row >= recover_after {
                if self.compass_refuted
                    || self.laser_refutes_recovery(&compass, reading.innovation_squared)
                {
                    self.compass_refuted = true;
                    update.refused_by_laser = true;
                    lockout.confirmed();
                    self.compass_lockout = lockout;
                    return Ok(update);
                }
                let fused = self.recover(&compass, reading.innovation_squared)?;
                // The NIS the heading had at the predicted state, past the gate.
                update.outcome = UpdateOutcome {
                    nis: outcome.nis,
                    ..fused
                };
                update.recovered = true;
                lockout.confirmed();
            }
        }
        self.compass_lockout = lockout;
        Ok(update)
    }

    /// Ends a compass lock-out with `compass`, whose innovation `ν` (given as `ν²`) the
    /// filter expected within `S = P_θθ + σ²`. The run of readings shows the heading further off than the
    /// filter allows, by an error the filter did not model, of variance
    /// `q = max(0, ν² − S)` (which makes the heading's NIS at most 1). Nothing says how
    /// the rest of the state moved with it but the filter's own correlations, so the
    /// error is added along the regression of the estimated errors on the heading's,
    /// `v = Cov(δx, θ) / P_θθ`: process noise `q v vᵀ`. The position keeps the share of
    /// the heading's correction it would have had, and the rest of the covariance is as
    /// it was. A first-scan map against which no line has been fused yet turns with the
    /// robot (its heading may be the error; see `MapErrors::heading_noise_added`). Then
    /// the heading is fused without the gate. On an error the state is as before.
    fn recover(
        &mut self,
        compass: &Compass<f64>,
        innovation_squared: f64,
    ) -> Result<UpdateOutcome<f64>, LocalizerError> {
        let (along_pose, q) = self.recovery_noise(compass, innovation_squared);
        let p_theta = self.ekf.covariance()[(2, 2)];
        self.atomically(|localizer| {
            localizer
                .ekf
                .add_process_noise(&(along_pose * along_pose.transpose() * q))?;
            localizer
                .map_errors
                .heading_noise_added(&along_pose, p_theta, q);
            localizer.fuse_state(compass, None)
        })
        .map_err(LocalizerError::Filter)
    }

    /// The direction `v = Cov(δx, θ) / P_θθ` and the variance `q = max(0, ν² − S)` of the
    /// error a recovery adds ([`recover`](Self::recover)).
    fn recovery_noise(
        &self,
        compass: &Compass<f64>,
        innovation_squared: f64,
    ) -> (Vector3<f64>, f64) {
        let p = self.ekf.covariance();
        let p_theta = p[(2, 2)];
        let q = (innovation_squared - p_theta - compass.variance).max(0.0);
        (p.column(2) / p_theta, q)
    }

    /// Whether the laser refutes a recovery with `compass`. Against a map, the last scan's
    /// lines are scored at the filter's pose and at the pose the recovery would give, as
    /// a relocalization scores its hypotheses ([`fit_poses`]). The recovery is refused
    /// if they fit the filter's pose at least [`RelocalizeParams::min_margin`] times
    /// better: the compass would override lines that side with the filter. A first-scan
    /// map was placed with the filter's own heading, so its lines side with the filter
    /// whatever its error: there the compass decides, as in the paper (a constant compass
    /// bias and a wrong initial heading look the same to it). A lock-out while the laser still agrees with the filter is the compass's
    /// fault (stuck, biased, a disturbed field), not the filter's. With no map or no lines
    /// there is nothing to judge by, and the recovery goes ahead.
    fn laser_refutes_recovery(&self, compass: &Compass<f64>, innovation_squared: f64) -> bool {
        if self.map_from_first_scan || self.map.is_empty() || self.lines.is_empty() {
            return false;
        }
        let (along_pose, q) = self.recovery_noise(compass, innovation_squared);
        let mut trial = self.ekf;
        let recovered = trial
            .add_process_noise(&(along_pose * along_pose.transpose() * q))
            .and_then(|()| trial.update_considering(compass, &Considered::none(), None));
        if recovered.is_err() {
            return false;
        }
        let params = RelocalizeParams::default();
        let poses = [self.ekf.pose(), trial.pose()];
        let fits = fit_poses(
            &self.lines,
            &self.map,
            &self.config.laser_mount,
            &poses,
            &params,
        );
        let better = |a: &Hypothesis, b: &Hypothesis| {
            a.inliers > 0 && a.score > 0.0 && a.score >= params.min_margin * b.score
        };
        better(&fits.fits[0], &fits.fits[1])
    }

    /// Fuses an absolute position `(x, y)` in the map frame (m) with covariance
    /// `covariance` (m²), e.g. a GPS fix projected about an origin: `h(x) = (x, y)`. With a
    /// `gate`, a position whose `NIS` fails the 2-dof test is rejected and the state
    /// left unchanged (`accepted == false`).
    pub fn update_position(
        &mut self,
        x: f64,
        y: f64,
        covariance: Matrix2<f64>,
        gate: Option<&ChiSquareGate<f64>>,
    ) -> Result<UpdateOutcome<f64>, LocalizerError> {
        let position = Position::new(x, y, covariance).map_err(LocalizerError::Filter)?;
        self.travel.reset();
        self.update_state(&position, gate)
    }

    /// Fuses a measurement of the state alone, and lets a first-scan map's placement take
    /// its share (see [`Localizer::with_first_scan_map`]). On an error the state is as
    /// before.
    fn update_state<const M: usize>(
        &mut self,
        measurement: &impl Measurement<f64, M>,
        gate: Option<&ChiSquareGate<f64>>,
    ) -> Result<UpdateOutcome<f64>, LocalizerError> {
        self.atomically(|localizer| localizer.fuse_state(measurement, gate))
            .map_err(LocalizerError::Filter)
    }

    /// [`update_state`](Self::update_state) without the way back: on an error the filter
    /// or the map's errors may be half updated.
    fn fuse_state<const M: usize>(
        &mut self,
        measurement: &impl Measurement<f64, M>,
        gate: Option<&ChiSquareGate<f64>>,
    ) -> Result<UpdateOutcome<f64>, ekf_core::Error> {
        let update = self
            .ekf
            .update_considering(measurement, &Considered::none(), gate)?;
        self.map_errors
            .state_measured(&update.innovation, &update.outcome, &mut self.map)?;
        Ok(update.outcome)
    }

    /// Runs `step` on the filter, the map and the map's errors; if it fails, puts them
    /// back as they were. Not to be nested: the map's errors keep one saved copy.
    fn atomically<R>(
        &mut self,
        step: impl FnOnce(&mut Self) -> Result<R, ekf_core::Error>,
    ) -> Result<R, ekf_core::Error> {
        let before = self.ekf;
        self.map_errors.save(&self.map);
        let result = step(self);
        if result.is_err() {
            self.ekf = before;
            self.map_errors.restore(&mut self.map);
        }
        result
    }

    /// One laser step: extract, match at the predicted state, fuse sequentially (see the
    /// type's documentation). Fails only on an invalid scan header or a non-finite
    /// result; the state is then as before the call.
    pub fn update_scan(&mut self, scan: &LaserScan<'_>) -> Result<ScanReport, LocalizerError> {
        self.update_scan_timed(scan, &mut ())
    }

    /// [`update_scan`](Self::update_scan), telling `clock` when each stage ends, so a
    /// caller with a clock (this crate has none) can time extraction, matching and the
    /// update separately.
    pub fn update_scan_timed(
        &mut self,
        scan: &LaserScan<'_>,
        clock: &mut impl StageClock,
    ) -> Result<ScanReport, LocalizerError> {
        clock.scan_started();
        self.travel.reset();
        self.fusions.clear();
        let extracted = self.extractor.extract(scan, &mut self.lines);
        clock.stage_done(ScanStage::Extraction);
        if let Err(e) = extracted {
            self.clear_matches();
            return Err(e.into());
        }
        let mut report = ScanReport {
            extracted: self.lines.len(),
            ..ScanReport::default()
        };
        if self.build_map_from_next_scan {
            let (map, sources) = LineMap::from_scan_with_sources(&self.lines, &self.sensor_pose())
                .map_err(LocalizerError::Filter)?;
            self.map_errors = MapErrors::of_first_scan(
                &map,
                &self.lines,
                &sources,
                &self.ekf.pose(),
                self.ekf.covariance(),
                &self.config.laser_mount,
            );
            self.map = map;
            self.build_map_from_next_scan = false;
            self.clear_matches();
            report.map_built = true;
            return Ok(report);
        }
        self.match_and_fuse(report, Some(scan), clock)
    }

    /// The laser step for lines already extracted (sensor frame, as
    /// [`last_lines`](Self::last_lines) gives them): match at the current state and fuse,
    /// as [`update_scan`](Self::update_scan) does after its extraction, but without the
    /// scan's points: no pieces of a wall are fitted together and no missed wall is
    /// fitted from points (`merged` and `refitted` stay 0). A loop-closure
    /// check refines a pose this way against a part of a map. Fails, leaving the filter as
    /// it was, on a line that is not finite or whose covariance is not positive definite.
    pub fn update_lines(&mut self, lines: &[ObservedLine]) -> Result<ScanReport, LocalizerError> {
        for line in lines {
            line.validate().map_err(LocalizerError::Filter)?;
        }
        self.travel.reset();
        self.fusions.clear();
        self.lines.clear();
        self.lines.extend_from_slice(lines);
        let report = ScanReport {
            extracted: lines.len(),
            ..ScanReport::default()
        };
        self.match_and_fuse(report, None, &mut ())
    }

    /// Matches [`last_lines`](Self::last_lines) against the map at the predicted state
    /// and fuses the matches (steps 2 and 3 of a scan update), then, given the scan, the
    /// walls its lines missed (step 4).
    fn match_and_fuse(
        &mut self,
        mut report: ScanReport,
        scan: Option<&LaserScan<'_>>,
        clock: &mut impl StageClock,
    ) -> Result<ScanReport, LocalizerError> {
        self.matcher.match_lines_with(
            &self.lines,
            &self.map,
            &self.map_errors,
            &self.ekf,
            &self.config.laser_mount,
            &mut self.matches,
        );
        clock.stage_done(ScanStage::Matching);
        report.matched = self.matches.matches().len();
        report.rejected = self.matches.rejections().len();
        let fused = self.atomically(|localizer| {
            localizer.fuse_matches(&mut report, scan.is_some())?;
            match scan {
                Some(scan) if localizer.refits(&report) => {
                    localizer.fuse_missed_walls(scan, &mut report)
                }
                _ => Ok(()),
            }
        });
        clock.stage_done(ScanStage::Update);
        if let Err(e) = fused {
            self.fusions.clear();
            return Err(LocalizerError::Filter(e));
        }
        if report.fused > 0 {
            // The laser agrees with the filter's heading: rejected compass readings are
            // the compass's trouble, not a lock-out.
            self.compass_lockout.confirmed();
        }
        Ok(report)
    }

    /// Step 3 of a scan update: fuses the matches in order, each re-linearised at the
    /// current state (and a first-scan map's wall moved to its current placement) and
    /// re-gated; counts and records what happened to each. Then the rest of the map
    /// follows the placement.
    fn fuse_matches(
        &mut self,
        report: &mut ScanReport,
        merge: bool,
    ) -> Result<(), ekf_core::Error> {
        self.merged_lines.clear();
        for i in 0..self.matches.matches().len() {
            let m = self.matches.matches()[i];
            let Some(line) = self.lines.get(m.observed).copied() else {
                continue;
            };
            let before = self.merged_lines.len();
            let merged = if merge {
                self.merged_pieces(m.observed, m.map)
            } else {
                None
            };
            // The joint line if it passes the gate; else (refused, or its update failed,
            // leaving the state as it was) the line alone, and the lines it would have
            // joined are not merged.
            let mut outcome = None;
            if let Some(merged) = merged {
                if let Ok(Some(o)) = self.fuse_line(m.map, &merged) {
                    outcome = o.accepted.then_some(o);
                }
            }
            if outcome.is_none() {
                self.merged_lines.truncate(before);
            }
            let pieces = self.merged_lines.len() - before;
            report.merged += pieces;
            let outcome = match outcome {
                Some(o) => o,
                None => match self.fuse_line(m.map, &line)? {
                    Some(o) => o,
                    None => continue,
                },
            };
            if outcome.accepted {
                report.fused += 1;
            } else {
                report.refused += 1;
            }
            self.fusions.push(LineFusion {
                observed: m.observed,
                map: m.map,
                nis: outcome.nis,
                accepted: outcome.accepted,
                merged: pieces,
            });
        }
        self.map_errors.move_walls(&mut self.map);
        Ok(())
    }

    /// The line fitted to the beams of observed line `observed` and of the lines whose
    /// best wall, `wall`, went to it (pieces of one wall that extraction kept apart, at a
    /// door or clutter) and are one line with it by extraction's merge test; the lines it
    /// joins are appended to `merged_lines`. `None` if there are none, or their points are
    /// not one straight line (see [`LineExtractor::fit_beams`]).
    fn merged_pieces(&mut self, observed: usize, wall: usize) -> Option<ObservedLine> {
        let line = self.lines.get(observed)?;
        let mut beams = core::mem::take(&mut self.merge_beams);
        beams.clear();
        let before = self.merged_lines.len();
        for r in self.matches.rejections() {
            let RejectReason::MapLineTaken { map, by } = r.reason else {
                continue;
            };
            let Some(piece) = self.lines.get(r.observed) else {
                continue;
            };
            if map == wall && by == observed && self.extractor.collinear(line, piece) {
                if let Some(pieces) = self.extractor.beams_of(r.observed) {
                    beams.extend_from_slice(pieces);
                    self.merged_lines.push(r.observed);
                }
            }
        }
        let merged = (self.merged_lines.len() > before)
            .then(|| {
                beams.extend_from_slice(self.extractor.beams_of(observed)?);
                beams.sort_unstable_by_key(|b| b.start);
                self.extractor.fit_beams(&beams)
            })
            .flatten();
        self.merge_beams = beams;
        merged
    }

    /// Whether step 4 runs after the lines of `report` were fused: when configured, and
    /// only once at least [`REFIT_AFTER_LINES`] lines agreed with the state, as a pose
    /// the scan's own lines do not confirm would find walls for its points where there
    /// are none.
    fn refits(&self, report: &ScanReport) -> bool {
        self.config.matching.refit_missed_walls && report.fused >= REFIT_AFTER_LINES
    }

    /// Step 4 of a scan update: the walls no fused line lies on that enough of the scan's
    /// points do (see `missed_walls.rs`), each fitted as a line and fused with the gate.
    fn fuse_missed_walls(
        &mut self,
        scan: &LaserScan<'_>,
        report: &mut ScanReport,
    ) -> Result<(), ekf_core::Error> {
        let mut missed = core::mem::take(&mut self.missed_walls);
        let mut fused_lines = core::mem::take(&mut self.fused_lines);
        fused_lines.clear();
        fused_lines.extend(
            self.fusions
                .iter()
                .filter(|f| f.accepted)
                .filter_map(|f| self.lines.get(f.observed).copied()),
        );
        fused_lines.extend(
            self.merged_lines
                .iter()
                .filter_map(|&i| self.lines.get(i).copied()),
        );
        let extraction = self.extractor.params();
        let (min_points, min_length) = (extraction.min_points, extraction.min_length);
        let at = Tracing {
            pose: self.ekf.pose(),
            covariance: self.ekf.covariance(),
            mount: self.config.laser_mount,
            range_var: extraction.range_sigma * extraction.range_sigma,
            map_var: self.config.matching.map_sigma_r * self.config.matching.map_sigma_r,
            gate: self.point_gate,
        };
        let fusions = &self.fusions;
        missed.find(
            scan,
            self.extractor.beam_directions(),
            &self.map,
            &at,
            &fused_lines,
            |w| fusions.iter().any(|f| f.accepted && f.map == w),
        );
        let mut result = Ok(());
        for k in 0..missed.len() {
            let Some((wall, runs)) = missed.get(k) else {
                continue;
            };
            let points: usize = runs.iter().map(Range::len).sum();
            if points < min_points {
                continue;
            }
            let Some(line) = self.extractor.fit_beams(runs) else {
                continue;
            };
            if line.length() < min_length {
                continue;
            }
            match self.fuse_line(wall, &line) {
                Ok(Some(outcome)) if outcome.accepted => report.refitted += 1,
                Ok(_) => {}
                Err(e) => {
                    result = Err(e);
                    break;
                }
            }
        }
        self.map_errors.move_walls(&mut self.map);
        self.missed_walls = missed;
        self.fused_lines = fused_lines;
        result
    }

    /// Fuses the observed `line` (sensor frame) as a sighting of wall `wall`, gated: a
    /// first-scan map's wall is first moved to the map's current placement, its error is
    /// considered, and the state's correlation with the walls is carried along; the noise
    /// is the line's plus the map's ([`MatchParams::line_noise`](crate::MatchParams::line_noise)).
    /// `None` if there is no such wall.
    fn fuse_line(
        &mut self,
        wall: usize,
        line: &ObservedLine,
    ) -> Result<Option<UpdateOutcome<f64>>, ekf_core::Error> {
        self.map_errors.move_wall(wall, &mut self.map);
        let Some(map_wall) = self.map.segments.get(wall) else {
            return Ok(None);
        };
        let model = LaserLine {
            observed: line.line,
            covariance: self.config.matching.line_noise(&line.covariance),
            map_line: map_wall.line,
            mount: self.config.laser_mount,
        };
        let gate = Some(self.matcher.gate());
        let pose = self.ekf.pose();
        let mount = &self.config.laser_mount;
        let considered = self
            .map_errors
            .considered(wall, &model.map_line, mount, &pose);
        let Some(considered) = considered else {
            return self.ekf.update(&model, gate).map(Some);
        };
        let update = self.ekf.update_considering(&model, &considered, gate)?;
        self.map_errors.line_fused(wall, &considered, &update)?;
        Ok(Some(update.outcome))
    }

    /// Empties the match result (after a scan that was not matched).
    fn clear_matches(&mut self) {
        self.matcher.match_lines(
            &[],
            &self.map,
            &self.ekf,
            &self.config.laser_mount,
            &mut self.matches,
        );
    }

    /// Searches the map for the robot's pose from the last scan's lines alone, within
    /// `window` ([`crate::relocalize()`]); the filter is left as it is.
    pub fn relocalize(
        &self,
        window: &SearchWindow,
        params: &RelocalizeParams,
    ) -> Option<Relocalization> {
        relocalize(
            &self.lines,
            &self.map,
            &self.config.laser_mount,
            window,
            params,
        )
    }

    /// Scores the last scan's lines at each of `poses` in the map, as
    /// [`relocalize`](Self::relocalize) scores its hypotheses ([`crate::fit_poses`]).
    pub fn fit_poses(&self, poses: &[Pose2<f64>], params: &RelocalizeParams) -> PoseFits {
        fit_poses(
            &self.lines,
            &self.map,
            &self.config.laser_mount,
            poses,
            params,
        )
    }

    /// Replaces the map (a map that grows, or a corrected one) and keeps the filter's
    /// state. The new map is a given map: a first-scan map's error model, which belongs to
    /// the walls it was built with, is dropped, and no scan builds a map any more.
    pub fn replace_map(&mut self, map: LineMap) {
        self.map = map;
        self.map_errors = MapErrors::default();
        self.build_map_from_next_scan = false;
        self.map_from_first_scan = false;
        self.clear_matches();
    }

    /// Restarts the filter at `pose` with `covariance` (after a relocalization): the
    /// state's history and a compass lock-out are forgotten; the map stays.
    pub fn reset(
        &mut self,
        pose: Pose2<f64>,
        covariance: Matrix3<f64>,
    ) -> Result<(), LocalizerError> {
        self.ekf = Ekf::new(pose, covariance).map_err(LocalizerError::Filter)?;
        self.compass_lockout = CompassLockout::default();
        self.travel.reset();
        Ok(())
    }

    /// The odometry travelled since the last measurement, over which the next odometry
    /// step's noise is taken.
    pub fn travel(&self) -> OdometryTravel<f64> {
        self.travel
    }

    /// The pose estimate `(x, y, θ)`.
    pub fn pose(&self) -> Pose2<f64> {
        self.ekf.pose()
    }

    /// The covariance `P` of `(x, y, θ)`.
    pub fn covariance(&self) -> &Matrix3<f64> {
        self.ekf.covariance()
    }

    /// Replaces the laser's mounting pose (e.g. once it is known from a log's
    /// `/tf_static`). Fails, leaving the old one, if it is not finite.
    pub fn set_laser_mount(&mut self, mount: Pose2<f64>) -> Result<(), LocalizerError> {
        self.config.laser_mount =
            mount
                .validated("laser mount")
                .map_err(|error| LocalizerError::Config {
                    group: "laser_mount",
                    error,
                })?;
        Ok(())
    }

    /// The laser's pose in the world: pose ⊕ laser mount. Observed lines and their end
    /// points map into the world with it.
    pub fn sensor_pose(&self) -> Pose2<f64> {
        self.ekf.pose().compose(&self.config.laser_mount)
    }

    /// The filter itself, for inspection.
    pub fn ekf(&self) -> &Ekf<f64> {
        &self.ekf
    }

    /// The map (empty until the first scan for [`with_first_scan_map`](Self::with_first_scan_map);
    /// such a map then moves rigidly as the filter learns where it was placed from).
    pub fn map(&self) -> &LineMap {
        &self.map
    }

    /// The configuration.
    pub fn config(&self) -> &LocalizerConfig {
        &self.config
    }

    /// The lines extracted from the last scan (sensor frame), indexed as in the matches.
    pub fn last_lines(&self) -> &[ObservedLine] {
        &self.lines
    }

    /// The association of the last scan's lines with the map, at the predicted state.
    pub fn last_matches(&self) -> &MatchResult {
        &self.matches
    }

    /// What the sequential update did with each match of the last scan, in fusion order.
    pub fn last_fusions(&self) -> &[LineFusion] {
        &self.fusions
    }
}

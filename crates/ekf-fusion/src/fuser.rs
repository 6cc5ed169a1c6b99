//! Fusing inputs that come in stamp order: motion predicts the state to its stamp, a
//! heading, a position or a scan is fused at its own stamp after the state is brought
//! there at the last motion rate, and the loss monitor checks every scan.

use crate::config::{FusionConfig, Mode, Tracking as TrackingMode};
use crate::consistency::ConsistencyMonitor;
use crate::counts::FusionCounts;
use crate::motion::{MotionClock, MotionStep};
use crate::tracking::{self, Tracking};
use crate::verification::{self, Verification, Verified};
use crate::wheels::{Contradiction, OdometryTracker, WheelTracker, JUMP_FIELD};
use crate::{FusionError, Input, Scan, Skip};
use alloc::vec::Vec;
use ekf_core::{ChiSquareGate, Pose2, UpdateOutcome};
use lrf_lines::{
    CompassUpdate, ExtractionError, LineMap, Localizer, LocalizerError, RelocalizeParams,
    ScanReport, StageClock,
};
use nalgebra::{Matrix3, Point2};

/// A motion reading's step over its interval `(t0, t1]`, and the contradiction between
/// its encoder angles and velocities if the velocities were used.
type StepOver = (MotionStep, u64, u64, Option<Contradiction>);

/// The kinds of measurement whose duplicates are caught ([`Fuser::duplicate`]).
#[derive(Debug, Clone, Copy)]
enum Measured {
    Heading = 0,
    Position = 1,
    Scan = 2,
}

/// What fusing one input did.
// A scan's outcome (with its predicted state) is a few hundred bytes more than the
// others': the value is returned once per input and never stored in bulk, and boxing it
// would allocate on every scan of an embedded loop.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
pub enum Fused {
    /// A motion reading: whether any of its interval was predicted through (nothing is
    /// when it ends before the state's time).
    Motion {
        /// Whether the state was predicted.
        predicted: bool,
    },
    /// A wheel reading whose encoder angles stood still against its velocities for
    /// [`crate::wheels::CONTRADICTED_READINGS`] readings: predicted from the velocities.
    MotionFromVelocities(Contradiction),
    /// A heading, fused or rejected by the gate.
    Heading {
        /// The heading (rad).
        heading: f64,
        /// The update.
        update: CompassUpdate,
    },
    /// A position fix, fused or rejected by the gate.
    Position(UpdateOutcome<f64>),
    /// A scan's update.
    Scan(ScanFused),
    /// A scan whose header the line extractor refused.
    ScanRefused(ExtractionError),
    /// A reference pose, handed back in stamp order.
    Reference(Pose2<f64>),
    /// An input the mode does not fuse (a scan without laser, a heading without compass).
    NotFused,
    /// A measurement stamped before the initial state: its time is already in it.
    BeforeStart,
    /// A reading that could not be used.
    Skipped(Skip),
}

/// What a scan's update did, with what the loss monitor made of it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ScanFused {
    /// The update that stands (after a relocalization, the one at the new pose).
    pub report: ScanReport,
    /// The state predicted to the scan's time, before its lines were fused (and before
    /// any relocalization at this scan).
    pub predicted: Option<Predicted>,
    /// A loss began at this scan.
    pub lost: Option<TrackingChange>,
    /// Tracking again by the scan's own lines after a declared loss.
    pub regained: Option<TrackingChange>,
    /// The filter was restarted at this pose, which the map search found and the scan
    /// verified.
    pub relocalized: Option<Verified>,
    /// The scan ended with the filter lost or unconfirmed: its pose is a guess.
    pub lost_after: bool,
    /// The motion source was silent before this scan (a motion gap, [`tracking`]): what
    /// the robot did meanwhile is not in the prediction. Reported whether or not loss
    /// detection is on.
    pub motion_gap: bool,
    /// An over-confident stretch began ([`crate::consistency`]).
    pub over_confident: bool,
}

/// The filter's state predicted to a scan's time by the motion alone.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Predicted {
    /// The pose.
    pub pose: Pose2<f64>,
    /// Its covariance.
    pub covariance: Matrix3<f64>,
}

/// A change of the tracking state, with the counts as they were when it happened.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TrackingChange {
    /// For a loss: whether a motion gap caused it (else scans with no line fused).
    pub motion_gap: bool,
    /// Losses so far.
    pub losses: u64,
    /// Scans spent lost before this one.
    pub scans_lost: u64,
}

/// The filter's state predicted ahead of what has been fused
/// ([`crate::TimedLocalizer::pose_now`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Forecast {
    /// The time it refers to (ns): the newest motion reading predicted through, or
    /// `fused_ns` if none was.
    pub t_ns: u64,
    /// The time of the fused state it was predicted from (ns).
    pub fused_ns: u64,
    /// The pose.
    pub pose: Pose2<f64>,
    /// Its covariance.
    pub covariance: Matrix3<f64>,
}

/// Fuses inputs given in stamp order (see the module documentation). The time-ordered
/// [`crate::TimedLocalizer`] puts them in that order; a caller whose inputs already are
/// in order can use this directly.
#[derive(Debug, Clone)]
pub struct Fuser {
    mode: Mode,
    start_ns: u64,
    localizer: Localizer,
    clock: MotionClock,
    wheels: WheelTracker,
    odometry: OdometryTracker,
    position_gate: ChiSquareGate<f64>,
    tracking: Tracking,
    consistency: ConsistencyMonitor,
    counts: FusionCounts,
    /// Stamps of the last heading, position and scan fused (see [`Measured`]).
    last_measured: [Option<u64>; 3],
}

impl Fuser {
    /// A filter at `initial` with covariance `p0`, referring to `start_ns` (motion before
    /// it is already in the initial pose), localizing in `map`, or in the first scan's
    /// lines if `None` (the paper's mode). Fails on a configuration
    /// [`FusionConfig::validate`] refuses.
    pub fn new(
        config: &FusionConfig,
        initial: Pose2<f64>,
        p0: Matrix3<f64>,
        start_ns: u64,
        map: Option<LineMap>,
    ) -> Result<Self, FusionError> {
        config.validate()?;
        let tracking = match (config.tracking, map.is_some()) {
            (TrackingMode::Off, _) => Tracking::new(false),
            (_, false) => return Err(FusionError::TrackingNeedsMap),
            (TrackingMode::FromInitialPose, true) => Tracking::new(true),
            (TrackingMode::Global, true) => Tracking::global(),
        };
        let localizer_config = config.localizer.clone();
        let localizer = match map {
            Some(map) => Localizer::new(localizer_config, initial, p0, map)?,
            None => Localizer::with_first_scan_map(localizer_config, initial, p0)?,
        };
        let position_gate = ChiSquareGate::from_probability(config.position_gate_probability, 2)
            .map_err(|error| LocalizerError::Config {
                group: "gps",
                error,
            })?;
        Ok(Self {
            mode: config.mode,
            start_ns,
            localizer,
            clock: MotionClock::starting_at(start_ns),
            wheels: WheelTracker::new(config.max_wheel_turns_per_s),
            odometry: OdometryTracker::default(),
            position_gate,
            tracking,
            consistency: ConsistencyMonitor::default(),
            counts: FusionCounts::default(),
            last_measured: [None; 3],
        })
    }

    /// Which measurements it fuses.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The filter, its map and what the last scan's lines did.
    pub fn localizer(&self) -> &Localizer {
        &self.localizer
    }

    /// The filter, to change its map or restart it at a corrected pose between inputs
    /// (a map that grows, a loop closure). The tracking monitor is not told: use it with
    /// tracking off, or where a change of map or pose is not a loss or a recovery.
    pub fn localizer_mut(&mut self) -> &mut Localizer {
        &mut self.localizer
    }

    /// What has been fused, counted.
    pub fn counts(&self) -> &FusionCounts {
        &self.counts
    }

    /// Counts an input that came more than the lag late.
    pub(crate) fn count_too_late(&mut self) {
        self.counts.too_late += 1;
    }

    /// Scans the filter had been lost for at the last scan (0: tracking).
    pub fn lost_for(&self) -> u32 {
        self.tracking.lost_for
    }

    /// The time the fused state refers to (ns); `None` until a motion step was fused.
    pub fn state_ns(&self) -> Option<u64> {
        self.clock.state_ns()
    }

    /// Fuses `input` at `stamp_ns`, telling `clock` when a scan update's stages end.
    pub fn fuse(
        &mut self,
        stamp_ns: u64,
        input: &Input,
        clock: &mut impl StageClock,
    ) -> Result<Fused, FusionError> {
        match input {
            Input::WheelAngles { .. } | Input::WheelVelocities { .. } | Input::OdometryPose(_) => {
                self.motion(stamp_ns, input)
            }
            Input::Heading { heading, variance } => self.heading(stamp_ns, *heading, *variance),
            Input::Position { x, y, covariance } => {
                if stamp_ns < self.start_ns {
                    return Ok(Fused::BeforeStart);
                }
                if let Some(duplicate) = self.duplicate(Measured::Position, stamp_ns) {
                    return Ok(duplicate);
                }
                self.catch_up(stamp_ns)?;
                let outcome = self.localizer.update_position(
                    *x,
                    *y,
                    *covariance,
                    Some(&self.position_gate),
                )?;
                let counts = &mut self.counts.positions;
                if outcome.accepted {
                    counts.accepted += 1;
                } else {
                    counts.rejected += 1;
                }
                Ok(Fused::Position(outcome))
            }
            Input::Scan(scan) => self.scan(stamp_ns, scan, clock),
            Input::Reference(pose) => Ok(Fused::Reference(*pose)),
        }
    }

    /// The step a motion reading makes over its interval `(t0, t1]`, from `wheels` and
    /// `odometry` (this fuser's trackers, or copies for a forecast).
    fn step_of(
        wheels: &mut WheelTracker,
        odometry: &mut OdometryTracker,
        stamp_ns: u64,
        input: &Input,
    ) -> Option<Result<StepOver, Skip>> {
        let step = match input {
            Input::WheelAngles {
                left,
                right,
                velocities,
            } => wheels
                .angles(stamp_ns, *left, *right, *velocities)
                .map(|(s, seen)| {
                    let (step, t0, t1) = MotionStep::wheels_until(s, stamp_ns);
                    (step, t0, t1, seen)
                }),
            Input::WheelVelocities { left, right } => {
                wheels.velocities(stamp_ns, *left, *right).map(|s| {
                    let (step, t0, t1) = MotionStep::wheels_until(s, stamp_ns);
                    (step, t0, t1, None)
                })
            }
            Input::OdometryPose(pose) => odometry
                .motion(stamp_ns, pose)
                .map(|(m, t0)| (MotionStep::Odometry(m), t0, stamp_ns, None)),
            _ => return None,
        };
        Some(step)
    }

    fn motion(&mut self, stamp_ns: u64, input: &Input) -> Result<Fused, FusionError> {
        self.tracking.motion(stamp_ns);
        let Some(step) = Self::step_of(&mut self.wheels, &mut self.odometry, stamp_ns, input)
        else {
            return Ok(Fused::NotFused);
        };
        let (step, t0, t1, contradiction) = match step {
            Ok(step) => step,
            Err(skip) => {
                if matches!(skip, Skip::Implausible { field, .. } if field == JUMP_FIELD) {
                    // Where the robot went is unknown: the laser decides at the next scan.
                    self.tracking.motion_jumped = true;
                }
                return Ok(Fused::Skipped(skip));
            }
        };
        // Only the part of the interval after the time the state refers to.
        let Some(part) = self.clock.advance(step, t0, t1) else {
            return Ok(Fused::Motion { predicted: false });
        };
        self.predict(part)?;
        self.counts.motion_steps += 1;
        Ok(match contradiction {
            Some(seen) => {
                self.counts.wheel_velocities_used += 1;
                Fused::MotionFromVelocities(seen)
            }
            None => Fused::Motion { predicted: true },
        })
    }

    /// Predicts the filter through one motion step.
    fn predict(&mut self, step: MotionStep) -> Result<(), FusionError> {
        match step {
            MotionStep::Wheels(s) => self.localizer.predict_wheels(&s)?,
            MotionStep::Odometry(m) => self.localizer.predict_odometry(&m)?,
        }
        let config = self.localizer.config();
        if let Some(pending) = self.tracking.verification.as_mut() {
            if pending.predict(step, config).is_err() {
                // A candidate the motion model cannot carry: the verification ends, and
                // the next lost scan searches again.
                self.tracking.verification = None;
            }
        }
        Ok(())
    }

    /// A measurement stamped as the previous one of its kind: a duplicated message (a
    /// sensor does not measure twice at one instant), skipped rather than fused twice,
    /// which would count its information twice.
    fn duplicate(&mut self, kind: Measured, stamp_ns: u64) -> Option<Fused> {
        let previous = self.last_measured[kind as usize].replace(stamp_ns);
        (previous == Some(stamp_ns)).then_some(Fused::Skipped(Skip::TimeNotIncreasing {
            previous_ns: stamp_ns,
            stamp_ns,
        }))
    }

    /// Brings the state to `t_ns` before a measurement is fused there
    /// ([`MotionClock::extrapolate`]).
    fn catch_up(&mut self, t_ns: u64) -> Result<(), FusionError> {
        match self.clock.extrapolate(t_ns) {
            Some(step) => self.predict(step),
            None => Ok(()),
        }
    }

    fn heading(
        &mut self,
        stamp_ns: u64,
        heading: f64,
        variance: Option<f64>,
    ) -> Result<Fused, FusionError> {
        if !self.mode.uses_compass() {
            return Ok(Fused::NotFused);
        }
        if stamp_ns < self.start_ns {
            return Ok(Fused::BeforeStart);
        }
        if let Some(duplicate) = self.duplicate(Measured::Heading, stamp_ns) {
            return Ok(duplicate);
        }
        self.catch_up(stamp_ns)?;
        let variance = variance.unwrap_or(self.localizer.config().compass.variance);
        let update = self
            .localizer
            .update_compass_with_variance(heading, variance)?;
        let counts = &mut self.counts.compass;
        if update.outcome.accepted {
            counts.accepted += 1;
            counts.recovered += u64::from(update.recovered);
        } else {
            counts.rejected += 1;
            counts.refused_by_laser += u64::from(update.refused_by_laser);
            counts.not_following += u64::from(update.not_following);
        }
        Ok(Fused::Heading { heading, update })
    }

    fn scan(
        &mut self,
        stamp_ns: u64,
        scan: &Scan,
        clock: &mut impl StageClock,
    ) -> Result<Fused, FusionError> {
        self.counts.lines.scans += 1;
        if stamp_ns < self.start_ns {
            return Ok(Fused::BeforeStart);
        }
        if !self.mode.uses_laser() {
            return Ok(Fused::NotFused);
        }
        if let Some(duplicate) = self.duplicate(Measured::Scan, stamp_ns) {
            return Ok(duplicate);
        }
        self.catch_up(stamp_ns)?;
        let predicted = Predicted {
            pose: self.localizer.pose(),
            covariance: *self.localizer.covariance(),
        };
        let report = match self.localizer.update_scan_timed(&scan.as_scan(), clock) {
            Ok(r) => r,
            Err(LocalizerError::Extraction(e)) => return Ok(Fused::ScanRefused(e)),
            Err(e) => return Err(e.into()),
        };
        let gap = self.tracking.gap_before_scan(stamp_ns);
        let mut fused = ScanFused {
            report,
            predicted: Some(predicted),
            motion_gap: gap,
            ..ScanFused::default()
        };
        self.check_tracking(scan, stamp_ns, gap, &mut fused)?;
        if self.tracking.lost_for > 0 {
            self.counts.tracking.scans_lost += 1;
            fused.lost_after = true;
        }
        let accepted = self
            .localizer
            .last_fusions()
            .iter()
            .filter(|f| f.accepted)
            .map(|f| f.nis);
        fused.over_confident = self
            .consistency
            .scan(accepted, &mut self.counts.consistency);
        let (l, r) = (&mut self.counts.lines, &fused.report);
        l.scans_used += 1;
        l.extracted += r.extracted as u64;
        l.matched += r.matched as u64;
        l.rejected += r.rejected as u64;
        l.fused += r.fused as u64;
        l.refused += r.refused as u64;
        l.refitted += r.refitted as u64;
        l.merged += r.merged as u64;
        Ok(Fused::Scan(fused))
    }

    /// The loss monitor after a scan's update ([`tracking`]): on a motion gap, while lost,
    /// or while the heading is less certain than the search resolves, searches the map
    /// and restarts the filter at a verified pose. A search made while lost, with
    /// odometry since the scan before, only nominates candidates, which the next scans
    /// judge ([`crate::verification`]); after a motion gap, or for a check of a tracked
    /// estimate, the search's own scan decides. Leaves in `fused.report` the report of
    /// the update that stands.
    fn check_tracking(
        &mut self,
        scan: &Scan,
        now: u64,
        gap: bool,
        fused: &mut ScanFused,
    ) -> Result<(), FusionError> {
        if !self.tracking.enabled {
            return Ok(());
        }
        let report = fused.report;
        let lost_now = self.tracking.scan_fused(report.extracted, report.fused);
        let params = RelocalizeParams::default();
        let uncertain = tracking::uncertain(self.localizer.covariance(), &params);
        if gap {
            self.tracking.verification = None;
        }
        let fresh = self.tracking.lost_for == 0;
        // A loss begins on a motion gap or unfused scans while tracking, or while
        // unconfirmed without a declared loss (after a refused check).
        if (fresh || !self.tracking.declared) && (gap || lost_now) {
            self.tracking.declared = true;
            let counts = &mut self.counts.tracking;
            counts.losses += 1;
            counts.motion_gaps += u64::from(gap);
            fused.lost = Some(TrackingChange {
                motion_gap: gap,
                losses: counts.losses,
                scans_lost: counts.scans_lost,
            });
        } else if fresh {
            if !uncertain {
                return Ok(());
            }
        } else if !gap && !self.tracking.unlocked && self.fused_lines_fix_position(&params) {
            // Regained by tracking alone.
            self.confirm(fused);
            return Ok(());
        }
        let verify = !gap && (lost_now || self.tracking.lost_for > 0);
        if let Some(mut pending) = self.tracking.verification.take() {
            if pending.add_scan(&self.localizer, &params).is_err() {
                // A candidate the scan cannot restart (a non-finite pose): refused.
                self.counts.tracking.refused += 1;
                self.tracking.still_lost();
                return Ok(());
            }
            if !pending.done() {
                self.tracking.verification = Some(pending);
                self.tracking.still_lost();
                return Ok(());
            }
            let Some(won) = pending.verdict(&params) else {
                self.counts.tracking.refused += 1;
                self.tracking.still_lost();
                return Ok(());
            };
            return self.restart_at(scan, now, won, &params, fused, true);
        }
        let pose = self.localizer.pose();
        let cov = self.localizer.covariance();
        let window = self
            .tracking
            .window(Point2::new(pose.x, pose.y), cov[(0, 0)] + cov[(1, 1)]);
        self.counts.tracking.searches += 1;
        let found = self.localizer.relocalize(&window, &params);
        if verify {
            match found.filter(|f| f.explains_scan(&params)) {
                Some(found) => {
                    let candidates =
                        Verification::start(&found, &params).map_err(LocalizerError::Filter)?;
                    self.tracking.verification = Some(candidates);
                }
                None => self.counts.tracking.refused += 1,
            }
            self.tracking.still_lost();
            return Ok(());
        }
        let Some(found) = found.filter(|r| r.is_unambiguous(&params)) else {
            self.counts.tracking.refused += 1;
            self.tracking.still_lost();
            return Ok(());
        };
        let won = Verified {
            pose: found.best.pose,
            covariance: verification::restart_covariance(&params),
            inliers: found.best.inliers,
            score: found.best.score,
            runner_up: found.runner_up,
        };
        // After a motion gap one scan placed the robot and nothing checks it yet.
        self.restart_at(scan, now, won, &params, fused, !gap)
    }

    /// Restarts the filter at the pose a search found (`won`) unless the estimate is
    /// already there, and fuses the scan again: kept if at least
    /// [`tracking::MIN_VERIFIED_LINES`] lines fuse, otherwise the filter is put back.
    ///
    /// A `confirmed` pose (verified over several scans, or a check of an estimate the
    /// filter still trusted) ends the loss. One scan's answer after a motion gap does
    /// not: the filter restarts there but stays lost until a scan tracked from it by the
    /// motion model fixes the position ([`tracking::fix_position`]). A search that puts
    /// the robot where the estimate already was confirms it, unless the filter was
    /// already lost (that estimate is not a tracked one either).
    fn restart_at(
        &mut self,
        scan: &Scan,
        now: u64,
        won: Verified,
        params: &RelocalizeParams,
        fused: &mut ScanFused,
        confirmed: bool,
    ) -> Result<(), FusionError> {
        let best = won.pose;
        if !params.elsewhere(&best, &self.localizer.pose()) {
            // The estimate is where the search puts it: confirmed, unless both are one
            // scan's word (an estimate that was itself a single scan's answer).
            if confirmed || self.tracking.lost_for == 0 {
                self.confirm(fused);
            } else {
                self.tracking.unconfirmed();
            }
            return Ok(());
        }
        let saved = self.localizer.clone();
        self.localizer.reset(best, won.covariance)?;
        let verified = match self.localizer.update_scan(&scan.as_scan()) {
            Ok(r) if r.fused >= tracking::MIN_VERIFIED_LINES => Some(r),
            _ => None,
        };
        let counts = &mut self.counts.tracking;
        match verified {
            Some(r) => {
                counts.relocalizations += 1;
                if counts.first_relocalizations_ns.len() < 10 {
                    counts.first_relocalizations_ns.push(now);
                }
                fused.report = r;
                fused.relocalized = Some(won);
                if confirmed {
                    self.confirm(fused);
                } else {
                    self.tracking.unconfirmed();
                }
            }
            None => {
                self.localizer = saved;
                counts.refused += 1;
                self.tracking.still_lost();
            }
        }
        Ok(())
    }

    /// The filter's pose is confirmed: tracking again. A declared loss that ends without
    /// a relocalization at this scan (by tracking alone, or a search that found the
    /// estimate where it was) is reported as regained.
    fn confirm(&mut self, fused: &mut ScanFused) {
        let declared = self.tracking.declared;
        self.tracking.locked(&mut self.counts.tracking);
        self.tracking.verification = None;
        if declared && fused.relocalized.is_none() {
            let counts = &self.counts.tracking;
            fused.regained = Some(TrackingChange {
                motion_gap: false,
                losses: counts.losses,
                scans_lost: counts.scans_lost,
            });
        }
    }

    /// Whether the last scan's fused lines fix the position ([`tracking::fix_position`]).
    fn fused_lines_fix_position(&self, params: &RelocalizeParams) -> bool {
        let lines = self.localizer.last_lines();
        let normals: Vec<f64> = self
            .localizer
            .last_fusions()
            .iter()
            .filter(|f| f.accepted)
            .filter_map(|f| lines.get(f.observed).map(|l| l.line.beta))
            .collect();
        tracking::fix_position(&normals, params)
    }

    /// The fused state predicted through `motion` (motion readings in stamp order, each
    /// after the last one fused), as fusing them would predict it; the fuser is left as
    /// it is. Readings it would skip are skipped. `None` until a motion step has been
    /// fused: before that the state has no time.
    pub fn forecast<'m>(
        &self,
        motion: impl IntoIterator<Item = (u64, &'m Input)>,
    ) -> Result<Option<Forecast>, FusionError> {
        let Some(fused_ns) = self.clock.state_ns() else {
            return Ok(None);
        };
        let (mut ekf, mut travel) = (*self.localizer.ekf(), self.localizer.travel());
        let (mut clock, mut wheels, mut odometry) =
            (self.clock, self.wheels.clone(), self.odometry.clone());
        let config = self.localizer.config();
        let mut t_ns = fused_ns;
        for (stamp, input) in motion {
            let Some(Ok((step, t0, t1, _))) =
                Self::step_of(&mut wheels, &mut odometry, stamp, input)
            else {
                continue;
            };
            if let Some(part) = clock.advance(step, t0, t1) {
                part.predict(&mut ekf, config, &mut travel)
                    .map_err(LocalizerError::Filter)?;
            }
            t_ns = t_ns.max(stamp);
        }
        Ok(Some(Forecast {
            t_ns,
            fused_ns,
            pose: ekf.pose(),
            covariance: *ekf.covariance(),
        }))
    }
}

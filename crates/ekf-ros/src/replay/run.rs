//! The replay loop: messages turned into the time-ordered localizer's inputs, and what
//! it did with them written to the sinks (the trajectory, the output bag, the summary).

use super::events::{self, ReplayEvent};
use super::inputs::{
    self, gps_position, heading_from_imu, heading_from_magnetic_field, planar, wheel_input,
};
use super::outputs::OutputBag;
use super::summary::{self, ReplaySummary};
use super::{laser_mount, load_map, reference_pose, sink, stamps};
use super::{Preamble, ReplayError, ReplayOptions, ReplayOutcome, ScanHook};
use crate::config::Config;
use crate::mcap_io::{BagMessage, ChannelInfo, ReadError};
use crate::ros2::diagnostic_msgs::DiagnosticStatus;
use crate::ros2::sensor_msgs::JointState;
use crate::ros2::AnyMessage;
use crate::trajectory::StampedPose;
use ekf_core::Pose2;
use ekf_fusion::{
    consistency, Forecast, Fused, Fuser, Input, Scan, ScanFused, Skip, Step, TimedLocalizer,
    Tracking, TrackingChange,
};
use lrf_lines::{ScanStage, StageClock};
use nalgebra::Matrix3;
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

/// Times the scan stages with a monotonic clock.
struct StageTimer {
    last: Instant,
    stages: [summary::LatencyHistogram; 3],
}

impl StageClock for StageTimer {
    fn scan_started(&mut self) {
        self.last = Instant::now();
    }

    fn stage_done(&mut self, stage: ScanStage) {
        let now = Instant::now();
        let us = now.duration_since(self.last).as_secs_f64() * 1e6;
        self.last = now;
        let i = match stage {
            ScanStage::Extraction => 0,
            ScanStage::Matching => 1,
            ScanStage::Update => 2,
        };
        self.stages[i].record(us);
    }
}

/// Least log time between two `ekf/input` diagnostics of the same check (ns).
const FLAG_DIAGNOSTICS_EVERY_NS: u64 = 1_000_000_000;

/// Compass readings in a row that do not follow the robot's turns before a warning says
/// so (a single one is an outlier).
const NOT_FOLLOWING_WARNED_AFTER: u32 = 3;

/// What a topic's messages are to the filter ([`Run::role`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Motion,
    Scan,
    Compass,
    Fix,
    Reference,
}

/// A heading reading as an input.
fn heading_input(heading: Result<inputs::Heading, Skip>) -> Result<Input, Skip> {
    heading.map(|h| Input::Heading {
        heading: h.heading,
        variance: h.variance,
    })
}

/// What a held input carries for its report: the channel it came on and its log time
/// (warnings name the log time; the input is fused at its stamp).
#[derive(Debug, Clone)]
struct Tag {
    channel: Arc<ChannelInfo>,
    log_time: u64,
}

/// The state of one replay loop: the time-ordered localizer, its outputs, and the
/// conversion of messages into its inputs. `replay` drives it over a log; `ekf live` over
/// messages it makes from devices and records, so a replay of the recording repeats it
/// exactly.
pub struct Run<'a> {
    config: &'a Config,
    log: String,
    use_joints: bool,
    localizer: TimedLocalizer<Tag>,
    out: Option<OutputBag>,
    pub(super) summary: ReplaySummary,
    poses: sink::PoseSink,
    timer: StageTimer,
    map_written: bool,
    /// The last wheel reading was predicted from its velocities (a stretch is warned
    /// about once).
    wheels_contradicted: bool,
    /// Compass readings in a row that did not follow the robot's turns.
    compass_not_following: u32,
    /// Events and lost scans, if trajectories are kept.
    events: Option<events::EventLog>,
    /// Log time of the last `ekf/input` diagnostics written per check.
    flagged_at: HashMap<&'static str, u64>,
    /// What each fused scan is handed to, if anything.
    hook: Option<&'a mut dyn ScanHook>,
}

impl<'a> Run<'a> {
    /// Sets up the filter (laser mount, initial state, map) and creates the outputs.
    /// Inputs are held back by `max_lag_ns` to be fused in stamp order
    /// ([`TimedLocalizer`]); 0 fuses each as it comes (for inputs already in order).
    pub fn start(
        config: &'a Config,
        options: &ReplayOptions,
        preamble: &Preamble,
        use_joints: bool,
        log_name: &str,
        motion_topic: &str,
        max_lag_ns: u64,
    ) -> Result<Self, ReplayError> {
        let t = &config.topics;
        let mut summary = ReplaySummary {
            log: log_name.to_owned(),
            mode: options.mode.name().into(),
            motion_topic: motion_topic.to_owned(),
            ..ReplaySummary::default()
        };

        // Laser mount: tf_static, else the configuration.
        let mut fusion = config.fusion(options.mode);
        let (mount, source) = laser_mount(preamble, config)?;
        fusion.localizer.laser_mount = mount;
        summary.laser_mount_source = source.into();
        summary.laser_mount = [mount.x, mount.y, mount.theta];
        let tf_without_scanner = !preamble.transforms.is_empty() && preamble.scan_frame.is_some();
        if source == "config" && config.laser.mount_from_tf_static && tf_without_scanner {
            // As robot_localization warns when a transform it needs is missing: the log
            // has static transforms, just not the one to the scanner.
            summary.notes.push(format!(
                "{} has transforms, but none from {} to the scans' frame {}: the laser mount \
                 comes from localizer.laser_mount",
                t.tf_static,
                config.laser.base_frame,
                preamble.scan_frame.as_deref().unwrap_or_default()
            ));
        }

        // Initial state.
        if options.global && options.map.is_none() {
            return Err(ReplayError::GlobalNeedsMap);
        }
        fusion.tracking = match (options.global, options.map.is_some()) {
            (true, _) => Tracking::Global,
            (false, true) => Tracking::FromInitialPose,
            (false, false) => Tracking::Off,
        };
        let (start_ns, initial) = if options.init_from_truth && !options.global {
            let (t0, pose) = preamble
                .first_reference
                .ok_or_else(|| ReplayError::NoReference {
                    log: log_name.to_owned(),
                    topic: t.ground_truth.clone(),
                })?;
            (t0, pose)
        } else {
            let i = &config.initial;
            (0, Pose2::new(i.x, i.y, i.theta))
        };
        let (sxy, sth) = (config.initial.sigma_xy, config.initial.sigma_theta);
        let p0 = Matrix3::from_diagonal(&nalgebra::Vector3::new(sxy * sxy, sxy * sxy, sth * sth));

        let map = match &options.map {
            Some(path) => {
                summary.map = path.display().to_string();
                Some(load_map(path)?)
            }
            None => {
                summary.map = "first scan".into();
                None
            }
        };
        let fuser = Fuser::new(&fusion, initial, p0, start_ns, map)?;
        summary.map_segments = fuser.localizer().map().len();

        let out = options
            .out_mcap
            .as_deref()
            .map(OutputBag::create)
            .transpose()?;
        let mut run = Run {
            config,
            log: log_name.to_owned(),
            use_joints,
            localizer: TimedLocalizer::new(fuser, max_lag_ns),
            out,
            summary,
            poses: sink::PoseSink::new(options.tum.as_deref(), options.keep_trajectories)?,
            timer: StageTimer {
                last: Instant::now(),
                stages: Default::default(),
            },
            map_written: false,
            wheels_contradicted: false,
            compass_not_following: 0,
            events: options.keep_trajectories.then(events::EventLog::default),
            flagged_at: HashMap::new(),
            hook: None,
        };
        if let Some(out) = run.out.as_mut() {
            if options.map.is_some() {
                out.map(start_ns, run.localizer.fuser().localizer().map())?;
                run.map_written = true;
            }
        }
        Ok(run)
    }

    /// Hands every fused scan to `hook` ([`ScanHook`]) from now on.
    pub fn with_hook(mut self, hook: &'a mut dyn ScanHook) -> Self {
        self.hook = Some(hook);
        self
    }

    /// The time-ordered localizer's fuser: the filter, its map and the counts.
    pub fn fuser(&self) -> &Fuser {
        self.localizer.fuser()
    }

    /// The filter.
    pub fn filter(&self) -> &lrf_lines::Localizer {
        self.localizer.fuser().localizer()
    }

    /// The output bag, when there is one (live mode records its raw messages into it).
    pub fn output(&mut self) -> Option<&mut OutputBag> {
        self.out.as_mut()
    }

    /// Finishes every output, whatever happened before, and returns the results with
    /// `failure` (the error that ended the loop, if any). Inputs still held are not fused:
    /// [`fuse_held`](Self::fuse_held) does that.
    pub fn finish(
        self,
        started: Instant,
        failure: Option<ReplayError>,
    ) -> Result<ReplayOutcome, ReplayError> {
        let Run {
            poses,
            timer,
            out,
            localizer,
            mut summary,
            events,
            ..
        } = self;
        let events = events.unwrap_or_default();
        let fuser = localizer.fuser();
        let counts = fuser.counts();
        summary.motion_steps = counts.motion_steps;
        summary.lines = counts.lines;
        summary.compass = counts.compass;
        summary.gps = counts.positions;
        summary.tracking = counts.tracking.clone();
        summary.tracking.lost_at_end = fuser.lost_for();
        summary.consistency = counts.consistency.clone();
        summary.too_late = counts.too_late;
        // Finish both outputs, then report the first error.
        let bag_finished = out.map_or(Ok(()), OutputBag::finish);
        let poses = poses.finish()?;
        bag_finished?;
        let map = fuser.localizer().map().clone();
        summary.map_segments = map.len();
        let [ext, mat, upd] = &timer.stages;
        summary.timings = summary::Timings {
            extraction: ext.timing(),
            matching: mat.timing(),
            update: upd.timing(),
        };
        summary.poses_written = poses.written;
        summary.accuracy = poses.accuracy.map(|a| summary::Accuracy {
            matched_poses: a.matched,
            position_rmse_m: a.position_rmse,
            position_median_m: a.position_median,
            position_p95_m: a.position_p95,
            position_max_m: a.position_max,
            share_over_half_m: a.share_over_half_m,
            share_over_1m: a.share_over_1m,
            heading_rmse_deg: a.heading_rmse.to_degrees(),
        });
        summary.wall_time_s = started.elapsed().as_secs_f64();
        let kept = poses.kept.unwrap_or_default();
        Ok(ReplayOutcome {
            summary,
            trajectory: kept.estimate,
            covariances: kept.covariances,
            reference: kept.reference,
            lost_scans_ns: events.lost_scans,
            events: events.events,
            map,
            failure,
        })
    }

    /// A message skipped or flagged by `check`: counted and warned about in the summary,
    /// and an `ekf/input` status on `/ekf/diagnostics` with the count so far (the first
    /// of each check, then at most one a second of log time).
    fn flag(
        &mut self,
        topic: &str,
        log_time: u64,
        check: &'static str,
        reason: String,
    ) -> Result<(), ReplayError> {
        let count = self.summary.warn(topic, log_time, check, reason.clone());
        let due = self
            .flagged_at
            .get(check)
            .is_none_or(|last| log_time >= last.saturating_add(FLAG_DIAGNOSTICS_EVERY_NS));
        if let (true, Some(out)) = (due, &mut self.out) {
            self.flagged_at.insert(check, log_time);
            let values = vec![
                ("topic", topic.to_owned()),
                ("check", check.to_owned()),
                ("count", count.to_string()),
            ];
            out.diagnostics(
                log_time,
                "ekf/input",
                DiagnosticStatus::WARN,
                &reason,
                values,
            )?;
        }
        Ok(())
    }

    /// Damage the reader read past: a warning, an entry in the summary's `damaged` list,
    /// a diagnostics message in the output bag and a comment in the TUM file, each
    /// saying which log times were lost. `false` if `e` is not such damage (it ends the
    /// log).
    pub fn read_past(&mut self, e: &ReadError) -> Result<bool, ReplayError> {
        let Some(stretch) = summary::DamagedStretch::of(e) else {
            return Ok(false);
        };
        let t_ns = stretch.lost.from_ns.unwrap_or(0);
        self.summary.warn(
            &stretch.file,
            t_ns,
            "damaged_log",
            format!("damaged chunk read past: {e}"),
        );
        let text = format!(
            "{} at byte {} read past ({}): {}",
            stretch.file, stretch.byte_offset, stretch.lost, stretch.reason
        );
        self.poses.comment(&format!("damaged log: {text}"))?;
        if let Some(out) = &mut self.out {
            let secs =
                |t: Option<u64>| t.map_or_else(String::new, |t| format!("{:.9}", t as f64 * 1e-9));
            let values = vec![
                ("file", stretch.file.clone()),
                ("byte_offset", stretch.byte_offset.to_string()),
                ("lost_from_s", secs(stretch.lost.from_ns)),
                ("lost_to_s", secs(stretch.lost.to_ns)),
                ("reason", stretch.reason.clone()),
            ];
            out.diagnostics(
                t_ns,
                "ekf/log",
                DiagnosticStatus::WARN,
                &format!("damaged log: {text}"),
                values,
            )?;
        }
        self.summary.damaged.push(stretch);
        Ok(true)
    }

    /// One message as it is read: decoded if it is an input, turned into one and pushed,
    /// then every input whose turn has come is fused, each at its stamp
    /// ([`TimedLocalizer`]).
    pub fn handle(&mut self, message: &BagMessage) -> Result<(), ReplayError> {
        let Some(role) = self.role(message.topic()) else {
            self.count(message.topic());
            return Ok(());
        };
        let decoded = match message.decode() {
            Ok(decoded) => decoded,
            Err(_) if role == Role::Reference => {
                self.count(message.topic());
                return self.flag(
                    message.topic(),
                    message.log_time,
                    "reference_invalid",
                    "reference pose is not finite or not decodable".into(),
                );
            }
            // One undecodable message is skipped, not the end of the log.
            Err(e) => {
                self.count(message.topic());
                self.summary.undecodable += 1;
                return self.flag(
                    message.topic(),
                    message.log_time,
                    "undecodable",
                    format!("skipped: {e}"),
                );
            }
        };
        let stamp = stamps::stamp_of(message);
        self.handle_decoded(&message.channel, message.log_time, stamp, decoded)
    }

    /// A message already decoded (`ekf live` hands over the ones it makes), logged on
    /// `channel` at `log_time` and stamped `stamp`: as [`handle`](Self::handle).
    pub fn handle_decoded(
        &mut self,
        channel: &Arc<ChannelInfo>,
        log_time: u64,
        stamp: u64,
        message: AnyMessage,
    ) -> Result<(), ReplayError> {
        let topic = channel.topic.as_str();
        self.count(topic);
        let Some(role) = self.role(topic) else {
            return Ok(());
        };
        let Some(input) = self.input(topic, log_time, role, message)? else {
            return Ok(());
        };
        let tag = Tag {
            channel: channel.clone(),
            log_time,
        };
        if let Err(late) = self.localizer.push(stamp, input, tag) {
            let (_, tag) = &late.item;
            let reason = format!(
                "stamped {} ns, before {} ns already fused: more than [timing] max_lag late, \
                 dropped",
                late.stamp, late.after
            );
            let (topic, log_time) = (tag.channel.topic.clone(), tag.log_time);
            self.flag(&topic, log_time, "too_late", reason)?;
        }
        while let Some(step) = self.localizer.next_ready(&mut self.timer) {
            self.report(step?)?;
        }
        Ok(())
    }

    /// Counts a message read on `topic`.
    fn count(&mut self, topic: &str) {
        *self
            .summary
            .messages_read
            .entry(topic.to_owned())
            .or_default() += 1;
    }

    /// What a topic's messages are to the filter, if anything: the configured motion
    /// source, the laser, the compass (in the modes that fuse it), GPS fixes (if
    /// `gps.fuse`) and the reference.
    fn role(&self, topic: &str) -> Option<Role> {
        let t = &self.config.topics;
        let motion_topic = if self.use_joints {
            &t.joint_states
        } else {
            &t.odom
        };
        if topic == motion_topic {
            Some(Role::Motion)
        } else if topic == t.scan {
            Some(Role::Scan)
        } else if topic == t.compass && self.fuser().mode().uses_compass() {
            Some(Role::Compass)
        } else if topic == t.fix && self.config.gps.fuse {
            Some(Role::Fix)
        } else if topic == t.ground_truth {
            Some(Role::Reference)
        } else {
            None
        }
    }

    /// Fuses every input still held, in stamp order (at the end of the log).
    pub fn fuse_held(&mut self) -> Result<(), ReplayError> {
        while let Some(step) = self.localizer.next_held(&mut self.timer) {
            self.report(step?)?;
        }
        Ok(())
    }

    /// The filter input a decoded message in `role` is, if any; one that cannot be one
    /// is named in a warning.
    fn input(
        &mut self,
        topic: &str,
        log_time: u64,
        role: Role,
        message: AnyMessage,
    ) -> Result<Option<Input>, ReplayError> {
        let converted = match (role, message) {
            (Role::Motion, AnyMessage::JointState(js)) => {
                let m = &self.config.motion;
                wheel_input(&js, &m.left_joint, &m.right_joint).map_err(|names| {
                    ReplayError::MissingJoints {
                        log: self.log.clone(),
                        topic: topic.into(),
                        left: m.left_joint.clone(),
                        right: m.right_joint.clone(),
                        names,
                    }
                })?
            }
            (Role::Motion, AnyMessage::Odometry(o)) => {
                Ok(Input::OdometryPose(planar(&o.pose.pose)))
            }
            (Role::Scan, AnyMessage::LaserScan(scan)) => Ok(Input::Scan(scan.into_scan())),
            (Role::Compass, AnyMessage::Imu(imu)) => {
                heading_input(heading_from_imu(&imu, &self.config.compass_calibration))
            }
            (Role::Compass, AnyMessage::MagneticField(m)) => heading_input(
                heading_from_magnetic_field(&m, &self.config.compass_calibration),
            ),
            (Role::Fix, AnyMessage::NavSatFix(fix)) => {
                let map_offset = self.config.compass_calibration.map_offset;
                match gps_position(&fix, &self.config.gps, map_offset) {
                    Ok((x, y, covariance)) => Ok(Input::Position { x, y, covariance }),
                    Err(refused) => {
                        self.flag(topic, log_time, refused.check(), refused.to_string())?;
                        return Ok(None);
                    }
                }
            }
            (Role::Reference, message) => match reference_pose(&message) {
                Some(pose) => Ok(Input::Reference(pose)),
                None => {
                    self.flag(
                        topic,
                        log_time,
                        "reference_invalid",
                        "reference pose is not finite or not decodable".into(),
                    )?;
                    return Ok(None);
                }
            },
            _ => return Ok(None),
        };
        match converted {
            Ok(input) => Ok(Some(input)),
            Err(skip) => {
                self.flag(topic, log_time, skip.check(), skip.to_string())?;
                Ok(None)
            }
        }
    }

    /// Reports one fused input: the trajectory, the output bag, warnings and events.
    fn report(&mut self, step: Step<Tag>) -> Result<(), ReplayError> {
        let now = step.stamp_ns;
        let Tag { channel, log_time } = &step.tag;
        match step.fused {
            Fused::Motion { predicted } => {
                if predicted {
                    self.record_pose(now)?;
                }
                self.wheels_contradicted = false;
            }
            Fused::MotionFromVelocities(seen) => {
                if !std::mem::replace(&mut self.wheels_contradicted, true) {
                    self.flag(
                        &channel.topic,
                        *log_time,
                        "encoders_contradict_velocities",
                        format!(
                            "position: the encoder angles moved ({:.4}, {:.4}) rad over the \
                             interval while the velocities say ({:.4}, {:.4}) rad: stuck \
                             encoder counts? the velocities are used",
                            seen.angles[0], seen.angles[1], seen.velocities[0], seen.velocities[1]
                        ),
                    )?;
                }
                self.record_pose(now)?;
            }
            Fused::Skipped(Skip::First) | Fused::BeforeStart => {}
            Fused::Skipped(skip) => {
                self.flag(&channel.topic, *log_time, skip.check(), skip.to_string())?
            }
            Fused::Heading { heading, update } => {
                if update.refused_by_laser {
                    self.flag(
                        &channel.topic,
                        *log_time,
                        "compass_against_laser",
                        format!(
                            "heading {heading:.4} rad: {} readings in a row failed the gate \
                             and the lock-out recovery was refused: the last scan's lines fit \
                             the filter's heading better (a stuck or biased compass?)",
                            update.rejected_in_a_row
                        ),
                    )?;
                }
                // One reading that does not follow is an outlier, which the gate would
                // have refused too; a stretch of them is a stuck or broken compass.
                self.compass_not_following = match update.not_following {
                    true => self.compass_not_following + 1,
                    false => 0,
                };
                if self.compass_not_following == NOT_FOLLOWING_WARNED_AFTER {
                    self.flag(
                        &channel.topic,
                        *log_time,
                        "compass_stuck",
                        format!(
                            "heading {heading:.4} rad: {NOT_FOLLOWING_WARNED_AFTER} readings in \
                             a row do not follow the robot's turns as odometry measured them \
                             (a stuck compass?); not fused"
                        ),
                    )?;
                }
                self.heading(now, heading, &update)?
            }
            Fused::Position(_) => self.record_pose(now)?,
            // A scan's update comes only from a scan input.
            Fused::Scan(fused) => {
                if let Input::Scan(scan) = &step.input {
                    self.scan(now, &fused, scan)?
                }
            }
            Fused::ScanRefused(e) => {
                self.flag(&channel.topic, *log_time, "scan_refused", e.to_string())?
            }
            Fused::Reference(pose) => self.poses.reference(StampedPose::new(now, pose)),
            // A scan in a mode without the laser: the state at its stamp, as a pose.
            Fused::NotFused if matches!(step.input, Input::Scan(_)) => self.record_pose(now)?,
            Fused::NotFused => {}
        }
        Ok(())
    }

    fn heading(
        &mut self,
        now: u64,
        heading: f64,
        update: &lrf_lines::CompassUpdate,
    ) -> Result<(), ReplayError> {
        if !update.outcome.accepted {
            self.mark(now, ReplayEvent::CompassRejected);
        }
        if let Some(out) = self.out.as_mut() {
            let (level, text) = match (update.outcome.accepted, update.recovered) {
                (true, false) => (0, "fused"),
                (true, true) => (1, "fused without the gate: consistent rejections in a row"),
                (false, _) if update.not_following => (
                    1,
                    "not fused: does not follow the robot's turns as odometry measured them",
                ),
                (false, _) if update.refused_by_laser => (
                    1,
                    "rejected, its lock-out recovery refused: the laser fits the filter's \
                     heading better",
                ),
                (false, _) => (1, "rejected by the chi-square gate"),
            };
            out.diagnostics(
                now,
                "ekf/compass",
                level,
                text,
                vec![
                    ("nis", format!("{:.4}", update.outcome.nis)),
                    ("heading_rad", format!("{heading:.6}")),
                    ("rejected_in_a_row", update.rejected_in_a_row.to_string()),
                ],
            )?;
        }
        // The corrected pose, like after a motion step or a scan: at one stamp the TUM
        // trajectory and the accuracy keep the last.
        self.record_pose(now)
    }

    /// A scan's update: the loss monitor's reports, then the map, the markers and the
    /// scan's diagnostics, then the pose.
    fn scan(&mut self, now: u64, fused: &ScanFused, scan: &Scan) -> Result<(), ReplayError> {
        if fused.lost.is_some() {
            self.mark(now, ReplayEvent::Lost);
        }
        if fused.relocalized.is_some() {
            self.mark(now, ReplayEvent::Relocalized);
        }
        if fused.lost_after {
            if let Some(log) = self.events.as_mut() {
                log.lost_scans.push(now);
            }
        }
        let report = fused.report;
        if report.rejected + report.refused > 0 {
            self.mark(now, ReplayEvent::LinesRefused);
        }
        if let Some(out) = self.out.as_mut() {
            let localizer = self.localizer.fuser().localizer();
            write_scan_outputs(out, now, fused, localizer, &mut self.map_written)?;
        }
        if let Some(hook) = self.hook.as_mut() {
            if hook.scan_fused(now, fused, scan, self.localizer.fuser_mut())? {
                self.map_written = false;
            }
        }
        self.record_pose(now)
    }

    /// An `ekf/tracking` diagnostics message: a loss (level 2) or its end (level 0).
    /// Notes `event` at `now` for the picture, if events are kept.
    fn mark(&mut self, now: u64, event: ReplayEvent) {
        if let Some(log) = self.events.as_mut() {
            log.events.push((now, event));
        }
    }

    /// A pose for the TUM trajectory and the output bag.
    fn record_pose(&mut self, now: u64) -> Result<(), ReplayError> {
        let filter = self.filter();
        let (pose, covariance) = (filter.pose(), *filter.covariance());
        self.poses
            .estimate(StampedPose::new(now, pose), &covariance)?;
        if let Some(out) = self.out.as_mut() {
            out.pose(now, &pose, &covariance)?;
        }
        Ok(())
    }

    /// The pose now: the fused state predicted through the inputs held and then through
    /// `joint_states` (wheel readings not handed to the run yet, oldest first), as fusing
    /// them would (paper eqs. 5–9, from the same encoder increments); the filter is left as
    /// it is ([`TimedLocalizer::pose_now`]). `None` until a motion step has been fused.
    pub fn forecast<'m>(
        &self,
        joint_states: impl IntoIterator<Item = &'m JointState>,
    ) -> Result<Option<Forecast>, ReplayError> {
        let m = &self.config.motion;
        let inputs: Vec<(u64, Input)> = joint_states
            .into_iter()
            .filter(|_| self.use_joints)
            .filter_map(|js| {
                let stamp = js.header.stamp.to_nanos().filter(|&s| s > 0)?;
                let input = wheel_input(js, &m.left_joint, &m.right_joint).ok()?.ok()?;
                Some((stamp, input))
            })
            .collect();
        let more = inputs.iter().map(|(stamp, input)| (*stamp, input));
        Ok(self.localizer.pose_now(more)?)
    }
}

/// The output bag's record of one scan's update, in the order a reader sees them: the
/// loss monitor's diagnostics, the consistency warning, the map (when the scan built
/// it), the scan's markers and its diagnostics.
fn write_scan_outputs(
    out: &mut OutputBag,
    now: u64,
    fused: &ScanFused,
    localizer: &lrf_lines::Localizer,
    map_written: &mut bool,
) -> Result<(), ReplayError> {
    let tracking_status = |out: &mut OutputBag, level, message: &str, c: &TrackingChange| {
        let values = vec![
            ("scans_lost", c.scans_lost.to_string()),
            ("losses", c.losses.to_string()),
        ];
        out.diagnostics(now, "ekf/tracking", level, message, values)
    };
    if let Some(lost) = &fused.lost {
        let why = if lost.motion_gap {
            "lost: the motion source was silent since the last scan (a motion gap)"
        } else {
            "lost: scans in a row with lines and none fused"
        };
        tracking_status(out, 2, why, lost)?;
    }
    if let Some(regained) = &fused.regained {
        tracking_status(out, 0, "tracking again: the scan's lines fused", regained)?;
    }
    if let Some(won) = &fused.relocalized {
        let best = won.pose;
        out.diagnostics(
            now,
            "ekf/relocalization",
            1,
            if fused.lost_after {
                "relocalized, unconfirmed: the filter restarted at the pose the map search \
                 found in this scan alone (after a motion gap); still lost until a scan \
                 tracked from it fixes the position"
            } else {
                "relocalized: the filter restarted at the pose the map search found"
            },
            vec![
                ("x", format!("{:.3}", best.x)),
                ("y", format!("{:.3}", best.y)),
                ("theta", format!("{:.4}", best.theta)),
                ("inliers", won.inliers.to_string()),
                ("score_m", format!("{:.2}", won.score)),
                ("runner_up_m", format!("{:.2}", won.runner_up)),
            ],
        )?;
    }
    if fused.over_confident {
        out.diagnostics(
            now,
            "ekf/consistency",
            1,
            "over-confident: the lines' innovations are larger than the covariance allows",
            vec![
                ("window_scans", consistency::WINDOW_SCANS.to_string()),
                (
                    "band_probability",
                    consistency::BAND_PROBABILITY.to_string(),
                ),
            ],
        )?;
    }
    let report = fused.report;
    // The first-scan map once built, a map a hook replaced at the scan after.
    if !*map_written && !localizer.map().is_empty() {
        out.map(now, localizer.map())?;
        *map_written = true;
    }
    let fusions = localizer.last_fusions();
    let accepted: Vec<usize> = fusions
        .iter()
        .filter(|f| f.accepted)
        .map(|f| f.observed)
        .collect();
    let nis: Vec<String> = fusions.iter().map(|f| format!("{:.3}", f.nis)).collect();
    out.scan_markers(
        now,
        &localizer.sensor_pose(),
        localizer.last_lines(),
        &accepted,
        &localizer.pose(),
        localizer.covariance(),
    )?;
    let rejections: Vec<String> = localizer
        .last_matches()
        .rejections()
        .iter()
        .map(|r| format!("line {}: {}", r.observed, r.reason))
        .collect();
    let values = vec![
        ("lines_extracted", report.extracted.to_string()),
        ("lines_matched", report.matched.to_string()),
        ("lines_rejected", report.rejected.to_string()),
        ("lines_fused", report.fused.to_string()),
        ("lines_refused", report.refused.to_string()),
        ("lines_merged", report.merged.to_string()),
        ("walls_refitted", report.refitted.to_string()),
        ("nis", nis.join(" ")),
        ("rejections", rejections.join("; ")),
    ];
    let level = u8::from(report.extracted > 0 && report.fused == 0 && !report.map_built);
    out.diagnostics(
        now,
        "ekf/scan",
        level,
        if level == 0 { "ok" } else { "no line fused" },
        values,
    )?;
    Ok(())
}

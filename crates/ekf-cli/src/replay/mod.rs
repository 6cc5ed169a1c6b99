//! `ekf replay`: a ROS 2 bag through the filter, in log-time order and streaming.
//!
//! Motion comes from `sensor_msgs/JointState` (wheel speeds) or `nav_msgs/Odometry`
//! (pose deltas); headings from `sensor_msgs/Imu` or `sensor_msgs/MagneticField`; scans
//! from `sensor_msgs/LaserScan`; the reference from `nav_msgs/Odometry` or
//! `geometry_msgs/PoseStamped`; the laser mount from `/tf_static` when present. Outputs:
//! an MCAP for Foxglove/ROS 2 ([`outputs`]), a TUM trajectory with a pose at every
//! motion step and every scan (log times), and a [`ReplaySummary`].
//!
//! A damaged log is processed up to the damage; the outputs are then finished and the
//! failure is returned next to the results ([`ReplayOutcome::failure`]).

pub mod accuracy;
pub mod consistency;
pub mod events;
pub mod inputs;
pub mod outputs;
pub mod reorder;
mod sink;
pub mod summary;
pub mod tracking;
pub mod verification;

use crate::config::{Config, MotionSource};
use crate::mcap_io::{BagMessage, BagReader, MessageError, ReadError, WriteError};
use crate::ros2::geometry_msgs::TransformStamped;
use crate::ros2::sensor_msgs::JointState;
use crate::ros2::{type_name_matches, AnyMessage};
use crate::trajectory::{StampedPose, Trajectory};
use ekf_core::ChiSquareGate;
use ekf_core::{Motion, Pose2, WheelSpeeds};
pub use events::ReplayEvent;
use inputs::{
    gps_position, heading_from_imu, heading_from_magnetic_field, mount_from_tf, pose2,
    OdometryTracker, Skip, WheelTracker,
};
use lrf_lines::{LineMap, Localizer, LocalizerError, RelocalizeParams, ScanStage, StageClock};
use nalgebra::{Matrix3, Point2};
use outputs::OutputBag;
use std::path::{Path, PathBuf};
use std::time::Instant;
pub use summary::ReplaySummary;

/// The paper's four estimator configurations (Fig. 9/10); the default is all sensors,
/// laser + compass (as `ekf replay`'s).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mode {
    /// Prediction only: dead reckoning.
    Odometry,
    /// Prediction + compass.
    Compass,
    /// Prediction + laser lines.
    Laser,
    /// Prediction + laser lines + compass.
    #[default]
    LaserCompass,
}

impl Mode {
    /// All four, in the paper's order.
    pub const ALL: [Mode; 4] = [
        Mode::Odometry,
        Mode::Compass,
        Mode::Laser,
        Mode::LaserCompass,
    ];

    /// The name used on the command line and in summaries.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Odometry => "odometry",
            Mode::Compass => "compass",
            Mode::Laser => "laser",
            Mode::LaserCompass => "laser+compass",
        }
    }

    /// Whether the mode fuses the compass.
    pub fn uses_compass(self) -> bool {
        matches!(self, Mode::Compass | Mode::LaserCompass)
    }

    /// Whether the mode fuses laser lines.
    pub fn uses_laser(self) -> bool {
        matches!(self, Mode::Laser | Mode::LaserCompass)
    }
}

/// What to replay and where to write. The default is `ekf replay LOG` with no flags:
/// laser + compass, a first-scan map, the configured initial pose, no files written.
#[derive(Debug, Clone, Default)]
pub struct ReplayOptions {
    /// Estimator configuration.
    pub mode: Mode,
    /// A line map (JSON); `None`: the map is built from the first scan, as in the paper.
    pub map: Option<PathBuf>,
    /// Start at the first reference pose instead of `config.initial`.
    pub init_from_truth: bool,
    /// Global localization: no initial pose; the map is searched from the first scans
    /// ([`tracking`]) and the filter starts where the search locks on. Needs a map.
    pub global: bool,
    /// Output bag.
    pub out_mcap: Option<PathBuf>,
    /// Output TUM trajectory.
    pub tum: Option<PathBuf>,
    /// Keep the estimated and reference trajectories in memory (for plots); otherwise the
    /// replay streams in memory that does not grow with the log.
    pub keep_trajectories: bool,
}

/// Why a replay could not start or could not finish.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// Global localization was asked for without a map to search.
    #[error("--global needs a map (--map MAP.json): there is nothing to search without one")]
    GlobalNeedsMap,
    /// The log could not be read.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// A topic the mode needs is not in the log.
    #[error("{log}: no topic {topic} ({role}); the log has: {available}{hint}")]
    MissingTopic {
        /// The log.
        log: String,
        /// The missing topic.
        topic: String,
        /// What it was needed for.
        role: &'static str,
        /// The topics the log has, with their types.
        available: String,
        /// What to do about it, if there is a way (empty or starting with a separator).
        hint: &'static str,
    },
    /// A topic carries a type the replay cannot use for its role.
    #[error("{log}: topic {topic} has type {actual}; expected {expected}")]
    WrongType {
        /// The log.
        log: String,
        /// The topic.
        topic: String,
        /// What it carries.
        actual: String,
        /// What the role needs.
        expected: &'static str,
    },
    /// The wheel joints are not in the joint states.
    #[error("{log}: {topic}: no joints named {left:?} and {right:?} (set motion.left_joint/right_joint); the message has {names:?}")]
    MissingJoints {
        /// The log.
        log: String,
        /// The joint-state topic.
        topic: String,
        /// Configured left joint.
        left: String,
        /// Configured right joint.
        right: String,
        /// The joints the message has.
        names: Vec<String>,
    },
    /// `--init-from-truth` without a reference pose in the log.
    #[error("{log}: --init-from-truth needs a reference pose on {topic}, but none was found")]
    NoReference {
        /// The log.
        log: String,
        /// The reference topic.
        topic: String,
    },
    /// The map file could not be read or parsed.
    #[error("{path}: {message}")]
    Map {
        /// The map file.
        path: String,
        /// What went wrong (the parser names the entry and field).
        message: String,
    },
    /// The laser is not mounted level (tilted, or upside down so its scans are mirrored).
    #[error("/tf_static: the transform {parent} -> {child} tilts the laser {tilt_deg:.1}° from level (more than 5°; 180° is upside down); ekf models a level, upright scanner: mount it so, or set laser.mount_from_tf_static = false and give localizer.laser_mount if the scans are in fact level")]
    TiltedLaser {
        /// The transform's parent frame.
        parent: String,
        /// Its child frame.
        child: String,
        /// The tilt (degrees).
        tilt_deg: f64,
    },
    /// The filter refused its configuration or failed.
    #[error("{0}")]
    Filter(#[from] LocalizerError),
    /// A message could not be decoded.
    #[error(transparent)]
    Message(#[from] MessageError),
    /// An output could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
    /// The TUM file could not be written.
    #[error("{path}: {source}")]
    Tum {
        /// The TUM file.
        path: String,
        /// What the OS said.
        source: std::io::Error,
    },
}

/// The results of a replay.
#[derive(Debug)]
pub struct ReplayOutcome {
    /// Counts, timings, accuracy.
    pub summary: ReplaySummary,
    /// The estimate at every motion step and scan (empty unless
    /// [`ReplayOptions::keep_trajectories`]).
    pub trajectory: Trajectory,
    /// The covariance `(x, y, θ)` of each pose of [`trajectory`](Self::trajectory).
    pub covariances: Vec<Matrix3<f64>>,
    /// The log's reference poses (empty if none, or unless kept).
    pub reference: Trajectory,
    /// Log times (ns) of the scans that ended with the filter lost (empty unless kept).
    pub lost_scans_ns: Vec<u64>,
    /// What the picture marks, each at its stamp (ns), in order (empty unless kept).
    pub events: Vec<(u64, ReplayEvent)>,
    /// The map at the end: the given one, or the one built from the first scan (empty
    /// without the laser).
    pub map: LineMap,
    /// Set when the log broke off (damage, a decode failure): everything before it was
    /// processed and the outputs are finished.
    pub failure: Option<ReplayError>,
}

/// Topic types accepted for each role.
const MOTION_JOINTS: &str = "sensor_msgs/msg/JointState";
const MOTION_ODOM: &str = "nav_msgs/msg/Odometry";
const SCAN: &str = "sensor_msgs/msg/LaserScan";
const COMPASS: [&str; 2] = ["sensor_msgs/msg/Imu", "sensor_msgs/msg/MagneticField"];
const REFERENCE: [&str; 2] = ["nav_msgs/msg/Odometry", "geometry_msgs/msg/PoseStamped"];

/// Times the scan stages with a monotonic clock.
struct StageTimer {
    last: Instant,
    stages: [summary::LatencyHistogram; 3],
}

impl StageClock for StageTimer {
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

/// What the first pass over the log found: the scan frame, static transforms up to the
/// first scan, and the first reference pose.
pub(crate) struct Preamble {
    pub(crate) scan_frame: Option<String>,
    pub(crate) transforms: Vec<TransformStamped>,
    pub(crate) first_reference: Option<(u64, Pose2<f64>)>,
}

/// Replays `log` with `config`. `progress(done, total)` is called as messages are read.
pub fn replay(
    log: &Path,
    config: &Config,
    options: &ReplayOptions,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<ReplayOutcome, ReplayError> {
    let started = Instant::now();
    let log_name = log.display().to_string();
    let bag = BagReader::open(log)?;
    let topic_type = |topic: &str| {
        bag.topics()
            .iter()
            .find(|t| t.topic == topic)
            .map(|t| t.type_name.clone())
    };
    let available = || bag.describe_topics();
    let missing = |topic: &str, role: &'static str, hint: &'static str| ReplayError::MissingTopic {
        log: log_name.clone(),
        topic: topic.into(),
        role,
        available: available(),
        hint,
    };
    let check_type =
        |topic: &str, expected: &[&str], what: &'static str| -> Result<(), ReplayError> {
            match topic_type(topic) {
                Some(actual) if !expected.iter().any(|e| type_name_matches(e, &actual)) => {
                    Err(ReplayError::WrongType {
                        log: log_name.clone(),
                        topic: topic.into(),
                        actual,
                        expected: what,
                    })
                }
                _ => Ok(()),
            }
        };
    let t = &config.topics;

    // Motion source.
    let use_joints = match config.motion.source {
        MotionSource::JointStates => true,
        MotionSource::Odom => false,
        MotionSource::Auto => topic_type(&t.joint_states).is_some(),
    };
    let motion_topic = if use_joints { &t.joint_states } else { &t.odom };
    if topic_type(motion_topic).is_none() {
        // With `auto`, neither topic is there: name both, not just the fallback.
        let (topic, role) = match config.motion.source {
            MotionSource::Auto => (
                format!("{} or {}", t.joint_states, t.odom),
                "wheel joint states or odometry",
            ),
            MotionSource::JointStates => (motion_topic.clone(), "wheel joint states"),
            MotionSource::Odom => (motion_topic.clone(), "odometry"),
        };
        return Err(missing(&topic, role, TOPIC_HINT));
    }
    check_type(
        &t.joint_states,
        &[MOTION_JOINTS],
        "sensor_msgs/msg/JointState",
    )?;
    check_type(&t.odom, &[MOTION_ODOM], "nav_msgs/msg/Odometry")?;
    check_type(&t.scan, &[SCAN], "sensor_msgs/msg/LaserScan")?;
    check_type(
        &t.compass,
        &COMPASS,
        "sensor_msgs/msg/Imu or sensor_msgs/msg/MagneticField",
    )?;
    check_type(
        &t.ground_truth,
        &REFERENCE,
        "nav_msgs/msg/Odometry or geometry_msgs/msg/PoseStamped",
    )?;
    if options.mode.uses_laser() && topic_type(&t.scan).is_none() {
        let hint = if options.mode == Mode::LaserCompass {
            "; mode compass (--mode compass) needs no laser, or name the laser's topic in \
             [topics] scan"
        } else {
            TOPIC_HINT
        };
        return Err(missing(&t.scan, "laser scans", hint));
    }
    if options.mode.uses_compass() && topic_type(&t.compass).is_none() {
        let hint = if options.mode == Mode::LaserCompass {
            "; mode laser (--mode laser) needs no compass, or name the compass's topic in \
             [topics] compass"
        } else {
            "; mode odometry (--mode odometry) needs no compass, or name the compass's topic \
             in [topics] compass"
        };
        return Err(missing(&t.compass, "compass", hint));
    }

    let preamble = read_preamble(&bag, config, options.init_from_truth)?;
    let mut run = Run::start(
        config,
        options,
        &preamble,
        use_joints,
        &log_name,
        motion_topic,
    )?;
    if topic_type(&t.ground_truth).is_none() {
        // A log without a reference is normal; one whose reference is under another name
        // would silently report no accuracy.
        let candidates: Vec<&str> = bag
            .topics()
            .iter()
            .filter(|c| c.topic != *motion_topic)
            .filter(|c| REFERENCE.iter().any(|r| type_name_matches(r, &c.type_name)))
            .map(|c| c.topic.as_str())
            .collect();
        if !candidates.is_empty() {
            run.summary.notes.push(format!(
                "no reference on {}, so no accuracy; if {} is the reference, name it in \
                 [topics] ground_truth",
                t.ground_truth,
                candidates.join(" or ")
            ));
        }
    }
    let total: u64 = bag.topics().iter().map(|t| t.message_count).sum();
    let mut failure = None;
    let mut done = 0;
    let mut order = reorder::Reorder::new((config.timing.max_lag * 1e9) as u64);
    let mut read_failure = None;
    'read: for message in bag.messages()? {
        let message = match message {
            Ok(m) => m,
            Err(e) => {
                read_failure = Some(e.into());
                break;
            }
        };
        if let Err(late) = order.push(message) {
            run.too_late(&late);
        }
        while let Some((stamp, ready)) = order.pop_ready() {
            if let Err(e) = run.handle(&ready, stamp) {
                failure = Some(e);
                break 'read;
            }
        }
        done += 1;
        progress(done, total);
    }
    // What was read before the end (or the damage) is fused, in stamp order.
    while let Some((stamp, ready)) = order.pop().filter(|_| failure.is_none()) {
        if let Err(e) = run.handle(&ready, stamp) {
            failure = Some(e);
        }
    }
    let failure = failure.or(read_failure);
    run.finish(started, failure)
}

/// The laser's mounting pose: `base_frame` → the scan's frame from `/tf_static` when
/// the log has that chain and the configuration allows it, else `localizer.laser_mount`.
/// Returns the pose and where it came from (`tf_static` or `config`).
pub(crate) fn laser_mount(
    preamble: &Preamble,
    config: &Config,
) -> Result<(Pose2<f64>, &'static str), ReplayError> {
    let from_tf = config
        .laser
        .mount_from_tf_static
        .then(|| {
            preamble
                .scan_frame
                .as_deref()
                .and_then(|f| mount_from_tf(&preamble.transforms, &config.laser.base_frame, f))
        })
        .flatten();
    match from_tf {
        Some(Ok(mount)) => Ok((mount, "tf_static")),
        Some(Err(t)) => Err(ReplayError::TiltedLaser {
            parent: t.parent,
            child: t.child,
            tilt_deg: t.tilt.to_degrees(),
        }),
        None => Ok((config.localizer.laser_mount, "config")),
    }
}

/// Reads a JSON line map.
pub fn load_map(path: &Path) -> Result<LineMap, ReplayError> {
    let map_error = |message: String| ReplayError::Map {
        path: path.display().to_string(),
        message,
    };
    let bytes = std::fs::read(path).map_err(|e| map_error(e.to_string()))?;
    LineMap::from_json_bytes(&bytes).map_err(|e| map_error(e.to_string()))
}

/// Reads the start of the log: static transforms and the scan frame up to the first scan,
/// and (when asked) the first reference pose. Stops as soon as it has them.
pub(crate) fn read_preamble(
    bag: &BagReader,
    config: &Config,
    want_reference: bool,
) -> Result<Preamble, ReplayError> {
    let t = &config.topics;
    let mut p = Preamble {
        scan_frame: None,
        transforms: Vec::new(),
        first_reference: None,
    };
    let has_scan = bag.topics().iter().any(|i| i.topic == t.scan);
    for message in bag.messages()? {
        let Ok(message) = message else { break };
        let topic = message.topic();
        if p.scan_frame.is_none() && topic == t.tf_static {
            if let Ok(AnyMessage::TFMessage(tf)) = message.decode() {
                p.transforms.extend(tf.transforms);
            }
        } else if p.scan_frame.is_none() && topic == t.scan {
            if let Ok(AnyMessage::LaserScan(scan)) = message.decode() {
                p.scan_frame = Some(scan.header.frame_id);
            }
        } else if want_reference && p.first_reference.is_none() && topic == t.ground_truth {
            p.first_reference = reference_pose(&message).map(|pose| (message.log_time, pose));
        }
        let scan_done = p.scan_frame.is_some() || !has_scan;
        if scan_done && (!want_reference || p.first_reference.is_some()) {
            break;
        }
    }
    Ok(p)
}

pub(crate) fn reference_pose(message: &BagMessage) -> Option<Pose2<f64>> {
    match message.decode().ok()? {
        AnyMessage::Odometry(o) => pose2(&o.pose.pose),
        AnyMessage::PoseStamped(p) => pose2(&p.pose),
        _ => None,
    }
}

/// What to do about a missing topic the mode cannot do without.
pub(crate) const TOPIC_HINT: &str = "; name the log's topic in the config's [topics] table";

/// Longest time after the end of the last motion message up to which the state is
/// brought forward at that message's rate.
const MAX_EXTRAPOLATION_NS: u64 = 200_000_000;

/// One motion message's step over its whole interval.
#[derive(Debug, Clone, Copy)]
enum MotionStep {
    /// Wheel speeds held over `dt`.
    Wheels(WheelSpeeds<f64>),
    /// An odometry pose delta.
    Odometry(Motion<f64>),
}

impl MotionStep {
    /// Wheel speeds over the interval `(t0, t1]` that ends at `stamp` (a joint state's)
    /// and lasts the speeds' `dt`: `(step, t0, t1)`.
    fn wheels_until(speeds: WheelSpeeds<f64>, stamp: u64) -> (Self, u64, u64) {
        let t0 = stamp - (speeds.dt * 1e9).round() as u64;
        (MotionStep::Wheels(speeds), t0, stamp)
    }

    /// The part of the step after a fraction `1 − f` of its interval has passed.
    fn part(self, f: f64) -> Self {
        match self {
            MotionStep::Wheels(s) => MotionStep::Wheels(WheelSpeeds { dt: s.dt * f, ..s }),
            MotionStep::Odometry(m) => MotionStep::Odometry(Motion {
                ds: m.ds * f,
                dtheta: m.dtheta * f,
            }),
        }
    }

    /// The step per second, for a step over `dt` seconds.
    fn rate(self, dt: f64) -> MotionRate {
        match self {
            MotionStep::Wheels(s) => MotionRate(MotionStep::Wheels(WheelSpeeds { dt: 1.0, ..s })),
            MotionStep::Odometry(m) => MotionRate(MotionStep::Odometry(Motion {
                ds: m.ds / dt,
                dtheta: m.dtheta / dt,
            })),
        }
    }
}

/// A motion step per second of time.
#[derive(Debug, Clone, Copy)]
struct MotionRate(MotionStep);

impl MotionRate {
    /// The step over `dt` seconds at this rate.
    fn over(self, dt: f64) -> MotionStep {
        self.0.part(dt)
    }
}

/// The time the filter state refers to, and the rate and end of the last motion step.
#[derive(Debug, Clone, Copy, Default)]
struct MotionClock {
    state_ns: Option<u64>,
    rate: Option<MotionRate>,
    /// The end of the last motion step taken (ns): extrapolation at its rate reaches at
    /// most [`MAX_EXTRAPOLATION_NS`] beyond it.
    motion_ns: Option<u64>,
    /// The time of the initial state: motion before it is already in the initial pose (a
    /// reference pose taken as the start), so only the part of a step after it counts.
    start_ns: u64,
}

impl MotionClock {
    /// A clock whose initial state refers to `start_ns`.
    fn starting_at(start_ns: u64) -> Self {
        Self {
            start_ns,
            ..Self::default()
        }
    }

    /// Takes a motion step over `(t0, t1]` and returns the part of it after the time the
    /// state already refers to (a scan or heading in between was fused at its own time,
    /// after a prediction at the previous rate, or the initial state's time); `None` if
    /// nothing of it is left.
    fn advance(&mut self, step: MotionStep, t0: u64, t1: u64) -> Option<MotionStep> {
        if t1 <= self.start_ns {
            return None;
        }
        let start = self.state_ns.map_or(t0, |s| s.max(t0)).max(self.start_ns);
        self.state_ns = Some(self.state_ns.map_or(t1, |s| s.max(t1)));
        self.motion_ns = Some(self.motion_ns.map_or(t1, |s| s.max(t1)));
        self.rate = Some(step.rate((t1 - t0) as f64 * 1e-9));
        (start < t1).then(|| step.part((t1 - start) as f64 / (t1 - t0) as f64))
    }

    /// The step that brings the state from its time to `t_ns` at the last motion rate,
    /// if `t_ns` is later than the state and at most [`MAX_EXTRAPOLATION_NS`] after the
    /// end of the last motion step; the state then refers to `t_ns`. Later times are left
    /// to the next motion message (the robot may have stopped). The limit counts from the
    /// last motion message, not from the last extrapolation: a source that falls silent
    /// is not carried on at its last rate scan after scan.
    fn extrapolate(&mut self, t_ns: u64) -> Option<MotionStep> {
        let (state, rate, motion) = (self.state_ns?, self.rate?, self.motion_ns?);
        if t_ns <= state || t_ns - motion > MAX_EXTRAPOLATION_NS {
            return None;
        }
        self.state_ns = Some(t_ns);
        Some(rate.over((t_ns - state) as f64 * 1e-9))
    }
}

/// The filter's state predicted ahead of what has been fused: see [`Run::forecast`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Forecast {
    /// The time it refers to (ns): the newest wheel reading predicted through, or
    /// `fused_ns` if none was.
    pub t_ns: u64,
    /// The time of the fused state it was predicted from (ns).
    pub fused_ns: u64,
    /// The pose.
    pub pose: Pose2<f64>,
    /// Its covariance.
    pub covariance: Matrix3<f64>,
}

/// The state of one replay loop: the filter, its outputs and the trackers that turn
/// messages into filter inputs. `replay` drives it over a log; `ekf live` over messages
/// it makes from devices and records, so a replay of the recording repeats it exactly.
pub(crate) struct Run<'a> {
    config: &'a Config,
    log: String,
    mode: Mode,
    start_ns: u64,
    use_joints: bool,
    localizer: Localizer,
    out: Option<OutputBag>,
    summary: ReplaySummary,
    poses: sink::PoseSink,
    clock: MotionClock,
    wheels: WheelTracker,
    odometry: OdometryTracker,
    timer: StageTimer,
    map_written: bool,
    gps_gate: ChiSquareGate<f64>,
    tracking: tracking::Tracking,
    /// Events and lost scans, if trajectories are kept.
    events: Option<events::EventLog>,
    consistency: consistency::ConsistencyMonitor,
}

impl<'a> Run<'a> {
    /// Sets up the filter (laser mount, initial state, map) and creates the outputs.
    pub(crate) fn start(
        config: &'a Config,
        options: &ReplayOptions,
        preamble: &Preamble,
        use_joints: bool,
        log_name: &str,
        motion_topic: &str,
    ) -> Result<Self, ReplayError> {
        let t = &config.topics;
        let mut summary = ReplaySummary {
            log: log_name.to_owned(),
            mode: options.mode.name().into(),
            motion_topic: motion_topic.to_owned(),
            ..ReplaySummary::default()
        };

        // Laser mount: tf_static, else the configuration.
        let mut localizer_config = config.localizer.clone();
        let (mount, source) = laser_mount(preamble, config)?;
        localizer_config.laser_mount = mount;
        summary.laser_mount_source = source.into();
        summary.laser_mount = [mount.x, mount.y, mount.theta];

        // Initial state.
        if options.global && options.map.is_none() {
            return Err(ReplayError::GlobalNeedsMap);
        }
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

        let localizer = match &options.map {
            Some(path) => {
                let map = load_map(path)?;
                summary.map = path.display().to_string();
                Localizer::new(localizer_config, initial, p0, map)?
            }
            None => {
                summary.map = "first scan".into();
                Localizer::with_first_scan_map(localizer_config, initial, p0)?
            }
        };
        summary.map_segments = localizer.map().len();

        let out = options
            .out_mcap
            .as_deref()
            .map(OutputBag::create)
            .transpose()?;
        let mut run = Run {
            config,
            log: log_name.to_owned(),
            mode: options.mode,
            start_ns,
            use_joints,
            localizer,
            out,
            summary,
            poses: sink::PoseSink::new(options.tum.as_deref(), options.keep_trajectories)?,
            clock: MotionClock::starting_at(start_ns),
            wheels: WheelTracker::new(
                &config.motion.left_joint,
                &config.motion.right_joint,
                config.devices.max_wheel_turns_per_s,
            ),
            odometry: OdometryTracker::default(),
            timer: StageTimer {
                last: Instant::now(),
                stages: Default::default(),
            },
            map_written: false,
            tracking: if options.global {
                tracking::Tracking::global()
            } else {
                tracking::Tracking::new(options.map.is_some())
            },
            events: options.keep_trajectories.then(events::EventLog::default),
            consistency: consistency::ConsistencyMonitor::default(),
            gps_gate: ChiSquareGate::from_probability(config.gps.gate_probability, 2).map_err(
                |error| LocalizerError::Config {
                    group: "gps",
                    error,
                },
            )?,
        };
        if let Some(out) = run.out.as_mut() {
            if options.map.is_some() {
                out.map(start_ns, run.localizer.map())?;
                run.map_written = true;
            }
        }
        Ok(run)
    }

    /// The output bag, when there is one (live mode records its raw messages into it).
    pub(crate) fn output(&mut self) -> Option<&mut OutputBag> {
        self.out.as_mut()
    }

    /// Finishes every output, whatever happened before, and returns the results with
    /// `failure` (the error that ended the loop, if any).
    pub(crate) fn finish(
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
            tracking,
            events,
            ..
        } = self;
        let events = events.unwrap_or_default();
        summary.tracking.lost_at_end = tracking.lost_for;
        // Finish both outputs, then report the first error.
        let bag_finished = out.map_or(Ok(()), OutputBag::finish);
        let poses = poses.finish()?;
        bag_finished?;
        summary.map_segments = localizer.map().len();
        let map = localizer.map().clone();
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

    /// One message, fused at `now` (its header stamp, or its log time; warnings name its
    /// log time).
    pub(crate) fn handle(&mut self, message: &BagMessage, now: u64) -> Result<(), ReplayError> {
        let topic = message.topic();
        *self
            .summary
            .messages_read
            .entry(topic.to_owned())
            .or_default() += 1;
        let t = &self.config.topics;
        let is_motion = if self.use_joints {
            topic == t.joint_states
        } else {
            topic == t.odom
        };
        if is_motion {
            self.motion(message, now)
        } else if topic == t.scan {
            self.scan(message, now)
        } else if topic == t.compass && self.mode.uses_compass() {
            self.compass(message, now)
        } else if topic == t.fix && self.config.gps.fuse {
            self.gps(message, now)
        } else if topic == t.ground_truth {
            if let Some(pose) = reference_pose(message) {
                self.poses.reference(StampedPose::new(now, pose));
            } else {
                self.summary.warn(
                    topic,
                    message.log_time,
                    "reference pose is not finite or not decodable".into(),
                );
            }
            Ok(())
        } else {
            Ok(())
        }
    }

    fn skip(&mut self, topic: &str, now: u64, skip: Skip) {
        if skip != Skip::First {
            self.summary.warn(topic, now, skip.to_string());
        }
    }

    fn motion(&mut self, message: &BagMessage, now: u64) -> Result<(), ReplayError> {
        let topic = message.topic();
        self.tracking.motion(now);
        let step = match message.decode()? {
            AnyMessage::JointState(js) => {
                let stamp = js.header.stamp.to_nanos().filter(|&s| s > 0).unwrap_or(now);
                let speeds =
                    self.wheels
                        .speeds(stamp, &js)
                        .map_err(|names| ReplayError::MissingJoints {
                            log: self.log.clone(),
                            topic: topic.into(),
                            left: self.config.motion.left_joint.clone(),
                            right: self.config.motion.right_joint.clone(),
                            names,
                        })?;
                speeds.map(|s| MotionStep::wheels_until(s, stamp))
            }
            AnyMessage::Odometry(o) => {
                let stamp = o.header.stamp.to_nanos().filter(|&s| s > 0).unwrap_or(now);
                self.odometry
                    .motion(stamp, &o.pose.pose)
                    .map(|(m, t0)| (MotionStep::Odometry(m), t0, stamp))
            }
            _ => return Ok(()),
        };
        match step {
            Err(skip) => self.skip(topic, message.log_time, skip),
            Ok((step, t0, t1)) => {
                if self.apply_motion(step, t0, t1)? {
                    self.summary.motion_steps += 1;
                    self.record_pose(now)?;
                }
            }
        }
        Ok(())
    }

    /// Predicts over the motion interval `(t0, t1]`, or only its part after the time the
    /// state already refers to ([`MotionClock::advance`]). Returns whether anything was
    /// predicted.
    fn apply_motion(&mut self, step: MotionStep, t0: u64, t1: u64) -> Result<bool, ReplayError> {
        let Some(part) = self.clock.advance(step, t0, t1) else {
            return Ok(false);
        };
        self.predict(part)?;
        Ok(true)
    }

    /// Predicts the filter through one motion step.
    fn predict(&mut self, step: MotionStep) -> Result<(), ReplayError> {
        let before = self.localizer.pose();
        match step {
            MotionStep::Wheels(s) => self.localizer.predict_wheels(&s)?,
            MotionStep::Odometry(m) => self.localizer.predict_odometry(&m)?,
        }
        if let Some(pending) = self.tracking.verification.as_mut() {
            pending.moved(&before.inverse().compose(&self.localizer.pose()));
        }
        Ok(())
    }

    /// The state predicted through wheel readings that have not been fused yet
    /// (`joint_states`, oldest first, each following the last one fused): where the robot
    /// is at the newest of them, while measurements made before it may still be on their
    /// way (`ekf live` holds readings back until then). Each reading is predicted as
    /// fusing it would (paper eqs. 5–9, from the same encoder increments); the filter is
    /// left as it is. Readings this run would skip are skipped; with odometry as the
    /// motion source, or nothing to predict from, it is the fused state at its own time.
    /// `None` until a motion step has been fused: before that the state has no time.
    pub(crate) fn forecast<'m>(
        &self,
        joint_states: impl IntoIterator<Item = &'m JointState>,
    ) -> Result<Option<Forecast>, ReplayError> {
        let Some(fused_ns) = self.clock.state_ns else {
            return Ok(None);
        };
        let mut ekf = *self.localizer.ekf();
        let (mut clock, mut wheels) = (self.clock, self.wheels.clone());
        let config = self.localizer.config();
        let mut t_ns = fused_ns;
        for js in joint_states.into_iter().filter(|_| self.use_joints) {
            let Some(stamp) = js.header.stamp.to_nanos().filter(|&s| s > 0) else {
                continue;
            };
            let Ok(Ok(speeds)) = wheels.speeds(stamp, js) else {
                continue;
            };
            let (step, t0, t1) = MotionStep::wheels_until(speeds, stamp);
            if let Some(MotionStep::Wheels(s)) = clock.advance(step, t0, t1) {
                ekf.predict_wheels(&config.robot, &s, &config.wheel_noise)
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

    /// Brings the state to `t_ns` before a scan or heading is fused there
    /// ([`MotionClock::extrapolate`]).
    fn catch_up(&mut self, t_ns: u64) -> Result<(), ReplayError> {
        match self.clock.extrapolate(t_ns) {
            Some(step) => self.predict(step),
            None => Ok(()),
        }
    }

    fn compass(&mut self, message: &BagMessage, now: u64) -> Result<(), ReplayError> {
        if now < self.start_ns {
            return Ok(());
        }
        let cal = &self.config.compass_calibration;
        let (stamp, heading) = match message.decode()? {
            AnyMessage::Imu(imu) => (imu.header.stamp, heading_from_imu(&imu, cal)),
            AnyMessage::MagneticField(m) => (m.header.stamp, heading_from_magnetic_field(&m, cal)),
            _ => return Ok(()),
        };
        let h = match heading {
            Ok(h) => h,
            Err(skip) => {
                self.skip(message.topic(), message.log_time, skip);
                return Ok(());
            }
        };
        self.catch_up(stamp.to_nanos().filter(|&t| t > 0).unwrap_or(now))?;
        let variance = h.variance.unwrap_or(self.config.localizer.compass.variance);
        let update = self
            .localizer
            .update_compass_with_variance(h.heading, variance)?;
        let counts = &mut self.summary.compass;
        if update.outcome.accepted {
            counts.accepted += 1;
            counts.recovered += u64::from(update.recovered);
        } else {
            counts.rejected += 1;
            self.mark(now, ReplayEvent::CompassRejected);
        }
        if let Some(out) = self.out.as_mut() {
            let (level, text) = match (update.outcome.accepted, update.recovered) {
                (true, false) => (0, "fused"),
                (true, true) => (1, "fused without the gate: consistent rejections in a row"),
                (false, _) => (1, "rejected by the chi-square gate"),
            };
            out.diagnostics(
                now,
                "ekf/compass",
                level,
                text,
                vec![
                    ("nis", format!("{:.4}", update.outcome.nis)),
                    ("heading_rad", format!("{:.6}", h.heading)),
                    ("rejected_in_a_row", update.rejected_in_a_row.to_string()),
                ],
            )?;
        }
        // The corrected pose, like after a motion step or a scan: at one stamp the TUM
        // trajectory and the accuracy keep the last.
        self.record_pose(now)
    }

    /// A GPS fix as a position in the map ([`crate::config::GpsConfig`]).
    fn gps(&mut self, message: &BagMessage, now: u64) -> Result<(), ReplayError> {
        if now < self.start_ns {
            return Ok(());
        }
        let AnyMessage::NavSatFix(fix) = message.decode()? else {
            return Ok(());
        };
        let map_offset = self.config.compass_calibration.map_offset;
        let (x, y, covariance) = match gps_position(&fix, &self.config.gps, map_offset) {
            Ok(position) => position,
            Err(refused) => {
                self.summary
                    .warn(message.topic(), message.log_time, refused.to_string());
                return Ok(());
            }
        };
        self.catch_up(
            fix.header
                .stamp
                .to_nanos()
                .filter(|&t| t > 0)
                .unwrap_or(now),
        )?;
        let outcome = self
            .localizer
            .update_position(x, y, covariance, Some(&self.gps_gate))?;
        if outcome.accepted {
            self.summary.gps.accepted += 1;
        } else {
            self.summary.gps.rejected += 1;
        }
        self.record_pose(now)
    }

    fn scan(&mut self, message: &BagMessage, now: u64) -> Result<(), ReplayError> {
        self.summary.lines.scans += 1;
        if now < self.start_ns {
            return Ok(());
        }
        if self.mode.uses_laser() {
            let AnyMessage::LaserScan(scan) = message.decode()? else {
                return Ok(());
            };
            self.catch_up(
                scan.header
                    .stamp
                    .to_nanos()
                    .filter(|&t| t > 0)
                    .unwrap_or(now),
            )?;
            self.timer.last = Instant::now();
            let report = match self
                .localizer
                .update_scan_timed(&scan.as_scan(), &mut self.timer)
            {
                Ok(r) => r,
                Err(LocalizerError::Extraction(e)) => {
                    self.summary
                        .warn(message.topic(), message.log_time, e.to_string());
                    return Ok(());
                }
                Err(e) => return Err(e.into()),
            };
            let gap = self.tracking.gap_before_scan(now);
            let report = self.check_tracking(&scan, now, gap, report)?;
            if self.tracking.lost_for > 0 {
                self.summary.tracking.scans_lost += 1;
                if let Some(log) = self.events.as_mut() {
                    log.lost_scans.push(now);
                }
            }
            self.check_consistency(now)?;
            let l = &mut self.summary.lines;
            l.scans_used += 1;
            l.extracted += report.extracted as u64;
            l.matched += report.matched as u64;
            l.rejected += report.rejected as u64;
            l.fused += report.fused as u64;
            l.refused += report.refused as u64;
            if report.rejected + report.refused > 0 {
                self.mark(now, ReplayEvent::LinesRefused);
            }
            if let Some(out) = self.out.as_mut() {
                if report.map_built && !self.map_written {
                    out.map(now, self.localizer.map())?;
                    self.map_written = true;
                }
                let fused: Vec<usize> = self
                    .localizer
                    .last_fusions()
                    .iter()
                    .filter(|f| f.accepted)
                    .map(|f| f.observed)
                    .collect();
                let nis: Vec<String> = self
                    .localizer
                    .last_fusions()
                    .iter()
                    .map(|f| format!("{:.3}", f.nis))
                    .collect();
                out.scan_markers(
                    now,
                    &self.localizer.sensor_pose(),
                    self.localizer.last_lines(),
                    &fused,
                    &self.localizer.pose(),
                    self.localizer.covariance(),
                )?;
                let rejections: Vec<String> = self
                    .localizer
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
                    ("nis", nis.join(" ")),
                    ("rejections", rejections.join("; ")),
                ];
                let level =
                    u8::from(report.extracted > 0 && report.fused == 0 && !report.map_built);
                out.diagnostics(
                    now,
                    "ekf/scan",
                    level,
                    if level == 0 { "ok" } else { "no line fused" },
                    values,
                )?;
            }
        }
        self.record_pose(now)
    }

    /// The consistency monitor after a scan's update ([`consistency`]): one
    /// `/ekf/diagnostics` message when an over-confident stretch starts.
    fn check_consistency(&mut self, now: u64) -> Result<(), ReplayError> {
        let fused = self
            .localizer
            .last_fusions()
            .iter()
            .filter(|f| f.accepted)
            .map(|f| f.nis);
        let started = self.consistency.scan(fused, &mut self.summary.consistency);
        if let (true, Some(out)) = (started, self.out.as_mut()) {
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
        Ok(())
    }

    /// The loss monitor after a scan's update ([`tracking`]): on a motion gap, while lost,
    /// or while the heading is less certain than the search resolves, searches the map
    /// and restarts the filter at a verified pose. A search made while lost, with
    /// odometry since the scan before, only nominates candidates, which the next scans
    /// judge ([`verification`]); after a motion gap, or for a check of a tracked
    /// estimate, the search's own scan decides. Returns the report of the update that
    /// stands.
    fn check_tracking(
        &mut self,
        scan: &crate::ros2::sensor_msgs::LaserScan,
        now: u64,
        gap: bool,
        report: lrf_lines::ScanReport,
    ) -> Result<lrf_lines::ScanReport, ReplayError> {
        if !self.tracking.enabled {
            return Ok(report);
        }
        let lost_now = self.tracking.scan_fused(report.extracted, report.fused);
        let params = RelocalizeParams::default();
        let uncertain = tracking::uncertain(self.localizer.covariance(), &params);
        if gap {
            self.tracking.verification = None;
        }
        if self.tracking.lost_for == 0 {
            if gap || lost_now {
                self.tracking.declared = true;
                let counts = &mut self.summary.tracking;
                counts.losses += 1;
                counts.motion_gaps += u64::from(gap);
                self.mark(now, ReplayEvent::Lost);
                let why = if gap {
                    "lost: the motion source was silent since the last scan (a motion gap)"
                } else {
                    "lost: scans in a row with lines and none fused"
                };
                self.tracking_status(now, 2, why)?;
            } else if !uncertain {
                return Ok(report);
            }
        } else if !gap && !self.tracking.unlocked && report.fused >= tracking::MIN_VERIFIED_LINES {
            // Regained by tracking alone.
            self.tracking.lost_for = 0;
            self.tracking.verification = None;
            if std::mem::replace(&mut self.tracking.declared, false) {
                self.tracking_status(now, 0, "tracking again: the scan's lines fused")?;
            }
            return Ok(report);
        }
        let verify = !gap && (lost_now || self.tracking.lost_for > 0);
        if let Some(mut pending) = self.tracking.verification.take() {
            pending.add_scan(&self.localizer.fit_poses(&pending.poses(), &params));
            if !pending.done() {
                self.tracking.verification = Some(pending);
                self.tracking.lost_for += 1;
                return Ok(report);
            }
            let Some(won) = pending.verdict(&params) else {
                self.summary.tracking.refused += 1;
                self.tracking.lost_for += 1;
                return Ok(report);
            };
            return self.restart_at(scan, now, won, &params, report);
        }
        let pose = self.localizer.pose();
        let cov = self.localizer.covariance();
        let window = self
            .tracking
            .window(Point2::new(pose.x, pose.y), cov[(0, 0)] + cov[(1, 1)]);
        self.summary.tracking.searches += 1;
        let found = self.localizer.relocalize(&window, &params);
        if verify {
            match found.filter(|f| f.explains_scan(&params)) {
                Some(found) => {
                    self.tracking.verification = Some(verification::Verification::start(&found))
                }
                None => self.summary.tracking.refused += 1,
            }
            self.tracking.lost_for += 1;
            return Ok(report);
        }
        let Some(found) = found.filter(|r| r.is_unambiguous(&params)) else {
            self.summary.tracking.refused += 1;
            self.tracking.lost_for += 1;
            return Ok(report);
        };
        let won = verification::Verified {
            pose: found.best.pose,
            inliers: found.best.inliers,
            score: found.best.score,
            runner_up: found.runner_up,
        };
        self.restart_at(scan, now, won, &params, report)
    }

    /// Restarts the filter at the pose a search found (`won`) unless the estimate is
    /// already there, and fuses the scan again: kept if at least
    /// [`tracking::MIN_VERIFIED_LINES`] lines fuse, otherwise the filter is put back.
    /// Returns the report of the update that stands.
    fn restart_at(
        &mut self,
        scan: &crate::ros2::sensor_msgs::LaserScan,
        now: u64,
        won: verification::Verified,
        params: &RelocalizeParams,
        report: lrf_lines::ScanReport,
    ) -> Result<lrf_lines::ScanReport, ReplayError> {
        let best = won.pose;
        if !params.elsewhere(&best, &self.localizer.pose()) {
            // The estimate is where the search puts it.
            self.tracking.locked(&mut self.summary.tracking);
            return Ok(report);
        }
        let saved = self.localizer.clone();
        self.localizer
            .reset(best, tracking::restart_covariance(params))?;
        let again = self.localizer.update_scan(&scan.as_scan());
        let verified = match again {
            Ok(r) if r.fused >= tracking::MIN_VERIFIED_LINES => Some(r),
            _ => None,
        };
        let counts = &mut self.summary.tracking;
        match verified {
            Some(r) => {
                counts.relocalizations += 1;
                if counts.first_relocalizations_ns.len() < 10 {
                    counts.first_relocalizations_ns.push(now);
                }
                self.tracking.locked(counts);
                self.mark(now, ReplayEvent::Relocalized);
                if let Some(out) = self.out.as_mut() {
                    out.diagnostics(
                        now,
                        "ekf/relocalization",
                        1,
                        "relocalized: the filter restarted at the pose the map search found",
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
                Ok(r)
            }
            None => {
                self.localizer = saved;
                counts.refused += 1;
                self.tracking.lost_for += 1;
                Ok(report)
            }
        }
    }

    /// A message that came after the lag: counted and named, not fused.
    fn too_late(&mut self, late: &reorder::TooLate) {
        self.summary.too_late += 1;
        self.summary.warn(
            &late.topic,
            late.log_time,
            format!(
                "stamped {} ns, before {} ns already fused: more than [timing] max_lag late, dropped",
                late.stamp, late.after
            ),
        );
    }

    /// An `ekf/tracking` diagnostics message: a loss (level 2) or its end (level 0).
    /// Notes `event` at `now` for the picture, if events are kept.
    fn mark(&mut self, now: u64, event: ReplayEvent) {
        if let Some(log) = self.events.as_mut() {
            log.events.push((now, event));
        }
    }

    fn tracking_status(&mut self, now: u64, level: u8, message: &str) -> Result<(), ReplayError> {
        let Some(out) = self.out.as_mut() else {
            return Ok(());
        };
        let values = vec![
            ("scans_lost", self.summary.tracking.scans_lost.to_string()),
            ("losses", self.summary.tracking.losses.to_string()),
        ];
        Ok(out.diagnostics(now, "ekf/tracking", level, message, values)?)
    }

    /// A pose for the TUM trajectory and the output bag.
    fn record_pose(&mut self, now: u64) -> Result<(), ReplayError> {
        let pose = self.localizer.pose();
        self.poses
            .estimate(StampedPose::new(now, pose), self.localizer.covariance())?;
        if let Some(out) = self.out.as_mut() {
            out.pose(now, &pose, self.localizer.covariance())?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::devices::modbus_base::WheelTicks;
    use crate::live::messages::{self, Recorder};
    use crate::ros2::{RosMessage, Stamped};

    fn run(config: &Config) -> Run<'_> {
        let options = ReplayOptions {
            mode: Mode::Compass,
            map: None,
            init_from_truth: false,
            out_mcap: None,
            tum: None,
            keep_trajectories: false,
            global: false,
        };
        let preamble = Preamble {
            scan_frame: None,
            transforms: Vec::new(),
            first_reference: None,
        };
        let t = &config.topics.joint_states;
        Run::start(config, &options, &preamble, true, "test", t).unwrap()
    }

    fn feed<M: RosMessage + Stamped>(
        run: &mut Run<'_>,
        recorder: &mut Recorder,
        topic: &str,
        m: &M,
    ) {
        let message = recorder.record(None, topic, m).unwrap();
        run.handle(&message, message.log_time).unwrap();
    }

    #[test]
    fn extrapolation_reaches_only_shortly_past_the_last_motion_step() {
        const MS: u64 = 1_000_000;
        let mut clock = MotionClock::default();
        let step = MotionStep::Odometry(Motion {
            ds: 0.1,
            dtheta: 0.02,
        });
        // A step of 0.1 m over 100 ms, then scans 50, 150 and 250 ms after it ends.
        assert!(clock.advance(step, 1000 * MS, 1100 * MS).is_some());
        let ds = |s: Option<MotionStep>| match s {
            Some(MotionStep::Odometry(m)) => Some((m.ds * 1e6).round() / 1e6),
            _ => None,
        };
        assert_eq!(ds(clock.extrapolate(1150 * MS)), Some(0.05));
        assert_eq!(ds(clock.extrapolate(1150 * MS)), None, "already there");
        assert_eq!(ds(clock.extrapolate(1250 * MS)), Some(0.1));
        assert_eq!(
            ds(clock.extrapolate(1350 * MS)),
            None,
            "250 ms after the last motion message: not carried on"
        );
        // The next message's step counts only after the time the state refers to.
        assert_eq!(ds(clock.advance(step, 1200 * MS, 1300 * MS)), Some(0.05));
    }

    #[test]
    fn a_forecast_is_the_state_fusing_the_wheel_readings_would_give() {
        let config = Config::default();
        let (mut fused, mut all) = (run(&config), run(&config));
        let mut recorder = Recorder::new(Path::new("test"));
        // Wheel readings every 0.1 s of a robot turning left; a compass heading between
        // the second and third, so the third is predicted only over its last half.
        let joints: Vec<_> = (0..6)
            .map(|i| {
                let ticks = WheelTicks {
                    left: 40 * i,
                    right: 55 * i,
                };
                messages::joint_state(&config, 1_000_000_000 + i as u64 * 100_000_000, ticks)
            })
            .collect();
        // A bearing of 90° less a little: heading 0.02 rad, within the gate.
        let bearing = std::f64::consts::FRAC_PI_2 - 0.02;
        let heading = messages::compass(&config, 1_150_000_000, bearing);
        let (topic, compass) = (&config.topics.joint_states, &config.topics.compass);
        assert_eq!(fused.forecast(&joints).unwrap(), None, "nothing fused yet");
        for run in [&mut fused, &mut all] {
            feed(run, &mut recorder, topic, &joints[0]);
            feed(run, &mut recorder, topic, &joints[1]);
            feed(run, &mut recorder, compass, &heading);
        }
        for j in &joints[2..] {
            feed(&mut all, &mut recorder, topic, j);
        }
        assert_eq!(fused.summary.compass.accepted, 1);
        let before = *fused.localizer.ekf();
        let forecast = fused.forecast(&joints[2..]).unwrap().unwrap();

        assert_eq!(
            *fused.localizer.ekf(),
            before,
            "the filter is left as it was"
        );
        assert_eq!(forecast.fused_ns, 1_150_000_000);
        assert_eq!(forecast.t_ns, 1_500_000_000);
        assert_eq!(forecast.pose, all.localizer.pose());
        assert_eq!(forecast.covariance, *all.localizer.covariance());
        assert!(
            forecast.pose.theta > before.pose().theta + 0.01,
            "it turned"
        );
        // Nothing held back: the fused state at its own time.
        let now = fused.forecast(&[]).unwrap().unwrap();
        assert_eq!((now.t_ns, now.pose), (1_150_000_000, before.pose()));
    }
}

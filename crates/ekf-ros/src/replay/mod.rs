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
mod error;
pub mod events;
pub mod grow_map;
mod hook;
pub mod inputs;
pub mod outputs;
mod run;
mod sink;
pub mod stamps;
pub mod summary;

pub use error::ReplayError;
pub use hook::ScanHook;
pub use run::Run;

use crate::config::{Config, MotionSource};
use crate::mcap_io::BagReader;
use crate::ros2::geometry_msgs::TransformStamped;
use crate::ros2::{type_name_matches, AnyMessage};
use crate::trajectory::Trajectory;
use ekf_core::Pose2;
pub use events::ReplayEvent;
use inputs::{mount_from_tf, pose2};
use lrf_lines::LineMap;
use nalgebra::Matrix3;
use std::path::{Path, PathBuf};
use std::time::Instant;
pub use summary::ReplaySummary;

pub use ekf_fusion::Mode;

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
    /// ([`ekf_fusion::tracking`]) and the filter starts where the search locks on. Needs a map.
    pub global: bool,
    /// Output bag.
    pub out_mcap: Option<PathBuf>,
    /// Output TUM trajectory.
    pub tum: Option<PathBuf>,
    /// Keep adding walls to the map as the robot explores ([`grow_map::MapGrowth`]);
    /// [`ReplayOutcome::map`] is then the grown map.
    pub grow_map: bool,
    /// Keep the estimated and reference trajectories in memory (for plots); otherwise the
    /// replay streams in memory that does not grow with the log.
    pub keep_trajectories: bool,
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

/// What the first pass over the log found: the scan frame, static transforms up to the
/// first scan, and the first reference pose.
pub struct Preamble {
    /// The frame of the first scan.
    pub scan_frame: Option<String>,
    /// The static transforms up to the first scan.
    pub transforms: Vec<TransformStamped>,
    /// The first reference pose and its log time (ns), when asked for.
    pub first_reference: Option<(u64, Pose2<f64>)>,
}

/// Replays `log` with `config`. `progress(done, total)` is called as messages are read.
pub fn replay(
    log: &Path,
    config: &Config,
    options: &ReplayOptions,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<ReplayOutcome, ReplayError> {
    replay_with(log, config, options, None, progress)
}

/// [`replay`], handing every fused scan to `hook` when there is one ([`ScanHook`]).
pub fn replay_with(
    log: &Path,
    config: &Config,
    options: &ReplayOptions,
    hook: Option<&mut dyn ScanHook>,
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
        (config.timing.max_lag * 1e9) as u64,
    )?;
    // Growth needs the first-scan map and a filter without the loss monitor: a given
    // map would be replaced by the grown one, and walls would be placed before a global
    // search locked on.
    if options.grow_map && (options.map.is_some() || options.global || hook.is_some()) {
        return Err(ReplayError::GrowMapNeedsFirstScan);
    }
    let mut growth = match options.grow_map {
        true => Some(grow_map::MapGrowth::new(&config.slam)?),
        false => None,
    };
    let hook = hook.or(growth.as_mut().map(|g| g as &mut dyn ScanHook));
    if let Some(hook) = hook {
        run = run.with_hook(hook);
    }
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
    let (mut failure, mut read_failure) = (None, None);
    let mut done = 0;
    for message in bag.messages()? {
        let message = match message {
            Ok(m) => m,
            Err(e) => match run.read_past(&e) {
                Ok(true) => continue,
                Ok(false) => {
                    read_failure = Some(e.into());
                    break;
                }
                Err(write_failed) => {
                    failure = Some(write_failed);
                    break;
                }
            },
        };
        if let Err(e) = run.handle(&message) {
            failure = Some(e);
            break;
        }
        done += 1;
        progress(done, total);
    }
    // What was read before the end (or the damage) is fused, in stamp order.
    if failure.is_none() {
        failure = run.fuse_held().err();
    }
    run.finish(started, failure.or(read_failure))
}

/// The laser's mounting pose: `base_frame` → the scan's frame from `/tf_static` when
/// the log has that chain and the configuration allows it, else `localizer.laser_mount`.
/// Returns the pose and where it came from (`tf_static` or `config`).
pub fn laser_mount(
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
pub fn read_preamble(
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
        // Damage read past is reported by the replay itself; the stream ends at any other.
        let Ok(message) = message else { continue };
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
            p.first_reference = message
                .decode()
                .ok()
                .and_then(|m| reference_pose(&m))
                .map(|pose| (message.log_time, pose));
        }
        let scan_done = p.scan_frame.is_some() || !has_scan;
        if scan_done && (!want_reference || p.first_reference.is_some()) {
            break;
        }
    }
    Ok(p)
}

/// The reference pose a decoded `nav_msgs/Odometry` or `geometry_msgs/PoseStamped` holds;
/// `None` if not finite or another type.
pub fn reference_pose(message: &AnyMessage) -> Option<Pose2<f64>> {
    match message {
        AnyMessage::Odometry(o) => pose2(&o.pose.pose),
        AnyMessage::PoseStamped(p) => pose2(&p.pose),
        _ => None,
    }
}

/// What to do about a missing topic the mode cannot do without.
pub const TOPIC_HINT: &str = "; name the log's topic in the config's [topics] table";

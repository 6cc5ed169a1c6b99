//! Why a replay could not start or could not finish.

use crate::mcap_io::{MessageError, ReadError, WriteError};
use ekf_fusion::FusionError;
use lrf_lines::LocalizerError;

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
    /// `--grow-map` with a given map, global localization or another scan hook.
    #[error("--grow-map grows the first scan's map: it cannot be combined with --map or --global")]
    GrowMapNeedsFirstScan,
    /// The SLAM pose graph could not be built or solved.
    #[error("map build --slam: {0}")]
    Slam(String),
}

impl From<FusionError> for ReplayError {
    fn from(e: FusionError) -> Self {
        match e {
            FusionError::Localizer(e) => Self::Filter(e),
            FusionError::Setting(e) => Self::Filter(LocalizerError::Setting(e)),
            FusionError::TrackingNeedsMap => Self::GlobalNeedsMap,
        }
    }
}

//! `ekf evaluate EST --truth REF`: absolute and relative pose errors as `evo` defines them.

use crate::eval::{ape, rpe, AlignMode, ApeOptions, ApeSummary, EvalError, RpeOptions, RpeSummary};
use crate::mcap_io::{BagReader, MessageError, ReadError};
use crate::replay::inputs::pose2;
use crate::ros2::geometry_msgs::{PoseStamped, PoseWithCovarianceStamped};
use crate::ros2::nav_msgs::Odometry;
use crate::ros2::{type_name_matches, AnyMessage, RosMessage};
use crate::trajectory::Trajectory;
use crate::tum::{read_tum_file, TumError};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// Why an evaluation failed.
#[derive(Debug, thiserror::Error)]
pub enum EvaluateError {
    /// A trajectory file could not be read.
    #[error(transparent)]
    Tum(#[from] TumError),
    /// The trajectories could not be compared (no poses matched in time, …).
    #[error("{0}")]
    Eval(#[from] EvalError),
    /// A bag could not be read.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// A message in a bag could not be decoded.
    #[error(transparent)]
    Message(#[from] MessageError),
    /// The pose topic carries messages that are not poses.
    #[error("{path}: topic {topic} carries {type_name}; expected one of {expected}")]
    NotPoses {
        /// The bag.
        path: String,
        /// The topic.
        topic: String,
        /// Its message type.
        type_name: String,
        /// The pose types that can be read.
        expected: String,
    },
    /// A bag has none of the pose topics looked for.
    #[error("{path}: no pose topic {wanted}; the bag has: {available}")]
    NoPoseTopic {
        /// The bag.
        path: String,
        /// The topics looked for.
        wanted: String,
        /// Its topics and types.
        available: String,
    },
}

/// Topics read from a bag, in this order of preference, unless one is named: the
/// replay's estimate, then the log's reference.
pub const POSE_TOPICS: [&str; 2] = ["/ekf/pose", "/ground_truth"];

/// What `ekf evaluate` reports; `--json` prints it as JSON.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EvaluationReport {
    /// Absolute pose error (ATE: `ape.translation_m.rmse`).
    pub ape: ApeSummary,
    /// Relative pose error between consecutive matched poses.
    pub rpe: RpeSummary,
}

/// Reads a trajectory: a TUM text file, or a ROS 2 bag (an MCAP or `.db3` file or a bag
/// directory, [`crate::mcap_io::sniff::is_bag`]) whose `topic` (default:
/// the first of [`POSE_TOPICS`] it has) carries `geometry_msgs/PoseWithCovarianceStamped`,
/// `geometry_msgs/PoseStamped` or `nav_msgs/Odometry`; stamps are log times.
pub fn load_trajectory(path: &Path, topic: Option<&str>) -> Result<Trajectory, EvaluateError> {
    if !crate::mcap_io::sniff::is_bag(path) {
        return Ok(read_tum_file(path)?);
    }
    let bag = BagReader::open(path)?;
    let has = |t: &str| bag.topics().iter().any(|i| i.topic == t);
    let wanted: Vec<&str> = topic.map_or(POSE_TOPICS.to_vec(), |t| vec![t]);
    let Some(topic) = wanted.iter().copied().find(|t| has(t)) else {
        return Err(EvaluateError::NoPoseTopic {
            path: path.display().to_string(),
            wanted: wanted.join(" or "),
            available: bag.describe_topics(),
        });
    };
    let pose_types = [
        PoseWithCovarianceStamped::type_name(),
        PoseStamped::type_name(),
        Odometry::type_name(),
    ];
    if let Some(other) = bag.topics().iter().find(|i| {
        i.topic == topic
            && !pose_types
                .iter()
                .any(|p| type_name_matches(p, &i.type_name))
    }) {
        return Err(EvaluateError::NotPoses {
            path: path.display().to_string(),
            topic: topic.into(),
            type_name: match other.type_name.as_str() {
                "" => "messages without a schema".into(),
                name => name.into(),
            },
            expected: pose_types.join(", "),
        });
    }
    let mut trajectory = Trajectory::default();
    for message in bag.messages()? {
        let message = message?;
        if message.topic() != topic {
            continue;
        }
        let pose = match message.decode()? {
            AnyMessage::PoseWithCovarianceStamped(p) => pose2(&p.pose.pose),
            AnyMessage::PoseStamped(p) => pose2(&p.pose),
            AnyMessage::Odometry(o) => pose2(&o.pose.pose),
            _ => None,
        };
        if let Some(pose) = pose {
            trajectory.push(message.log_time, pose);
        }
    }
    Ok(trajectory)
}

/// Compares `estimate` with `reference`: APE and RPE (delta 1 frame), in the same frame
/// unless `align` asks for a rigid (SE(2)) Umeyama alignment first, as `evo -a`.
pub fn evaluate(
    estimate: &Trajectory,
    reference: &Trajectory,
    align: bool,
) -> Result<EvaluationReport, EvaluateError> {
    let mut ape_options = ApeOptions::default();
    let mut rpe_options = RpeOptions::default();
    if align {
        ape_options.alignment.mode = AlignMode::Rigid;
        rpe_options.alignment.mode = AlignMode::Rigid;
    }
    Ok(EvaluationReport {
        ape: ape(reference, estimate, &ape_options)?.summary,
        rpe: rpe(reference, estimate, &rpe_options)?.summary,
    })
}

impl EvaluationReport {
    /// A short human-readable table.
    pub fn to_table(&self) -> String {
        let mut s = String::new();
        let a = &self.ape;
        let _ = writeln!(
            s,
            "matched poses: {} (estimate {}, reference {})",
            a.matched_poses, a.estimate_poses, a.reference_poses
        );
        let _ = writeln!(
            s,
            "{:<28} {:>10} {:>10} {:>10} {:>10}",
            "", "rmse", "mean", "median", "max"
        );
        let rows = [
            ("APE position (m)", &a.translation_m),
            ("APE heading (deg)", &a.heading_error_deg),
            ("RPE position (m/frame)", &self.rpe.translation_m),
            ("RPE heading (deg/frame)", &self.rpe.heading_error_deg),
        ];
        for (name, st) in rows {
            let _ = writeln!(
                s,
                "{name:<28} {:>10.4} {:>10.4} {:>10.4} {:>10.4}",
                st.rmse, st.mean, st.median, st.max
            );
        }
        s
    }
}

//! What `ekf live` reports: its events as they happen, its summary at the end, and why
//! it failed.

use crate::devices::DeviceError;
use ekf_core::Pose2;
use ekf_ros::mcap_io::WriteError;
use ekf_ros::replay::{ReplayError, ReplaySummary};
use nalgebra::Matrix3;
use std::collections::BTreeMap;

/// What the run reports as it goes.
#[derive(Debug, Clone, PartialEq)]
pub enum LiveEvent {
    /// The estimate now, reported as wheel readings arrive (at most one per reading, each
    /// later than the one before, none until a first motion step has been fused): the
    /// fused state predicted through the wheel readings still held back (measurements
    /// made before them may still be arriving; see [`run`](super::run)), as robot_localization's
    /// `predict_to_current_time` does. The recording keeps the fused estimates.
    Pose {
        /// Time (ns since the Unix epoch): when the newest wheel reading held back was
        /// made, or the fused state's time if none is.
        t_ns: u64,
        /// Time of the fused state it was predicted from (ns since the Unix epoch).
        fused_ns: u64,
        /// The pose.
        pose: Pose2<f64>,
        /// Its covariance.
        covariance: Matrix3<f64>,
    },
    /// A device connected, failed or came back; or (`filter`) a pose could not be
    /// predicted ahead.
    Device {
        /// `laser`, `base`, `gps` or `filter`.
        device: &'static str,
        /// 0 OK, 1 warning.
        level: u8,
        /// What happened.
        text: String,
    },
}

impl LiveEvent {
    /// A pose as one JSON object (`ekf live --json` prints one per line): `t_ns`,
    /// `fused_ns`, `x`, `y`, `theta`, `sigma_xy` (`[σx, σy]`) and `sigma_theta`. `None`
    /// for a device event.
    pub fn pose_json(&self) -> Option<serde_json::Value> {
        match self {
            LiveEvent::Pose {
                t_ns,
                fused_ns,
                pose,
                covariance,
            } => Some(serde_json::json!({
                "t_ns": t_ns, "fused_ns": fused_ns,
                "x": pose.x, "y": pose.y, "theta": pose.theta,
                "sigma_xy": [covariance[(0, 0)].sqrt(), covariance[(1, 1)].sqrt()],
                "sigma_theta": covariance[(2, 2)].sqrt(),
            })),
            LiveEvent::Device { .. } => None,
        }
    }
}

/// One line as `ekf live` prints it: a pose with its time (s), position, heading, the
/// position's σ (√(σx² + σy²)) and how long it has been predicted on odometry alone; or
/// a device's message, prefixed `warning: ` when it is one.
impl std::fmt::Display for LiveEvent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LiveEvent::Pose {
                t_ns,
                fused_ns,
                pose,
                covariance,
            } => write!(
                f,
                "{:.3}  x {:8.3} m  y {:8.3} m  θ {:7.2}°  σxy {:.3} m  (odometry since {:.2} s)",
                *t_ns as f64 * 1e-9,
                pose.x,
                pose.y,
                pose.theta.to_degrees(),
                (covariance[(0, 0)] + covariance[(1, 1)]).sqrt(),
                t_ns.saturating_sub(*fused_ns) as f64 * 1e-9
            ),
            LiveEvent::Device { level, text, .. } => {
                let what = if *level == 0 { "" } else { "warning: " };
                write!(f, "{what}{text}")
            }
        }
    }
}

/// Counts of everything that happened, per device and in the filter.
#[derive(Debug, Clone, serde::Serialize)]
pub struct LiveSummary {
    /// The filter's summary (as `ekf replay` reports it for the recording).
    pub filter: ReplaySummary,
    /// Each device's counters since its last (re)connection.
    pub devices: BTreeMap<&'static str, serde_json::Value>,
    /// Reconnections per device.
    pub reconnects: BTreeMap<&'static str, u64>,
    /// Base reads that repeated the previous sample.
    pub base_repeated_samples: u64,
    /// Base samples whose replies were lost (counter jumps).
    pub base_missed_samples: u64,
    /// Base reads refused: an encoder change no wheel can make in the time, or a
    /// sample counter that stepped back (the controller restarted its counts).
    pub base_implausible_samples: u64,
    /// Base reconnections after which the controller had counted on: the wheel motion
    /// of the outage was kept (fused as one step, its noise growing with the distance).
    pub base_outages_bridged: u64,
    /// Base reconnections to a restarted controller: the motion of the outage is lost.
    pub base_restarts: u64,
    /// Compass bearings out of range (not fused).
    pub compass_invalid: u64,
    /// GPS fixes recorded.
    pub gps_fixes: u64,
    /// Measurements that arrived after a later one had been fused: dropped.
    pub late_readings: u64,
    /// The recording, if any.
    pub recording: Option<String>,
}

/// The summary as `ekf live` prints it at the end: the filter's counts, each device's
/// counters and reconnections, and the recording.
impl std::fmt::Display for LiveSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = &self.filter;
        writeln!(
            f,
            "live: motion steps {}, scans {} (used {}), lines fused {}, compass fused {}",
            s.motion_steps, s.lines.scans, s.lines.scans_used, s.lines.fused, s.compass.accepted
        )?;
        for (device, counters) in &self.devices {
            writeln!(f, "  {device}: {counters}")?;
        }
        for (device, n) in &self.reconnects {
            writeln!(f, "  {device}: reconnected {n} times")?;
        }
        if self.base_outages_bridged + self.base_restarts > 0 {
            writeln!(
                f,
                "  base after reconnecting: the motion of the outage kept {} times, the \
                 controller restarted {} times",
                self.base_outages_bridged, self.base_restarts
            )?;
        }
        if let Some(r) = &self.recording {
            writeln!(f, "  recording: {r}")?;
        }
        Ok(())
    }
}

/// Why a live run failed.
#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    /// A device could not be brought up.
    #[error(transparent)]
    Device(#[from] DeviceError),
    /// The configuration does not suit live mode.
    #[error("{0}")]
    Config(String),
    /// The filter or its outputs failed.
    #[error(transparent)]
    Filter(#[from] ReplayError),
    /// A message could not be recorded.
    #[error(transparent)]
    Record(#[from] WriteError),
}

/// The result of a run: the summary, and the error that ended it early, if any (the
/// recording is finished either way).
#[derive(Debug)]
pub struct LiveOutcome {
    /// Counts.
    pub summary: LiveSummary,
    /// Why the run ended early.
    pub failure: Option<LiveError>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_and_summary_as_printed() {
        let pose = LiveEvent::Pose {
            t_ns: 12_345_000_000,
            fused_ns: 12_245_000_000,
            pose: Pose2::new(1.5, -2.25, std::f64::consts::FRAC_PI_2),
            covariance: Matrix3::from_diagonal(&nalgebra::Vector3::new(0.0009, 0.0016, 0.0001)),
        };
        assert_eq!(
            pose.to_string(),
            "12.345  x    1.500 m  y   -2.250 m  θ   90.00°  σxy 0.050 m  (odometry since 0.10 s)"
        );
        let json = pose.pose_json().unwrap();
        assert_eq!(json["t_ns"], 12_345_000_000u64);
        assert_eq!(json["sigma_xy"][1], 0.04);
        assert_eq!(json["sigma_theta"], 0.01);
        let warning = LiveEvent::Device {
            device: "base",
            level: 1,
            text: "base: no reply".into(),
        };
        assert_eq!(warning.to_string(), "warning: base: no reply");
        assert_eq!(warning.pose_json(), None);
        let mut filter = ReplaySummary {
            motion_steps: 10,
            ..Default::default()
        };
        filter.lines.scans = 4;
        filter.lines.scans_used = 3;
        filter.lines.fused = 7;
        filter.compass.accepted = 2;
        let summary = LiveSummary {
            filter,
            devices: BTreeMap::from([("laser", serde_json::json!({"scans": 4}))]),
            reconnects: BTreeMap::from([("base", 1)]),
            base_repeated_samples: 0,
            base_missed_samples: 0,
            base_implausible_samples: 0,
            base_outages_bridged: 0,
            base_restarts: 0,
            compass_invalid: 0,
            gps_fixes: 0,
            late_readings: 0,
            recording: Some("run.mcap: 40 messages".into()),
        };
        assert_eq!(
            summary.to_string(),
            "live: motion steps 10, scans 4 (used 3), lines fused 7, compass fused 2\n  \
             laser: {\"scans\":4}\n  base: reconnected 1 times\n  recording: run.mcap: 40 \
             messages\n"
        );
    }
}

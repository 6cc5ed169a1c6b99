//! Writes a simulated run as a ROS 2 bag with the topics of docs/ARCHITECTURE.md §4: wheel encoder
//! angles on `/joint_states`, the compass on `/compass` (`sensor_msgs/Imu`, with the
//! compass's variance), sweeps on `/scan`, the laser mount on `/tf_static`, and the true
//! pose on `/ground_truth`; plus an MCAP metadata record `simulation` naming the scenario,
//! the seed and every noise parameter. The same scenario and seed give the same bytes.

use super::scenario::Scenario;
use super::sensors::LASER_RANGE_MIN;
use super::stepper::Sample;
use ekf_ros::mcap_io::{BagWriter, WriteError};
use ekf_ros::ros2::build::{
    compass_imu, header, laser_scan, mount_transform, odometry, BASE_FRAME, MAP_FRAME,
};
use ekf_ros::ros2::sensor_msgs::JointState;
use std::path::Path;

/// Joint names of the wheels (the configuration's defaults).
pub const WHEEL_JOINTS: [&str; 2] = ["left_wheel_joint", "right_wheel_joint"];

/// A bag being written from a simulation.
pub struct LogRecorder {
    writer: BagWriter,
    scenario: Scenario,
    last_ticks: Option<[i64; 2]>,
    messages: u64,
}

impl LogRecorder {
    /// Creates `path` and writes the metadata of `scenario` run with `seed`.
    pub fn create(path: &Path, scenario: &Scenario, seed: u64) -> Result<Self, WriteError> {
        let mut writer = BagWriter::create(path)?;
        writer.write_metadata(
            "simulation",
            &[
                ("generator", "ekf simulate".into()),
                ("scenario", scenario.name.clone()),
                ("seed", seed.to_string()),
                ("dt_s", scenario.dt.to_string()),
                ("duration_s", scenario.duration_s.to_string()),
                ("robot", json(&scenario.robot)),
                ("compass", json(&scenario.compass)),
                ("laser", json(&scenario.laser)),
                ("drive", json(&scenario.drive)),
                (
                    "ground_truth",
                    "/ground_truth is the simulated true pose".into(),
                ),
            ],
        )?;
        Ok(Self {
            writer,
            scenario: scenario.clone(),
            last_ticks: None,
            messages: 0,
        })
    }

    /// Writes one step: at the first, the laser mount; then wheel angles and speeds,
    /// the compass, the scan if any, and the true pose, all stamped `sample.t_ns`.
    pub fn record(&mut self, sample: &Sample) -> Result<(), WriteError> {
        let t = sample.t_ns;
        let s = &self.scenario;
        if self.last_ticks.is_none() {
            self.writer
                .write_at("/tf_static", t, &mount_transform(t, &s.laser.mount))?;
            self.messages += 1;
        }
        let tick = s.robot.tick();
        let previous = self.last_ticks.unwrap_or(sample.ticks);
        let joints = JointState {
            header: header(t, BASE_FRAME),
            name: WHEEL_JOINTS.iter().map(|n| (*n).to_owned()).collect(),
            position: sample.ticks.iter().map(|&n| n as f64 * tick).collect(),
            velocity: (0..2)
                .map(|w| (sample.ticks[w] - previous[w]) as f64 * tick / s.dt)
                .collect(),
            effort: Vec::new(),
        };
        self.last_ticks = Some(sample.ticks);
        self.writer.write("/joint_states", &joints)?;
        let variance = s.compass.sigma.powi(2);
        self.writer.write(
            "/compass",
            &compass_imu(t, sample.compass.heading, variance),
        )?;
        self.messages += 2;
        if let Some(ranges) = &sample.scan {
            let l = &s.laser;
            let scan = laser_scan(
                t,
                l.angle_min(),
                l.resolution,
                (LASER_RANGE_MIN, l.max_range),
                ranges.to_vec(),
            );
            self.writer.write("/scan", &scan)?;
            self.messages += 1;
        }
        self.writer
            .write("/ground_truth", &odometry(t, &sample.truth, MAP_FRAME))?;
        self.messages += 1;
        Ok(())
    }

    /// Messages written so far.
    pub fn messages(&self) -> u64 {
        self.messages
    }

    /// Finishes the file (summary and index).
    pub fn finish(self) -> Result<(), WriteError> {
        self.writer.finish()
    }
}

/// JSON text of a parameter struct for the metadata record.
fn json<T: serde::Serialize>(value: &T) -> String {
    serde_json::to_string(value).unwrap_or_default()
}

//! What a replay writes to its output bag, for Foxglove and ROS 2 tools: the pose with
//! covariance, line markers (extracted, matched, the map), the 2σ covariance ellipse, and
//! per-update diagnostics.

use crate::mcap_io::{BagWriter, WriteError};
use crate::ros2::builtin_interfaces::Time;
use crate::ros2::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue};
use crate::ros2::geometry_msgs::{
    Point, Pose, PoseWithCovariance, PoseWithCovarianceStamped, Quaternion, Vector3,
};
use crate::ros2::std_msgs::{ColorRGBA, Header};
use crate::ros2::visualization_msgs::{Marker, MarkerArray};
use ekf_core::Pose2;
use lrf_lines::{LineMap, ObservedLine};
use nalgebra::{Matrix2, Matrix3, Point2, SymmetricEigen};

/// Topic of the pose estimate (`geometry_msgs/PoseWithCovarianceStamped`).
pub const POSE_TOPIC: &str = "/ekf/pose";
/// Topic of the line markers and the covariance ellipse (`visualization_msgs/MarkerArray`).
pub const MARKERS_TOPIC: &str = "/ekf/markers";
/// Topic of the map's markers, written once (`visualization_msgs/MarkerArray`).
pub const MAP_TOPIC: &str = "/ekf/map";
/// Topic of the per-update diagnostics (`diagnostic_msgs/DiagnosticArray`).
pub const DIAGNOSTICS_TOPIC: &str = "/ekf/diagnostics";
/// The frame of every output.
pub const MAP_FRAME: &str = "map";

/// Chi-square quantile for 2 dof at 0.8647 (`exp(−2) = 1 − p`): the ellipse that holds
/// a 2-D Gaussian's "2σ" contour, `r² = 4`.
const TWO_SIGMA_SQUARED: f64 = 4.0;

fn header(t_ns: u64) -> Header {
    Header {
        stamp: Time::from_nanos(t_ns).unwrap_or_default(),
        frame_id: MAP_FRAME.into(),
    }
}

fn color(r: f32, g: f32, b: f32) -> ColorRGBA {
    ColorRGBA { r, g, b, a: 1.0 }
}

fn point(p: &Point2<f64>) -> Point {
    Point {
        x: p.x,
        y: p.y,
        z: 0.0,
    }
}

/// The output bag of a replay.
pub struct OutputBag {
    writer: BagWriter,
}

impl OutputBag {
    /// Creates the bag.
    pub fn create(path: &std::path::Path) -> Result<Self, WriteError> {
        Ok(Self {
            writer: BagWriter::create(path)?,
        })
    }

    /// The pose and its covariance. The 6×6 covariance is row-major over
    /// (x, y, z, roll, pitch, yaw); z, roll and pitch are not estimated and left 0.
    pub fn pose(
        &mut self,
        t_ns: u64,
        pose: &Pose2<f64>,
        p: &Matrix3<f64>,
    ) -> Result<(), WriteError> {
        let mut covariance = [0.0; 36];
        let index = [0, 1, 5];
        for (i, &ri) in index.iter().enumerate() {
            for (j, &cj) in index.iter().enumerate() {
                covariance[ri * 6 + cj] = p[(i, j)];
            }
        }
        let msg = PoseWithCovarianceStamped {
            header: header(t_ns),
            pose: PoseWithCovariance {
                pose: Pose {
                    position: Point {
                        x: pose.x,
                        y: pose.y,
                        z: 0.0,
                    },
                    orientation: Quaternion::from_yaw(pose.theta),
                },
                covariance,
            },
        };
        self.writer.write(POSE_TOPIC, &msg)
    }

    /// The map's segments as a line list.
    pub fn map(&mut self, t_ns: u64, map: &LineMap) -> Result<(), WriteError> {
        let points = map
            .segments
            .iter()
            .flat_map(|s| [point(&s.start), point(&s.end)])
            .collect();
        let marker = line_list(t_ns, "map", 0, points, color(0.6, 0.6, 0.6), 0.05);
        self.writer.write_at(
            MAP_TOPIC,
            t_ns,
            &MarkerArray {
                markers: vec![marker],
            },
        )
    }

    /// After a scan: the extracted lines (world frame, at `sensor`), those that were
    /// fused, and the 2σ position ellipse.
    pub fn scan_markers(
        &mut self,
        t_ns: u64,
        sensor: &Pose2<f64>,
        lines: &[ObservedLine],
        fused: &[usize],
        pose: &Pose2<f64>,
        p: &Matrix3<f64>,
    ) -> Result<(), WriteError> {
        let world = |l: &ObservedLine| {
            [
                point(&sensor.transform_point(&l.start)),
                point(&sensor.transform_point(&l.end)),
            ]
        };
        let extracted = lines.iter().flat_map(world).collect();
        let matched = fused
            .iter()
            .filter_map(|&i| lines.get(i))
            .flat_map(world)
            .collect();
        let markers = vec![
            line_list(t_ns, "extracted", 0, extracted, color(1.0, 0.6, 0.0), 0.03),
            line_list(t_ns, "matched", 0, matched, color(0.0, 0.8, 0.2), 0.05),
            covariance_ellipse(t_ns, pose, p),
        ];
        self.writer
            .write_at(MARKERS_TOPIC, t_ns, &MarkerArray { markers })
    }

    /// One diagnostics message: a status named `name` with key/value pairs.
    pub fn diagnostics(
        &mut self,
        t_ns: u64,
        name: &str,
        level: u8,
        message: &str,
        values: Vec<(&str, String)>,
    ) -> Result<(), WriteError> {
        let status = DiagnosticStatus {
            level,
            name: name.into(),
            message: message.into(),
            hardware_id: "ekf".into(),
            values: values
                .into_iter()
                .map(|(key, value)| KeyValue {
                    key: key.into(),
                    value,
                })
                .collect(),
        };
        self.writer.write(
            DIAGNOSTICS_TOPIC,
            &DiagnosticArray {
                header: header(t_ns),
                status: vec![status],
            },
        )
    }

    /// The underlying bag writer, for messages of other kinds (live mode records its raw
    /// device readings next to the estimates).
    pub fn writer(&mut self) -> &mut BagWriter {
        &mut self.writer
    }

    /// Finishes the bag (summary and footer). Dropping it without calling this still
    /// finishes it, best effort.
    pub fn finish(self) -> Result<(), WriteError> {
        self.writer.finish()
    }
}

fn line_list(t_ns: u64, ns: &str, id: i32, points: Vec<Point>, c: ColorRGBA, width: f64) -> Marker {
    Marker {
        header: header(t_ns),
        ns: ns.into(),
        id,
        r#type: Marker::LINE_LIST,
        action: Marker::ADD,
        pose: Pose::default(),
        scale: Vector3 {
            x: width,
            y: 0.0,
            z: 0.0,
        },
        color: c,
        points,
        ..Marker::default()
    }
}

/// The 2σ ellipse of the position covariance as a closed line strip: the contour
/// `dᵀ P_xy⁻¹ d = 4` around the estimate.
fn covariance_ellipse(t_ns: u64, pose: &Pose2<f64>, p: &Matrix3<f64>) -> Marker {
    let pxy = Matrix2::new(p[(0, 0)], p[(0, 1)], p[(1, 0)], p[(1, 1)]);
    let eig = SymmetricEigen::new(pxy);
    let axes = eig
        .eigenvalues
        .map(|l| (l.max(0.0) * TWO_SIGMA_SQUARED).sqrt());
    let points = (0..=36)
        .map(|k| {
            let a = f64::from(k) * std::f64::consts::TAU / 36.0;
            let local =
                eig.eigenvectors * nalgebra::Vector2::new(axes[0] * a.cos(), axes[1] * a.sin());
            Point {
                x: pose.x + local[0],
                y: pose.y + local[1],
                z: 0.0,
            }
        })
        .collect();
    Marker {
        r#type: Marker::LINE_STRIP,
        ..line_list(
            t_ns,
            "covariance_2sigma",
            0,
            points,
            color(0.2, 0.4, 1.0),
            0.02,
        )
    }
}

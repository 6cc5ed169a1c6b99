//! One message of every supported type, with distinctive field values, on its own topic.
//! Shared by the `write_sample_bag` example (read back by the Python check) and the Rust
//! round-trip tests; `tests/python/test_mcap_readable.py` checks the same values.

use ekf_cli::ros2::builtin_interfaces::{Duration, Time};
use ekf_cli::ros2::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue};
use ekf_cli::ros2::geometry_msgs::{
    Point, Pose, PoseStamped, PoseWithCovariance, PoseWithCovarianceStamped, Quaternion, Transform,
    TransformStamped, Twist, TwistWithCovariance, Vector3,
};
use ekf_cli::ros2::nav_msgs::Odometry;
use ekf_cli::ros2::sensor_msgs::{
    CompressedImage, Imu, JointState, LaserScan, MagneticField, NavSatFix, NavSatStatus,
};
use ekf_cli::ros2::std_msgs::{ColorRGBA, Header};
use ekf_cli::ros2::tf2_msgs::TFMessage;
use ekf_cli::ros2::visualization_msgs::{Marker, MarkerArray, MeshFile, UVCoordinate};
use ekf_cli::ros2::AnyMessage;

/// Stamp of every sample message: 100 s + 250 ns.
pub const STAMP: Time = Time {
    sec: 100,
    nanosec: 250,
};

/// Log time (ns) of the `i`-th sample message: the stamp plus `i` µs, so they are ordered.
pub fn log_time(i: usize) -> u64 {
    STAMP.to_nanos().expect("positive stamp") + i as u64 * 1000
}

fn header(frame: &str) -> Header {
    Header {
        stamp: STAMP,
        frame_id: frame.into(),
    }
}

/// Covariance with entry `k` = `k + offset`, so misplaced entries are visible.
fn covariance36(offset: f64) -> [f64; 36] {
    std::array::from_fn(|k| k as f64 + offset)
}

fn covariance9(offset: f64) -> [f64; 9] {
    std::array::from_fn(|k| k as f64 + offset)
}

fn pose() -> Pose {
    Pose {
        position: Point {
            x: 1.5,
            y: -2.5,
            z: 0.25,
        },
        orientation: Quaternion::from_yaw(0.5),
    }
}

fn twist() -> Twist {
    Twist {
        linear: Vector3 {
            x: 0.4,
            y: 0.0,
            z: 0.0,
        },
        angular: Vector3 {
            x: 0.0,
            y: 0.0,
            z: -0.3,
        },
    }
}

fn transform_stamped() -> TransformStamped {
    TransformStamped {
        header: header("map"),
        child_frame_id: "odom".into(),
        transform: Transform {
            translation: Vector3 {
                x: 3.0,
                y: 4.0,
                z: 0.0,
            },
            rotation: Quaternion::from_yaw(-1.0),
        },
    }
}

fn diagnostic_status() -> DiagnosticStatus {
    DiagnosticStatus {
        level: DiagnosticStatus::WARN,
        name: "ekf: laser".into(),
        message: "2 lines gated out".into(),
        hardware_id: "lms221".into(),
        values: vec![
            KeyValue {
                key: "matched".into(),
                value: "4".into(),
            },
            KeyValue {
                key: "gated".into(),
                value: "2".into(),
            },
        ],
    }
}

fn marker() -> Marker {
    Marker {
        header: header("map"),
        ns: "lines".into(),
        id: 7,
        r#type: Marker::LINE_LIST,
        action: Marker::ADD,
        pose: pose(),
        scale: Vector3 {
            x: 0.05,
            y: 0.0,
            z: 0.0,
        },
        color: ColorRGBA {
            r: 1.0,
            g: 0.5,
            b: 0.0,
            a: 1.0,
        },
        lifetime: Duration {
            sec: 2,
            nanosec: 500,
        },
        frame_locked: true,
        points: vec![
            Point {
                x: 0.0,
                y: 0.0,
                z: 0.0,
            },
            Point {
                x: 1.0,
                y: 2.0,
                z: 0.0,
            },
        ],
        colors: vec![ColorRGBA {
            r: 0.0,
            g: 1.0,
            b: 0.0,
            a: 0.5,
        }],
        texture_resource: "embedded://tex".into(),
        texture: CompressedImage {
            header: header("cam"),
            format: "png".into(),
            data: vec![0x89, b'P', b'N', b'G'],
        },
        uv_coordinates: vec![UVCoordinate { u: 0.25, v: 0.75 }],
        text: "wall 3".into(),
        mesh_resource: "embedded://mesh".into(),
        mesh_file: MeshFile {
            filename: "m.stl".into(),
            data: vec![1, 2, 3],
        },
        mesh_use_embedded_materials: true,
    }
}

/// `(topic, message)` for every supported type, in a fixed order.
pub fn messages() -> Vec<(&'static str, AnyMessage)> {
    vec![
        ("/sample/time", STAMP.into()),
        ("/sample/header", header("base_link").into()),
        ("/sample/point", pose().position.into()),
        ("/sample/quaternion", Quaternion::from_yaw(0.5).into()),
        ("/sample/vector3", twist().angular.into()),
        ("/sample/pose", pose().into()),
        (
            "/sample/pose_stamped",
            PoseStamped {
                header: header("map"),
                pose: pose(),
            }
            .into(),
        ),
        (
            "/sample/pose_with_covariance",
            PoseWithCovariance {
                pose: pose(),
                covariance: covariance36(0.5),
            }
            .into(),
        ),
        (
            "/sample/pose_with_covariance_stamped",
            PoseWithCovarianceStamped {
                header: header("map"),
                pose: PoseWithCovariance {
                    pose: pose(),
                    covariance: covariance36(100.0),
                },
            }
            .into(),
        ),
        ("/sample/twist", twist().into()),
        (
            "/sample/twist_with_covariance",
            TwistWithCovariance {
                twist: twist(),
                covariance: covariance36(-36.0),
            }
            .into(),
        ),
        ("/sample/transform", transform_stamped().transform.into()),
        ("/sample/transform_stamped", transform_stamped().into()),
        (
            "/odom",
            Odometry {
                header: header("odom"),
                child_frame_id: "base_link".into(),
                pose: PoseWithCovariance {
                    pose: pose(),
                    covariance: covariance36(0.0),
                },
                twist: TwistWithCovariance {
                    twist: twist(),
                    covariance: covariance36(1000.0),
                },
            }
            .into(),
        ),
        (
            "/joint_states",
            JointState {
                header: header(""),
                name: vec!["wheel_left".into(), "wheel_right".into()],
                position: vec![0.1, 0.2],
                velocity: vec![3.0, 3.5],
                effort: vec![],
            }
            .into(),
        ),
        (
            "/scan",
            LaserScan {
                header: header("laser"),
                angle_min: -1.5,
                angle_max: 1.5,
                angle_increment: 1.5,
                time_increment: 0.001,
                scan_time: 0.2,
                range_min: 0.1,
                range_max: 8.0,
                ranges: vec![1.0, 2.0, 4.0],
                intensities: vec![10.0, 20.0, 30.0],
            }
            .into(),
        ),
        (
            "/compass",
            Imu {
                header: header("imu"),
                orientation: Quaternion::from_yaw(1.25),
                orientation_covariance: covariance9(0.0),
                angular_velocity: twist().angular,
                angular_velocity_covariance: covariance9(10.0),
                linear_acceleration: twist().linear,
                linear_acceleration_covariance: covariance9(20.0),
            }
            .into(),
        ),
        (
            "/magnetic_field",
            MagneticField {
                header: header("mag"),
                magnetic_field: Vector3 {
                    x: 2.0e-5,
                    y: -1.0e-5,
                    z: 4.0e-5,
                },
                magnetic_field_covariance: covariance9(1.0),
            }
            .into(),
        ),
        (
            "/sample/nav_sat_status",
            NavSatStatus {
                status: NavSatStatus::STATUS_SBAS_FIX,
                service: NavSatStatus::SERVICE_GPS | NavSatStatus::SERVICE_GALILEO,
            }
            .into(),
        ),
        (
            "/fix",
            NavSatFix {
                header: header("gps"),
                status: NavSatStatus {
                    status: NavSatStatus::STATUS_NO_FIX,
                    service: NavSatStatus::SERVICE_GLONASS,
                },
                latitude: 48.1,
                longitude: 11.6,
                altitude: 520.5,
                position_covariance: covariance9(2.0),
                position_covariance_type: NavSatFix::COVARIANCE_TYPE_DIAGONAL_KNOWN,
            }
            .into(),
        ),
        (
            "/tf",
            TFMessage {
                transforms: vec![transform_stamped(), TransformStamped::default()],
            }
            .into(),
        ),
        ("/sample/marker", marker().into()),
        (
            "/ekf/lines",
            MarkerArray {
                markers: vec![marker(), Marker::default()],
            }
            .into(),
        ),
        (
            "/sample/key_value",
            KeyValue {
                key: "k".into(),
                value: "v".into(),
            }
            .into(),
        ),
        ("/sample/diagnostic_status", diagnostic_status().into()),
        (
            "/diagnostics",
            DiagnosticArray {
                header: header(""),
                status: vec![diagnostic_status()],
            }
            .into(),
        ),
    ]
}

//! Hand-derived CDR bytes for a few messages: decoding gives the expected values and
//! encoding gives the same bytes back. Offsets in the comments count from the first byte
//! after the 4-byte encapsulation header, which is where CDR alignment starts in ROS 2.

use ekf_cli::ros2::builtin_interfaces::Time;
use ekf_cli::ros2::geometry_msgs::{Point, Pose, PoseStamped, Quaternion};
use ekf_cli::ros2::sensor_msgs::{JointState, LaserScan};
use ekf_cli::ros2::std_msgs::Header;
use ekf_cli::ros2::{AnyMessage, CdrError, RosMessage};

/// Decodes `bytes` as `T`, checks it equals `expected`, and checks it encodes back to `bytes`.
fn check_golden<T: RosMessage + PartialEq + std::fmt::Debug>(bytes: &[u8], expected: &T) {
    let decoded = T::decode(bytes).expect("golden bytes decode");
    assert_eq!(&decoded, expected);
    assert_eq!(expected.encode().expect("encodes"), bytes);
}

#[test]
fn header_golden_bytes() {
    #[rustfmt::skip]
    let bytes = [
        0x00, 0x01, 0x00, 0x00, // encapsulation: CDR little-endian, options 0
        0xD2, 0x04, 0x00, 0x00, // @0  stamp.sec = 1234 (int32)
        0x2E, 0x16, 0x00, 0x00, // @4  stamp.nanosec = 5678 (uint32)
        0x04, 0x00, 0x00, 0x00, // @8  frame_id length = 4, counting the NUL
        b'm', b'a', b'p', 0x00, // @12 "map" + NUL
    ];
    let header = Header {
        stamp: Time {
            sec: 1234,
            nanosec: 5678,
        },
        frame_id: "map".into(),
    };
    check_golden(&bytes, &header);
}

#[test]
fn laser_scan_with_three_ranges_golden_bytes() {
    #[rustfmt::skip]
    let bytes = [
        0x00, 0x01, 0x00, 0x00, // encapsulation
        0x01, 0x00, 0x00, 0x00, // @0  header.stamp.sec = 1
        0x02, 0x00, 0x00, 0x00, // @4  header.stamp.nanosec = 2
        0x06, 0x00, 0x00, 0x00, // @8  frame_id length = 6
        b'l', b'a', b's', b'e', b'r', 0x00, // @12 "laser" + NUL, ends at 18
        0x00, 0x00,             // @18 padding: float32 aligns to 4
        0x00, 0x00, 0xC0, 0xBF, // @20 angle_min = -1.5
        0x00, 0x00, 0xC0, 0x3F, // @24 angle_max = 1.5
        0x00, 0x00, 0xC0, 0x3F, // @28 angle_increment = 1.5
        0x00, 0x00, 0x00, 0x00, // @32 time_increment = 0
        0x00, 0x00, 0x80, 0x3E, // @36 scan_time = 0.25
        0x00, 0x00, 0x00, 0x3F, // @40 range_min = 0.5
        0x00, 0x00, 0x00, 0x41, // @44 range_max = 8
        0x03, 0x00, 0x00, 0x00, // @48 ranges length = 3
        0x00, 0x00, 0x80, 0x3F, // @52 ranges[0] = 1
        0x00, 0x00, 0x00, 0x40, // @56 ranges[1] = 2
        0x00, 0x00, 0x80, 0x40, // @60 ranges[2] = 4
        0x00, 0x00, 0x00, 0x00, // @64 intensities length = 0
    ];
    let scan = LaserScan {
        header: Header {
            stamp: Time { sec: 1, nanosec: 2 },
            frame_id: "laser".into(),
        },
        angle_min: -1.5,
        angle_max: 1.5,
        angle_increment: 1.5,
        time_increment: 0.0,
        scan_time: 0.25,
        range_min: 0.5,
        range_max: 8.0,
        ranges: vec![1.0, 2.0, 4.0],
        intensities: vec![],
    };
    check_golden(&bytes, &scan);
}

#[test]
fn pose_stamped_aligns_doubles_relative_to_payload_start() {
    // "odom" + NUL ends at payload offset 17, so the first float64 is padded to 24. Aligning
    // to the buffer start (header included) would put it at 20 instead.
    #[rustfmt::skip]
    let bytes = [
        0x00, 0x01, 0x00, 0x00, // encapsulation
        0x0A, 0x00, 0x00, 0x00, // @0  stamp.sec = 10
        0x00, 0x00, 0x00, 0x00, // @4  stamp.nanosec = 0
        0x05, 0x00, 0x00, 0x00, // @8  frame_id length = 5
        b'o', b'd', b'o', b'm', 0x00, // @12 "odom" + NUL, ends at 17
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // @17 padding to 24
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xF0, 0x3F, // @24 position.x = 1
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x40, // @32 position.y = 2
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // @40 position.z = 0
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // @48 orientation.x = 0
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // @56 orientation.y = 0
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // @64 orientation.z = 0
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xF0, 0x3F, // @72 orientation.w = 1
    ];
    let pose = PoseStamped {
        header: Header {
            stamp: Time {
                sec: 10,
                nanosec: 0,
            },
            frame_id: "odom".into(),
        },
        pose: Pose {
            position: Point {
                x: 1.0,
                y: 2.0,
                z: 0.0,
            },
            orientation: Quaternion::default(),
        },
    };
    check_golden(&bytes, &pose);
}

#[test]
fn joint_state_string_sequence_golden_bytes() {
    #[rustfmt::skip]
    let bytes = [
        0x00, 0x01, 0x00, 0x00, // encapsulation
        0x03, 0x00, 0x00, 0x00, // @0  stamp.sec = 3
        0x00, 0x00, 0x00, 0x00, // @4  stamp.nanosec = 0
        0x01, 0x00, 0x00, 0x00, // @8  frame_id length = 1 (empty string, just the NUL)
        0x00,                   // @12 NUL
        0x00, 0x00, 0x00,       // @13 padding: uint32 aligns to 4
        0x02, 0x00, 0x00, 0x00, // @16 name: 2 strings
        0x05, 0x00, 0x00, 0x00, // @20 name[0] length = 5
        b'l', b'e', b'f', b't', 0x00, // @24 "left" + NUL
        0x00, 0x00, 0x00,       // @29 padding
        0x06, 0x00, 0x00, 0x00, // @32 name[1] length = 6
        b'r', b'i', b'g', b'h', b't', 0x00, // @36 "right" + NUL
        0x00, 0x00,             // @42 padding
        0x02, 0x00, 0x00, 0x00, // @44 position: 2 doubles (48 is 8-aligned, no padding)
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xE0, 0x3F, // @48 position[0] = 0.5
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xE0, 0xBF, // @56 position[1] = -0.5
        0x00, 0x00, 0x00, 0x00, // @64 velocity: empty
        0x00, 0x00, 0x00, 0x00, // @68 effort: empty
    ];
    let joints = JointState {
        header: Header {
            stamp: Time { sec: 3, nanosec: 0 },
            frame_id: String::new(),
        },
        name: vec!["left".into(), "right".into()],
        position: vec![0.5, -0.5],
        velocity: vec![],
        effort: vec![],
    };
    check_golden(&bytes, &joints);
}

#[test]
fn trailing_padding_from_fast_dds_is_accepted() {
    let header = Header {
        stamp: Time { sec: 1, nanosec: 0 },
        frame_id: "ab".into(), // payload length 15: Fast-DDS pads it to 16
    };
    let mut bytes = header.encode().unwrap();
    bytes.push(0);
    assert_eq!(Header::decode(&bytes).unwrap(), header);
}

#[test]
fn any_message_decodes_by_full_or_short_type_name() {
    let header = Header {
        stamp: Time { sec: 7, nanosec: 8 },
        frame_id: "base_link".into(),
    };
    let bytes = header.encode().unwrap();
    for name in ["std_msgs/msg/Header", "std_msgs/Header"] {
        let any = AnyMessage::decode(name, &bytes).unwrap();
        assert_eq!(any, AnyMessage::Header(header.clone()));
        assert_eq!(any.type_name(), "std_msgs/msg/Header");
        assert_eq!(any.encode().unwrap(), bytes);
    }
    let err = AnyMessage::decode("sensor_msgs/msg/PointCloud2", &bytes).unwrap_err();
    assert!(
        err.to_string().contains("sensor_msgs/msg/PointCloud2"),
        "{err}"
    );
}

#[test]
fn bad_payloads_give_errors_naming_the_problem() {
    assert!(matches!(
        Header::decode(&[0, 1]),
        Err(CdrError::MissingHeader { len: 2 })
    ));
    assert!(matches!(
        Header::decode(&[0, 7, 0, 0, 0, 0, 0, 0]),
        Err(CdrError::Encapsulation { header: [0, 7] })
    ));
    // A string that claims 4 GiB must fail fast, not allocate.
    let bytes = [
        0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0xFF, b'x',
    ];
    let err = Header::decode(&bytes).unwrap_err();
    assert!(err.to_string().contains("std_msgs/msg/Header"), "{err}");
}

#[test]
fn time_converts_to_and_from_nanoseconds() {
    let t = Time::from_nanos(1_500_000_000_250).unwrap();
    assert_eq!(
        t,
        Time {
            sec: 1500,
            nanosec: 250
        }
    );
    assert_eq!(t.to_nanos(), Some(1_500_000_000_250));
    assert_eq!(
        Time {
            sec: -1,
            nanosec: 0
        }
        .to_nanos(),
        None
    );
    assert_eq!(Time::from_nanos(u64::MAX), None);
}

#[test]
fn quaternion_yaw_round_trips() {
    for yaw in [-3.0, -1.0, 0.0, 0.5, 3.1] {
        assert!((Quaternion::from_yaw(yaw).yaw() - yaw).abs() < 1e-12);
    }
}

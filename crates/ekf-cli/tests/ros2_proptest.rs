//! Property tests of the CDR codecs: arbitrary and mutated bytes never panic any decoder,
//! and random values survive encode → decode.

#[allow(dead_code)] // only the messages are used here
#[path = "../examples/write_sample_bag/sample.rs"]
mod sample;

use ekf_cli::ros2::builtin_interfaces::Time;
use ekf_cli::ros2::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue};
use ekf_cli::ros2::sensor_msgs::{JointState, LaserScan};
use ekf_cli::ros2::std_msgs::Header;
use ekf_cli::ros2::{AnyMessage, RosMessage, SUPPORTED};
use proptest::collection::vec;
use proptest::prelude::*;

/// Feeds `bytes` to the decoder of every supported type; only errors may come out.
fn decode_all(bytes: &[u8]) {
    for def in SUPPORTED {
        let _ = AnyMessage::decode(def.name, bytes);
    }
}

fn header() -> impl Strategy<Value = Header> {
    (any::<i32>(), 0u32..1_000_000_000, "[^\u{0}]{0,12}").prop_map(|(sec, nanosec, frame)| Header {
        stamp: Time { sec, nanosec },
        frame_id: frame,
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn random_bytes_never_panic(body in vec(any::<u8>(), 0..400), cdr_header in any::<bool>()) {
        let mut bytes = if cdr_header { vec![0, 1, 0, 0] } else { Vec::new() };
        bytes.extend(body);
        decode_all(&bytes);
    }

    #[test]
    fn mutated_valid_messages_never_panic(
        which in 0usize..26,
        flips in vec((any::<prop::sample::Index>(), any::<u8>()), 1..4),
        cut in any::<prop::sample::Index>(),
    ) {
        let messages = sample::messages();
        let mut bytes = messages[which % messages.len()].1.encode().unwrap();
        for (at, mask) in flips {
            let i = at.index(bytes.len());
            bytes[i] ^= mask;
        }
        decode_all(&bytes);
        bytes.truncate(cut.index(bytes.len()));
        decode_all(&bytes);
    }

    #[test]
    fn laser_scans_round_trip(
        header in header(),
        angles in (any::<f32>(), any::<f32>(), any::<f32>()),
        ranges in vec(any::<f32>().prop_filter("NaN != NaN", |r| !r.is_nan()), 0..50),
    ) {
        let scan = LaserScan {
            header,
            angle_min: angles.0,
            angle_max: angles.1,
            angle_increment: angles.2,
            intensities: ranges.iter().map(|r| r * 2.0).collect(),
            ranges,
            ..LaserScan::default()
        };
        prop_assert_eq!(LaserScan::decode(&scan.encode().unwrap()).unwrap(), scan);
    }

    #[test]
    fn strings_and_nested_sequences_round_trip(
        header in header(),
        names in vec("[^\u{0}]{0,10}", 0..5),
        values in vec(("[^\u{0}]{0,8}", "[^\u{0}]{0,8}"), 0..4),
        level in any::<u8>(),
    ) {
        let joints = JointState {
            header: header.clone(),
            position: (0..names.len()).map(|i| i as f64 * 0.5).collect(),
            name: names.clone(),
            ..JointState::default()
        };
        prop_assert_eq!(JointState::decode(&joints.encode().unwrap()).unwrap(), joints);
        let diagnostics = DiagnosticArray {
            header,
            status: vec![DiagnosticStatus {
                level,
                name: names.concat(),
                values: values
                    .into_iter()
                    .map(|(key, value)| KeyValue { key, value })
                    .collect(),
                ..DiagnosticStatus::default()
            }],
        };
        prop_assert_eq!(
            DiagnosticArray::decode(&diagnostics.encode().unwrap()).unwrap(),
            diagnostics
        );
    }
}

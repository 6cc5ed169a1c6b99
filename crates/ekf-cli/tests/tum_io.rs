//! TUM reading and writing: exact stamps, yaw from quaternions, round trips and error
//! messages that name file, line and column.

use ekf_cli::trajectory::Trajectory;
use ekf_cli::tum::{read_tum, read_tum_file, write_tum, write_tum_file, TumError};
use ekf_core::Pose2;
use proptest::prelude::*;
use std::f64::consts::PI;

fn read(text: &str) -> Result<Trajectory, TumError> {
    read_tum(text.as_bytes(), "test.txt")
}

#[test]
fn writes_nine_decimals_zero_z_and_yaw_quaternion() {
    let mut t = Trajectory::new();
    t.push(1_700_000_000_000_000_001, Pose2::new(1.5, -2.25, PI / 2.0));
    t.push(5, Pose2::new(0.0, 0.0, 0.0));
    let mut out = Vec::new();
    write_tum(&mut out, &t).unwrap();
    let text = String::from_utf8(out).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "# timestamp tx ty tz qx qy qz qw");
    let (s, c) = (PI / 4.0).sin_cos();
    assert_eq!(
        lines[1],
        format!("1700000000.000000001 1.5 -2.25 0 0 0 {s} {c}")
    );
    assert_eq!(lines[2], "0.000000005 0 0 0 0 0 0 1");
    assert_eq!(lines.len(), 3);
}

#[test]
fn reads_comments_blank_lines_tabs_and_bom() {
    let text = "\u{feff}# header\n\n  # indented comment\n1.5\t1 2 3 0 0 0 1\r\n2 0 0 0 0 0 1 0\n";
    let t = read(text).unwrap();
    assert_eq!(t.len(), 2);
    assert_eq!(t.samples[0].t_ns, 1_500_000_000);
    assert_eq!((t.samples[0].pose.x, t.samples[0].pose.y), (1.0, 2.0));
    assert_eq!(t.samples[0].pose.theta, 0.0);
    // qz = 1, qw = 0 is a half turn.
    assert!((t.samples[1].pose.theta - PI).abs() < 1e-12);
}

#[test]
fn stamps_are_exact_beyond_f64_precision() {
    // 1700000000.123456789 is not representable as f64 (it reads back as ...456835).
    let t =
        read("1700000000.123456789 0 0 0 0 0 0 1\n1.700000000987654321e+09 0 0 0 0 0 0 1").unwrap();
    assert_eq!(t.samples[0].t_ns, 1_700_000_000_123_456_789);
    assert_eq!(t.samples[1].t_ns, 1_700_000_000_987_654_321);
}

#[test]
fn yaw_from_a_general_quaternion() {
    // Yaw 0.7 composed with roll 0.2 (R = Rz(ψ)·Rx(φ)): the yaw formula recovers ψ.
    let (psi, phi) = (0.7_f64, 0.2_f64);
    let (sz, cz) = (psi / 2.0).sin_cos();
    let (sx, cx) = (phi / 2.0).sin_cos();
    let (qw, qx, qy, qz) = (cz * cx, cz * sx, sz * sx, sz * cx);
    let t = read(&format!("0 0 0 0 {qx} {qy} {qz} {qw}")).unwrap();
    assert!((t.samples[0].pose.theta - psi).abs() < 1e-12);
    // A quaternion that is not normalised gives the same yaw.
    let t = read(&format!("0 0 0 0 0 0 {} {}", 3.0 * sz, 3.0 * cz)).unwrap();
    assert!((t.samples[0].pose.theta - psi).abs() < 1e-12);
}

#[test]
fn errors_name_file_line_column_and_expectation() {
    let err = read("# c\n0 0 0 0 0 0 0 1\n1 2 x 0 0 0 0 1\n").unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.starts_with("test.txt:3: column 3 (ty) is \"x\", expected a finite decimal number"),
        "{msg}"
    );
    assert!(matches!(
        err,
        TumError::Field {
            line: 3,
            column: 3,
            ..
        }
    ));

    let msg = read("-1 0 0 0 0 0 0 1").unwrap_err().to_string();
    assert!(
        msg.starts_with(
            "test.txt:1: column 1 (timestamp) is \"-1\", expected non-negative decimal seconds"
        ),
        "{msg}"
    );

    let msg = read("1 0 0 0 0 0 1").unwrap_err().to_string();
    assert!(
        msg.contains("test.txt:1: expected 8 whitespace-separated fields"),
        "{msg}"
    );
    assert!(msg.ends_with("found 7"), "{msg}");

    let msg = read("1 0 0 0 0 0 0 inf").unwrap_err().to_string();
    assert!(msg.contains("column 8 (qw)"), "{msg}");

    let err = read("1 0 0 0 0 0 0 0").unwrap_err();
    assert!(
        matches!(err, TumError::ZeroQuaternion { line: 1, .. }),
        "{err}"
    );
}

#[test]
fn file_round_trip_and_missing_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("traj.txt");
    let mut t = Trajectory::new();
    t.push(42, Pose2::new(0.1, 0.2, -3.0));
    write_tum_file(&path, &t).unwrap();
    let back = read_tum_file(&path).unwrap();
    assert_eq!(back.samples[0].t_ns, 42);
    assert_eq!((back.samples[0].pose.x, back.samples[0].pose.y), (0.1, 0.2));

    let missing = dir.path().join("missing.txt");
    let msg = read_tum_file(&missing).unwrap_err().to_string();
    assert!(msg.starts_with(&missing.display().to_string()), "{msg}");
}

proptest! {
    #[test]
    fn round_trip_is_exact(
        poses in prop::collection::vec(
            (any::<u64>(), -1e6_f64..1e6, -1e6_f64..1e6, -PI..PI), 0..20)
    ) {
        let t: Trajectory = poses
            .iter()
            .map(|&(ns, x, y, th)| ekf_cli::trajectory::StampedPose::new(ns, Pose2::new(x, y, th)))
            .collect();
        let mut out = Vec::new();
        write_tum(&mut out, &t).unwrap();
        let back = read_tum(out.as_slice(), "round trip").unwrap();
        prop_assert_eq!(back.len(), t.len());
        for (a, b) in t.iter().zip(&back) {
            prop_assert_eq!(a.t_ns, b.t_ns);
            prop_assert_eq!(a.pose.x, b.pose.x);
            prop_assert_eq!(a.pose.y, b.pose.y);
            prop_assert!(ekf_core::angle_diff(a.pose.theta, b.pose.theta).abs() < 1e-12);
        }
    }
}

/// The tum_trajectory fuzz target's find (fuzz/regressions/tum_trajectory/): a
/// quaternion component of 1.482e305 overflowed the squares of the yaw formula, and the
/// row was read with a NaN heading (written back as NaN, which does not read). The yaw is
/// now computed on the components scaled by the largest, and a (near) zero quaternion is
/// refused with its line.
#[test]
fn huge_quaternions_give_their_yaw_and_tiny_ones_are_refused() {
    let t = read("1 0 0 0 0 0 0 1482E302\n2 0 0 0 0 0 1e300 1e300\n").unwrap();
    assert_eq!(t.samples[0].pose.theta, 0.0);
    assert!((t.samples[1].pose.theta - PI / 2.0).abs() < 1e-12);
    let mut written = Vec::new();
    write_tum(&mut written, &t).unwrap();
    let again = read(std::str::from_utf8(&written).unwrap()).unwrap();
    assert_eq!(again.samples.len(), 2);
    assert_eq!(
        read("# tiny\n1 0 0 0 1e-9 0 0 1e-9\n")
            .unwrap_err()
            .to_string(),
        "test.txt:2: columns 5-8 (qx qy qz qw) are zero or nearly so (norm at most 1e-6), \
         expected a unit quaternion"
    );
}

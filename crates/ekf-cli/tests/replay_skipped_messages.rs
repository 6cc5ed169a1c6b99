//! `ekf replay` on messages it must skip: time going backwards, duplicate stamps, NaN
//! fields. The replay finishes, counts them as warnings with the reason, and the estimate
//! is neither affected by them nor ever NaN.

mod replay_support;

use ekf_cli::ros2::geometry_msgs::PoseWithCovarianceStamped;
use ekf_cli::ros2::AnyMessage;
use replay_support::*;
use serde_json::{json, Value};
use std::path::Path;

fn p(path: &Path) -> &str {
    path.to_str().expect("utf-8 path")
}

/// A 6 s drive (straight ahead, then the first turn) with constant wheel speeds.
fn short(motion: MotionTopic) -> Scenario {
    Scenario {
        loops: 1,
        max_steps: Some(120),
        motion,
        wheel_noise: 0.0,
        ..Scenario::default()
    }
}

/// Replays `items` (written to `dir/name.mcap`) and returns the summary and TUM text.
fn run(dir: &Path, name: &str, items: &[Item], mode: &str) -> (Value, String) {
    let log = dir.join(format!("{name}.mcap"));
    write_bag(&log, items);
    let tum = dir.join(format!("{name}.tum"));
    let s = replay_json(&log, &["--mode", mode, "--tum", p(&tum)]);
    let text = std::fs::read_to_string(&tum).expect("TUM written");
    (s, text)
}

fn motion_item(items: &[Item], topic: &str, k: usize) -> Item {
    items
        .iter()
        .find(|i| i.topic == topic && i.t_ns == motion_stamp(k))
        .cloned()
        .unwrap_or_else(|| panic!("no {topic} message at step {k}"))
}

/// `msg` with its header stamp set to `stamp` and wildly wrong values, so using it
/// would show in the poses.
fn with_stamp_and_garbage(item: &Item, stamp: u64) -> AnyMessage {
    let t = ekf_cli::ros2::builtin_interfaces::Time::from_nanos(stamp).expect("stamp");
    match &item.msg {
        AnyMessage::JointState(js) => {
            let mut js = js.clone();
            js.header.stamp = t;
            js.position.iter_mut().for_each(|x| *x += 100.0);
            js.velocity = vec![50.0, -50.0];
            AnyMessage::JointState(js)
        }
        AnyMessage::Odometry(o) => {
            let mut o = o.clone();
            o.header.stamp = t;
            o.pose.pose.position.x += 5.0;
            AnyMessage::Odometry(o)
        }
        other => panic!("not a motion message: {other:?}"),
    }
}

fn time_disorder(motion: MotionTopic, topic: &str) {
    let dir = tempfile::tempdir().expect("tempdir");
    let clean = build(&short(motion));
    // Received 30 ms after step 10 but stamped at step 5, 530 ms late: more than the
    // 0.5 s `[timing] max_lag`, so too late to be fused in stamp order; received 30 ms
    // after step 20 with step 20's stamp again. (A stamp going backwards within the lag
    // is put in its place; the motion trackers' own check is unit-tested in
    // `replay/inputs.rs`.)
    let late = motion_stamp(10) + 30_000_000;
    let again = motion_stamp(20) + 30_000_000;
    let mut bad = clean.clone();
    for (log_time, k, stamp) in [(late, 10, motion_stamp(5)), (again, 20, motion_stamp(20))] {
        let item = motion_item(&clean, topic, k);
        bad.push(Item {
            t_ns: log_time,
            topic: topic.into(),
            msg: with_stamp_and_garbage(&item, stamp),
        });
    }
    bad.sort_by_key(|i| i.t_ns);

    for mode in ["odometry", "laser+compass"] {
        let (s_clean, tum_clean) = run(dir.path(), &format!("clean_{mode}"), &clean, mode);
        let (s_bad, tum_bad) = run(dir.path(), &format!("bad_{mode}"), &bad, mode);
        assert_eq!(s_clean["warning_count"], 0, "{mode}");
        assert_eq!(s_bad["warning_count"], 2, "{mode}: {:#}", s_bad["warnings"]);
        assert_eq!(
            s_bad["warnings"],
            json!([
                {
                    "topic": topic,
                    "log_time_ns": late,
                    "check": "too_late",
                    "reason": format!(
                        "stamped {} ns, before {} ns already fused: more than [timing] \
                         max_lag late, dropped",
                        motion_stamp(5),
                        // The last message handed on: step 5's scan, 500 ns later.
                        scan_stamp(5)
                    ),
                },
                {
                    "topic": topic,
                    "log_time_ns": again,
                    "check": "duplicate_stamp",
                    "reason": format!("duplicate stamp {} ns", motion_stamp(20)),
                },
            ]),
            "{mode}"
        );
        assert_eq!(s_bad["too_late"], 1, "{mode}");
        // Both extra messages were read, the one dropped as too late too.
        assert_eq!(
            s_bad["messages_read"][topic].as_u64(),
            s_clean["messages_read"][topic].as_u64().map(|n| n + 2)
        );
        assert_eq!(s_bad["motion_steps"], s_clean["motion_steps"], "{mode}");
        assert!(
            tum_bad == tum_clean,
            "{mode}: the skipped messages changed the poses"
        );
    }
}

#[test]
fn joint_states_going_back_in_time_or_repeating_a_stamp_are_skipped_with_a_warning() {
    time_disorder(MotionTopic::Joints, "/joint_states");
}

#[test]
fn odometry_going_back_in_time_or_repeating_a_stamp_is_skipped_with_a_warning() {
    time_disorder(MotionTopic::Odom, "/odom");
}

/// Sets fields to NaN in the message of `topic` at log time `t`.
fn poison(items: &mut [Item], topic: &str, t: u64, f: impl Fn(&mut AnyMessage)) {
    let item = items
        .iter_mut()
        .find(|i| i.topic == topic && i.t_ns == t)
        .unwrap_or_else(|| panic!("no {topic} at {t}"));
    f(&mut item.msg);
}

fn last_pose(tum: &str) -> [f64; 3] {
    let line = tum.lines().last().expect("rows");
    let f: Vec<f64> = line
        .split_whitespace()
        .skip(1)
        .map(|x| x.parse().expect("number"))
        .collect();
    [f[0], f[1], 2.0 * f[5].atan2(f[6])]
}

#[test]
fn nan_fields_are_skipped_with_warnings_and_never_reach_the_estimate() {
    let dir = tempfile::tempdir().expect("tempdir");
    let clean = build(&short(MotionTopic::Joints));
    let mut bad = clean.clone();
    poison(&mut bad, "/joint_states", motion_stamp(10), |m| {
        if let AnyMessage::JointState(js) = m {
            js.velocity[0] = f64::NAN;
        }
    });
    poison(&mut bad, "/joint_states", motion_stamp(20), |m| {
        if let AnyMessage::JointState(js) = m {
            js.position[1] = f64::NAN;
        }
    });
    poison(&mut bad, "/compass", compass_stamp(30), |m| {
        if let AnyMessage::Imu(imu) = m {
            imu.orientation.z = f64::NAN;
        }
    });
    poison(&mut bad, "/ground_truth", motion_stamp(40), |m| {
        if let AnyMessage::Odometry(o) = m {
            o.pose.pose.position.y = f64::NAN;
        }
    });
    // NaN ranges are invalid readings, not used: six dropouts in every scan. (The
    // extractor cuts lines at invalid beams, so NaN in, say, every seventh beam leaves
    // no run long enough for a line.)
    for item in bad.iter_mut().filter(|i| i.topic == "/scan") {
        if let AnyMessage::LaserScan(scan) = &mut item.msg {
            scan.ranges
                .iter_mut()
                .skip(30)
                .step_by(60)
                .for_each(|r| *r = f32::NAN);
        }
    }

    let log = dir.path().join("nan.mcap");
    write_bag(&log, &bad);
    let out = dir.path().join("nan.out.mcap");
    let tum = dir.path().join("nan.tum");
    let s = replay_json(&log, &["--out", p(&out), "--tum", p(&tum)]);
    // The NaN velocity at step 10 sits beside finite positions, which are what the
    // replay differentiates: it is not used and not a warning.
    assert_eq!(s["warning_count"], 3, "{:#}", s["warnings"]);
    let reasons: Vec<(&str, u64, &str)> = s["warnings"]
        .as_array()
        .expect("warnings")
        .iter()
        .map(|w| {
            (
                w["topic"].as_str().expect("topic"),
                w["log_time_ns"].as_u64().expect("time"),
                w["reason"].as_str().expect("reason"),
            )
        })
        .collect();
    assert_eq!(
        reasons,
        [
            ("/joint_states", motion_stamp(20), "position is not finite"),
            ("/compass", compass_stamp(30), "orientation is not finite"),
            (
                "/ground_truth",
                motion_stamp(40),
                "reference pose is not finite or not decodable"
            ),
        ]
    );
    // Scans with NaN ranges are still used.
    let scans = bad.iter().filter(|i| i.topic == "/scan").count() as u64;
    assert_eq!(s["lines"]["scans_used"].as_u64(), Some(scans));
    assert!(
        s["lines"]["fused"].as_u64().expect("fused") > scans,
        "{:#}",
        s["lines"]
    );
    // The NaN readings do not derail the estimate. Measured with the default map noise:
    // 0.055 m here, 0.046 m on the same bag without the NaNs and dropouts.
    let rmse = s["accuracy"]["position_rmse_m"].as_f64().expect("rmse");
    assert!(rmse < 0.07, "rmse {rmse}");

    // No NaN anywhere in the outputs.
    let rows = read_tum_rows(&tum);
    assert_eq!(
        rows.len() as u64,
        s["poses_written"].as_u64().expect("poses")
    );
    for (t, v) in &rows {
        assert!(v.iter().all(|x| x.is_finite()), "{t}: {v:?}");
    }
    let bag = ekf_cli::mcap_io::BagReader::open(&out).expect("output opens");
    let mut poses = 0;
    for m in bag.messages().expect("stream") {
        let m = m.expect("message");
        if m.topic() == "/ekf/pose" {
            let pose: PoseWithCovarianceStamped = m.decode_as().expect("pose");
            let q = pose.pose.pose;
            let values = [q.position.x, q.position.y, q.orientation.z, q.orientation.w];
            assert!(values.iter().all(|x| x.is_finite()), "{values:?}");
            assert!(pose.pose.covariance.iter().all(|x| x.is_finite()));
            poses += 1;
        }
    }
    assert!(poses > 100, "{poses} poses");
}

#[test]
fn a_skipped_wheel_reading_loses_no_motion() {
    // Dead reckoning with a NaN velocity at step 10 and a NaN position at step 20 must end
    // where it ends without them: the next reading covers the skipped interval.
    let dir = tempfile::tempdir().expect("tempdir");
    let clean = build(&short(MotionTopic::Joints));
    for (k, velocity) in [(10, true), (20, false), (30, true)] {
        let mut bad = clean.clone();
        poison(&mut bad, "/joint_states", motion_stamp(k), |m| {
            if let AnyMessage::JointState(js) = m {
                if velocity {
                    js.velocity[1] = f64::NAN;
                } else {
                    js.position[0] = f64::NAN;
                }
            }
        });
        let (_, tum_clean) = run(dir.path(), "clean", &clean, "odometry");
        let (s, tum_bad) = run(dir.path(), &format!("bad_{k}"), &bad, "odometry");
        // Positions are differentiated; a NaN velocity beside them is not even looked at.
        assert_eq!(s["warning_count"], if velocity { 0 } else { 1 });
        let (a, b) = (last_pose(&tum_clean), last_pose(&tum_bad));
        let d = (a[0] - b[0]).hypot(a[1] - b[1]);
        assert!(
            d < 1e-6 && (a[2] - b[2]).abs() < 1e-6,
            "step {k} (NaN {}): end pose {b:?} instead of {a:?} ({d:.4} m off)",
            if velocity { "velocity" } else { "position" }
        );
    }
}

#[test]
fn nan_odometry_poses_are_skipped_and_lose_no_motion() {
    let dir = tempfile::tempdir().expect("tempdir");
    let clean = build(&short(MotionTopic::Odom));
    let mut bad = clean.clone();
    poison(&mut bad, "/odom", motion_stamp(10), |m| {
        if let AnyMessage::Odometry(o) = m {
            o.pose.pose.orientation.w = f64::NAN;
        }
    });
    let (_, tum_clean) = run(dir.path(), "clean", &clean, "laser+compass");
    let (s, tum_bad) = run(dir.path(), "bad", &bad, "laser+compass");
    assert_eq!(
        s["warnings"],
        json!([{
            "topic": "/odom",
            "log_time_ns": motion_stamp(10),
            "check": "non_finite",
            "reason": "pose is not finite"
        }])
    );
    for line in tum_bad.lines().skip(1) {
        assert!(!line.contains("NaN") && !line.contains("inf"), "{line}");
    }
    let (a, b) = (last_pose(&tum_clean), last_pose(&tum_bad));
    assert!(
        (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-3,
        "end pose {b:?} instead of {a:?}"
    );
}

#[test]
fn an_imu_without_orientation_is_not_fused() {
    // sensor_msgs/Imu: -1 in orientation_covariance[0] means "no orientation estimate";
    // such a message (here with the all-zero quaternion such IMUs send, whose yaw would
    // read as 0) must be skipped, not fused as a heading of 0.
    let dir = tempfile::tempdir().expect("tempdir");
    let clean = build(&short(MotionTopic::Joints));
    let mut bad = clean.clone();
    for k in [2, 4] {
        poison(&mut bad, "/compass", compass_stamp(k), |m| {
            if let AnyMessage::Imu(imu) = m {
                imu.orientation = ekf_cli::ros2::geometry_msgs::Quaternion {
                    x: 0.0,
                    y: 0.0,
                    z: 0.0,
                    w: 0.0,
                };
                imu.orientation_covariance = [0.0; 9];
                imu.orientation_covariance[0] = -1.0;
            }
        });
    }
    let (s_clean, _) = run(dir.path(), "clean", &clean, "compass");
    let (s, _) = run(dir.path(), "no_orientation", &bad, "compass");
    let reason = "orientation not provided (orientation_covariance[0] = -1)";
    assert_eq!(
        s["warnings"],
        json!([
            {"topic": "/compass", "log_time_ns": compass_stamp(2), "check": "not_provided", "reason": reason},
            {"topic": "/compass", "log_time_ns": compass_stamp(4), "check": "not_provided", "reason": reason},
        ])
    );
    let fused = |s: &Value| {
        s["compass"]["accepted"].as_u64().expect("accepted")
            + s["compass"]["rejected"].as_u64().expect("rejected")
    };
    assert_eq!(fused(&s) + 2, fused(&s_clean));
}

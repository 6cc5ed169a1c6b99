//! `ekf replay` on input it cannot use: missing topics, wrong message types, malformed
//! configurations and maps, wrong joint names. Each error must say what is wrong and
//! where, and the command must exit non-zero. Runs the real `ekf` binary.

mod replay_support;

use ekf_cli::ros2::AnyMessage;
use replay_support::*;
use std::path::{Path, PathBuf};

/// A short drive (4 s) with every topic.
fn short() -> Scenario {
    Scenario {
        loops: 1,
        max_steps: Some(40),
        ..Scenario::default()
    }
}

fn p(path: &Path) -> &str {
    path.to_str().expect("utf-8 path")
}

/// Runs `ekf replay ARGS`, expects exit code 1, returns (stdout, stderr).
fn replay_fails(args: &[&str]) -> (String, String) {
    let mut all = vec!["replay"];
    all.extend_from_slice(args);
    let out = ekf(&all);
    let (stdout, stderr) = texts(&out);
    assert_eq!(
        out.status.code(),
        Some(1),
        "ekf {all:?} should fail\nstdout: {stdout}\nstderr: {stderr}"
    );
    (stdout, stderr)
}

const ALL_BUT_SCAN: &str = "/compass (sensor_msgs/msg/Imu), \
    /ground_truth (nav_msgs/msg/Odometry), /joint_states (sensor_msgs/msg/JointState), \
    /tf_static (tf2_msgs/msg/TFMessage)";

#[test]
fn laser_mode_without_scans_lists_the_topics_the_log_has() {
    let dir = tempfile::tempdir().expect("tempdir");
    let s = Scenario {
        scan_every: 0,
        ..short()
    };
    let (log, _) = write_scenario(dir.path(), "noscan.mcap", &s);
    let hints = [
        (
            "laser",
            "name the log's topic in the config's [topics] table",
        ),
        (
            "laser+compass",
            "mode compass (--mode compass) needs no laser, or name the laser's topic in \
             [topics] scan",
        ),
    ];
    for (mode, hint) in hints {
        let (stdout, stderr) = replay_fails(&[p(&log), "--mode", mode]);
        assert_eq!(
            stderr,
            format!(
                "ekf: error: {}: no topic /scan (laser scans); the log has: {ALL_BUT_SCAN}; \
                 {hint}\n",
                p(&log)
            ),
            "{mode}"
        );
        assert_eq!(stdout, "", "nothing was replayed");
    }
    // The modes that do not need the laser run.
    let s = replay_json(&log, &["--mode", "compass"]);
    assert_eq!(s["motion_steps"], 40);
}

#[test]
fn compass_mode_without_compass_lists_the_topics_the_log_has() {
    let dir = tempfile::tempdir().expect("tempdir");
    let s = Scenario {
        compass_every: 0,
        ..short()
    };
    let (log, _) = write_scenario(dir.path(), "nocompass.mcap", &s);
    let topics = "/ground_truth (nav_msgs/msg/Odometry), /joint_states \
                  (sensor_msgs/msg/JointState), /scan (sensor_msgs/msg/LaserScan), /tf_static \
                  (tf2_msgs/msg/TFMessage)";
    let (_, stderr) = replay_fails(&[p(&log), "--mode", "compass"]);
    assert_eq!(
        stderr,
        format!(
            "ekf: error: {}: no topic /compass (compass); the log has: {topics}; mode odometry \
             (--mode odometry) needs no compass, or name the compass's topic in [topics] \
             compass\n",
            p(&log)
        )
    );
    // The default mode (laser + compass) says how to go without the compass.
    let (_, stderr) = replay_fails(&[p(&log)]);
    assert_eq!(
        stderr,
        format!(
            "ekf: error: {}: no topic /compass (compass); the log has: {topics}; mode laser \
             (--mode laser) needs no compass, or name the compass's topic in [topics] compass\n",
            p(&log)
        )
    );
    let s = replay_json(&log, &["--mode", "laser"]);
    assert_eq!(s["motion_steps"], 40);
}

#[test]
fn a_log_with_neither_joint_states_nor_odometry_names_both_and_lists_its_topics() {
    let dir = tempfile::tempdir().expect("tempdir");
    let s = Scenario {
        motion: MotionTopic::None,
        ..short()
    };
    let (log, _) = write_scenario(dir.path(), "nomotion.mcap", &s);
    let (_, stderr) = replay_fails(&[p(&log), "--mode", "odometry"]);
    assert_eq!(
        stderr,
        format!(
            "ekf: error: {}: no topic /joint_states or /odom (wheel joint states or odometry); \
             the log has: /compass (sensor_msgs/msg/Imu), /ground_truth (nav_msgs/msg/Odometry), \
             /scan (sensor_msgs/msg/LaserScan), /tf_static (tf2_msgs/msg/TFMessage); name the \
             log's topic in the config's [topics] table\n",
            p(&log)
        )
    );
    // Forcing a source names that one.
    let config = dir.path().join("odom.toml");
    std::fs::write(&config, "[motion]\nsource = \"odom\"\n").expect("write config");
    let (_, stderr) = replay_fails(&[p(&log), "--config", p(&config)]);
    assert!(
        stderr.starts_with(&format!(
            "ekf: error: {}: no topic /odom (odometry); the log has: /compass",
            p(&log)
        )),
        "{stderr}"
    );
}

#[test]
fn an_empty_log_says_it_has_no_topics() {
    let dir = tempfile::tempdir().expect("tempdir");
    let log = dir.path().join("empty.mcap");
    write_bag(&log, &[]);
    let (_, stderr) = replay_fails(&[p(&log)]);
    assert_eq!(
        stderr,
        format!(
            "ekf: error: {}: no topic /joint_states or /odom (wheel joint states or odometry); \
             the log has: no topics; name the log's topic in the config's [topics] table\n",
            p(&log)
        )
    );
}

#[test]
fn a_topic_with_the_wrong_message_type_names_topic_actual_and_expected_type() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut items = build(&short());
    for item in items.iter_mut().filter(|i| i.topic == "/scan") {
        item.msg = AnyMessage::Odometry(odometry(item.t_ns, &P2::default()));
    }
    let log = dir.path().join("scan_is_odom.mcap");
    write_bag(&log, &items);
    let (stdout, stderr) = replay_fails(&[p(&log)]);
    assert_eq!(
        stderr,
        format!(
            "ekf: error: {}: topic /scan has type nav_msgs/msg/Odometry; \
             expected sensor_msgs/msg/LaserScan\n",
            p(&log)
        )
    );
    assert_eq!(stdout, "");

    let mut items = build(&short());
    for item in items.iter_mut().filter(|i| i.topic == "/compass") {
        item.msg = AnyMessage::JointState(joint_state(item.t_ns, ("a", "b"), [0.0; 2], [0.0; 2]));
    }
    let log = dir.path().join("compass_is_joints.mcap");
    write_bag(&log, &items);
    let (_, stderr) = replay_fails(&[p(&log), "--mode", "compass"]);
    assert_eq!(
        stderr,
        format!(
            "ekf: error: {}: topic /compass has type sensor_msgs/msg/JointState; \
             expected sensor_msgs/msg/Imu or sensor_msgs/msg/MagneticField\n",
            p(&log)
        )
    );
}

/// Writes `text` to `dir/name` and runs a replay of `log` with it as `--config`.
fn config_error(dir: &Path, log: &Path, name: &str, text: &str) -> (PathBuf, String) {
    let config = dir.join(name);
    std::fs::write(&config, text).expect("write config");
    let (stdout, stderr) = replay_fails(&[p(log), "--config", p(&config)]);
    assert_eq!(stdout, "", "nothing replayed with a bad config");
    (config, stderr)
}

#[test]
fn a_malformed_config_names_file_line_and_key() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (log, _) = write_scenario(dir.path(), "run.mcap", &short());

    // TOML syntax error: an unterminated string on line 3.
    let (config, stderr) = config_error(
        dir.path(),
        &log,
        "syntax.toml",
        "[topics]\nscan = \"/scan\"\nodom = \"/odom\n",
    );
    let prefix = format!(
        "ekf: error: {}: TOML parse error at line 3, column",
        p(&config)
    );
    assert!(stderr.starts_with(&prefix), "{stderr}");
    assert!(stderr.contains("odom = \"/odom"), "{stderr}");

    // Unknown key (a typo) on line 4.
    let (config, stderr) = config_error(
        dir.path(),
        &log,
        "unknown.toml",
        "[localizer.robot]\nwheel_radius = 0.05\ntrack = 0.6\nwheel_radus = 0.05\n",
    );
    let prefix = format!(
        "ekf: error: {}: TOML parse error at line 4, column 1",
        p(&config)
    );
    assert!(stderr.starts_with(&prefix), "{stderr}");
    assert!(stderr.contains("unknown field `wheel_radus`"), "{stderr}");

    // Wrong type on line 2.
    let (config, stderr) = config_error(
        dir.path(),
        &log,
        "type.toml",
        "[localizer.robot]\ntrack = \"wide\"\n",
    );
    let prefix = format!(
        "ekf: error: {}: TOML parse error at line 2, column 9",
        p(&config)
    );
    assert!(stderr.starts_with(&prefix), "{stderr}");
    assert!(stderr.contains("track = \"wide\""), "{stderr}");
    assert!(stderr.contains("invalid type: string \"wide\""), "{stderr}");

    // Out of range on line 6.
    let (config, stderr) = config_error(
        dir.path(),
        &log,
        "range.toml",
        "# a robot\n[topics]\nscan = \"/scan\"\n[localizer.robot]\nwheel_radius = 0.05\n\
         track = -0.6\n",
    );
    assert_eq!(
        stderr,
        format!(
            "ekf: error: {}: line 6: localizer.robot.track: expected a finite number > 0, \
             found -0.6\n",
            p(&config)
        )
    );
    let (config, stderr) = config_error(
        dir.path(),
        &log,
        "probability.toml",
        "[localizer.compass]\n\ngate_probability = 1.5\n",
    );
    assert_eq!(
        stderr,
        format!(
            "ekf: error: {}: line 3: localizer.compass.gate_probability: expected a \
             probability in (0, 1), found 1.5\n",
            p(&config)
        )
    );

    // A config file that does not exist.
    let missing = dir.path().join("nope.toml");
    let (_, stderr) = replay_fails(&[p(&log), "--config", p(&missing)]);
    assert_eq!(
        stderr,
        format!(
            "ekf: error: {}: No such file or directory (os error 2)\n",
            p(&missing)
        )
    );
}

const GOOD_SEGMENT: &str = r#"{"start": [-1.5, -2.0], "end": [4.5, -2.0]}"#;

fn map_file(dir: &Path, name: &str, segments: &str) -> PathBuf {
    let path = dir.join(name);
    let text = format!(
        "{{\n  \"format\": \"ekf-loc line map\",\n  \"version\": 1,\n  \"frame_id\": \"map\",\n  \
         \"segments\": [\n    {segments}\n  ]\n}}\n"
    );
    std::fs::write(&path, text).expect("write map");
    path
}

#[test]
fn an_unreadable_map_names_the_file_and_the_entry() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (log, _) = write_scenario(dir.path(), "run.mcap", &short());

    let missing = dir.path().join("missing.json");
    let (_, stderr) = replay_fails(&[p(&log), "--map", p(&missing)]);
    assert_eq!(
        stderr,
        format!(
            "ekf: error: {}: No such file or directory (os error 2)\n",
            p(&missing)
        )
    );

    // Invalid JSON: a trailing comma after the second segment (line 7).
    let bad = map_file(
        dir.path(),
        "syntax.json",
        &format!("{GOOD_SEGMENT},\n    {GOOD_SEGMENT},"),
    );
    let (_, stderr) = replay_fails(&[p(&log), "--map", p(&bad)]);
    assert_eq!(
        stderr,
        format!(
            "ekf: error: {}: segments[2]: invalid JSON at line 8, column 3: trailing comma\n",
            p(&bad)
        )
    );

    // A segment without an end point.
    let bad = map_file(
        dir.path(),
        "field.json",
        &format!("{GOOD_SEGMENT},\n    {{\"start\": [4.5, -2.0]}}"),
    );
    let (_, stderr) = replay_fails(&[p(&log), "--map", p(&bad)]);
    assert_eq!(
        stderr,
        format!(
            "ekf: error: {}: segments[1]: missing field `end`\n",
            p(&bad)
        )
    );

    // The same map with the field replays.
    let good = map_file(dir.path(), "good.json", GOOD_SEGMENT);
    let s = replay_json(&log, &["--map", p(&good)]);
    assert_eq!(s["map_segments"], 1);
}

#[test]
fn wrong_joint_names_list_the_joints_the_message_has() {
    let dir = tempfile::tempdir().expect("tempdir");
    let s = Scenario {
        joint_names: ("wheel_l".into(), "wheel_r".into()),
        ..short()
    };
    let (log, _) = write_scenario(dir.path(), "joints.mcap", &s);
    let (_, stderr) = replay_fails(&[p(&log), "--mode", "odometry"]);
    assert_eq!(
        stderr,
        format!(
            "ekf: error: {}: /joint_states: no joints named \"left_wheel_joint\" and \
             \"right_wheel_joint\" (set motion.left_joint/right_joint); the message has \
             [\"wheel_l\", \"wheel_r\"]\n",
            p(&log)
        )
    );
    // Naming them in the configuration fixes it.
    let config = dir.path().join("joints.toml");
    std::fs::write(
        &config,
        "[motion]\nleft_joint = \"wheel_l\"\nright_joint = \"wheel_r\"\n",
    )
    .expect("write config");
    let s = replay_json(&log, &["--mode", "odometry", "--config", p(&config)]);
    assert_eq!(s["motion_steps"], 40);
}

#[test]
fn a_reference_under_another_name_is_pointed_out_not_silently_missing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (log, _) = write_scenario(dir.path(), "ref.mcap", &short());
    let config = dir.path().join("truth.toml");
    std::fs::write(&config, "[topics]\nground_truth = \"/truth\"\n").expect("write config");
    let s = replay_json(&log, &["--mode", "compass", "--config", p(&config)]);
    assert_eq!(s["accuracy"], serde_json::Value::Null);
    assert_eq!(
        s["notes"],
        serde_json::json!([
            "no reference on /truth, so no accuracy; if /ground_truth is the reference, name \
             it in [topics] ground_truth"
        ])
    );
    // With the reference found, nothing to say.
    let s = replay_json(&log, &["--mode", "compass"]);
    assert!(s["accuracy"].is_object());
    assert_eq!(s["notes"], serde_json::json!([]));
}

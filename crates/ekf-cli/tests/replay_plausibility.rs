//! Bad sensor data is noticed: copies of the bundled simulated bag with one input broken
//! in the ways a robot breaks it. Each replays (laser + compass, the defaults of the
//! paper's robot) with a warning naming the topic and the check, and places the robot
//! within 5 cm RMSE, the bad readings left out or replaced by what the other sensors
//! say. Without the checks these cost from 0.5 m to 9 m.

use ekf_cli::config::Config;
use ekf_cli::mcap_io::{BagReader, BagWriter};
use ekf_cli::replay::{replay, ReplayOptions, ReplaySummary};
use ekf_cli::ros2::geometry_msgs::Quaternion;
use ekf_cli::ros2::AnyMessage;
use std::path::{Path, PathBuf};

fn testdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata")
        .join(name)
}

/// A copy of `src` at `dst` with `f` applied to every decoded message (topic, log time).
fn mutated(src: &Path, dst: &Path, mut f: impl FnMut(&str, u64, &mut AnyMessage)) {
    let bag = BagReader::open(src).unwrap();
    let mut out = BagWriter::create(dst).unwrap();
    for m in bag.messages().unwrap() {
        let m = m.unwrap();
        let mut msg = m.decode().unwrap();
        f(m.topic(), m.log_time, &mut msg);
        out.write_any(m.topic(), m.log_time, &msg).unwrap();
    }
    out.finish().unwrap();
}

/// The replay from the first reference pose, with the paper room's line map if
/// `given_map`, else with the first scan's (the paper's mode).
fn run_with(log: &Path, given_map: bool) -> (f64, ReplaySummary) {
    let config = Config::preset("paper-robot").unwrap();
    let options = ReplayOptions {
        init_from_truth: true,
        map: given_map.then(|| testdata("paper-room.json")),
        ..ReplayOptions::default()
    };
    let outcome = replay(log, &config, &options, &mut |_, _| {}).unwrap();
    assert!(outcome.failure.is_none());
    let s = outcome.summary;
    (s.accuracy.as_ref().unwrap().position_rmse_m, s)
}

fn run(log: &Path) -> (f64, ReplaySummary) {
    run_with(log, false)
}

/// Replays the bag broken by `f` (with the first-scan map, or the room's if
/// `given_map`); checks the RMSE bound, that the first warning is on `topic`, names the
/// check `check` and says `says`, and that the summary counts it under that check.
fn check_with(
    given_map: bool,
    name: &str,
    (topic, check): (&str, &str),
    says: &str,
    f: impl FnMut(&str, u64, &mut AnyMessage),
) {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("broken.mcap");
    mutated(&testdata("sim-paper.mcap"), &log, f);
    let (rmse, s) = run_with(&log, given_map);
    let first = s
        .warnings
        .first()
        .unwrap_or_else(|| panic!("{name}: no warning"));
    eprintln!(
        "{name}: {rmse:.4} m, {} warnings; {}",
        s.warning_count, first.reason
    );
    assert_eq!(first.topic, topic, "{name}");
    assert_eq!(first.check, check, "{name}");
    assert!(first.reason.contains(says), "{name}: {}", first.reason);
    assert!(
        s.checks.get(check).copied().unwrap_or(0) >= 1,
        "{name}: {:?}",
        s.checks
    );
    assert!(rmse <= 0.05, "{name}: position RMSE {rmse:.4} m");
}

fn check(
    name: &str,
    topic_and_check: (&str, &str),
    says: &str,
    f: impl FnMut(&str, u64, &mut AnyMessage),
) {
    check_with(false, name, topic_and_check, says, f)
}

const T0: u64 = 20_000_000_000;

#[test]
fn the_clean_bag_gives_no_warning() {
    let (rmse, s) = run(&testdata("sim-paper.mcap"));
    assert_eq!(s.warning_count, 0, "{:?}", s.warnings);
    assert!(rmse < 0.011, "{rmse}");
}

#[test]
fn encoder_angles_that_stand_still_while_the_velocities_turn_give_way_to_the_velocities() {
    let mut first: Option<Vec<f64>> = None;
    check(
        "joints stuck",
        ("/joint_states", "encoders_contradict_velocities"),
        "the velocities are used",
        |topic, _, m| {
            if let (AnyMessage::JointState(js), "/joint_states") = (m, topic) {
                match &first {
                    None => first = Some(js.position.clone()),
                    Some(p) => js.position = p.clone(),
                }
            }
        },
    );
}

#[test]
fn an_encoder_spike_and_an_encoder_step_are_skipped() {
    let spike = |topic: &str, t: u64, m: &mut AnyMessage| {
        if let (AnyMessage::JointState(js), "/joint_states") = (m, topic) {
            if (T0..T0 + 20_000_000).contains(&t) {
                js.position[0] += 100.0;
            }
        }
    };
    check(
        "spike",
        ("/joint_states", "implausible"),
        "encoder increment",
        spike,
    );
    let step = |topic: &str, t: u64, m: &mut AnyMessage| {
        if let (AnyMessage::JointState(js), "/joint_states") = (m, topic) {
            if t >= T0 {
                js.position[0] += 100.0;
            }
        }
    };
    check(
        "step",
        ("/joint_states", "implausible"),
        "encoder increment",
        step,
    );
}

#[test]
fn a_stuck_compass_is_not_fused() {
    check(
        "compass stuck",
        ("/compass", "compass_stuck"),
        "do not follow",
        |topic, _, m| {
            if let (AnyMessage::Imu(imu), "/compass") = (m, topic) {
                imu.orientation = Quaternion::from_yaw(0.0);
            }
        },
    );
}

/// Against a given map the laser refuses the lock-out recovery a biased compass would
/// get. (Against a first-scan map it cannot: that map was placed with the filter's own
/// heading, and a constant compass bias looks like a wrong initial heading, which
/// `live_emulated` shows the compass must correct.)
#[test]
fn a_biased_compass_does_not_override_the_laser_against_a_given_map() {
    check_with(
        true,
        "compass +30°",
        ("/compass", "compass_against_laser"),
        "recovery was refused",
        |topic, _, m| {
            if let (AnyMessage::Imu(imu), "/compass") = (m, topic) {
                let yaw = imu.orientation.yaw();
                imu.orientation = Quaternion::from_yaw(yaw + 30f64.to_radians());
            }
        },
    );
}

#[test]
fn a_non_unit_quaternion_is_refused() {
    check(
        "quaternion ×1.3",
        ("/compass", "implausible"),
        "unit quaternion",
        |topic, _, m| {
            if let (AnyMessage::Imu(imu), "/compass") = (m, topic) {
                let q = &mut imu.orientation;
                (q.x, q.y, q.z, q.w) = (1.3 * q.x, 1.3 * q.y, 1.3 * q.z, 1.3 * q.w);
            }
        },
    );
}

/// A magnetometer compass (`MagneticField`) whose field turns nearly vertical for 10 s
/// (a steel beam underfoot, a magnet on the robot) has no horizontal direction to give
/// a heading: those readings are refused, not fused as the bearing of a few nanotesla.
#[test]
fn a_magnetic_field_without_a_horizontal_component_is_refused() {
    use ekf_cli::ros2::geometry_msgs::Vector3;
    use ekf_cli::ros2::sensor_msgs::MagneticField;
    check(
        "field vertical",
        ("/compass", "implausible"),
        "horizontal component",
        |topic, t, m| {
            let AnyMessage::Imu(imu) = &*m else { return };
            if topic != "/compass" {
                return;
            }
            // The bearing (clockwise from north) that gives the Imu's heading.
            let bearing = std::f64::consts::FRAC_PI_2 - imu.orientation.yaw();
            let (mut x, mut y, mut z) = (2e-5 * bearing.cos(), 2e-5 * bearing.sin(), 4e-5);
            if (T0..T0 + 10_000_000_000).contains(&t) {
                (x, y, z) = (0.01 * x, 0.01 * y, 5e-5);
            }
            *m = AnyMessage::MagneticField(MagneticField {
                header: imu.header.clone(),
                magnetic_field: Vector3 { x, y, z },
                magnetic_field_covariance: [0.0; 9],
            });
        },
    );
}

/// A `/tf_static` without the scanner's frame: the mount falls back to the
/// configuration, and the summary says so instead of leaving it silent.
#[test]
fn a_tf_static_without_the_scan_frame_is_pointed_out() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("other_frame.mcap");
    mutated(&testdata("sim-paper.mcap"), &log, |topic, _, m| {
        if let (AnyMessage::TFMessage(tf), "/tf_static") = (m, topic) {
            for t in &mut tf.transforms {
                t.child_frame_id = "camera".into();
            }
        }
    });
    let (_, s) = run(&log);
    assert_eq!(s.laser_mount_source, "config");
    assert!(
        s.notes.iter().any(|n| n
            .contains("/tf_static has transforms, but none from base_link to the scans' frame")),
        "{:?}",
        s.notes
    );
}

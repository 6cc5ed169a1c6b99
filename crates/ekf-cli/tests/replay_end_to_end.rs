//! `ekf replay` end to end on a synthetic bag: a robot driving two loops in a 6 m × 4 m
//! room with 2–3 % wheel scale errors and wheel-speed noise, 361-beam scans (σ 1 cm, 2.5 m
//! range, so the far half of the room has no mapped wall in view), an Imu compass (σ 1°),
//! a ground truth and the laser 0.2 m ahead of the axle in /tf_static. The map is built
//! from the first scan, as in the paper.

mod replay_support;

use ekf_cli::mcap_io::BagReader;
use ekf_cli::ros2::diagnostic_msgs::DiagnosticArray;
use ekf_cli::ros2::geometry_msgs::PoseWithCovarianceStamped;
use ekf_cli::ros2::visualization_msgs::MarkerArray;
use nalgebra::{Matrix3, SymmetricEigen};
use replay_support::*;
use serde_json::Value;
use std::path::Path;

fn rmse(summary: &Value) -> f64 {
    summary["accuracy"]["position_rmse_m"]
        .as_f64()
        .unwrap_or_else(|| panic!("no accuracy in summary: {summary:#}"))
}

fn count(summary: &Value, pointer: &str) -> u64 {
    summary
        .pointer(pointer)
        .and_then(Value::as_u64)
        .unwrap_or_else(|| panic!("no {pointer} in summary: {summary:#}"))
}

fn path_str(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn tf_static_mount_is_used_and_the_four_modes_are_ordered_as_in_the_paper() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (log, _) = write_scenario(dir.path(), "room.mcap", &Scenario::default());

    let mut results = Vec::new();
    for mode in ["odometry", "compass", "laser", "laser+compass"] {
        let s = replay_json(&log, &["--mode", mode]);
        assert_eq!(s["mode"], mode);
        assert_eq!(s["laser_mount_source"], "tf_static", "{mode}");
        assert_eq!(
            s["laser_mount"],
            serde_json::json!([0.2, 0.0, 0.0]),
            "{mode}"
        );
        assert_eq!(s["warning_count"], 0, "{mode}: {:#}", s["warnings"]);
        results.push((mode, rmse(&s)));
    }
    eprintln!("position RMSE per mode: {results:?}");
    let (_, odometry) = results[0];
    let (_, laser_compass) = results[3];
    for &(mode, r) in &results[1..] {
        assert!(
            r < odometry,
            "{mode} ({r:.4} m) not better than odometry ({odometry:.4} m): {results:?}"
        );
    }
    let (_, compass) = results[1];
    let (_, laser) = results[2];
    assert!(laser_compass < compass && laser < compass, "{results:?}");
    // With a first-scan map (whose own error no later scan removes) the compass adds
    // little to the lines: laser + compass and laser alone differ by about 1 %, either
    // way depending on the map noise, so only "not worse beyond 5 %" is asserted.
    assert!(laser_compass <= 1.05 * laser, "{results:?}");
    // Measured (seed 7) with map noise 2 cm / 1°: odometry 0.624, compass 0.061,
    // laser 0.0460, laser+compass 0.0464 m; without map noise laser 0.041, laser+compass 0.040 m.
    // Seeds 1-5 give the same order (laser+compass beats laser by 1-5 %, the compass
    // holding the heading while no mapped wall is in view) and laser+compass 3.0-4.3 cm.
    assert!(
        laser_compass < 0.05,
        "laser+compass RMSE {laser_compass:.4} m"
    );
    // The drift the scale errors cause is real: dead reckoning is off by decimetres.
    assert!(odometry > 0.3, "odometry RMSE {odometry:.4} m");
}

#[test]
fn without_tf_static_the_configured_mount_is_used() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (log, _) = write_scenario(dir.path(), "room.mcap", &Scenario::default());
    let config = dir.path().join("no_tf.toml");
    std::fs::write(&config, "[laser]\nmount_from_tf_static = false\n").expect("write config");
    let s = replay_json(&log, &["--config", path_str(&config)]);
    assert_eq!(s["laser_mount_source"], "config");
    assert_eq!(s["laser_mount"], serde_json::json!([0.0, 0.0, 0.0]));
    // The 0.2 m the configuration misses shows in the accuracy.
    let with_tf = replay_json(&log, &[]);
    assert!(
        rmse(&s) > rmse(&with_tf),
        "wrong mount {} m, tf_static mount {} m",
        rmse(&s),
        rmse(&with_tf)
    );
}

#[test]
fn tum_has_a_row_at_every_motion_step_compass_reading_and_scan_with_log_times_to_the_nanosecond() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (log, items) = write_scenario(dir.path(), "room.mcap", &Scenario::default());
    let tum = dir.path().join("est.tum");
    let s = replay_json(&log, &["--tum", path_str(&tum)]);

    // Every joint state but the first (which only sets the start), every compass reading
    // and every scan; one row per stamp.
    let joints: Vec<u64> = items
        .iter()
        .filter(|i| i.topic == "/joint_states")
        .map(|i| i.t_ns)
        .collect();
    let scans: Vec<u64> = items
        .iter()
        .filter(|i| i.topic == "/scan")
        .map(|i| i.t_ns)
        .collect();
    let compass: Vec<u64> = items
        .iter()
        .filter(|i| i.topic == "/compass")
        .map(|i| i.t_ns)
        .collect();
    let mut expected: Vec<u64> = joints[1..]
        .iter()
        .chain(&scans)
        .chain(&compass)
        .copied()
        .collect();
    expected.sort_unstable();
    expected.dedup();
    let rows = read_tum_rows(&tum);
    let stamps: Vec<&str> = rows.iter().map(|(t, _)| t.as_str()).collect();
    let expected_text: Vec<String> = expected.iter().map(|&t| stamp_text(t)).collect();
    assert_eq!(stamps, expected_text);
    assert_eq!(count(&s, "/poses_written"), expected.len() as u64);
    assert_eq!(count(&s, "/motion_steps"), joints.len() as u64 - 1);
    assert_eq!(count(&s, "/lines/scans"), scans.len() as u64);
    for (t, v) in &rows {
        assert!(v.iter().all(|x| x.is_finite()), "{t}: {v:?}");
        assert_eq!((v[2], v[3], v[4]), (0.0, 0.0, 0.0), "{t}: planar pose");
    }
}

#[test]
fn output_bag_has_poses_with_valid_covariances_markers_map_and_diagnostics() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (log, items) = write_scenario(dir.path(), "room.mcap", &Scenario::default());
    let out = dir.path().join("out.mcap");
    let s = replay_json(&log, &["--out", path_str(&out)]);

    let n = |topic: &str| items.iter().filter(|i| i.topic == topic).count() as u64;
    let motion_steps = n("/joint_states") - 1;
    let (scans, compass) = (n("/scan"), n("/compass"));
    assert_eq!(count(&s, "/motion_steps"), motion_steps);
    assert_eq!(count(&s, "/lines/scans_used"), scans);
    assert_eq!(
        count(&s, "/compass/accepted") + count(&s, "/compass/rejected"),
        compass
    );
    assert!(count(&s, "/lines/fused") > scans, "{:#}", s["lines"]);

    let counts = count_messages(&out);
    let expected = [
        // A pose after every motion step, scan and compass update.
        ("/ekf/pose", motion_steps + scans + compass),
        ("/ekf/markers", scans),
        ("/ekf/map", 1),
        ("/ekf/diagnostics", scans + compass),
    ];
    assert_eq!(counts, expected.map(|(t, c)| (t.to_string(), c)).into());

    let map_segments = count(&s, "/map_segments");
    assert!(map_segments >= 3, "map of {map_segments} segments");
    let bag = BagReader::open(&out).expect("output bag opens");
    let mut previous = 0;
    let mut statuses = std::collections::BTreeMap::<String, u64>::new();
    for m in bag.messages().expect("stream") {
        let m = m.expect("message");
        assert!(m.log_time >= previous);
        previous = m.log_time;
        match m.topic() {
            "/ekf/pose" => {
                let p: PoseWithCovarianceStamped = m.decode_as().expect("pose decodes");
                assert_eq!(p.header.frame_id, "map");
                assert_eq!(p.header.stamp.to_nanos(), Some(m.log_time));
                let c = &p.pose.covariance;
                assert!(c.iter().all(|x| x.is_finite()), "{c:?}");
                for i in 0..6 {
                    for j in 0..6 {
                        assert_eq!(c[i * 6 + j], c[j * 6 + i], "asymmetric at ({i},{j})");
                    }
                }
                let idx = [0, 1, 5];
                let block = Matrix3::from_fn(|i, j| c[idx[i] * 6 + idx[j]]);
                let min = SymmetricEigen::new(block).eigenvalues.min();
                assert!(
                    min >= -1e-12 * block.norm(),
                    "x/y/yaw covariance not PSD at {}: {block}",
                    m.log_time
                );
                assert!(block[(0, 0)] > 0.0 && block[(2, 2)] > 0.0);
            }
            "/ekf/map" => {
                let a: MarkerArray = m.decode_as().expect("map decodes");
                let points = &a.markers[0].points;
                // One line per segment of the map built from the first scan: the walls
                // within 2.5 m of the start, the one behind cut where the scan wraps.
                assert_eq!(points.len() as u64, 2 * map_segments, "{points:?}");
                for p in points {
                    let off = [p.x - ROOM_X0, ROOM_X1 - p.x, p.y - ROOM_Y0, ROOM_Y1 - p.y]
                        .map(f64::abs)
                        .into_iter()
                        .fold(f64::INFINITY, f64::min);
                    assert!(off < 0.1, "map end point {p:?} is {off} m off the walls");
                }
            }
            "/ekf/markers" => {
                let a: MarkerArray = m.decode_as().expect("markers decode");
                let ns: Vec<&str> = a.markers.iter().map(|k| k.ns.as_str()).collect();
                assert_eq!(ns, ["extracted", "matched", "covariance_2sigma"]);
                assert!(a
                    .markers
                    .iter()
                    .all(|k| k.points.iter().all(|q| q.x.is_finite())));
            }
            "/ekf/diagnostics" => {
                let d: DiagnosticArray = m.decode_as().expect("diagnostics decode");
                assert_eq!(d.status.len(), 1);
                *statuses.entry(d.status[0].name.clone()).or_default() += 1;
            }
            _ => {}
        }
    }
    assert_eq!(
        statuses,
        [
            ("ekf/compass".to_string(), compass),
            ("ekf/scan".to_string(), scans)
        ]
        .into()
    );
}

#[test]
fn replaying_the_same_bag_twice_gives_byte_identical_tum_files() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (log, _) = write_scenario(dir.path(), "room.mcap", &Scenario::default());
    let (a, b) = (dir.path().join("a.tum"), dir.path().join("b.tum"));
    replay_json(&log, &["--tum", path_str(&a)]);
    replay_json(&log, &["--tum", path_str(&b)]);
    let (ta, tb) = (
        std::fs::read(&a).expect("read a"),
        std::fs::read(&b).expect("read b"),
    );
    assert!(ta.len() > 1000, "TUM file too short: {} bytes", ta.len());
    assert!(ta == tb, "TUM outputs differ");
}

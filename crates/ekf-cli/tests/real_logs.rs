//! `ekf replay` end to end on the bundled real logs (testdata/README.md): the ACES
//! building with its line map, in the paper's four configurations, and the MRPT office.

use ekf_cli::config::Config;
use ekf_cli::replay::{replay, Mode, ReplayOptions, ReplaySummary};
use std::path::PathBuf;

fn testdata(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata")
        .join(name)
}

fn run(log: &str, mode: Mode, map: Option<&str>) -> ReplaySummary {
    let options = ReplayOptions {
        mode,
        map: map.map(testdata),
        init_from_truth: map.is_some(),
        out_mcap: None,
        tum: None,
        keep_trajectories: false,
        global: false,
        grow_map: false,
    };
    let outcome = replay(&testdata(log), &Config::default(), &options, &mut |_, _| {}).unwrap();
    assert!(outcome.failure.is_none(), "{:?}", outcome.failure);
    outcome.summary
}

#[test]
fn aces_four_modes_in_the_papers_order() {
    let rmse: Vec<(Mode, f64, ReplaySummary)> = Mode::ALL
        .iter()
        .map(|&m| {
            let s = run("aces.mcap", m, Some("aces-map.json"));
            (
                m,
                s.accuracy.expect("aces has a reference").position_rmse_m,
                s,
            )
        })
        .collect();
    let table: Vec<String> = rmse
        .iter()
        .map(|(m, r, _)| format!("{}: {r:.3} m", m.name()))
        .collect();
    let [odometry, compass, laser, both] = [rmse[0].1, rmse[1].1, rmse[2].1, rmse[3].1];
    // Raw odometry drifts by metres (about 10 m RMSE over the whole run).
    assert!(odometry > 5.0, "{table:?}");
    assert!(
        compass < odometry && laser < compass && both < compass,
        "{table:?}"
    );
    // Issue acceptance: laser only ≤ 0.20 m. Measured when this test was written:
    // laser 0.093 m, laser + compass 0.092 m.
    assert!(laser <= 0.12, "{table:?}");
    assert!(both <= 0.12, "{table:?}");
    let laser_summary = &rmse[2].2;
    assert_eq!(laser_summary.lines.scans_used, 440);
    assert_eq!(laser_summary.accuracy.unwrap().matched_poses, 440);
    assert!(
        laser_summary.lines.fused > 1000,
        "{:?}",
        laser_summary.lines
    );
    assert_eq!(laser_summary.laser_mount_source, "tf_static");
    assert_eq!(
        laser_summary.warning_count, 0,
        "{:?}",
        laser_summary.warnings
    );
    // The synthetic compass (σ 2°) is fused, and the gate drops only a few readings.
    let compass_counts = rmse[1].2.compass;
    assert_eq!(compass_counts.accepted + compass_counts.rejected, 440);
    assert!(compass_counts.rejected <= 22, "{compass_counts:?}");
}

#[test]
fn mrpt_office_with_the_first_scan_map() {
    let s = run("mrpt-office.mcap", Mode::Laser, None);
    assert_eq!(s.messages_read.get("/scan"), Some(&225));
    assert_eq!(s.messages_read.get("/odom"), Some(&224));
    // The first odometry message only sets the start.
    assert_eq!(s.motion_steps, 223);
    assert_eq!(s.lines.scans_used, 225);
    assert!(s.map_segments >= 5, "{s:?}");
    // The laser sits 0.78 m ahead of the robot's origin (from /tf_static).
    assert_eq!(s.laser_mount_source, "tf_static");
    assert!((s.laser_mount[0] - 0.78).abs() < 1e-12);
    assert!(s.lines.fused > 100, "{:?}", s.lines);
    assert!(s.accuracy.is_none());
    assert_eq!(s.warning_count, 0, "{:?}", s.warnings);
}

#[test]
fn aces_map_from_the_reference_and_from_the_first_scan() {
    use ekf_cli::commands::map::{build_map, MapSource};
    let config = Config::default();
    let (map, s) = build_map(
        &testdata("aces.mcap"),
        &config,
        MapSource::Reference(Default::default()),
    )
    .unwrap();
    assert_eq!((s.scans_used, s.scans_skipped), (440, 0));
    assert_eq!(s.laser_mount_source, "tf_static");
    // The bundled map was made this way; building it again gives the same segments.
    let bundled = std::fs::read_to_string(testdata("aces-map.json")).unwrap();
    assert_eq!(map.to_json().unwrap(), bundled);
    let (first, s) = build_map(
        &testdata("aces.mcap"),
        &config,
        MapSource::FirstScan {
            init_from_truth: true,
        },
    )
    .unwrap();
    assert_eq!(s.scans_used, 1);
    assert_eq!(first.len() as u64, s.lines);
    assert!(
        first.len() >= 3 && first.len() < map.len(),
        "{} segments",
        first.len()
    );
    // Without a reference the map cannot be placed along it.
    let err = build_map(
        &testdata("mrpt-office.mcap"),
        &config,
        MapSource::Reference(Default::default()),
    )
    .unwrap_err();
    assert!(err.to_string().contains("/ground_truth"), "{err}");
}

#[test]
fn map_build_without_scans_names_the_missing_topic() {
    use ekf_cli::commands::map::{build_map, MapSource};
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("odometry-only.mcap");
    let mut w = ekf_cli::mcap_io::BagWriter::create(&log).unwrap();
    w.write("/odom", &ekf_cli::ros2::nav_msgs::Odometry::default())
        .unwrap();
    w.finish().unwrap();
    let err = build_map(
        &log,
        &Config::default(),
        MapSource::FirstScan {
            init_from_truth: false,
        },
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("no topic /scan (laser scans)")
            && err.contains("/odom (nav_msgs/msg/Odometry)"),
        "{err}"
    );
}

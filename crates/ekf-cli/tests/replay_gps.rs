//! GPS fixes as position measurements (`[gps]` in the configuration): off by default,
//! fused about the configured origin when on, outliers refused by the 2-dof gate.

mod replay_support;

use ekf_cli::geo::GeoOrigin;
use ekf_cli::mcap_io::BagWriter;
use ekf_cli::ros2::build::{header, odometry, BASE_FRAME, MAP_FRAME};
use ekf_cli::ros2::sensor_msgs::{JointState, NavSatFix, NavSatStatus};
use ekf_core::Pose2;
use replay_support::{ekf, replay_json};
use std::path::Path;

const ORIGIN: GeoOrigin = GeoOrigin {
    latitude: 10.77,
    longitude: 106.66,
    altitude: 0.0,
};

/// 60 s driving east at 0.5 m/s from the origin. The encoders report the right wheel 2 %
/// fast, so dead reckoning curves left; fixes once a second at the true position with a
/// deterministic ±0.5 m error, at 30 s one fix 40 m off, and at 40.5 s a second fix
/// off the globe with a zero covariance.
fn write_log(path: &Path) {
    let mut bag = BagWriter::create(path).unwrap();
    let (r, dt) = (0.05, 0.1);
    let omega = 0.5 / r;
    let (mut left, mut right) = (0.0, 0.0);
    for k in 0..=600u64 {
        let t = k * 100_000_000;
        let x = 0.5 * k as f64 * dt;
        let joints = JointState {
            header: header(t, BASE_FRAME),
            name: vec!["left_wheel_joint".into(), "right_wheel_joint".into()],
            position: vec![left, right],
            velocity: vec![omega, omega * 1.02],
            effort: vec![],
        };
        bag.write("/joint_states", &joints).unwrap();
        left += omega * dt;
        right += omega * 1.02 * dt;
        bag.write(
            "/ground_truth",
            &odometry(t, &Pose2::new(x, 0.0, 0.0), MAP_FRAME),
        )
        .unwrap();
        if k % 10 == 5 {
            let wiggle = 0.5 * ((k as f64) * 0.7).sin();
            let offset = if k == 305 { 40.0 } else { 0.0 };
            let f = ORIGIN.fix_at(x + wiggle, -wiggle + offset);
            let mut fix = NavSatFix {
                header: header(t, "gps"),
                status: NavSatStatus {
                    status: NavSatStatus::STATUS_FIX,
                    service: NavSatStatus::SERVICE_GPS,
                },
                latitude: f.latitude,
                longitude: f.longitude,
                ..NavSatFix::default()
            };
            fix.position_covariance[0] = 0.25;
            fix.position_covariance[4] = 0.25;
            fix.position_covariance[8] = 1.0;
            fix.position_covariance_type = NavSatFix::COVARIANCE_TYPE_DIAGONAL_KNOWN;
            bag.write("/fix", &fix).unwrap();
            if k == 405 {
                // A receiver's garbage: off the globe, reporting an exact position.
                fix.latitude = 100.67;
                fix.longitude = 181.5;
                fix.position_covariance = [0.0; 9];
                bag.write("/fix", &fix).unwrap();
            }
        }
    }
    bag.finish().unwrap();
}

/// `ekf replay --json` in odometry mode from the first reference pose, with `extra`
/// arguments.
fn replay(log: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["--mode", "odometry", "--init-from-truth"];
    args.extend_from_slice(extra);
    replay_json(log, &args)
}

#[test]
fn fixes_pull_a_drifting_estimate_back_and_an_outlier_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("gps.mcap");
    write_log(&log);

    let off = replay(&log, &[]);
    assert_eq!(off["gps"]["accepted"], 0);
    let drift = off["accuracy"]["position_max_m"].as_f64().unwrap();
    assert!(drift > 5.0, "dead reckoning should drift: {off}");

    let config = dir.path().join("gps.toml");
    std::fs::write(
        &config,
        "[gps]\nfuse = true\norigin_latitude = 10.77\norigin_longitude = 106.66\n",
    )
    .unwrap();
    let on = replay(&log, &["--config", config.to_str().unwrap()]);
    assert_eq!(on["gps"]["accepted"], 59, "{on}");
    assert_eq!(on["gps"]["rejected"], 1, "{on}");
    // The garbage fix is neither: refused before the gate, with the reason.
    assert_eq!(on["warning_count"], 1, "{on}");
    let warning = &on["warnings"][0];
    assert_eq!(warning["topic"], "/fix");
    let reason = warning["reason"].as_str().unwrap();
    assert!(
        reason.contains("off the globe: latitude 100.67°"),
        "{reason}"
    );
    let rmse = on["accuracy"]["position_rmse_m"].as_f64().unwrap();
    assert!(rmse < 1.0, "{on}");

    // The table says so too.
    let out = ekf(&[
        "replay",
        log.to_str().unwrap(),
        "--mode",
        "odometry",
        "--init-from-truth",
        "--config",
        config.to_str().unwrap(),
    ]);
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(table.contains("gps: fused 59, rejected 1"), "{table}");
}

#[test]
fn a_bad_origin_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("gps.mcap");
    write_log(&log);
    let config = dir.path().join("bad.toml");
    std::fs::write(&config, "[gps]\nfuse = true\norigin_latitude = 95.0\n").unwrap();
    let out = ekf(&[
        "replay",
        log.to_str().unwrap(),
        "--config",
        config.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("line 3") && err.contains("gps.origin_latitude"),
        "{err}"
    );
}

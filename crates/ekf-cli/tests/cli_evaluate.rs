//! `ekf evaluate` end to end: the binary's JSON equals evo's numbers for the golden pair,
//! and a missing file is a clear error with a non-zero exit.

mod ekf_bin;

use ekf_bin::{ekf, run_fails, run_ok};

fn golden(name: &str) -> String {
    format!("{}/tests/golden/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn evo_case(case: &str, metric: &str) -> f64 {
    let text = std::fs::read_to_string(golden("evo_expected.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["cases"][case]["translation_m"][metric].as_f64().unwrap()
}

/// Runs `ekf evaluate ARGS`, which must fail, and returns what it printed on stderr.
fn evaluate_fails(args: &[&str]) -> String {
    let out = run_fails(ekf().arg("evaluate").args(args));
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn run_json(extra: &[&str]) -> serde_json::Value {
    let out = run_ok(
        ekf()
            .args([
                "evaluate",
                &golden("evo_est.txt"),
                "--truth",
                &golden("evo_ref.txt"),
                "--json",
            ])
            .args(extra),
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn json_matches_evo() {
    let v = run_json(&[]);
    let got = v["ape"]["translation_m"]["rmse"].as_f64().unwrap();
    assert!(
        (got - evo_case("ape_none", "rmse")).abs() < 1e-9,
        "ATE {got}"
    );
    assert_eq!(v["ape"]["matched_poses"], 117);
    let aligned = run_json(&["--align"]);
    let got = aligned["ape"]["translation_m"]["rmse"].as_f64().unwrap();
    assert!(
        (got - evo_case("ape_align", "rmse")).abs() < 1e-9,
        "aligned ATE {got}"
    );
}

#[test]
fn missing_file_names_it_and_fails() {
    let err = evaluate_fails(&["no-such-estimate.txt", "--truth", &golden("evo_ref.txt")]);
    assert!(err.contains("no-such-estimate.txt"), "stderr: {err}");
}

#[test]
fn mcap_and_tum_outputs_of_a_replay_evaluate_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let (mcap, tum) = (dir.path().join("est.mcap"), dir.path().join("est.tum"));
    let data = |f: &str| format!("{}/../../testdata/{f}", env!("CARGO_MANIFEST_DIR"));
    let aces = data("aces.mcap");
    run_ok(
        ekf()
            .args([
                "replay",
                &aces,
                "--map",
                &data("aces-map.json"),
                "--init-from-truth",
                "--mode",
                "laser",
            ])
            .arg("--out")
            .arg(&mcap)
            .arg("--tum")
            .arg(&tum),
    );
    let ate = |est: &std::path::Path| {
        let out = run_ok(
            ekf()
                .arg("evaluate")
                .arg(est)
                .args(["--truth", &aces, "--json"]),
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        (
            v["ape"]["translation_m"]["rmse"].as_f64().unwrap(),
            v["ape"]["matched_poses"].as_u64().unwrap(),
        )
    };
    let (from_mcap, from_tum) = (ate(&mcap), ate(&tum));
    assert_eq!(from_mcap.1, 440);
    assert_eq!(from_tum.1, 440);
    assert!(
        (from_mcap.0 - from_tum.0).abs() < 1e-9,
        "{from_mcap:?} vs {from_tum:?}"
    );
    // A bag without a pose topic names the topics it has.
    let err = evaluate_fails(&[&data("mrpt-office.mcap"), "--truth", &aces]);
    assert!(
        err.contains("no pose topic") && err.contains("/scan (sensor_msgs/msg/LaserScan)"),
        "{err}"
    );
    // A named topic that carries no poses is refused, not read as an empty trajectory.
    let err = evaluate_fails(&[&aces, "--est-topic", "/scan", "--truth", &aces]);
    assert_eq!(
        err,
        format!(
            "ekf: error: {}: topic /scan carries sensor_msgs/msg/LaserScan; expected one of \
             geometry_msgs/msg/PoseWithCovarianceStamped, geometry_msgs/msg/PoseStamped, \
             nav_msgs/msg/Odometry\n",
            aces
        )
    );
}

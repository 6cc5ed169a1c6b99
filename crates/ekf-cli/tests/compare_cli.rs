//! `ekf compare` end to end: the binary's JSON and SVG on the synthetic room log, and the
//! error (non-zero exit, the topic named) on a log without a reference.

mod compare_common;
mod ekf_bin;

use compare_common::{write_room_bag, BagContents};
use ekf_bin::{ekf, run_fails, run_ok};

#[test]
fn json_and_svg_from_the_binary() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("room.mcap");
    let svg = dir.path().join("fig9_10.svg");
    write_room_bag(&log, BagContents::default());
    let out = run_ok(
        ekf()
            .arg("compare")
            .arg(&log)
            .arg("--init-from-truth")
            .arg("--svg")
            .arg(&svg)
            .arg("--json"),
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is one JSON");
    let modes = v["modes"].as_array().unwrap();
    let names: Vec<&str> = modes.iter().map(|m| m["mode"].as_str().unwrap()).collect();
    assert_eq!(names, ["odometry", "compass", "laser", "laser+compass"]);
    let rmse = |i: usize| {
        assert_eq!(modes[i]["status"], "ran", "{}", modes[i]);
        modes[i]["accuracy"]["position_rmse_m"].as_f64().unwrap()
    };
    assert!(rmse(0) > 10.0 * rmse(2) && rmse(0) > 10.0 * rmse(3), "{v}");
    assert!(rmse(0) > rmse(1), "{v}");

    let text = std::fs::read_to_string(&svg).expect("--svg wrote the file");
    let doc = roxmltree::Document::parse(&text).expect("SVG is XML");
    let texts: Vec<&str> = doc
        .descendants()
        .filter(|n| n.has_tag_name("text"))
        .filter_map(|n| n.text().map(str::trim))
        .collect();
    for name in ["reference", "odometry", "compass", "laser", "laser+compass"] {
        assert!(texts.contains(&name), "{name}: {texts:?}");
    }
    // One file: no second SVG next to it.
    let files = std::fs::read_dir(dir.path()).unwrap().count();
    assert_eq!(files, 2);
}

#[test]
fn no_reference_fails_and_names_the_topic() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("bare.mcap");
    write_room_bag(
        &log,
        BagContents {
            reference: false,
            ..BagContents::default()
        },
    );
    let out = run_fails(ekf().arg("compare").arg(&log));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("needs a reference") && stderr.contains("/ground_truth"),
        "{stderr}"
    );
    assert!(out.stdout.is_empty());
}

//! Bags as robots record them. Measurements logged after their header stamps (a busy
//! robot computer) are fused at their stamps (`ekf_fusion::TimedLocalizer`): the bundled
//! simulated run, with its scans or its compass headings logged late, places the robot as
//! well as on time.

use ekf_cli::config::Config;
use ekf_cli::mcap_io::{BagReader, BagWriter};
use ekf_cli::replay::{replay, ReplayOptions, ReplaySummary};
use std::path::{Path, PathBuf};

fn testdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata")
        .join(name)
}

/// A copy of `src` in which the messages on `topic` are logged `delay_ns` later (their
/// header stamps unchanged), every message in log-time order.
fn delayed_copy(src: &Path, dst: &Path, topic: &str, delay_ns: u64) {
    let bag = BagReader::open(src).unwrap();
    let mut messages: Vec<(u64, u64, String, ekf_cli::ros2::AnyMessage)> = bag
        .messages()
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            let late = if m.topic() == topic { delay_ns } else { 0 };
            (
                m.log_time + late,
                m.index,
                m.topic().to_owned(),
                m.decode().unwrap(),
            )
        })
        .collect();
    messages.sort_by_key(|m| (m.0, m.1));
    let mut out = BagWriter::create(dst).unwrap();
    for (t, _, topic, message) in &messages {
        out.write_any(topic, *t, message).unwrap();
    }
    out.finish().unwrap();
}

/// `(position RMSE, summary)` of the default-mode replay (laser + compass, first-scan
/// map) from the first reference pose, with `[timing] max_lag = lag`.
fn run(log: &Path, lag: f64) -> (f64, ReplaySummary) {
    let mut config = Config::preset("paper-robot").unwrap();
    config.timing.max_lag = lag;
    let options = ReplayOptions {
        init_from_truth: true,
        ..ReplayOptions::default()
    };
    let outcome = replay(log, &config, &options, &mut |_, _| {}).unwrap();
    assert!(outcome.failure.is_none());
    let s = outcome.summary;
    (s.accuracy.as_ref().unwrap().position_rmse_m, s)
}

#[test]
fn scans_and_headings_logged_late_are_fused_at_their_stamps() {
    let dir = tempfile::tempdir().unwrap();
    let on_time = run(&testdata("sim-paper.mcap"), 0.5).0;
    for topic in ["/scan", "/compass"] {
        let late = dir.path().join("late.mcap");
        delayed_copy(&testdata("sim-paper.mcap"), &late, topic, 450_000_000);
        let (rmse, summary) = run(&late, 0.5);
        eprintln!("{topic} 450 ms late: {rmse:.4} m, on time {on_time:.4} m");
        assert!(
            rmse <= 1.1 * on_time,
            "{topic} 450 ms late: {rmse:.4} m against {on_time:.4} m on time"
        );
        assert_eq!(summary.too_late, 0, "{topic}");
    }
    // Fused in log order instead, late scans meet a state that has moved on.
    let late = dir.path().join("late.mcap");
    delayed_copy(&testdata("sim-paper.mcap"), &late, "/scan", 450_000_000);
    let (in_log_order, _) = run(&late, 0.0);
    eprintln!("/scan 450 ms late, in log order: {in_log_order:.4} m");
    assert!(
        in_log_order > 1.5 * on_time,
        "{in_log_order:.4} m in log order, {on_time:.4} m on time"
    );
}

#[test]
fn inputs_later_than_the_lag_are_dropped_and_counted() {
    let dir = tempfile::tempdir().unwrap();
    let late = dir.path().join("late.mcap");
    delayed_copy(&testdata("sim-paper.mcap"), &late, "/scan", 800_000_000);
    let (_, summary) = run(&late, 0.5);
    let bag = BagReader::open(&late).unwrap();
    let scans = bag
        .topics()
        .iter()
        .find(|t| t.topic == "/scan")
        .unwrap()
        .message_count;
    assert!(
        summary.too_late > scans / 2,
        "{} of {scans} scans dropped",
        summary.too_late
    );
    assert_eq!(summary.lines.scans + summary.too_late, scans);
    let w = &summary.warnings[0];
    assert_eq!(w.topic, "/scan");
    assert!(w.reason.contains("max_lag"), "{}", w.reason);
}

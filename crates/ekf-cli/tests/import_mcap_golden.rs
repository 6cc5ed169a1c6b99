//! Golden tests of the bags `ekf` writes, read back with our reader: `ekf import` of the
//! CARMEN fixture (two scans with their resets, a synthetic compass), and the start of
//! `ekf replay`'s output on the bundled MRPT log. Regenerate after an intended change
//! with `UPDATE_GOLDEN=1`.

use ekf_cli::commands::import::{import_log, LogFormat};
use ekf_cli::import::{CarmenFlavour, CarmenOptions, SyntheticCompass};
use ekf_cli::mcap_io::BagReader;
use ekf_cli::ros2::AnyMessage;
use std::fmt::Write as _;
use std::path::PathBuf;

/// The bag's topics with counts, then one line per message (at most `max_messages`).
fn dump(path: &std::path::Path, max_messages: usize) -> String {
    let bag = BagReader::open(path).unwrap();
    let mut out = String::new();
    for t in bag.topics() {
        writeln!(
            out,
            "topic {} {} x{}",
            t.topic, t.type_name, t.message_count
        )
        .unwrap();
    }
    for m in bag.messages().unwrap().take(max_messages) {
        let m = m.unwrap();
        let line = match m.decode().unwrap() {
            AnyMessage::Odometry(o) => {
                let p = &o.pose.pose;
                format!(
                    "{} -> {} x={:.6} y={:.6} yaw={:.6}",
                    o.header.frame_id,
                    o.child_frame_id,
                    p.position.x,
                    p.position.y,
                    p.orientation.yaw()
                )
            }
            AnyMessage::LaserScan(s) => format!(
                "{} angle_min={:.6} inc={:.6} range=[{}, {}] ranges={:?}",
                s.header.frame_id,
                s.angle_min,
                s.angle_increment,
                s.range_min,
                s.range_max,
                s.ranges
            ),
            AnyMessage::TFMessage(tf) => tf
                .transforms
                .iter()
                .map(|t| {
                    format!(
                        "{} -> {} x={:.3} y={:.3} yaw={:.6}",
                        t.header.frame_id,
                        t.child_frame_id,
                        t.transform.translation.x,
                        t.transform.translation.y,
                        t.transform.rotation.yaw()
                    )
                })
                .collect::<Vec<_>>()
                .join("; "),
            AnyMessage::Imu(i) => format!(
                "{} yaw={:.6} var={:e}",
                i.header.frame_id,
                i.orientation.yaw(),
                i.orientation_covariance[8]
            ),
            AnyMessage::PoseWithCovarianceStamped(p) => {
                let (c, q) = (&p.pose.covariance, &p.pose.pose);
                format!(
                    "{} x={:.6} y={:.6} yaw={:.6} cov_xx={:.3e} cov_xy={:.3e} cov_yy={:.3e} cov_yawyaw={:.3e}",
                    p.header.frame_id,
                    q.position.x,
                    q.position.y,
                    q.orientation.yaw(),
                    c[0],
                    c[1],
                    c[7],
                    c[35]
                )
            }
            AnyMessage::MarkerArray(a) => a
                .markers
                .iter()
                .map(|k| {
                    format!(
                        "{}:{} type {} points {}",
                        k.ns,
                        k.id,
                        k.r#type,
                        k.points.len()
                    )
                })
                .collect::<Vec<_>>()
                .join(", "),
            AnyMessage::DiagnosticArray(d) => d
                .status
                .iter()
                .map(|s| {
                    format!(
                        "{} level {} '{}' {}",
                        s.name,
                        s.level,
                        s.message,
                        s.values
                            .iter()
                            .map(|kv| format!("{}={}", kv.key, kv.value))
                            .collect::<Vec<_>>()
                            .join(" ")
                    )
                })
                .collect::<Vec<_>>()
                .join("; "),
            other => format!("unexpected {}", other.type_name()),
        };
        writeln!(out, "{} {} {}", m.log_time, m.topic(), line).unwrap();
    }
    out
}

fn check_golden(got: &str, name: &str) {
    let golden = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(name);
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        std::fs::write(&golden, got).unwrap();
    }
    let want = std::fs::read_to_string(&golden).unwrap();
    assert_eq!(
        got, want,
        "regenerate with UPDATE_GOLDEN=1 if the change is intended"
    );
}

#[test]
fn carmen_fixture_to_bag() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("fixture.mcap");
    let input =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/carmen_corrected.log");
    let options = CarmenOptions {
        flavour: CarmenFlavour::Auto,
        laser_max_range: 50.0,
        synthetic_compass: Some(SyntheticCompass {
            sigma_deg: 2.0,
            seed: 7,
        }),
        strict: false,
    };
    let summary = import_log(&input, &bag, LogFormat::Carmen(options)).unwrap();
    assert_eq!(
        (
            summary.stats.scans,
            summary.stats.references,
            summary.stats.compass
        ),
        (2, 2, 2)
    );
    check_golden(&dump(&bag, usize::MAX), "import_carmen_fixture.txt");
}

#[test]
fn replay_output_bag_start() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("replay.mcap");
    let log = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../testdata/mrpt-office.mcap");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_ekf"))
        .arg("replay")
        .arg(&log)
        .args(["--mode", "laser", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    // The topics with their counts, then the first 40 messages: the map from the first
    // scan, poses with covariances, line markers and diagnostics.
    check_golden(&dump(&out, 40), "replay_mrpt_office_start.txt");
}

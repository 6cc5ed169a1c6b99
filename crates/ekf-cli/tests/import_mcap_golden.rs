//! Golden test of `ekf import`'s output bag: the CARMEN fixture (two scans with their
//! resets) with a synthetic compass becomes exactly these messages, read back with our
//! reader. Regenerate after an intended change with `UPDATE_GOLDEN=1`.

use ekf_cli::commands::import::{import_log, LogFormat};
use ekf_cli::import::{CarmenFlavour, CarmenOptions, SyntheticCompass};
use ekf_cli::mcap_io::BagReader;
use ekf_cli::ros2::AnyMessage;
use std::fmt::Write as _;
use std::path::PathBuf;

fn dump(path: &std::path::Path) -> String {
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
    for m in bag.messages().unwrap() {
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
            other => format!("unexpected {}", other.type_name()),
        };
        writeln!(out, "{} {} {}", m.log_time, m.topic(), line).unwrap();
    }
    out
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
    let got = dump(&bag);
    let golden =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden/import_carmen_fixture.txt");
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        std::fs::write(&golden, &got).unwrap();
    }
    let want = std::fs::read_to_string(&golden).unwrap();
    assert_eq!(
        got, want,
        "regenerate with UPDATE_GOLDEN=1 if the change is intended"
    );
}

//! `ekf replay` on a truncated or corrupted bag: everything readable is processed, the
//! outputs are finished, and the error names the file and the byte where reading broke,
//! with a non-zero exit code.

mod replay_support;

use ekf_cli::mcap_io::BagReader;
use replay_support::*;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn p(path: &Path) -> &str {
    path.to_str().expect("utf-8 path")
}

/// A 20 s drive with a 256 kB filler message every second: several 1 MiB chunks.
fn chunked_log(dir: &Path) -> PathBuf {
    let s = Scenario {
        loops: 1,
        max_steps: Some(200),
        filler_bytes: 256 << 10,
        ..Scenario::default()
    };
    write_scenario(dir, "full.mcap", &s).0
}

/// What the library reads from `log`: messages before the damage, and the error.
fn read_until_damage(log: &Path) -> (u64, String) {
    let bag = BagReader::open(log).expect("a damaged bag still opens");
    let mut delivered = 0;
    for m in bag.messages().expect("stream") {
        match m {
            Ok(_) => delivered += 1,
            Err(e) => return (delivered, e.to_string()),
        }
    }
    panic!("{}: damage not detected", log.display());
}

struct Damaged {
    summary: Value,
    stderr: String,
    tum_rows: Vec<(String, [f64; 7])>,
    out_counts: std::collections::BTreeMap<String, u64>,
}

/// Replays a damaged log with every output and checks what every damaged replay must do.
fn replay_damaged(log: &Path, full_tum: &[(String, [f64; 7])]) -> Damaged {
    let dir = log.parent().expect("dir");
    let stem = log.file_stem().and_then(|s| s.to_str()).expect("stem");
    let (out, tum) = (
        dir.join(format!("{stem}.out.mcap")),
        dir.join(format!("{stem}.tum")),
    );
    let run = ekf(&[
        "replay",
        p(log),
        "--json",
        "--out",
        p(&out),
        "--tum",
        p(&tum),
    ]);
    let (stdout, stderr) = texts(&run);
    assert_eq!(run.status.code(), Some(1), "{stem}: {stderr}");

    // The error is the reader's, with the file and the byte offset.
    let (delivered, expected) = read_until_damage(log);
    assert_eq!(stderr, format!("ekf: error: {expected}\n"), "{stem}");
    assert!(stderr.contains(&format!("{}: truncated or corrupt MCAP at byte ", p(log))));
    assert!(
        stderr.contains(&format!("(after {delivered} messages)")),
        "{stderr}"
    );

    // The summary still comes, and counts everything read.
    let summary: Value = serde_json::from_str(&stdout)
        .unwrap_or_else(|e| panic!("{stem}: summary is not JSON ({e}): {stdout}"));
    let read: u64 = summary["messages_read"]
        .as_object()
        .expect("messages_read")
        .values()
        .map(|v| v.as_u64().expect("count"))
        .sum();
    assert_eq!(
        read, delivered,
        "{stem}: every delivered message is processed"
    );
    assert!(read > 0, "{stem}");
    let poses = summary["poses_written"].as_u64().expect("poses_written");
    assert!(poses > 0, "{stem}: {summary:#}");

    // The TUM file is written: the full run's rows up to the damage, unchanged.
    let tum_rows = read_tum_rows(&tum);
    assert_eq!(tum_rows.len() as u64, poses, "{stem}");
    assert_eq!(tum_rows[..], full_tum[..tum_rows.len()], "{stem}");

    // The output bag is finished and readable.
    let out_counts = count_messages(&out);
    let motion = summary["motion_steps"].as_u64().expect("motion_steps");
    let scans = summary["lines"]["scans_used"].as_u64().expect("scans_used");
    let compass = summary["compass"]["accepted"].as_u64().expect("accepted")
        + summary["compass"]["rejected"].as_u64().expect("rejected");
    assert_eq!(
        out_counts.get("/ekf/pose").copied(),
        Some(motion + scans + compass),
        "{stem}: {out_counts:?}"
    );
    assert_eq!(
        out_counts.get("/ekf/markers").copied(),
        Some(scans),
        "{stem}"
    );
    Damaged {
        summary,
        stderr,
        tum_rows,
        out_counts,
    }
}

/// The byte offset in "... at byte N ...".
fn byte_offset(stderr: &str) -> u64 {
    let rest = stderr
        .split(" at byte ")
        .nth(1)
        .unwrap_or_else(|| panic!("no byte offset in {stderr}"));
    rest.split_whitespace()
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no byte offset in {stderr}"))
}

fn full_run(log: &Path) -> Vec<(String, [f64; 7])> {
    let tum = log.with_extension("tum");
    replay_json(log, &["--tum", p(&tum)]);
    read_tum_rows(&tum)
}

#[test]
fn a_truncated_log_is_processed_up_to_the_cut() {
    let dir = tempfile::tempdir().expect("tempdir");
    let full = chunked_log(dir.path());
    let full_tum = full_run(&full);
    let bytes = std::fs::read(&full).expect("read bag");
    let len = bytes.len();
    assert!(
        len > 4 << 20,
        "bag of {len} bytes is too small for several chunks"
    );

    let mut previous_rows = 0;
    for cut in [len / 3, len / 2, 2 * len / 3, len - 100] {
        let log = dir.path().join(format!("cut_{cut}.mcap"));
        std::fs::write(&log, &bytes[..cut]).expect("write cut bag");
        let d = replay_damaged(&log, &full_tum);
        let at = byte_offset(&d.stderr);
        assert!(
            at <= cut as u64,
            "cut at {cut}, error at byte {at}: {}",
            d.stderr
        );
        assert!(
            d.tum_rows.len() >= previous_rows,
            "a longer file gave fewer poses"
        );
        previous_rows = d.tum_rows.len();
        assert!(d.out_counts.contains_key("/ekf/diagnostics"));
        assert_eq!(d.summary["laser_mount_source"], "tf_static");
    }
    // A cut in the summary section loses no message.
    assert_eq!(previous_rows, full_tum.len());
}

#[test]
fn a_corrupted_chunk_stops_the_replay_at_that_chunk() {
    let dir = tempfile::tempdir().expect("tempdir");
    let full = chunked_log(dir.path());
    let full_tum = full_run(&full);
    let bytes = std::fs::read(&full).expect("read bag");
    let chunks = mcap::Summary::read(&bytes)
        .expect("summary parses")
        .expect("summary present")
        .chunk_indexes;
    assert!(chunks.len() >= 4, "only {} chunks", chunks.len());

    for k in [1, chunks.len() / 2] {
        let chunk = &chunks[k];
        let data = chunk.compressed_data_offset().expect("data offset");
        let mut damaged = bytes.clone();
        damaged[(data + chunk.compressed_size / 2) as usize] ^= 0x5A;
        let log = dir.path().join(format!("flip_chunk_{k}.mcap"));
        std::fs::write(&log, &damaged).expect("write damaged bag");
        let d = replay_damaged(&log, &full_tum);
        assert_eq!(
            byte_offset(&d.stderr),
            chunk.chunk_start_offset,
            "{}",
            d.stderr
        );
        // Every pose before the damaged chunk, none after.
        let last = d.tum_rows.last().expect("rows").0.clone();
        let first_lost = stamp_text(chunk.message_start_time);
        assert!(
            last < first_lost,
            "pose at {last} after the damage at {first_lost}"
        );
        let expected = full_tum.iter().filter(|(t, _)| *t < first_lost).count();
        assert_eq!(d.tum_rows.len(), expected);
    }
}

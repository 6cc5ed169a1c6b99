//! `ekf replay` on a truncated or corrupted bag: everything readable is processed, the
//! outputs are finished. A cut end is an error naming the file and the byte where
//! reading broke, with a non-zero exit code; a damaged chunk with intact chunks after it
//! is read past, and the lost log times are reported.

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

/// The diagnostics statuses named `name` in the output bag `out`, in order.
fn statuses(out: &Path, name: &str) -> Vec<ekf_cli::ros2::diagnostic_msgs::DiagnosticStatus> {
    BagReader::open(out)
        .expect("output bag")
        .messages()
        .expect("stream")
        .map(|m| m.expect("output bag intact"))
        .filter_map(|m| match m.decode() {
            Ok(ekf_cli::ros2::AnyMessage::DiagnosticArray(a)) => Some(a),
            _ => None,
        })
        .flat_map(|a| a.status)
        .filter(|s| s.name == name)
        .collect()
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

/// A corrupted chunk in the middle (the bag's index intact) loses that chunk only: the
/// replay reads on after it and exits 0, and the summary, the TUM file and the output
/// bag each say which log times were lost.
#[test]
fn a_corrupted_chunk_is_read_past_and_the_lost_times_are_reported() {
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
        let (out, tum) = (log.with_extension("out.mcap"), log.with_extension("tum"));
        let summary = replay_json(&log, &["--out", p(&out), "--tum", p(&tum)]);

        let stretches = summary["damaged"].as_array().expect("damaged");
        assert_eq!(stretches.len(), 1, "{summary:#}");
        let d = &stretches[0];
        assert_eq!(d["file"], p(&log));
        assert_eq!(d["byte_offset"], chunk.chunk_start_offset);
        assert_eq!(d["lost"]["from_ns"], chunk.message_start_time);
        assert_eq!(d["lost"]["to_ns"], chunk.message_end_time);
        assert!(d["reason"].as_str().expect("reason").contains("CRC"), "{d}");
        assert!(summary["warnings"][0]["reason"]
            .as_str()
            .expect("warning")
            .starts_with("damaged chunk read past"));

        // Poses before the damaged chunk as in the full run, and poses after it to the end.
        let rows = read_tum_rows(&tum);
        let first_lost = stamp_text(chunk.message_start_time);
        let before = full_tum.iter().filter(|(t, _)| *t < first_lost).count();
        assert_eq!(rows[..before], full_tum[..before], "chunk {k}");
        let after_lost = stamp_text(chunk.message_end_time);
        assert!(
            rows.iter().any(|(t, _)| *t > after_lost),
            "chunk {k}: nothing after"
        );
        assert_eq!(rows.last().map(|r| &r.0), full_tum.last().map(|r| &r.0));
        let text = std::fs::read_to_string(&tum).expect("tum");
        let comment = format!(
            "# damaged log: {} at byte {}",
            p(&log),
            chunk.chunk_start_offset
        );
        assert!(
            text.contains(&comment),
            "no comment {comment:?} in the TUM file"
        );

        // The output bag carries the same report as a diagnostics message.
        assert_eq!(statuses(&out, "ekf/log").len(), 1, "chunk {k}");
    }
}

/// One scan whose CDR is cut short (it cannot be decoded) is skipped with a warning that
/// names the topic; the replay goes on and uses every other scan.
#[test]
fn an_undecodable_message_is_skipped_and_counted() {
    let dir = tempfile::tempdir().expect("tempdir");
    let s = Scenario {
        loops: 1,
        max_steps: Some(60),
        ..Scenario::default()
    };
    let (full, _) = write_scenario(dir.path(), "full.mcap", &s);
    let full_summary = replay_json(&full, &[]);
    let bytes = std::fs::read(&full).expect("read bag");
    let bad = dir.path().join("bad_scan.mcap");
    let mut writer = mcap::Writer::new(std::io::BufWriter::new(
        std::fs::File::create(&bad).expect("create"),
    ))
    .expect("writer");
    let mut scans = 0;
    let mut cut_at = 0;
    for message in mcap::MessageStream::new(&bytes).expect("stream") {
        let mut message = message.expect("message");
        if message.channel.topic == "/scan" {
            scans += 1;
            if scans == 5 {
                message.data = std::borrow::Cow::Owned(message.data[..10].to_vec());
                cut_at = message.log_time;
            }
        }
        writer.write(&message).expect("write");
    }
    writer.finish().expect("finish");

    let out = dir.path().join("bad_scan.out.mcap");
    let summary = replay_json(&bad, &["--out", p(&out)]);
    assert_eq!(summary["undecodable"], 1, "{summary:#}");
    assert_eq!(summary["checks"]["undecodable"], 1, "{summary:#}");
    let warning = &summary["warnings"][0];
    assert_eq!(warning["topic"], "/scan");
    assert_eq!(warning["check"], "undecodable");
    // The output bag says so on /ekf/diagnostics: an `ekf/input` status naming the check.
    let statuses = statuses(&out, "ekf/input");
    assert_eq!(statuses.len(), 1);
    let value = |k: &str| {
        statuses[0]
            .values
            .iter()
            .find(|v| v.key == k)
            .map(|v| v.value.clone())
    };
    assert_eq!(value("check").as_deref(), Some("undecodable"));
    assert_eq!(value("topic").as_deref(), Some("/scan"));
    assert_eq!(value("count").as_deref(), Some("1"));
    assert_eq!(warning["log_time_ns"], cut_at);
    assert!(
        warning["reason"]
            .as_str()
            .expect("reason")
            .starts_with("skipped: "),
        "{warning}"
    );
    let used = |s: &Value| s["lines"]["scans_used"].as_u64().expect("scans_used");
    assert_eq!(used(&summary) + 1, used(&full_summary));
}

/// The case: one flipped bit in the first chunk of the bundled simulated bag,
/// replayed from the first reference pose. It used to stop with "needs a reference pose
/// on /ground_truth, but none was found"; now the chunk's CRC failure is reported with
/// the times it lost, and the rest of the log replays from the first reference after it.
#[test]
fn a_flipped_bit_in_the_first_chunk_is_reported_as_such_and_the_rest_replays() {
    let dir = tempfile::tempdir().expect("tempdir");
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/sim-paper.mcap");
    let mut bytes = std::fs::read(&src).expect("read bag");
    bytes[20212] ^= 0x01;
    let log = dir.path().join("flipped.mcap");
    std::fs::write(&log, &bytes).expect("write");
    let summary = replay_json(&log, &["--init-from-truth"]);
    let d = &summary["damaged"][0];
    assert!(
        d["reason"]
            .as_str()
            .expect("reason")
            .starts_with("Chunk CRC failed"),
        "{d}"
    );
    assert_eq!(d["lost"]["from_ns"], 0, "{d}");
    let rmse = summary["accuracy"]["position_rmse_m"]
        .as_f64()
        .expect("accuracy");
    assert!(rmse < 0.05, "{rmse}");
}

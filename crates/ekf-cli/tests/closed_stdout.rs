//! A reader that closes standard output (`ekf config | head -n 1`, `ekf live | head`)
//! ends the command quietly and with success, and never cuts a recording short.

mod live_support;

use ekf_cli::devices::sick::RangeUnit;
use ekf_cli::mcap_io::BagReader;
use live_support::{ekf, live_on, start_emulators, still};
use std::process::Stdio;
use std::time::{Duration, Instant};

/// The write end of a pipe whose reader is already gone: every write to it fails with
/// EPIPE, so the test does not depend on which process runs first.
fn closed_pipe() -> std::io::PipeWriter {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    writer
}

#[test]
fn a_closed_stdout_ends_a_command_quietly() {
    let out = ekf()
        .arg("config")
        .stdout(closed_pipe())
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{:?}: {stderr}", out.status);
    assert_eq!(stderr, "");
}

#[test]
fn a_closed_stdout_stops_live_mode_with_its_recording_finished() {
    let dir = tempfile::tempdir().unwrap();
    let emulators = start_emulators(dir.path(), RangeUnit::Millimetres);
    let recording = dir.path().join("run.mcap");
    let mut live = live_on(&emulators, &recording)
        .stdout(closed_pipe())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // A robot standing still; the first pose printed finds nobody reading and must end
    // the run by itself, as Ctrl-C would.
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut k = 0u32;
    let status = loop {
        if let Some(status) = live.try_wait().unwrap() {
            break status;
        }
        assert!(Instant::now() < deadline, "ekf live did not stop");
        emulators.sample(still(k, false));
        k += 1;
        std::thread::sleep(Duration::from_millis(100));
    };
    emulators.stop();
    let stderr = std::io::read_to_string(live.stderr.take().unwrap()).unwrap();
    assert!(status.success(), "{status:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    // A finished file: every message reads back without damage.
    let messages = BagReader::open(&recording).unwrap().messages().unwrap();
    let poses = messages
        .map(Result::unwrap)
        .filter(|m| m.topic() == "/ekf/pose")
        .count();
    assert!(poses > 0, "{poses} poses recorded");
}

//! What the `ekf live` tests share: running the binary, and checking that `ekf replay`
//! of a live recording gives its poses bit for bit.

#![allow(dead_code)] // each test crate uses its own part

#[path = "../ekf_bin/mod.rs"]
mod ekf_bin;

pub use ekf_bin::ekf;
use ekf_bin::run_ok;
use ekf_cli::emulate::{Device, Emulators};
use ekf_cli::mcap_io::BagReader;
use std::path::Path;
use std::process::Command;

/// `ekf live --json` on the emulators' laser and base, recording to `recording`.
pub fn live_on(emulators: &Emulators, recording: &Path) -> Command {
    let mut live = ekf();
    live.args(["live", "--json", "--laser"])
        .arg(emulators.path(Device::Laser))
        .arg("--base")
        .arg(emulators.path(Device::Base))
        .arg("--record")
        .arg(recording);
    live
}

/// `(log time, CDR bytes)` of every message on `topic` of a bag.
pub fn messages(path: &Path, topic: &str) -> Vec<(u64, Vec<u8>)> {
    BagReader::open(path)
        .unwrap()
        .messages()
        .unwrap()
        .map(Result::unwrap)
        .filter(|m| m.topic() == topic)
        .map(|m| (m.log_time, m.data))
        .collect()
}

/// Replays `recording` (with `args`, e.g. `--config`) into `replayed` and asserts that
/// the replay writes exactly the recording's `/ekf/pose` messages, of which there must
/// be more than `min_poses`.
pub fn assert_replay_gives_the_same_poses(
    recording: &Path,
    replayed: &Path,
    args: &[&std::ffi::OsStr],
    min_poses: usize,
) {
    run_ok(
        ekf()
            .arg("replay")
            .arg(recording)
            .args(args)
            .arg("--out")
            .arg(replayed),
    );
    let live_poses = messages(recording, "/ekf/pose");
    assert!(live_poses.len() > min_poses, "{}", live_poses.len());
    assert_eq!(live_poses, messages(replayed, "/ekf/pose"));
}

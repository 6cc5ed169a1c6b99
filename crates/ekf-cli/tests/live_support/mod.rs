//! What the `ekf live` tests share: running the binary, and checking that `ekf replay`
//! of a live recording gives its poses bit for bit.

#![allow(dead_code)] // each test crate uses its own part

#[path = "../ekf_bin/mod.rs"]
mod ekf_bin;

pub use ekf_bin::ekf;
use ekf_bin::run_ok;
use ekf_cli::devices::sick::device::Sweep;
use ekf_cli::devices::sick::RangeUnit;
use ekf_cli::emulate::{Device, EmulatorOptions, Emulators, RobotSample};
use ekf_cli::mcap_io::BagReader;
use std::f64::consts::FRAC_PI_2;
use std::path::Path;
use std::process::Command;

/// Device emulators in `dir/dev` whose laser sends `unit`.
pub fn start_emulators(dir: &Path, unit: RangeUnit) -> Emulators {
    Emulators::start(&EmulatorOptions {
        dir: dir.join("dev"),
        unit,
        unit_id: 1,
    })
    .unwrap()
}

/// A robot standing still whose sweep `k` measures `1 + k/1000` m everywhere (so a
/// recorded scan says which sweep it is).
pub fn still(k: u32, with_scan: bool) -> RobotSample {
    RobotSample {
        t_ns: u64::from(k) * 100_000_000,
        left_ticks: 1000,
        right_ticks: 2000,
        bearing_deg: 45.0,
        motion: None,
        sweep: with_scan.then(|| Sweep {
            angle_min: -FRAC_PI_2,
            angle_increment: 0.5f64.to_radians(),
            ranges: vec![1.0 + f64::from(k) / 1000.0; 361],
        }),
        gps: None,
    }
}

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

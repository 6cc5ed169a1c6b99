//! Whole MCAP files: opened as `ekf replay` opens a bag (summary, or the recovery pass
//! when it is missing or damaged), every message streamed and decoded. Errors are fine;
//! panics, hangs and runaway allocations are not.
#![no_main]

use ekf_ros::mcap_io::BagReader;
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

/// One scratch file per fuzzing process (the reader takes a path).
fn scratch() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| std::env::temp_dir().join(format!("ekf-fuzz-{}.mcap", std::process::id())))
}

fuzz_target!(|data: &[u8]| {
    // SQLite files go to SQLite, which is not ours to fuzz.
    if data.starts_with(b"SQLite format 3\0") {
        return;
    }
    let path = scratch();
    std::fs::write(path, data).expect("scratch file");
    let Ok(bag) = BagReader::open(path) else {
        return;
    };
    let _ = bag.describe_topics();
    let Ok(messages) = bag.messages() else {
        return;
    };
    for message in messages.flatten() {
        let _ = message.decode();
    }
});

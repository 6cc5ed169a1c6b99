//! Bags for the MCAP tests: the sample of every type, and a bag large enough for several
//! chunks.

#![allow(dead_code)] // each test file uses a different part

#[path = "../../examples/write_sample_bag/sample.rs"]
pub mod sample;

use ekf_cli::mcap_io::{BagReader, BagWriter};
use ekf_cli::ros2::builtin_interfaces::Time;
use ekf_cli::ros2::sensor_msgs::LaserScan;
use ekf_cli::ros2::std_msgs::Header;
use std::path::Path;

/// Writes the sample bag (one message of every type) to `path`.
pub fn write_sample_bag(path: &Path) {
    let mut writer = BagWriter::create(path).unwrap();
    for (i, (topic, message)) in sample::messages().iter().enumerate() {
        writer
            .write_any(topic, sample::log_time(i), message)
            .unwrap();
    }
    writer.finish().unwrap();
}

/// A scan stamped `t_ns` with `beams` ranges that depend on `t_ns`.
pub fn scan(t_ns: u64, beams: usize) -> LaserScan {
    LaserScan {
        header: Header {
            stamp: Time::from_nanos(t_ns).unwrap(),
            frame_id: "laser".into(),
        },
        angle_increment: 0.01,
        range_max: 30.0,
        ranges: (0..beams)
            .map(|k| (t_ns % 1000) as f32 + k as f32 * 0.5)
            .collect(),
        ..LaserScan::default()
    }
}

/// Writes `count` 80 kB scans on `/scan`, 0.1 s apart and in stamp order (so file order is
/// log-time order), filling several 1 MiB chunks. Returns `(log_time, payload)` per message.
pub fn write_multi_chunk_bag(path: &Path, count: u64) -> Vec<(u64, Vec<u8>)> {
    let mut writer = BagWriter::create(path).unwrap();
    for i in 0..count {
        writer
            .write("/scan", &scan(1_000_000_000 + i * 100_000_000, 20_000))
            .unwrap();
    }
    writer.finish().unwrap();
    read_all_ok(path).0
}

/// Reads every message of `path`: the `(log_time, payload)` of those delivered, and the
/// last error (the one that ended the stream, or the last damage read past), if any.
pub fn read_all_ok(path: &Path) -> (Vec<(u64, Vec<u8>)>, Option<ekf_cli::mcap_io::ReadError>) {
    let (out, mut errors) = read_all(path);
    (out, errors.pop())
}

/// Reads every message of `path`: the `(log_time, payload)` of those delivered, and every
/// error in the order met (damage read past, then the one that ended the stream).
pub fn read_all(path: &Path) -> (Vec<(u64, Vec<u8>)>, Vec<ekf_cli::mcap_io::ReadError>) {
    let bag = BagReader::open(path).unwrap();
    let mut out = Vec::new();
    let mut errors = Vec::new();
    for message in bag.messages().unwrap() {
        match message {
            Ok(m) => out.push((m.log_time, m.data)),
            Err(e) => errors.push(e),
        }
    }
    (out, errors)
}

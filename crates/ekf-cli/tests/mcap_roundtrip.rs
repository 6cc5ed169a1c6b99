//! Write → read round trips through `BagWriter` and `BagReader`, and our files read back
//! with the `mcap` crate's own reader.

mod mcap_common;

use ekf_cli::mcap_io::{BagReader, BagWriter, MessageError, MessageOrder, WriteError};
use ekf_cli::ros2::builtin_interfaces::Time;
use ekf_cli::ros2::nav_msgs::Odometry;
use ekf_cli::ros2::sensor_msgs::LaserScan;
use ekf_cli::ros2::tf2_msgs::TFMessage;
use ekf_cli::ros2::{AnyMessage, RosMessage, SUPPORTED};
use mcap_common::{sample, scan, write_sample_bag};

#[test]
fn every_message_type_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sample.mcap");
    write_sample_bag(&path);
    let expected = sample::messages();
    assert_eq!(
        expected.len(),
        SUPPORTED.len(),
        "the sample covers every type"
    );

    let bag = BagReader::open(&path).unwrap();
    assert_eq!(bag.order(), MessageOrder::LogTime);
    assert_eq!(bag.topics().len(), expected.len());
    for (topic, message) in &expected {
        let info = bag.topics().iter().find(|t| t.topic == *topic).unwrap();
        assert_eq!(info.type_name, message.type_name());
        assert_eq!(info.message_count, 1);
    }
    let read: Vec<_> = bag.messages().unwrap().map(Result::unwrap).collect();
    assert_eq!(read.len(), expected.len());
    for (i, (m, (topic, message))) in read.iter().zip(&expected).enumerate() {
        assert_eq!(m.index, i as u64);
        assert_eq!(m.topic(), *topic);
        assert_eq!(m.log_time, sample::log_time(i));
        assert_eq!(m.publish_time, m.log_time);
        assert_eq!(&m.decode().unwrap(), message, "{topic}");
    }
}

#[test]
fn typed_decode_and_wrong_type_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sample.mcap");
    write_sample_bag(&path);
    let bag = BagReader::open(&path).unwrap();
    let odom = bag
        .messages()
        .unwrap()
        .map(Result::unwrap)
        .find(|m| m.topic() == "/odom")
        .unwrap();
    let decoded: Odometry = odom.decode_as().unwrap();
    assert_eq!(decoded.child_frame_id, "base_link");

    let err = odom.decode_as::<LaserScan>().unwrap_err();
    assert!(matches!(err, MessageError::WrongType { .. }));
    let text = err.to_string();
    for needle in [
        "sample.mcap",
        "/odom",
        "sensor_msgs/msg/LaserScan",
        "nav_msgs/msg/Odometry",
    ] {
        assert!(text.contains(needle), "`{needle}` missing from: {text}");
    }
}

#[test]
fn corrupt_payload_error_names_topic_and_message() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.mcap");
    let mut writer = BagWriter::create(&path).unwrap();
    writer.write("/scan", &scan(5, 3)).unwrap();
    writer.finish().unwrap();
    let bag = BagReader::open(&path).unwrap();
    let mut message = bag.messages().unwrap().next().unwrap().unwrap();
    message.data.truncate(20); // cut inside the scan's float fields
    let err = message.decode().unwrap_err();
    let text = err.to_string();
    for needle in [
        "bad.mcap",
        "/scan",
        "message 0",
        "sensor_msgs/msg/LaserScan",
    ] {
        assert!(text.contains(needle), "`{needle}` missing from: {text}");
    }
}

#[test]
fn messages_come_in_log_time_order_across_chunks_and_topics() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("order.mcap");
    let mut writer = BagWriter::create(&path).unwrap();
    // Two topics written in opposite time directions, 80 kB each: many overlapping chunks.
    let times: Vec<u64> = (0..30).map(|i| 1_000_000_000 + i * 10_000_000).collect();
    for (a, b) in times.iter().zip(times.iter().rev()) {
        writer.write("/scan", &scan(*a, 20_000)).unwrap();
        writer.write("/scan_rear", &scan(*b + 1, 20_000)).unwrap();
    }
    writer.finish().unwrap();

    let bag = BagReader::open(&path).unwrap();
    assert_eq!(bag.order(), MessageOrder::LogTime);
    let log_times: Vec<u64> = bag
        .messages()
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            let scan: LaserScan = m.decode_as().unwrap();
            assert_eq!(scan.header.stamp.to_nanos(), Some(m.log_time));
            m.log_time
        })
        .collect();
    assert_eq!(log_times.len(), 60);
    assert!(log_times.windows(2).all(|w| w[0] <= w[1]), "{log_times:?}");
    let chunks = mcap::Summary::read(&std::fs::read(&path).unwrap())
        .unwrap()
        .unwrap()
        .chunk_indexes
        .len();
    assert!(chunks > 2, "test needs several chunks, got {chunks}");
}

#[test]
fn log_time_is_the_header_stamp_and_write_at_sets_it_for_headerless_messages() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("stamps.mcap");
    let mut writer = BagWriter::create(&path).unwrap();
    writer.write("/scan", &scan(7_000_000_123, 3)).unwrap();
    writer
        .write_at("/tf", 8_000_000_000, &TFMessage::default())
        .unwrap();
    writer.finish().unwrap();
    let times: Vec<(String, u64, u64)> = BagReader::open(&path)
        .unwrap()
        .messages()
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            (m.topic().to_owned(), m.log_time, m.publish_time)
        })
        .collect();
    assert_eq!(
        times,
        [
            ("/scan".to_owned(), 7_000_000_123, 7_000_000_123),
            ("/tf".to_owned(), 8_000_000_000, 8_000_000_000)
        ]
    );
}

#[test]
fn negative_stamp_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut writer = BagWriter::create(dir.path().join("neg.mcap")).unwrap();
    let mut s = scan(0, 1);
    s.header.stamp = Time {
        sec: -5,
        nanosec: 0,
    };
    let err = writer.write("/scan", &s).unwrap_err();
    assert!(
        matches!(err, WriteError::NegativeStamp { sec: -5, .. }),
        "{err}"
    );
}

#[test]
fn a_writer_dropped_without_finish_leaves_a_complete_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("dropped.mcap");
    let write = || -> Result<(), WriteError> {
        let mut writer = BagWriter::create(&path)?;
        for i in 0..5 {
            writer.write("/scan", &scan(1_000 + i, 10))?;
        }
        Err(WriteError::NegativeStamp {
            path: path.clone(),
            topic: "caller gave up".into(),
            sec: -1,
        })
    };
    assert!(write().is_err());
    let bag = BagReader::open(&path).unwrap();
    assert_eq!(bag.order(), MessageOrder::LogTime, "summary was written");
    assert_eq!(bag.topics()[0].message_count, 5);
    assert_eq!(bag.messages().unwrap().map(Result::unwrap).count(), 5);
}

#[test]
fn the_mcap_crate_reads_our_files() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sample.mcap");
    write_sample_bag(&path);
    let bytes = std::fs::read(&path).unwrap();

    let header = mcap::read::LinearReader::new(&bytes)
        .unwrap()
        .next()
        .unwrap()
        .unwrap();
    match header {
        mcap::records::Record::Header(h) => assert_eq!(h.profile, "ros2"),
        other => panic!("first record is {other:?}"),
    }
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let expected = sample::messages();
    assert_eq!(summary.stats.unwrap().message_count, expected.len() as u64);

    let mut seen = 0;
    for (message, (topic, original)) in mcap::MessageStream::new(&bytes).unwrap().zip(&expected) {
        let message = message.unwrap();
        let schema = message.channel.schema.as_ref().unwrap();
        assert_eq!(message.channel.topic, *topic);
        assert_eq!(message.channel.message_encoding, "cdr");
        assert_eq!(schema.encoding, "ros2msg");
        assert_eq!(schema.name, original.type_name());
        assert_eq!(&schema.data[..], original.def().schema_text().as_bytes());
        let decoded = AnyMessage::decode(&schema.name, &message.data).unwrap();
        assert_eq!(&decoded, original);
        seen += 1;
    }
    assert_eq!(seen, expected.len());
}

#[test]
fn laser_scan_converts_to_the_extractor_type() {
    let s = scan(0, 3);
    let view = s.as_scan();
    assert_eq!(view.ranges, &s.ranges[..]);
    assert_eq!(view.range_max, 30.0);
    assert_eq!(LaserScan::type_name(), "sensor_msgs/msg/LaserScan");
}

/// `close_chunks_every(1 s)`: 3.5 s of messages at 10 Hz make four chunks, each spanning
/// less than 1 s of log time, and a copy cut anywhere after the first chunk still gives
/// every message of the chunks before the cut.
#[test]
fn chunks_closed_by_log_time_bound_what_a_cut_loses() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("timed.mcap");
    let mut writer = BagWriter::create(&path).unwrap();
    writer.close_chunks_every(1_000_000_000);
    let times: Vec<u64> = (0..35).map(|i| 1_000_000_000 + i * 100_000_000).collect();
    for t in &times {
        writer.write("/scan", &scan(*t, 100)).unwrap();
    }
    writer.finish().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let chunks = mcap::Summary::read(&bytes).unwrap().unwrap().chunk_indexes;
    assert_eq!(chunks.len(), 4);
    for c in &chunks {
        assert!(c.message_end_time - c.message_start_time < 1_000_000_000);
    }
    for c in &chunks[1..] {
        // Cut inside chunk c: everything logged before it survives.
        let cut = (c.chunk_start_offset + c.chunk_length / 2) as usize;
        let cut_path = dir.path().join(format!("cut_{cut}.mcap"));
        std::fs::write(&cut_path, &bytes[..cut]).unwrap();
        let (delivered, _) = mcap_common::read_all(&cut_path);
        let expected: Vec<u64> = times
            .iter()
            .copied()
            .filter(|t| *t < c.message_start_time)
            .collect();
        let got: Vec<u64> = delivered.iter().map(|(t, _)| *t).collect();
        assert_eq!(got, expected);
    }
}

//! Truncated and corrupted bags: every message before the damage is delivered, then one
//! error that names the file and the byte where reading broke.

mod mcap_common;

use ekf_cli::mcap_io::{BagReader, BagWriter, LostRange, MessageOrder, ReadError};
use ekf_cli::ros2::sensor_msgs::LaserScan;
use ekf_cli::ros2::RosMessage;
use mcap::records::ChunkIndex;
use mcap_common::{read_all, read_all_ok, scan, write_multi_chunk_bag};
use std::path::Path;

/// Number of 80 kB scans: about six 1 MiB chunks.
const SCANS: u64 = 70;

fn corrupt_offset(err: &ReadError) -> u64 {
    match err {
        ReadError::Corrupt { offset, .. } => *offset,
        other => panic!("expected a Corrupt error, got {other}"),
    }
}

/// The chunk offset of a skipped damaged chunk, and the log times it reports lost.
fn skipped(err: &ReadError) -> (u64, LostRange) {
    match err {
        ReadError::SkippedChunk { offset, lost, .. } => (*offset, *lost),
        other => panic!("expected a SkippedChunk error, got {other}"),
    }
}

/// The messages of `original` outside `chunk`'s time range.
fn without(original: &[(u64, Vec<u8>)], chunk: &ChunkIndex) -> Vec<(u64, Vec<u8>)> {
    let lost = chunk.message_start_time..=chunk.message_end_time;
    original
        .iter()
        .filter(|(t, _)| !lost.contains(t))
        .cloned()
        .collect()
}

#[test]
fn truncated_files_deliver_everything_before_the_cut_then_say_where() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full.mcap");
    let original = write_multi_chunk_bag(&full, SCANS);
    assert_eq!(original.len() as u64, SCANS);
    let bytes = std::fs::read(&full).unwrap();
    let len = bytes.len();
    let first = &chunk_indexes(&full)[0];
    let first_chunk_end = first.chunk_start_offset + first.chunk_length;

    let mut previous = 0;
    for cut in [
        0,
        5,
        9,
        200,
        len / 4,
        len / 2,
        3 * len / 4,
        len - 200,
        len - 30,
        len - 1,
    ] {
        let path = dir.path().join(format!("cut_{cut}.mcap"));
        std::fs::write(&path, &bytes[..cut]).unwrap();
        // Cut before the first chunk ended: no channel, nothing readable, so the file
        // does not open, and the error says where it broke. Cut later, it opens.
        let opened = BagReader::open(&path);
        assert_eq!(
            opened.is_err(),
            (cut as u64) < first_chunk_end,
            "cut at {cut} (first chunk ends at {first_chunk_end})"
        );
        let bag = match opened {
            Ok(bag) => bag,
            Err(err) => {
                assert!(corrupt_offset(&err) <= cut as u64, "cut at {cut}: {err}");
                let text = err.to_string();
                assert!(text.contains(&format!("cut_{cut}.mcap")), "{text}");
                assert!(text.contains("after 0 messages"), "{text}");
                continue;
            }
        };
        assert_eq!(
            bag.order(),
            MessageOrder::LogTime,
            "cut at {cut}: index rebuilt"
        );

        let (delivered, err) = read_all_ok(&path);
        let err = err.unwrap_or_else(|| panic!("cut at {cut}: no error reported"));
        assert_eq!(delivered[..], original[..delivered.len()], "cut at {cut}");
        assert!(
            delivered.len() >= previous,
            "cut at {cut}: fewer than a shorter cut"
        );
        previous = delivered.len();
        let counted: u64 = bag.topics().iter().map(|t| t.message_count).sum();
        assert_eq!(
            counted,
            delivered.len() as u64,
            "cut at {cut}: topic counts"
        );

        assert!(corrupt_offset(&err) <= cut as u64, "cut at {cut}: {err}");
        let text = err.to_string();
        assert!(text.contains(&format!("cut_{cut}.mcap")), "{text}");
        assert!(text.contains("byte"), "{text}");
        assert!(
            text.contains(&format!("after {} messages", delivered.len())),
            "{text}"
        );
    }
    assert!(
        previous as u64 == SCANS,
        "a cut in the summary loses no message"
    );
}

/// Chunk indexes of the file at `path`.
fn chunk_indexes(path: &Path) -> Vec<mcap::records::ChunkIndex> {
    let bytes = std::fs::read(path).unwrap();
    mcap::Summary::read(&bytes).unwrap().unwrap().chunk_indexes
}

#[test]
fn a_flipped_byte_in_a_chunk_loses_that_chunk_only() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full.mcap");
    let original = write_multi_chunk_bag(&full, SCANS);
    let chunks = chunk_indexes(&full);
    assert!(
        chunks.len() >= 4,
        "need several chunks, got {}",
        chunks.len()
    );
    let bytes = std::fs::read(&full).unwrap();

    for k in [0, 2, chunks.len() - 1] {
        let chunk = &chunks[k];
        let data = chunk.compressed_data_offset().unwrap();
        for at in [
            data,
            data + chunk.compressed_size / 2,
            data + chunk.compressed_size - 1,
        ] {
            let mut damaged = bytes.clone();
            damaged[at as usize] ^= 0x5A;
            let path = dir.path().join(format!("flip_{at}.mcap"));
            std::fs::write(&path, &damaged).unwrap();

            let (delivered, errors) = read_all(&path);
            assert_eq!(errors.len(), 1, "flip at {at} in chunk {k}: {errors:?}");
            assert_eq!(
                delivered,
                without(&original, chunk),
                "flip at {at} in chunk {k}"
            );
            let (offset, lost) = skipped(&errors[0]);
            assert_eq!(offset, chunk.chunk_start_offset, "{}", errors[0]);
            assert_eq!(
                (lost.from_ns, lost.to_ns),
                (Some(chunk.message_start_time), Some(chunk.message_end_time))
            );
            let text = errors[0].to_string();
            assert!(
                text.contains(&format!("damaged chunk at byte {offset} skipped")),
                "{text}"
            );
        }
    }
}

/// The `mcap_bag` fuzz target's first find (fuzz/regressions/mcap_bag/): a chunk whose
/// compression-name length says 2.9 GB made the `mcap` crate reserve that much before
/// reading. The length is now checked against the record first, with the summary and
/// without it (the recovery pass), and the chunk is skipped as damage.
#[test]
fn a_chunk_header_length_that_overruns_its_record_is_damage_not_an_allocation() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full.mcap");
    let original = write_multi_chunk_bag(&full, SCANS);
    let chunks = chunk_indexes(&full);
    let chunk = &chunks[1];
    let mut bytes = std::fs::read(&full).unwrap();
    // Opcode and length (9 bytes), then start, end, uncompressed size and CRC (28 bytes).
    let name_len = (chunk.chunk_start_offset + 9 + 28) as usize;
    bytes[name_len..name_len + 4].copy_from_slice(&0xadf0_0000u32.to_le_bytes());
    let path = dir.path().join("indexed.mcap");
    std::fs::write(&path, &bytes).unwrap();
    let (delivered, errors) = read_all(&path);
    assert_eq!(delivered, without(&original, chunk));
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert_eq!(skipped(&errors[0]).0, chunk.chunk_start_offset);
    let text = errors[0].to_string();
    assert!(
        text.contains("record with opcode 06 length exceeds limit"),
        "{text}"
    );
    // Without the summary the recovery pass finds the same damage and reads on.
    let path = dir.path().join("cut.mcap");
    std::fs::write(&path, &bytes[..bytes.len() - 100]).unwrap();
    let (delivered, errors) = read_all(&path);
    assert_eq!(delivered, without(&original, chunk));
    assert_eq!(errors.len(), 2, "{errors:?}");
    assert_eq!(skipped(&errors[0]).0, chunk.chunk_start_offset);
    assert!(corrupt_offset(&errors[1]) > chunks.last().unwrap().chunk_start_offset);
}

#[test]
fn a_flipped_byte_in_a_truncated_file_loses_that_chunk_and_the_cut_end() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full.mcap");
    let original = write_multi_chunk_bag(&full, SCANS);
    let chunks = chunk_indexes(&full);
    let mut bytes = std::fs::read(&full).unwrap();
    let chunk = &chunks[1];
    let at = chunk.compressed_data_offset().unwrap() + chunk.compressed_size / 3;
    bytes[at as usize] ^= 0xFF;
    bytes.truncate(bytes.len() - 100);
    let path = dir.path().join("flip_and_cut.mcap");
    std::fs::write(&path, &bytes).unwrap();

    let (delivered, errors) = read_all(&path);
    // The damaged chunk, then the cut (inside the summary: no message lost there).
    assert_eq!(errors.len(), 2, "{errors:?}");
    assert_eq!(delivered, without(&original, chunk));
    let (offset, lost) = skipped(&errors[0]);
    let chunk_end = chunk.chunk_start_offset + chunk.chunk_length;
    assert!(
        (chunk.chunk_start_offset..=chunk_end).contains(&offset),
        "{offset} outside chunk {}..{chunk_end}: {}",
        chunk.chunk_start_offset,
        errors[0]
    );
    // Without an index, the lost times are bounded by the intact chunks around it.
    assert_eq!(lost.from_ns, Some(chunks[0].message_end_time));
    assert_eq!(lost.to_ns, Some(chunks[2].message_start_time));
    assert!(corrupt_offset(&errors[1]) > chunks.last().unwrap().chunk_start_offset);
}

#[test]
fn a_flipped_byte_in_the_summary_is_not_trusted_and_reported_after_the_messages() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full.mcap");
    let original = write_multi_chunk_bag(&full, SCANS);
    let mut bytes = std::fs::read(&full).unwrap();
    let footer = mcap::read::footer(&bytes).unwrap();
    let at = (footer.summary_start as usize + bytes.len()) / 2;
    bytes[at] ^= 0x01;
    let path = dir.path().join("bad_summary.mcap");
    std::fs::write(&path, &bytes).unwrap();

    let bag = BagReader::open(&path).unwrap();
    assert_eq!(
        bag.order(),
        MessageOrder::LogTime,
        "damaged summary is rebuilt"
    );
    assert_eq!(bag.topics()[0].message_count, SCANS);
    let (delivered, err) = read_all_ok(&path);
    assert_eq!(delivered, original);
    let err = err.expect("summary damage reported after the messages");
    assert!(corrupt_offset(&err) >= footer.summary_start, "{err}");
}

#[test]
fn a_truncated_bag_written_out_of_order_is_still_read_in_log_time_order() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full.mcap");
    let mut writer = BagWriter::create(&full).unwrap();
    let times: Vec<u64> = (0..40).map(|i| 1_000_000_000 + i * 10_000_000).collect();
    for (a, b) in times.iter().zip(times.iter().rev()) {
        writer.write("/scan", &scan(*a, 20_000)).unwrap();
        writer.write("/scan_rear", &scan(*b + 1, 20_000)).unwrap();
    }
    writer.finish().unwrap();
    let bytes = std::fs::read(&full).unwrap();
    let path = dir.path().join("cut.mcap");
    std::fs::write(&path, &bytes[..bytes.len() * 2 / 3]).unwrap();

    let bag = BagReader::open(&path).unwrap();
    assert_eq!(bag.order(), MessageOrder::LogTime);
    let (delivered, err) = read_all_ok(&path);
    assert!(err.is_some());
    assert!(delivered.len() > 10, "only {} delivered", delivered.len());
    let log_times: Vec<u64> = delivered.iter().map(|(t, _)| *t).collect();
    assert!(log_times.windows(2).all(|w| w[0] <= w[1]), "{log_times:?}");
}

#[test]
fn unchunked_files_are_read_in_file_order() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("unchunked.mcap");
    let mut writer = mcap::WriteOptions::new()
        .profile("ros2")
        .use_chunks(false)
        .create(std::io::BufWriter::new(
            std::fs::File::create(&path).unwrap(),
        ))
        .unwrap();
    let schema = writer
        .add_schema(
            LaserScan::type_name(),
            "ros2msg",
            LaserScan::schema_text().as_bytes(),
        )
        .unwrap();
    let channel = writer
        .add_channel(schema, "/scan", "cdr", &Default::default())
        .unwrap();
    for (sequence, t) in [3_000u64, 1_000, 2_000].into_iter().enumerate() {
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: sequence as u32,
            log_time: t,
            publish_time: t,
        };
        let data = scan(t, 2).encode().unwrap();
        writer.write_to_known_channel(&header, &data).unwrap();
    }
    writer.finish().unwrap();
    drop(writer);

    let bag = BagReader::open(&path).unwrap();
    assert_eq!(bag.order(), MessageOrder::File);
    assert_eq!(bag.topics()[0].message_count, 3);
    let times: Vec<u64> = bag
        .messages()
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            let s: LaserScan = m.decode_as().unwrap();
            assert_eq!(s.header.stamp.to_nanos(), Some(m.log_time));
            m.log_time
        })
        .collect();
    assert_eq!(times, [3_000, 1_000, 2_000]);
}

#[test]
fn a_missing_file_names_the_path() {
    let err = BagReader::open("/nonexistent/run.mcap").unwrap_err();
    assert!(matches!(err, ReadError::Open { .. }));
    assert!(err.to_string().contains("/nonexistent/run.mcap"), "{err}");
}

#[test]
fn a_file_that_is_not_mcap_does_not_open_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("notes.mcap");
    std::fs::write(&path, "# not a bag, but a text file of some length\n").unwrap();
    let err = BagReader::open(&path).unwrap_err();
    assert!(matches!(err, ReadError::NotABag { .. }), "{err}");
    let text = err.to_string();
    assert!(
        text.contains("notes.mcap: not a ROS 2 bag (MCAP or sqlite3): a text file"),
        "{text}"
    );
    // Binary that is not MCAP is corrupt at byte 0: its magic is wrong.
    std::fs::write(&path, [0u8, 159, 146, 150, 7, 7, 7, 7, 7, 7, 7, 7]).unwrap();
    let err = BagReader::open(&path).unwrap_err();
    assert_eq!(corrupt_offset(&err), 0, "{err}");
    assert!(err.to_string().contains("magic"), "{err}");
}

#[test]
fn a_wrong_end_magic_is_reported_where_it_starts_after_every_message() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("end.mcap");
    let original = write_multi_chunk_bag(&path, 5);
    let mut bytes = std::fs::read(&path).unwrap();
    let len = bytes.len();
    bytes[len - 1] ^= 0xff;
    std::fs::write(&path, &bytes).unwrap();
    let (delivered, err) = read_all_ok(&path);
    assert_eq!(delivered, original);
    let err = err.expect("the damage is reported after the messages");
    assert_eq!(corrupt_offset(&err), (len - 8) as u64, "{err}");
}

/// Every input that once crashed the `mcap_bag` fuzz target (fuzz/regressions/mcap_bag/)
/// opens or fails with an error, and streams to its end, without a panic (this test
/// binary has overflow checks on, as the fuzz build has).
#[test]
fn the_fuzz_regressions_read_without_a_panic() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/regressions/mcap_bag");
    let mut files = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        files += 1;
        if let Ok(bag) = BagReader::open(&path) {
            let read = bag.messages().unwrap().count();
            assert!(read < 10_000, "{}: {read} items", path.display());
        }
    }
    assert!(files >= 2, "regressions missing from {}", dir.display());
}

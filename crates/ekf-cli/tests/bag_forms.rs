//! Bags in every form `ros2 bag record` writes read as the same messages and replay to
//! the same result: one MCAP file, a sqlite3 `.db3` file (Humble's schema), a bag
//! directory with `metadata.yaml` split into several files, and the bag directory `ekf`
//! itself writes (`--out DIR/`).

use ekf_cli::config::Config;
use ekf_cli::mcap_io::metadata::{BagInfo, WrittenBag};
use ekf_cli::mcap_io::{BagReader, BagWriter, MessageOrder};
use ekf_cli::replay::{replay, ReplayOptions};
use std::path::{Path, PathBuf};

fn testdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata")
        .join(name)
}

/// (topic, type, log time, CDR bytes) of every message, in delivery order.
type Messages = Vec<(String, String, u64, Vec<u8>)>;

fn read_all(path: &Path) -> Messages {
    let bag = BagReader::open(path).unwrap();
    assert_eq!(bag.order(), MessageOrder::LogTime, "{}", path.display());
    bag.messages()
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            let c = &m.channel;
            (c.topic.clone(), c.type_name.clone(), m.log_time, m.data)
        })
        .collect()
}

/// Writes `messages` as a sqlite3 bag with the schema of rosbag2 on Humble.
fn write_db3(path: &Path, messages: &Messages) {
    let db = rusqlite::Connection::open(path).unwrap();
    db.execute_batch(
        "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
         INSERT INTO schema VALUES (3, 'humble');
         CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL,
                               metadata TEXT NOT NULL);
         CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
                             serialization_format TEXT NOT NULL,
                             offered_qos_profiles TEXT NOT NULL);
         CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,
                               timestamp INTEGER NOT NULL, data BLOB NOT NULL);
         CREATE INDEX timestamp_idx ON messages (timestamp ASC);",
    )
    .unwrap();
    let mut topics: Vec<(&str, &str)> = Vec::new();
    for (topic, type_name, time, data) in messages {
        let id = match topics
            .iter()
            .position(|t| *t == (topic.as_str(), type_name.as_str()))
        {
            Some(i) => i as i64 + 1,
            None => {
                topics.push((topic, type_name));
                db.execute(
                    "INSERT INTO topics VALUES (?1, ?2, ?3, 'cdr', '')",
                    (topics.len() as i64, topic, type_name),
                )
                .unwrap();
                topics.len() as i64
            }
        };
        db.execute(
            "INSERT INTO messages (topic_id, timestamp, data) VALUES (?1, ?2, ?3)",
            (id, *time as i64, data),
        )
        .unwrap();
    }
}

/// Writes `messages` as a bag directory of `parts` MCAP files, split by time as rosbag2
/// splits, with the metadata listing them.
fn write_split(dir: &Path, messages: &Messages, parts: usize) {
    std::fs::create_dir_all(dir).unwrap();
    let per_part = messages.len().div_ceil(parts);
    let mut info = BagInfo::for_written(&WrittenBag::default());
    info.relative_file_paths.clear();
    for (k, chunk) in messages.chunks(per_part).enumerate() {
        let name = format!("split_{k}.mcap");
        let mut w = BagWriter::create(dir.join(&name)).unwrap();
        for (topic, type_name, time, data) in chunk {
            let any = ekf_cli::ros2::AnyMessage::decode(type_name, data).unwrap();
            w.write_any(topic, *time, &any).unwrap();
        }
        w.finish().unwrap();
        info.relative_file_paths.push(name);
    }
    info.write(dir).unwrap();
}

/// Position RMSE of the default replay from the first reference pose.
fn replay_rmse(log: &Path) -> f64 {
    let config = Config::preset("paper-robot").unwrap();
    let options = ReplayOptions {
        init_from_truth: true,
        ..ReplayOptions::default()
    };
    let outcome = replay(log, &config, &options, &mut |_, _| {}).unwrap();
    assert!(outcome.failure.is_none(), "{}", log.display());
    outcome.summary.accuracy.unwrap().position_rmse_m
}

#[test]
fn every_form_of_a_bag_reads_and_replays_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let mcap = testdata("sim-paper.mcap");
    let messages = read_all(&mcap);
    let rmse = replay_rmse(&mcap);

    let db3 = dir.path().join("run_0.db3");
    write_db3(&db3, &messages);
    let split = dir.path().join("split");
    write_split(&split, &messages, 3);
    // A sqlite3 bag directory as Humble writes it, but with no metadata.yaml (the
    // recorder was killed): its one .db3 file is found.
    let db3_dir = dir.path().join("humble");
    std::fs::create_dir(&db3_dir).unwrap();
    std::fs::copy(&db3, db3_dir.join("humble_0.db3")).unwrap();

    for form in [&db3, &split, &db3_dir, &split.join("metadata.yaml")] {
        assert!(
            read_all(form) == messages,
            "{}: other messages",
            form.display()
        );
        assert_eq!(replay_rmse(form), rmse, "{}", form.display());
    }
    let topics = BagReader::open(&split).unwrap().topics().to_vec();
    assert_eq!(topics, BagReader::open(&mcap).unwrap().topics());
    assert_eq!(topics, BagReader::open(&db3).unwrap().topics());
}

#[test]
fn a_bag_directory_written_by_ekf_has_metadata_with_its_counts() {
    let dir = tempfile::tempdir().unwrap();
    let messages = read_all(&testdata("sim-paper.mcap"));
    let out = dir.path().join("out/");
    let mut w = BagWriter::create(&out).unwrap();
    // Readable as a bag directory from the start (a recording killed later stays one).
    assert!(BagInfo::read(&out).unwrap().is_some());
    for (topic, type_name, time, data) in &messages {
        let any = ekf_cli::ros2::AnyMessage::decode(type_name, data).unwrap();
        w.write_any(topic, *time, &any).unwrap();
    }
    w.finish().unwrap();
    assert!(out.join("out_0.mcap").is_file());
    let info = BagInfo::read(&out).unwrap().unwrap();
    assert_eq!(info.version, 8);
    assert_eq!(info.storage_identifier, "mcap");
    assert_eq!(info.relative_file_paths, ["out_0.mcap"]);
    assert_eq!(info.message_count, messages.len() as u64);
    let first = messages.iter().map(|m| m.2).min().unwrap();
    let last = messages.iter().map(|m| m.2).max().unwrap();
    assert_eq!(info.starting_time.nanoseconds_since_epoch, first);
    assert_eq!(info.duration.nanoseconds, last - first);
    let bag = BagReader::open(&out).unwrap();
    for topic in bag.topics() {
        let listed = info
            .topics_with_message_count
            .iter()
            .find(|t| t.topic_metadata.name == topic.topic)
            .unwrap();
        assert_eq!(listed.topic_metadata.type_name, topic.type_name);
        assert_eq!(listed.message_count, topic.message_count);
        assert_eq!(listed.topic_metadata.serialization_format, "cdr");
    }
    assert!(read_all(&out) == messages);
}

#[test]
fn damaged_and_foreign_sqlite_files_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let other = dir.path().join("other.db3");
    rusqlite::Connection::open(&other)
        .unwrap()
        .execute_batch("CREATE TABLE t(x INTEGER);")
        .unwrap();
    let err = BagReader::open(&other).unwrap_err().to_string();
    assert!(
        err.contains("not a ROS 2 bag (MCAP or sqlite3): a SQLite database without rosbag2's"),
        "{err}"
    );
    let bad = dir.path().join("bad.db3");
    let mut messages = read_all(&testdata("sim-paper.mcap"));
    messages.truncate(3);
    write_db3(&bad, &messages);
    rusqlite::Connection::open(&bad)
        .unwrap()
        .execute_batch("UPDATE messages SET timestamp = -5 WHERE id = 2;")
        .unwrap();
    let bag = BagReader::open(&bad).unwrap();
    let read: Vec<_> = bag.messages().unwrap().collect();
    assert_eq!(read.len(), 1, "the error, then nothing more");
    let err = read[0].as_ref().unwrap_err().to_string();
    assert!(
        err.contains("bad.db3: sqlite3 bag: message row 2 has the negative timestamp -5 ns"),
        "{err}"
    );
}

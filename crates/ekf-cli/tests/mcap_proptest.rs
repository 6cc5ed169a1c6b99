//! Property tests of the bag reader: arbitrary files and damaged copies of a valid bag
//! never panic it; it only delivers messages or reports errors.

mod mcap_common;

use ekf_cli::mcap_io::BagReader;
use mcap_common::write_sample_bag;
use proptest::collection::vec;
use proptest::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

const MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// Opens `path` and reads and decodes every message it yields.
fn read_everything(path: &Path) {
    let Ok(bag) = BagReader::open(path) else {
        return;
    };
    let _ = bag.topics();
    let Ok(messages) = bag.messages() else {
        return;
    };
    for message in messages {
        match message {
            Ok(m) => {
                let _ = m.decode();
            }
            Err(_) => break,
        }
    }
}

/// A valid sample bag, written once per test process.
fn sample_bag() -> &'static [u8] {
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    BYTES.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sample.mcap");
        write_sample_bag(&path);
        std::fs::read(path).unwrap()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn random_files_never_panic(body in vec(any::<u8>(), 0..2048), magic in any::<bool>()) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("random.mcap");
        let mut bytes = if magic { MAGIC.to_vec() } else { Vec::new() };
        bytes.extend(body);
        if magic {
            bytes.extend(MAGIC);
        }
        std::fs::write(&path, &bytes).unwrap();
        read_everything(&path);
    }

    #[test]
    fn damaged_bags_never_panic(
        flips in vec((any::<prop::sample::Index>(), 1u8..=255), 0..6),
        cut in any::<prop::sample::Index>(),
        truncate in any::<bool>(),
    ) {
        let mut bytes = sample_bag().to_vec();
        for (at, mask) in flips {
            let i = at.index(bytes.len());
            bytes[i] ^= mask;
        }
        if truncate {
            bytes.truncate(cut.index(bytes.len()));
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("damaged.mcap");
        std::fs::write(&path, &bytes).unwrap();
        read_everything(&path);
    }
}

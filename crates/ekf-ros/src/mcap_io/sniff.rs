//! What a path given as a bag is, before its storage is read: a ROS 2 bag directory
//! (`ros2 bag record` writes one, with `metadata.yaml` and its storage files, split into
//! several when the recording was long), an MCAP file, a sqlite3 `.db3` file (the default
//! storage of ROS 2 Humble and earlier), or something else that deserves its own name in
//! the error (a text file such as a TUM or CSV trajectory; a gzip file such as a CARMEN
//! log).

use super::metadata::{BagInfo, METADATA_FILE};
use super::ReadError;
use std::io::Read;
use std::path::{Path, PathBuf};

/// The first bytes of every MCAP file.
const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// The first bytes of every SQLite 3 database.
const SQLITE_MAGIC: &[u8] = b"SQLite format 3\0";

/// The first bytes of a gzip stream.
const GZIP_MAGIC: &[u8] = b"\x1f\x8b";

/// How a storage file keeps its messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Storage {
    /// MCAP (`ros2 bag record -s mcap`, the default from ROS 2 Iron on).
    Mcap,
    /// rosbag2's sqlite3 storage (`.db3`).
    Sqlite,
}

/// Whether `path` is read as a bag rather than as a text trajectory: a directory, or a
/// file that starts like MCAP or SQLite.
pub fn is_bag(path: &Path) -> bool {
    path.is_dir() || {
        let head = head(path);
        head.starts_with(MCAP_MAGIC) || head.starts_with(SQLITE_MAGIC)
    }
}

/// The storage files of the bag at `path`, in recording order: `path` itself if it is a
/// storage file; for a bag directory (or its `metadata.yaml`), the files its metadata
/// lists, or without metadata its `.mcap` and `.db3` files in split order. Anything else
/// is a [`ReadError::NotABag`] that says what it is and what to do.
pub(crate) fn storage_files(path: &Path) -> Result<Vec<(PathBuf, Storage)>, ReadError> {
    if path.file_name().is_some_and(|n| n == METADATA_FILE) {
        if let Some(dir) = path.parent().filter(|d| d.is_dir()) {
            return directory_files(dir);
        }
    }
    if path.is_dir() {
        return directory_files(path);
    }
    Ok(vec![(path.to_path_buf(), storage_of(path)?)])
}

/// Up to 64 bytes from the start of `path`; fewer (or none) if it is shorter or unreadable.
fn head(path: &Path) -> Vec<u8> {
    let mut head = Vec::with_capacity(64);
    if let Ok(file) = std::fs::File::open(path) {
        // A short or unreadable file is left to the storage reader's own error.
        let _ = file.take(64).read_to_end(&mut head);
    }
    head
}

/// The storage of the file `path`, judged by its first bytes.
fn storage_of(path: &Path) -> Result<Storage, ReadError> {
    let head = head(path);
    let not_a_bag = |what: &str, hint: &str| ReadError::NotABag {
        path: path.to_path_buf(),
        what: what.into(),
        hint: hint.into(),
    };
    if head.starts_with(SQLITE_MAGIC) {
        return Ok(Storage::Sqlite);
    }
    if head.starts_with(GZIP_MAGIC) {
        return Err(not_a_bag(
            "a gzip file",
            "a CARMEN log (.log.gz) is turned into a bag with `ekf import carmen LOG --out \
             LOG.mcap`",
        ));
    }
    let text = !head.is_empty()
        && std::str::from_utf8(&head).is_ok_and(|s| {
            s.chars()
                .all(|c| !c.is_control() || c.is_ascii_whitespace())
        });
    if text && !head.starts_with(MCAP_MAGIC) {
        return Err(not_a_bag(
            "a text file",
            "a trajectory (TUM or CSV) goes to `ekf evaluate EST --truth REF`; a CARMEN or \
             MRPT log is turned into a bag with `ekf import`",
        ));
    }
    // MCAP, or a damaged file that the MCAP reader describes (bad magic, cut short).
    Ok(Storage::Mcap)
}

/// The storage files of the bag directory `dir`.
fn directory_files(dir: &Path) -> Result<Vec<(PathBuf, Storage)>, ReadError> {
    let paths = match BagInfo::read(dir)? {
        Some(info) if !info.relative_file_paths.is_empty() => {
            let paths = info.storage_paths(dir)?;
            if let Some(missing) = paths.iter().find(|p| !p.is_file()) {
                return Err(ReadError::Metadata {
                    path: dir.join(METADATA_FILE),
                    message: format!(
                        "lists the storage file {}, which is missing",
                        missing.display()
                    ),
                });
            }
            paths
        }
        // No metadata (a recording cut short before rosbag2 wrote it), or one that
        // lists no file.
        _ => unlisted_storage_files(dir),
    };
    if paths.is_empty() {
        return Err(ReadError::NotABag {
            path: dir.to_path_buf(),
            what: "a directory without a bag's storage file (.mcap or .db3)".into(),
            hint: "pass a bag directory written by `ros2 bag record`, or an .mcap or .db3 file"
                .into(),
        });
    }
    paths
        .into_iter()
        .map(|p| storage_of(&p).map(|s| (p, s)))
        .collect()
}

/// A directory's `.mcap` and `.db3` files in split order (`bag_2` before `bag_10`), for a
/// bag whose `metadata.yaml` was never written.
fn unlisted_storage_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_file() && p.extension().is_some_and(|e| e == "mcap" || e == "db3"))
        .collect();
    files.sort_by_key(|p| split_order(p));
    files
}

/// Sort key of a split storage file `NAME_K.ext`: (NAME, K, file name).
fn split_order(path: &Path) -> (String, u64, String) {
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned());
    let stem = stem.unwrap_or_default();
    let digits = stem.len() - stem.trim_end_matches(|c: char| c.is_ascii_digit()).len();
    let (name, number) = stem.split_at(stem.len() - digits);
    let name = name.to_owned();
    let file_name = path.file_name().map(|s| s.to_string_lossy().into_owned());
    (
        name,
        number.parse().unwrap_or(0),
        file_name.unwrap_or_default(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(files: &[(PathBuf, Storage)]) -> Vec<(String, Storage)> {
        files
            .iter()
            .map(|(p, s)| (p.file_name().unwrap().to_string_lossy().into_owned(), *s))
            .collect()
    }

    #[test]
    fn a_bag_directory_lists_its_storage_files_in_split_order() {
        let dir = tempfile::tempdir().unwrap();
        let bag = dir.path().join("run");
        std::fs::create_dir(&bag).unwrap();
        let err = storage_files(&bag).unwrap_err().to_string();
        assert!(
            err.contains("not a ROS 2 bag (MCAP or sqlite3): a directory without"),
            "{err}"
        );
        // Without metadata: split order, not name order.
        for name in ["run_10.mcap", "run_2.mcap", "run_0.db3"] {
            let magic = if name.ends_with("db3") {
                SQLITE_MAGIC
            } else {
                MCAP_MAGIC
            };
            std::fs::write(bag.join(name), magic).unwrap();
        }
        std::fs::write(bag.join("notes.txt"), "x").unwrap();
        assert_eq!(
            names(&storage_files(&bag).unwrap()),
            [
                ("run_0.db3".into(), Storage::Sqlite),
                ("run_2.mcap".into(), Storage::Mcap),
                ("run_10.mcap".into(), Storage::Mcap),
            ]
        );
        // With metadata: its list, in its order, old-style prefixed paths included; the
        // metadata file itself names the bag too.
        std::fs::write(
            bag.join(METADATA_FILE),
            "rosbag2_bagfile_information:\n  version: 4\n  storage_identifier: mcap\n  \
             relative_file_paths:\n    - run/run_10.mcap\n    - run_2.mcap\n",
        )
        .unwrap();
        let listed = [
            ("run_10.mcap".into(), Storage::Mcap),
            ("run_2.mcap".into(), Storage::Mcap),
        ];
        assert_eq!(names(&storage_files(&bag).unwrap()), listed);
        assert_eq!(
            names(&storage_files(&bag.join(METADATA_FILE)).unwrap()),
            listed
        );
        std::fs::remove_file(bag.join("run_2.mcap")).unwrap();
        let err = storage_files(&bag).unwrap_err().to_string();
        assert!(
            err.contains("metadata.yaml: lists the storage file"),
            "{err}"
        );
        assert!(err.contains("run_2.mcap, which is missing"), "{err}");
        std::fs::write(bag.join(METADATA_FILE), "rosbag2_bagfile_information: [1\n").unwrap();
        let err = storage_files(&bag).unwrap_err().to_string();
        assert!(
            err.starts_with(&format!("{}", bag.join(METADATA_FILE).display())),
            "{err}"
        );
        std::fs::write(
            bag.join(METADATA_FILE),
            "rosbag2_bagfile_information:\n  compression_format: zstd\n  \
             compression_mode: FILE\n  relative_file_paths: [run_10.mcap.zstd]\n",
        )
        .unwrap();
        let err = storage_files(&bag).unwrap_err().to_string();
        assert!(err.contains("compressed (zstd per file)"), "{err}");
    }

    #[test]
    fn files_are_named_by_what_they_are() {
        let dir = tempfile::tempdir().unwrap();
        let db3 = dir.path().join("x.db3");
        std::fs::write(&db3, [SQLITE_MAGIC, b"rest of the header"].concat()).unwrap();
        assert_eq!(
            names(&storage_files(&db3).unwrap()),
            [("x.db3".into(), Storage::Sqlite)]
        );
        assert!(is_bag(&db3) && is_bag(dir.path()));
        let tum = dir.path().join("est.tum");
        std::fs::write(
            &tum,
            "# timestamp tx ty tz qx qy qz qw\n1.0 0 0 0 0 0 0 1\n",
        )
        .unwrap();
        let err = storage_files(&tum).unwrap_err().to_string();
        assert!(
            err.starts_with(&format!(
                "{}: not a ROS 2 bag (MCAP or sqlite3): a text file",
                tum.display()
            )) && err.contains("ekf evaluate"),
            "{err}"
        );
        assert!(!is_bag(&tum));
        let gz = dir.path().join("aces.log.gz");
        std::fs::write(&gz, [0x1f, 0x8b, 8, 0]).unwrap();
        let err = storage_files(&gz).unwrap_err().to_string();
        assert!(
            err.contains("a gzip file") && err.contains("ekf import carmen"),
            "{err}"
        );
        let mcap = dir.path().join("ok.mcap");
        std::fs::write(&mcap, MCAP_MAGIC).unwrap();
        assert_eq!(
            names(&storage_files(&mcap).unwrap()),
            [("ok.mcap".into(), Storage::Mcap)]
        );
        assert!(is_bag(&mcap));
    }
}

//! What a path given as a bag is, before it is read as MCAP: a ROS 2 bag directory
//! (`ros2 bag record` writes one, with `metadata.yaml` and its storage files), an MCAP
//! file, or something else that deserves its own name in the error (a sqlite3 `.db3`
//! bag, the default storage of ROS 2 Humble and earlier; a text file such as a TUM or
//! CSV trajectory; a gzip file such as a CARMEN log).

use super::ReadError;
use std::io::Read;
use std::path::{Path, PathBuf};

/// The first bytes of every MCAP file.
const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// The first bytes of every SQLite 3 database.
const SQLITE_MAGIC: &[u8] = b"SQLite format 3\0";

/// What to do with a sqlite3 bag.
const CONVERT_DB3: &str = "convert it to MCAP with `ros2 bag convert -i BAG_DIR -o out.yaml`, \
                           out.yaml saying `output_bags: [{uri: BAG_mcap, storage_id: mcap}]`";

/// The first bytes of a gzip stream.
const GZIP_MAGIC: &[u8] = b"\x1f\x8b";

/// The MCAP file to read for `path`: `path` itself if it is a file that starts like MCAP;
/// for a bag directory, its one `.mcap` storage file. Otherwise a
/// [`ReadError::NotMcap`] that says what it is and what to do.
pub fn mcap_file(path: &Path) -> Result<PathBuf, ReadError> {
    if path.is_dir() {
        return storage_file(path);
    }
    let mut head = Vec::with_capacity(64);
    if let Ok(file) = std::fs::File::open(path) {
        // A short or unreadable file falls through to the MCAP reader's own error.
        let _ = file.take(64).read_to_end(&mut head);
    }
    let not_mcap = |what: &str, hint: &str| ReadError::NotMcap {
        path: path.to_path_buf(),
        what: what.into(),
        hint: hint.into(),
    };
    if head.starts_with(SQLITE_MAGIC) {
        return Err(not_mcap(
            "a SQLite database (a ROS 2 sqlite3 bag, .db3)",
            CONVERT_DB3,
        ));
    }
    if head.starts_with(GZIP_MAGIC) {
        return Err(not_mcap(
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
        return Err(not_mcap(
            "a text file",
            "a trajectory (TUM or CSV) goes to `ekf evaluate EST --truth REF`; a CARMEN or \
             MRPT log is turned into a bag with `ekf import`",
        ));
    }
    Ok(path.to_path_buf())
}

/// The storage file of the bag directory `dir`: its one `.mcap` file.
fn storage_file(dir: &Path) -> Result<PathBuf, ReadError> {
    let mut mcap = Vec::new();
    let mut db3 = 0;
    if let Ok(entries) = std::fs::read_dir(dir) {
        for entry in entries.flatten() {
            let p = entry.path();
            match p.extension().and_then(|e| e.to_str()) {
                Some("mcap") => mcap.push(p),
                Some("db3") => db3 += 1,
                _ => {}
            }
        }
    }
    mcap.sort();
    let not_mcap = |what: String, hint: &str| ReadError::NotMcap {
        path: dir.to_path_buf(),
        what,
        hint: hint.into(),
    };
    match (mcap.len(), db3) {
        (1, _) => Ok(mcap.remove(0)),
        (0, 0) => Err(not_mcap(
            "a directory without a bag's storage file (.mcap)".into(),
            "pass a bag directory written by `ros2 bag record -s mcap`, or an .mcap file",
        )),
        (0, n) => Err(not_mcap(
            format!("a ROS 2 sqlite3 bag directory ({n} .db3 file(s))"),
            CONVERT_DB3,
        )),
        (n, _) => Err(not_mcap(
            format!("a bag split into {n} .mcap files"),
            "replay one file at a time, or merge them with `mcap merge`",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bag_directory_opens_its_mcap_file_and_other_things_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let bag = dir.path().join("run");
        std::fs::create_dir(&bag).unwrap();
        std::fs::write(
            bag.join("metadata.yaml"),
            "rosbag2_bagfile_information: {}\n",
        )
        .unwrap();
        let err = mcap_file(&bag).unwrap_err().to_string();
        assert!(err.contains("without a bag's storage file"), "{err}");
        std::fs::write(bag.join("run_0.db3"), SQLITE_MAGIC).unwrap();
        let err = mcap_file(&bag).unwrap_err().to_string();
        assert!(
            err.contains("sqlite3 bag directory (1 .db3 file(s))"),
            "{err}"
        );
        assert!(err.contains("ros2 bag convert"), "{err}");
        std::fs::write(bag.join("run_0.mcap"), MCAP_MAGIC).unwrap();
        assert_eq!(mcap_file(&bag).unwrap(), bag.join("run_0.mcap"));
        std::fs::write(bag.join("run_1.mcap"), MCAP_MAGIC).unwrap();
        let err = mcap_file(&bag).unwrap_err().to_string();
        assert!(err.contains("split into 2 .mcap files"), "{err}");

        let db3 = dir.path().join("x.db3");
        std::fs::write(&db3, [SQLITE_MAGIC, b"rest of the header"].concat()).unwrap();
        let err = mcap_file(&db3).unwrap_err().to_string();
        assert!(
            err.starts_with(&format!(
                "{}: not an MCAP bag: a SQLite database",
                db3.display()
            )),
            "{err}"
        );
        let tum = dir.path().join("est.tum");
        std::fs::write(
            &tum,
            "# timestamp tx ty tz qx qy qz qw\n1.0 0 0 0 0 0 0 1\n",
        )
        .unwrap();
        let err = mcap_file(&tum).unwrap_err().to_string();
        assert!(
            err.contains("a text file") && err.contains("ekf evaluate"),
            "{err}"
        );
        let gz = dir.path().join("aces.log.gz");
        std::fs::write(&gz, [0x1f, 0x8b, 8, 0]).unwrap();
        let err = mcap_file(&gz).unwrap_err().to_string();
        assert!(
            err.contains("a gzip file") && err.contains("ekf import carmen"),
            "{err}"
        );
        let mcap = dir.path().join("ok.mcap");
        std::fs::write(&mcap, MCAP_MAGIC).unwrap();
        assert_eq!(mcap_file(&mcap).unwrap(), mcap);
    }
}

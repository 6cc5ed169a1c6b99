//! Output folders made with an error that names what is in the way.

use std::io::{Error, ErrorKind};
use std::path::Path;

/// Creates the output folder `dir` and its parents, as [`std::fs::create_dir_all`] does,
/// but when a file stands where a folder must be, says which one instead of the OS's
/// bare "File exists" or "Not a directory".
pub fn create_output_dir(dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| {
        if !matches!(
            e.kind(),
            ErrorKind::AlreadyExists | ErrorKind::NotADirectory
        ) {
            return e;
        }
        match dir.ancestors().find(|a| a.is_file()) {
            Some(file) if file == dir => Error::new(e.kind(), "exists as a file, not a folder"),
            Some(file) => Error::new(
                e.kind(),
                format!("{} is a file, not a folder", file.display()),
            ),
            None => e,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_in_the_way_of_an_output_folder_is_named() {
        let tmp = tempfile::tempdir().unwrap();
        let file = tmp.path().join("results");
        std::fs::write(&file, "not a folder").unwrap();
        let e = create_output_dir(&file).unwrap_err();
        assert_eq!(e.to_string(), "exists as a file, not a folder");
        let e = create_output_dir(&file.join("run1")).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!("{} is a file, not a folder", file.display())
        );
        let fresh = tmp.path().join("a/b");
        create_output_dir(&fresh).unwrap();
        assert!(fresh.is_dir());
        create_output_dir(&fresh).unwrap();
    }
}

//! Rust errors as Python exceptions, with the same messages the `ekf` command prints.
//!
//! Invalid values (a NaN, a covariance that is not positive definite, a malformed map or
//! config) become `ValueError`; a file that cannot be opened, read or written becomes
//! `OSError` (`FileNotFoundError` or `PermissionError` where the operating system says
//! so).

use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyPermissionError, PyValueError};
use pyo3::PyErr;
use std::error::Error;
use std::io;
use std::sync::Arc;

/// A `ValueError` with the error's message.
pub fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// `OSError` (or its subclass for the error's kind) with `message`.
pub fn os_error(kind: io::ErrorKind, message: String) -> PyErr {
    match kind {
        io::ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
        io::ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
        _ => PyOSError::new_err(message),
    }
}

/// `OSError` for an I/O failure on `path`: "`path`: what the OS said", as the CLI says it.
pub fn path_error(path: &std::path::Path, e: &io::Error) -> PyErr {
    os_error(e.kind(), format!("{}: {e}", path.display()))
}

/// The exception for an error of the file-reading layers (replay, map build, config): an
/// `OSError` if an I/O error is anywhere in its source chain, else a `ValueError`. The
/// message is the error's own, unchanged.
pub fn file_error(e: &(dyn Error + 'static)) -> PyErr {
    let mut cause: Option<&(dyn Error + 'static)> = Some(e);
    while let Some(c) = cause {
        let io = c
            .downcast_ref::<io::Error>()
            .or_else(|| c.downcast_ref::<Arc<io::Error>>().map(|a| a.as_ref()));
        if let Some(io) = io {
            return os_error(io.kind(), e.to_string());
        }
        cause = c.source();
    }
    value_error(e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use pyo3::Python;

    #[derive(Debug)]
    struct Wrapper(Arc<io::Error>);

    impl std::fmt::Display for Wrapper {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "log.mcap: read error: {}", self.0)
        }
    }

    impl Error for Wrapper {
        fn source(&self) -> Option<&(dyn Error + 'static)> {
            Some(&self.0)
        }
    }

    #[test]
    fn io_errors_in_the_chain_become_os_errors_with_the_outer_message() {
        Python::initialize();
        Python::attach(|py| {
            let e = Wrapper(Arc::new(io::Error::from(io::ErrorKind::NotFound)));
            let err = file_error(&e);
            assert!(err.is_instance_of::<PyFileNotFoundError>(py));
            assert_eq!(err.value(py).to_string(), e.to_string());
            let e = ekf_core::Error::NonFinite { what: "dt" };
            let err = file_error(&e);
            assert!(err.is_instance_of::<PyValueError>(py));
            assert_eq!(
                err.value(py).to_string(),
                "dt is not finite (NaN or infinite)"
            );
        });
    }
}

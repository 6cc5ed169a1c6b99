//! Why extraction refused its parameters or a scan.

use crate::scan::ScanError;
use core::fmt;

/// An extraction error: a parameter out of range or a scan header that cannot be trusted.
/// Invalid range readings are never errors; they are skipped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExtractionError {
    /// A field of [`ExtractionParams`](super::ExtractionParams) is out of range.
    InvalidParameter {
        /// The parameter, e.g. `"split_distance"`.
        name: &'static str,
        /// What it must be.
        expected: &'static str,
    },
    /// The scan header failed [`LaserScan::validate`](crate::LaserScan::validate).
    InvalidScan(ScanError),
}

impl From<ScanError> for ExtractionError {
    fn from(e: ScanError) -> Self {
        Self::InvalidScan(e)
    }
}

impl fmt::Display for ExtractionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::InvalidParameter { name, expected } => {
                write!(
                    f,
                    "invalid line extraction parameter: {name} must be {expected}"
                )
            }
            Self::InvalidScan(e) => e.fmt(f),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for ExtractionError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::InvalidScan(e) => Some(e),
            Self::InvalidParameter { .. } => None,
        }
    }
}

//! The error type of the filter core.
//!
//! Every fallible call validates before it touches the state, so an `Err` always leaves
//! the filter exactly as it was.

use core::fmt;

/// Why an input was refused. `what` names the offending parameter or field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Error {
    /// A value was NaN or infinite.
    NonFinite {
        /// The parameter or field that was not finite.
        what: &'static str,
    },
    /// A variance or standard deviation was negative.
    NegativeVariance {
        /// The parameter or field.
        what: &'static str,
    },
    /// A covariance matrix was not symmetric.
    NotSymmetric {
        /// The matrix.
        what: &'static str,
    },
    /// A covariance matrix was not positive definite.
    NotPositiveDefinite {
        /// The matrix.
        what: &'static str,
    },
    /// A parameter was outside its valid range.
    OutOfRange {
        /// The parameter.
        what: &'static str,
        /// What was expected, e.g. "> 0".
        expected: &'static str,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::NonFinite { what } => write!(f, "{what} is not finite (NaN or infinite)"),
            Error::NegativeVariance { what } => {
                write!(f, "{what} is negative; a variance must be ≥ 0")
            }
            Error::NotSymmetric { what } => write!(f, "{what} is not symmetric"),
            Error::NotPositiveDefinite { what } => write!(f, "{what} is not positive definite"),
            Error::OutOfRange { what, expected } => {
                write!(f, "{what} is out of range: expected {expected}")
            }
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for Error {}

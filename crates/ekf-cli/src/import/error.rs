//! The one error type of the importers: every variant names the line, and where a field
//! is at fault, the record type, the field and what was expected.

use thiserror::Error;

/// Why an import stopped. Field numbers count whitespace-separated words from 1, the
/// record tag being field 1 (as awk's `$k`).
#[derive(Debug, Error)]
pub enum ImportError {
    /// Reading from the source failed.
    #[error("line {line}: read failed: {source}")]
    Io {
        /// 1-based line number being read.
        line: u64,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The line is not UTF-8 text.
    #[error("line {line}: not UTF-8 text")]
    NotText {
        /// 1-based line number.
        line: u64,
    },
    /// The line is longer than the importer accepts (a binary file or a missing newline).
    #[error("line {line}: longer than {max} bytes")]
    LineTooLong {
        /// 1-based line number.
        line: u64,
        /// The limit in bytes.
        max: usize,
    },
    /// A field could not be read as what it must be.
    #[error("line {line}: {record} field {field} ({name}): expected {expected}, found '{found}'")]
    BadField {
        /// 1-based line number.
        line: u64,
        /// Record tag, e.g. `FLASER`.
        record: String,
        /// 1-based field number, the tag being field 1.
        field: usize,
        /// What the field means, e.g. `x` or `range`.
        name: &'static str,
        /// What it should have been, e.g. `a finite number`.
        expected: &'static str,
        /// The text found (cut to 40 characters).
        found: String,
    },
    /// The line has the wrong number of fields for its record type.
    #[error(
        "line {line}: {record}{}: expected {expected} fields, the line has {found}",
        context.as_deref().map(|c| format!(" {c}")).unwrap_or_default()
    )]
    FieldCount {
        /// 1-based line number.
        line: u64,
        /// Record tag.
        record: String,
        /// Why that many fields, for records whose length depends on a count in them,
        /// e.g. `declares 180 readings`.
        context: Option<String>,
        /// Number of fields the record needs, the tag included.
        expected: usize,
        /// Number of fields the line has.
        found: usize,
    },
    /// A timestamp needs repair and the import is strict.
    #[error(
        "line {line}: {record} field {field} ({name}): the time is {flaw} (--strict refuses \
         repairing it)"
    )]
    BadStamp {
        /// 1-based line number.
        line: u64,
        /// Record tag.
        record: &'static str,
        /// 1-based field number, the tag being field 1.
        field: usize,
        /// What the field means.
        name: &'static str,
        /// What is wrong with it, e.g. `negative`.
        flaw: &'static str,
    },
    /// The clock is broken throughout and the import is strict.
    #[error(
        "line {line}: the clock is broken throughout the first {stamps} stamped records \
         ({valid} positive times, {increasing} of {pairs} consecutive ones increasing); \
         --strict refuses importing the log in file order"
    )]
    BrokenClock {
        /// 1-based line number of the first record judged.
        line: u64,
        /// Records with a stamp of their own that were judged.
        stamps: usize,
        /// Of those, stamps that are positive times.
        valid: usize,
        /// Consecutive pairs of positive stamps that increase.
        increasing: usize,
        /// Consecutive pairs of positive stamps.
        pairs: usize,
    },
    /// The log's clock returns to its first stamp and runs on from there: a second copy
    /// of the log appended to the first (two gzip members, a log concatenated twice).
    #[error(
        "line {line}: the log starts over: from here the stamps run again from {stamp_s:.3} s, \
         back at the first record's {first_s:.3} s after {span_s:.1} s of log (a second \
         copy appended, e.g. a second gzip member?); the records before line {line} are \
         imported, the rest is not"
    )]
    StartsOver {
        /// 1-based line number where the log starts over.
        line: u64,
        /// The stamp there (s).
        stamp_s: f64,
        /// The log's first stamp (s).
        first_s: f64,
        /// How far the log had run before (s).
        span_s: f64,
    },
}

impl ImportError {
    /// Whether the error marks where the log ends rather than a fault in it: the records
    /// placed before it are imported ([`ImportError::StartsOver`]).
    pub fn ends_the_log(&self) -> bool {
        matches!(self, ImportError::StartsOver { .. })
    }
}

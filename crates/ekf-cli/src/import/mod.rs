//! Importers that turn real robot logs (CARMEN text logs, MRPT text exports) into a
//! stream of time-stamped records, ready to be written as ROS 2 messages.
//!
//! Each importer reads a `BufRead` one line at a time (memory stays bounded) and is an
//! iterator of `Result<ImportRecord, ImportError>`:
//!
//! ```no_run
//! use ekf_cli::import::{open_log, read_carmen, CarmenOptions, ImportRecord};
//!
//! let reader = open_log("aces-corrected.log.gz".as_ref())?;
//! let mut records = read_carmen(reader, CarmenOptions::default());
//! for record in &mut records {
//!     if let ImportRecord::Scan(scan) = record? {
//!         let _beams = scan.ranges.len();
//!     }
//! }
//! let _span_s = records.stats().span_ns() as f64 * 1e-9;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Common rules:
//! * times are nanoseconds taken from the log's own timestamps, converted from the decimal
//!   text without going through floating point;
//! * records come in file order. CARMEN stamps that need it are repaired from their
//!   neighbours (counted in [`ImportStats::time_repairs`]); time still going backwards
//!   (MRPT) is not sorted away but counted in [`ImportStats::backwards_time`]; equal
//!   stamps are normal (a scan and its reference);
//! * the first bad line ends the iteration with an error naming the line, the record
//!   type and the field, after every record before it was yielded.

mod carmen;
mod clock;
mod compass;
mod error;
mod fields;
mod lines;
mod mrpt;
mod range_limit;
mod record;
mod source;
mod stats;
mod stream;

pub use carmen::{read_carmen, CarmenFlavour, CarmenOptions, CarmenReader};
pub use clock::{PROBE_RECORDS, RESTART_RECORDS, SYNTHETIC_STEP_NS};
pub use compass::SyntheticCompass;
pub use error::ImportError;
pub use lines::MAX_LINE_BYTES;
pub use mrpt::{read_mrpt, MrptReader};
pub use record::{Compass, ImportRecord, Odometry, Reference, Scan};
pub use source::open_log;
pub use stats::{ImportStats, RangeMax, RangeMaxSource};
pub use stats::{RepairCount, TimeRepairs};

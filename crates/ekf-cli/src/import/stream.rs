//! The iterator shared by all importers: it pulls lines, hands each to a format's line
//! parser, and yields the records that parser emits, in file order.

use super::error::ImportError;
use super::lines::LineSource;
use super::record::ImportRecord;
use super::stats::ImportStats;
use std::collections::VecDeque;
use std::io::BufRead;

/// Where a line parser puts its records and counts skipped lines.
#[derive(Debug, Default)]
pub(crate) struct Output {
    /// Records waiting to be yielded (at most a few per line).
    pub(crate) queue: VecDeque<ImportRecord>,
    /// Counters; the stream adds the per-record ones as it yields.
    pub(crate) stats: ImportStats,
}

/// One log format: turns one line into zero or more records.
pub(crate) trait LineParser {
    /// Parses line `line` (`text`, without its line ending) into `out`.
    fn parse_line(&mut self, line: u64, text: &str, out: &mut Output) -> Result<(), ImportError>;

    /// Emits what the parser still holds back at the end of the input.
    fn finish(&mut self, _out: &mut Output) -> Result<(), ImportError> {
        Ok(())
    }
}

/// A streaming importer over a `BufRead`: yields records one by one, stops after the
/// first error (everything before it, including what the parser held back, is yielded
/// first), and then reports [`ImportStats`].
pub struct RecordStream<R, P> {
    lines: LineSource<R>,
    parser: P,
    out: Output,
    last_ns: Option<u64>,
    done: bool,
    /// The error that ended the input, yielded after the records held back before it.
    error: Option<ImportError>,
}

impl<R: BufRead, P> RecordStream<R, P> {
    pub(crate) fn new(reader: R, parser: P) -> Self {
        Self {
            lines: LineSource::new(reader),
            parser,
            out: Output::default(),
            last_ns: None,
            done: false,
            error: None,
        }
    }

    /// What was imported so far; complete once the iterator has returned `None`.
    pub fn stats(&self) -> &ImportStats {
        &self.out.stats
    }
}

impl<R: BufRead, P: LineParser> Iterator for RecordStream<R, P> {
    type Item = Result<ImportRecord, ImportError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if let Some(record) = self.out.queue.pop_front() {
                self.out.stats.count(&record, self.last_ns);
                self.last_ns = Some(record.t_ns());
                return Some(Ok(record));
            }
            if let Some(e) = self.error.take() {
                return Some(Err(e));
            }
            if self.done {
                return None;
            }
            let step = match self.lines.next_line() {
                Ok(Some((line, text))) => self.parser.parse_line(line, text, &mut self.out),
                Ok(None) => {
                    self.done = true;
                    self.parser.finish(&mut self.out)
                }
                Err(e) => Err(e),
            };
            if let Err(e) = step {
                self.done = true;
                if e.ends_the_log() {
                    // Everything placed before the point where the log ends is kept.
                } else if !self.out.queue.is_empty() {
                    // Records the failing line released (a strict clock) go with it.
                    self.out.queue.clear();
                } else if self.parser.finish(&mut self.out).is_err() {
                    self.out.queue.clear();
                }
                self.error = Some(e);
            }
        }
    }
}

//! Line-by-line reading of a text log with a bounded buffer: one line in memory at a
//! time, never the whole file.

use super::error::ImportError;
use std::io::{BufRead, Read};

/// Longest line accepted (bytes). Real lines are a few kB (a 361-beam scan is ~2.6 kB);
/// the cap keeps a binary file or a missing newline from filling memory.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// Reads numbered lines from a `BufRead`, reusing one buffer.
pub(crate) struct LineSource<R> {
    reader: R,
    buf: Vec<u8>,
    line: u64,
}

impl<R: BufRead> LineSource<R> {
    /// Wraps `reader`; the first line read is line 1.
    pub(crate) fn new(reader: R) -> Self {
        Self {
            reader,
            buf: Vec::new(),
            line: 0,
        }
    }

    /// The next line (number, text without the line ending), or `None` at the end.
    pub(crate) fn next_line(&mut self) -> Result<Option<(u64, &str)>, ImportError> {
        self.buf.clear();
        self.line += 1;
        let line = self.line;
        let limit = MAX_LINE_BYTES as u64 + 1;
        let n = (&mut self.reader)
            .take(limit)
            .read_until(b'\n', &mut self.buf)
            .map_err(|source| ImportError::Io { line, source })?;
        if n == 0 {
            return Ok(None);
        }
        if self.buf.last() == Some(&b'\n') {
            self.buf.pop();
        } else if self.buf.len() > MAX_LINE_BYTES {
            return Err(ImportError::LineTooLong {
                line,
                max: MAX_LINE_BYTES,
            });
        }
        let text = std::str::from_utf8(&self.buf).map_err(|_| ImportError::NotText { line })?;
        Ok(Some((line, text)))
    }
}

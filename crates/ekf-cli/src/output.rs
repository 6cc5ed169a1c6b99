//! Standard output for the command's results. A reader that goes away before the command
//! is done (`ekf live | head -n 5`) must not make it panic halfway through a recording:
//! the write reports [`Closed`], which `main` ends quietly with success, as a command
//! killed by SIGPIPE ends silently in a shell pipeline.

use std::fmt::Display;
use std::io::{ErrorKind, Write};

/// Standard output was closed by its reader.
#[derive(Debug, thiserror::Error)]
#[error("standard output was closed by its reader")]
pub struct Closed;

/// Writes `text` to standard output and flushes it (a pose printed by `ekf live` must
/// reach its reader now, not when a buffer fills).
pub fn emit(text: impl Display) -> Result<(), Box<dyn std::error::Error>> {
    let mut out = std::io::stdout().lock();
    write!(out, "{text}")
        .and_then(|()| out.flush())
        .map_err(|e| match e.kind() {
            ErrorKind::BrokenPipe => Box::new(Closed) as Box<dyn std::error::Error>,
            _ => format!("standard output: {e}").into(),
        })
}

/// [`emit`] followed by a newline.
pub fn emit_line(text: impl Display) -> Result<(), Box<dyn std::error::Error>> {
    emit(format_args!("{text}\n"))
}

//! The stamps of `ekf live`'s messages: nanoseconds since the Unix epoch, from a
//! monotonic clock.

use std::time::{Instant, SystemTime, UNIX_EPOCH};

/// Nanoseconds since the Unix epoch for monotonic instants.
pub(super) struct Clock {
    epoch_ns: u64,
    pub(super) started: Instant,
    last: u64,
}

impl Clock {
    pub(super) fn new() -> Self {
        let epoch_ns = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos() as u64);
        Self {
            epoch_ns,
            started: Instant::now(),
            last: 0,
        }
    }

    /// The stamp of `t` (instants before the clock started get its start).
    pub(super) fn stamp(&self, t: Instant) -> u64 {
        self.epoch_ns + t.saturating_duration_since(self.started).as_nanos() as u64
    }

    /// The stamp of now, strictly increasing per call (diagnostics).
    pub(super) fn now(&mut self) -> u64 {
        self.last = self.stamp(Instant::now()).max(self.last + 1);
        self.last
    }
}

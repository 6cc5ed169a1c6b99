//! Times of a periodic stream recovered from late reads: a scanner in continuous output
//! sends a telegram every period, but a busy host reads each one when it gets the CPU,
//! so the read times carry the host's delays. The true sends lie on a grid
//! `φ + k·T`; the least-delayed reads of a recent window pin the grid down (the lower
//! envelope, as the software phase-locked loops of laser drivers do), and each telegram
//! is timed on it. A read is never timed later than it happened, nor more than one
//! period earlier.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// Reads kept to estimate the period and the grid's phase: about six seconds of a
/// 5 Hz scanner, short enough to follow a drift between the device's clock and the
/// host's.
const WINDOW: usize = 32;

/// Reads needed before the grid is trusted; before that a read's own time is used.
const MIN_READS: usize = 8;

/// Recovers the send times of a periodic stream from its read times.
#[derive(Debug, Clone, Default)]
pub struct ArrivalClock {
    /// The latest read times, oldest first.
    reads: VecDeque<Instant>,
}

impl ArrivalClock {
    /// A clock that has seen no read.
    pub fn new() -> Self {
        Self::default()
    }

    /// The time of the telegram read at `read`: on the grid `φ + k·T` fitted to the
    /// window's reads, with `T` the median interval between reads (missed telegrams
    /// give multiples of it, which the median ignores) and `φ` the phase of the
    /// earliest read relative to the grid; `read` itself until the window has
    /// `MIN_READS` (8) reads, or if the reads are not periodic.
    pub fn time_of(&mut self, read: Instant) -> Instant {
        if self.reads.len() == WINDOW {
            self.reads.pop_front();
        }
        self.reads.push_back(read);
        if self.reads.len() < MIN_READS {
            return read;
        }
        let Some(period) = self.period() else {
            return read;
        };
        let first = self.reads[0];
        let t = period.as_secs_f64();
        // Each read's offset from the grid through the first read, in grid steps
        // rounded off: the smallest is the least-delayed read.
        let offsets = self.reads.iter().map(|r| {
            let since = r.duration_since(first).as_secs_f64();
            since - (since / t).round() * t
        });
        let least = offsets.fold(f64::INFINITY, f64::min);
        let since = read.duration_since(first).as_secs_f64();
        let on_grid = (since / t).round() * t + least;
        let early = since - on_grid;
        if !(0.0..=t).contains(&early) {
            return read;
        }
        read.checked_sub(Duration::from_secs_f64(early))
            .unwrap_or(read)
    }

    /// The median interval between consecutive reads of the window.
    fn period(&self) -> Option<Duration> {
        let mut gaps: Vec<Duration> = self
            .reads
            .iter()
            .zip(self.reads.iter().skip(1))
            .map(|(a, b)| b.duration_since(*a))
            .filter(|d| !d.is_zero())
            .collect();
        if gaps.len() < MIN_READS - 1 {
            return None;
        }
        gaps.sort_unstable();
        Some(gaps[gaps.len() / 2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: Duration = Duration::from_millis(200);

    #[test]
    fn late_reads_are_timed_on_the_grid_of_the_prompt_ones() {
        let start = Instant::now();
        let mut clock = ArrivalClock::new();
        // Sends every 200 ms; the host reads each 2 ms after, or late by up to 60 ms;
        // telegram 13 is lost.
        let delay_ms = |k: u32| match k % 5 {
            1 => 60,
            3 => 35,
            _ => 2,
        };
        for k in (0..40u32).filter(|k| *k != 13) {
            let sent = start + T * k;
            let read = sent + Duration::from_millis(delay_ms(k));
            let timed = clock.time_of(read);
            assert!(timed <= read, "never later than the read");
            if k >= 10 {
                // On the grid of the least-delayed reads: 2 ms after the send.
                let error = timed.duration_since(sent);
                assert!(
                    error.abs_diff(Duration::from_millis(2)) < Duration::from_micros(50),
                    "telegram {k}: timed {error:?} after its send"
                );
            }
        }
    }

    #[test]
    fn a_read_is_never_timed_later_than_it_happened_nor_a_period_earlier() {
        let start = Instant::now();
        let mut clock = ArrivalClock::new();
        let mut at = start;
        for k in 0..30u64 {
            // Not periodic: intervals of 100, 170, 240 ms ... 520 ms and round again
            // (median 310 ms).
            at += Duration::from_millis(100 + 70 * (k % 7));
            let timed = clock.time_of(at);
            assert!(timed <= at);
            assert!(at.duration_since(timed) <= Duration::from_millis(310));
        }
        // The first reads, before the window fills, are their own times.
        let mut fresh = ArrivalClock::new();
        assert_eq!(fresh.time_of(start), start);
    }
}

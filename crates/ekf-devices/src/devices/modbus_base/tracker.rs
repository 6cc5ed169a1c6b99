//! Cumulative wheel ticks from successive register reads: 32-bit counters unwrapped
//! (wrapping differences), repeated samples skipped, missed samples counted, and changes
//! no wheel can make (a controller that restarted its counts) refused.

use super::BaseReading;

/// Wheel positions in ticks since tracking started (unwrapped, signed).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WheelTicks {
    /// Left wheel.
    pub left: i64,
    /// Right wheel.
    pub right: i64,
}

/// Follows the encoder counts across reads.
#[derive(Debug, Clone)]
pub struct EncoderTracker {
    /// The reference read and its time (ns).
    last: Option<(BaseReading, u64)>,
    totals: WheelTicks,
    max_ticks_per_s: f64,
    /// Reads that repeated the previous sample (counter unchanged).
    pub repeated: u64,
    /// Samples the controller latched whose replies never arrived (counter jumps).
    pub missed: u64,
    /// Reads refused: an encoder changed by more than a wheel can turn in the time, or
    /// the sample counter stepped back (the controller restarted).
    pub implausible: u64,
}

impl EncoderTracker {
    /// A tracker for wheels that turn at most `max_ticks_per_s` ticks per second.
    pub fn new(max_ticks_per_s: f64) -> Self {
        Self {
            last: None,
            totals: WheelTicks { left: 0, right: 0 },
            max_ticks_per_s,
            repeated: 0,
            missed: 0,
            implausible: 0,
        }
    }

    /// The controller was (re)connected: its counts and sample counter may have
    /// restarted, so the next read is a new reference; the positions carry on from
    /// where they were (the motion while it was away is lost).
    pub fn restart(&mut self) {
        self.last = None;
    }

    /// The wheel positions after this read at `t_ns`, or `None` if it repeats the last
    /// sample or is refused. Differences are taken modulo 2³² (a counter that wraps
    /// between reads moves by less than 2³¹ ticks). A change larger than the wheels can
    /// make since the reference read, or a sample counter that steps back, is refused and
    /// counted; the read becomes the new reference (the controller restarted its counts).
    pub fn update(&mut self, reading: BaseReading, t_ns: u64) -> Option<WheelTicks> {
        let Some((last, last_ns)) = self.last else {
            self.last = Some((reading, t_ns));
            return Some(self.totals);
        };
        let jump = reading.counter.wrapping_sub(last.counter);
        if jump == 0 {
            self.repeated += 1;
            return None;
        }
        let left = i64::from(reading.left_ticks.wrapping_sub(last.left_ticks) as i32);
        let right = i64::from(reading.right_ticks.wrapping_sub(last.right_ticks) as i32);
        // One tick of slack each way: the counts are whole ticks.
        let possible = self.max_ticks_per_s * t_ns.saturating_sub(last_ns) as f64 * 1e-9 + 2.0;
        self.last = Some((reading, t_ns));
        if jump >= 0x8000 || left.abs() as f64 > possible || right.abs() as f64 > possible {
            self.implausible += 1;
            return None;
        }
        self.missed += u64::from(jump - 1);
        self.totals.left += left;
        self.totals.right += right;
        Some(self.totals)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(left: u32, right: u32, counter: u16) -> BaseReading {
        BaseReading {
            left_ticks: left,
            right_ticks: right,
            bearing_tenths: 0,
            counter,
        }
    }

    const S: u64 = 1_000_000_000;

    #[test]
    fn wrap_around_repeats_and_misses() {
        let mut t = EncoderTracker::new(1000.0);
        assert_eq!(
            t.update(read(u32::MAX - 5, 10, 65534), 0),
            Some(WheelTicks { left: 0, right: 0 })
        );
        // Left wraps forward past 2³², right runs backwards; the counter wraps too.
        assert_eq!(
            t.update(read(4, 2, 65535), S / 10),
            Some(WheelTicks {
                left: 10,
                right: -8
            })
        );
        assert_eq!(t.update(read(4, 2, 65535), 2 * S / 10), None);
        assert_eq!(t.repeated, 1);
        // Two replies lost: the counter jumps by 3; the ticks are still exact.
        assert_eq!(
            t.update(read(104, 2, 2), 4 * S / 10),
            Some(WheelTicks {
                left: 110,
                right: -8
            })
        );
        assert_eq!(t.missed, 2);
    }

    #[test]
    fn a_restarted_controller_is_no_wheel_motion() {
        // At most 1000 ticks/s: 0.1 s allows 102 ticks (with a tick of slack each way).
        let mut t = EncoderTracker::new(1000.0);
        t.update(read(5_000_000, 7_000_000, 900), 0);
        assert_eq!(
            t.update(read(5_000_100, 6_999_950, 901), S / 10),
            Some(WheelTicks {
                left: 100,
                right: -50
            })
        );
        // The controller restarted behind our back: counts and counter from 0.
        assert_eq!(t.update(read(3, 1, 1), 2 * S / 10), None);
        assert_eq!((t.implausible, t.missed), (1, 0));
        // It is the new reference: motion goes on from the totals.
        assert_eq!(
            t.update(read(13, 5, 2), 3 * S / 10),
            Some(WheelTicks {
                left: 110,
                right: -46
            })
        );
        // Reconnected after a power cycle: the next read only sets the reference,
        // even one that would be plausible (the counter stepped on by chance).
        t.restart();
        assert_eq!(
            t.update(read(40, 40, 3), 9 * S / 10),
            Some(WheelTicks {
                left: 110,
                right: -46
            })
        );
        assert_eq!(t.implausible, 1);
        // More ticks than a wheel turns in the time: refused.
        assert_eq!(t.update(read(40 + 103, 40, 4), 10 * S / 10), None);
        assert_eq!(t.implausible, 2);
    }
}

//! Cumulative wheel ticks from successive register reads: 32-bit counters unwrapped
//! (wrapping differences), repeated samples skipped, missed samples counted.

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
#[derive(Debug, Clone, Default)]
pub struct EncoderTracker {
    last: Option<BaseReading>,
    totals: Option<WheelTicks>,
    /// Reads that repeated the previous sample (counter unchanged).
    pub repeated: u64,
    /// Samples the controller latched whose replies never arrived (counter jumps).
    pub missed: u64,
}

impl EncoderTracker {
    /// The wheel positions after this read, or `None` if it repeats the last sample.
    /// Differences are taken modulo 2³² (a counter that wraps between reads moves by
    /// less than 2³¹ ticks).
    pub fn update(&mut self, reading: BaseReading) -> Option<WheelTicks> {
        let totals = match (self.last, self.totals) {
            (Some(last), Some(t)) => {
                let jump = reading.counter.wrapping_sub(last.counter);
                if jump == 0 {
                    self.repeated += 1;
                    return None;
                }
                self.missed += u64::from(jump - 1);
                WheelTicks {
                    left: t.left
                        + i64::from(reading.left_ticks.wrapping_sub(last.left_ticks) as i32),
                    right: t.right
                        + i64::from(reading.right_ticks.wrapping_sub(last.right_ticks) as i32),
                }
            }
            _ => WheelTicks { left: 0, right: 0 },
        };
        self.last = Some(reading);
        self.totals = Some(totals);
        Some(totals)
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

    #[test]
    fn wrap_around_repeats_and_misses() {
        let mut t = EncoderTracker::default();
        assert_eq!(
            t.update(read(u32::MAX - 5, 10, 65534)),
            Some(WheelTicks { left: 0, right: 0 })
        );
        // Left wraps forward past 2³², right runs backwards; the counter wraps too.
        assert_eq!(
            t.update(read(4, 2, 65535)),
            Some(WheelTicks {
                left: 10,
                right: -8
            })
        );
        assert_eq!(t.update(read(4, 2, 65535)), None);
        assert_eq!(t.repeated, 1);
        // Two replies lost: the counter jumps by 3; the ticks are still exact.
        assert_eq!(
            t.update(read(104, 2, 2)),
            Some(WheelTicks {
                left: 110,
                right: -8
            })
        );
        assert_eq!(t.missed, 2);
    }
}

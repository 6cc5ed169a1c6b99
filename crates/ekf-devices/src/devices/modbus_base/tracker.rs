//! Cumulative wheel ticks from successive register reads: 32-bit counters unwrapped
//! (wrapping differences), repeated samples skipped, missed samples counted, changes no
//! wheel can make (a controller that restarted its counts) refused, and the motion the
//! controller counted while its line was down kept.

use super::BaseReading;

/// Wheel positions in ticks since tracking started (unwrapped, signed).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WheelTicks {
    /// Left wheel.
    pub left: i64,
    /// Right wheel.
    pub right: i64,
}

/// Most polls a host makes per second; bounds the sample counter's step across an outage
/// of a controller that ran on (`ekf live` polls at 10 Hz).
const MAX_POLLS_PER_S: f64 = 100.0;

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
    /// Reconnections after which the controller had kept counting (its sample counter
    /// went on, the encoders moved no more than the wheels can): the motion of the
    /// outage was kept.
    pub outages_bridged: u64,
    /// Reconnections to a controller that had restarted (counter or counts from 0): the
    /// motion of the outage is lost, the positions carry on from where they were.
    pub restarts: u64,
    /// A reconnection happened since the last read.
    reconnected: bool,
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
            outages_bridged: 0,
            restarts: 0,
            reconnected: false,
        }
    }

    /// The controller was reconnected. If the line went down but the controller kept
    /// running (an unplugged cable, a silent RS-485 adapter), its counts went on: the
    /// next read then differs from the last by the motion of the outage, which is kept.
    /// If it restarted (a power cycle), its counts and sample counter begin again: the
    /// next read is a new reference and the positions carry on from where they were.
    /// The next read tells which (see [`Self::update`]).
    pub fn reconnected(&mut self) {
        self.reconnected = true;
    }

    /// The wheel positions after this read at `t_ns`, or `None` if it repeats the last
    /// sample or is refused. Differences are taken modulo 2³² (a counter that wraps
    /// between reads moves by less than 2³¹ ticks). A change larger than the wheels can
    /// make since the reference read, or a sample counter that steps back, is refused and
    /// counted; the read becomes the new reference (the controller restarted its counts).
    ///
    /// The first read after [`Self::reconnected`] is judged the same way: a counter that
    /// went on and a change the wheels can make in the time away is the motion of the
    /// outage, kept ([`Self::outages_bridged`]); otherwise the controller restarted, and
    /// the read is a new reference with no motion ([`Self::restarts`]).
    pub fn update(&mut self, reading: BaseReading, t_ns: u64) -> Option<WheelTicks> {
        let Some((last, last_ns)) = self.last else {
            self.reconnected = false;
            self.last = Some((reading, t_ns));
            return Some(self.totals);
        };
        let jump = reading.counter.wrapping_sub(last.counter);
        if jump == 0 {
            self.repeated += 1;
            return None;
        }
        // A repeated sample says nothing about the reconnection: the next new one does.
        let reconnected = std::mem::take(&mut self.reconnected);
        let elapsed_s = t_ns.saturating_sub(last_ns) as f64 * 1e-9;
        // A controller that ran on latched at most one sample per poll meanwhile; one
        // that restarted counts from 1, which reads as a jump of up to 2¹⁵ from an old
        // counter past 2¹⁵.
        let ran_on = f64::from(jump) <= 1.0 + MAX_POLLS_PER_S * elapsed_s;
        let left = i64::from(reading.left_ticks.wrapping_sub(last.left_ticks) as i32);
        let right = i64::from(reading.right_ticks.wrapping_sub(last.right_ticks) as i32);
        // One tick of slack each way: the counts are whole ticks.
        let possible = self.max_ticks_per_s * t_ns.saturating_sub(last_ns) as f64 * 1e-9 + 2.0;
        self.last = Some((reading, t_ns));
        let wheels_can = left.abs() as f64 <= possible && right.abs() as f64 <= possible;
        if jump >= 0x8000 || !wheels_can || (reconnected && !ran_on) {
            if reconnected {
                self.restarts += 1;
                return Some(self.totals);
            }
            self.implausible += 1;
            return None;
        }
        if reconnected {
            self.outages_bridged += 1;
        } else {
            self.missed += u64::from(jump - 1);
        }
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
        // Reconnected after the line was down 0.6 s while the controller ran on: its
        // counter went on by one (it latched nothing meanwhile) and the wheels moved no
        // more than they can in 0.6 s: the motion of the outage is kept.
        t.reconnected();
        assert_eq!(
            t.update(read(40, 40, 3), 9 * S / 10),
            Some(WheelTicks {
                left: 137,
                right: -11
            })
        );
        assert_eq!((t.outages_bridged, t.restarts, t.implausible), (1, 0, 1));
        // More ticks than a wheel turns in the time: refused.
        assert_eq!(t.update(read(40 + 103, 40, 4), 10 * S / 10), None);
        assert_eq!(t.implausible, 2);
        // Reconnected to a power-cycled controller: counter and counts from 0. No
        // motion, and not counted as implausible: a restart is what a reconnection can be.
        t.reconnected();
        assert_eq!(
            t.update(read(2, 3, 1), 20 * S / 10),
            Some(WheelTicks {
                left: 137,
                right: -11
            })
        );
        assert_eq!((t.outages_bridged, t.restarts, t.implausible), (1, 1, 2));
        // A power cycle from a counter past 2¹⁵ reads as a forward step of less than 2¹⁵,
        // but far more than the polls of 0.1 s: a restart, even with counts the wheels
        // could have made.
        let mut u = EncoderTracker::new(1000.0);
        u.update(read(50, 50, 40_000), 0);
        u.reconnected();
        // A repeat of the last sample first: it does not use up the reconnection.
        assert_eq!(u.update(read(50, 50, 40_000), S / 20), None);
        assert_eq!(
            u.update(read(20, 20, 1), S / 10),
            Some(WheelTicks { left: 0, right: 0 })
        );
        assert_eq!((u.outages_bridged, u.restarts, u.repeated), (0, 1, 1));
        // The restarted controller is the reference now.
        assert_eq!(
            t.update(read(12, 3, 2), 21 * S / 10),
            Some(WheelTicks {
                left: 147,
                right: -11
            })
        );
    }
}

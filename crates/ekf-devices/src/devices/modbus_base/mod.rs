//! The base controller (the paper's dsPIC on RS-485) over MODBUS RTU: the register map
//! (`docs/devices.md`), the polling client, encoder/compass tracking across counter
//! wrap-around and missed polls, and the controller side for emulation.

pub mod client;
pub mod device;
pub mod reply;
pub mod tracker;

pub use client::{BaseClient, BaseConfig, BaseCounters, REQUEST_CHARACTERS};
pub use reply::{PollFault, ReplyScanner};
pub use tracker::{EncoderTracker, WheelTicks};

/// First input register read: the block below is read in one request (function 04).
pub const FIRST_REGISTER: u16 = 0;
/// Number of input registers in the block.
pub const REGISTER_COUNT: u16 = 6;
/// Left encoder count, high word (u32, high word first, then the low word at +1).
pub const REG_LEFT_TICKS: usize = 0;
/// Right encoder count, high word (u32, high word first).
pub const REG_RIGHT_TICKS: usize = 2;
/// CMPS03 bearing in tenths of a degree, 0–3599, clockwise from magnetic north.
pub const REG_BEARING: usize = 4;
/// Sample counter (u16, wraps): +1 each time the controller latches the block for a read.
pub const REG_COUNTER: usize = 5;
/// Largest valid bearing register value (359.9°).
pub const MAX_BEARING_TENTHS: u16 = 3599;

/// One read of the register block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BaseReading {
    /// Left encoder count (wraps at 2³²).
    pub left_ticks: u32,
    /// Right encoder count (wraps at 2³²).
    pub right_ticks: u32,
    /// Compass bearing (tenths of a degree, clockwise from magnetic north).
    pub bearing_tenths: u16,
    /// Sample counter.
    pub counter: u16,
}

impl BaseReading {
    /// The readings of the register block.
    pub fn from_registers(r: &[u16; REGISTER_COUNT as usize]) -> Self {
        let u32_at = |i: usize| (u32::from(r[i]) << 16) | u32::from(r[i + 1]);
        Self {
            left_ticks: u32_at(REG_LEFT_TICKS),
            right_ticks: u32_at(REG_RIGHT_TICKS),
            bearing_tenths: r[REG_BEARING],
            counter: r[REG_COUNTER],
        }
    }

    /// The register block holding these readings.
    pub fn to_registers(self) -> [u16; REGISTER_COUNT as usize] {
        [
            (self.left_ticks >> 16) as u16,
            self.left_ticks as u16,
            (self.right_ticks >> 16) as u16,
            self.right_ticks as u16,
            self.bearing_tenths,
            self.counter,
        ]
    }

    /// The bearing in radians (clockwise from magnetic north), if the register holds a
    /// valid one.
    pub fn bearing(self) -> Option<f64> {
        (self.bearing_tenths <= MAX_BEARING_TENTHS)
            .then(|| (f64::from(self.bearing_tenths) / 10.0).to_radians())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registers_round_trip() {
        let r = BaseReading {
            left_ticks: 0xdead_beef,
            right_ticks: 7,
            bearing_tenths: 3599,
            counter: 65535,
        };
        assert_eq!(r.to_registers()[..2], [0xdead, 0xbeef]);
        assert_eq!(BaseReading::from_registers(&r.to_registers()), r);
        assert!((r.bearing().unwrap() - 359.9f64.to_radians()).abs() < 1e-12);
        let bad = BaseReading {
            bearing_tenths: 3600,
            ..r
        };
        assert_eq!(bad.bearing(), None);
    }
}
